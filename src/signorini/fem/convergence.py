"""Experimental orders of convergence and regression slopes."""

from __future__ import annotations

import numpy as np


def eoc(h: np.ndarray, e: np.ndarray) -> np.ndarray:
    """EOC_k = log(e_k / e_{k-1}) / log(h_k / h_{k-1}) (the paper's (27)); NaN for k = 0."""
    h, e = np.asarray(h, dtype=float), np.asarray(e, dtype=float)
    out = np.full(h.shape, np.nan)
    out[1:] = np.log(e[1:] / e[:-1]) / np.log(h[1:] / h[:-1])
    return out


def regression_slope(h: np.ndarray, e: np.ndarray) -> float:
    """Least-squares slope of log e against log h (the paper's "regr." row)."""
    slope, _ = np.polyfit(np.log(np.asarray(h, dtype=float)), np.log(np.asarray(e, dtype=float)), 1)
    return float(slope)

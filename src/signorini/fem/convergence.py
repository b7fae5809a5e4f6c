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


def eoc_uncertainty(h: np.ndarray, e: np.ndarray, de: np.ndarray) -> np.ndarray:
    """How far ``eoc(h, e)`` can move when each ``e_k`` moves by at most ``de_k``: to first order
    ``(de_k/e_k + de_{k-1}/e_{k-1}) / |log(h_k/h_{k-1})|``; NaN for k = 0."""
    h, rel = np.asarray(h, dtype=float), np.asarray(de, dtype=float) / np.asarray(e, dtype=float)
    out = np.full(h.shape, np.nan)
    out[1:] = (rel[1:] + rel[:-1]) / np.abs(np.log(h[1:] / h[:-1]))
    return out


def regression_uncertainty(h: np.ndarray, e: np.ndarray, de: np.ndarray) -> float:
    """How far ``regression_slope(h, e)`` can move when each ``e_k`` moves by at most ``de_k``: the
    slope is ``Σ w_k log e_k`` with ``w_k = (x_k − x̄) / Σ (x_j − x̄)²``, ``x = log h``, so to first
    order ``Σ |w_k| de_k / e_k``."""
    x = np.log(np.asarray(h, dtype=float))
    w = (x - x.mean()) / np.sum((x - x.mean()) ** 2)
    return float(np.sum(np.abs(w) * np.asarray(de, dtype=float) / np.asarray(e, dtype=float)))

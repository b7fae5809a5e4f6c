"""Intervals of measured times, of their ratios and of the exponents fitted to them.

A time measured several times (its *samples*, CPU seconds per call) is summarised by their median.
Its interval: the ``LEVEL`` percentile interval of a bootstrap of that median — ``RESAMPLES``
resamples, with replacement, of the samples, drawn by a generator seeded by ``SEED`` and a key of
the measurement (``median``), so that every rendering gives the same intervals whatever else was
measured.  A ratio of two times resamples the two independently; a least-squares exponent (log time
against log unknowns, log error against log time) is refitted through each resample.  These
intervals cover the variation of the samples only, not a departure from a fitted power law.  A time
with a single sample has no spread to resample: its bootstrap is its value alone, and a ratio or fit
all of whose times have one sample has no interval.  A ratio whose interval contains 1 is a tie
(``verdict``).
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Hashable, Sequence
from dataclasses import dataclass

import numpy as np

SEED = 0
RESAMPLES = 2000
LEVEL = 0.95  # the probability the percentile interval holds


def samples(times: str) -> np.ndarray:
    """The CPU seconds of a measurement's samples written as one text (space-separated; none: empty)."""
    return np.array([float(t) for t in times.split()], dtype=float)


@dataclass(frozen=True)
class Estimate:
    """A value, its bootstrap resamples and whether they vary (``spread``: an interval exists)."""

    value: float
    boot: np.ndarray
    spread: bool

    @property
    def interval(self) -> tuple[float, float] | None:
        """The ``LEVEL`` percentile interval of the resamples (None: no spread to resample)."""
        if not self.spread:
            return None
        tail = 50.0 * (1.0 - LEVEL)
        lo, hi = np.percentile(self.boot, [tail, 100.0 - tail])
        return float(lo), float(hi)

    def summary(self) -> dict:
        """``value``, ``lo``, ``hi`` (NaN without an interval) and ``interval`` (whether there is one)."""
        lo, hi = self.interval or (math.nan, math.nan)
        return {"value": self.value, "lo": lo, "hi": hi, "interval": self.spread}


def median(times: np.ndarray, key: Sequence[Hashable], value: float | None = None) -> Estimate:
    """The median of ``times`` (the samples) and its bootstrap, seeded by ``key`` (what identifies the
    measurement: the same resamples whatever else was measured); ``value``: the time reported when it
    is not the median itself (a constant added: a start's cost, the samples' rounding), the
    resamples shifted alike."""
    t = np.asarray(times, dtype=float)
    value = float(np.median(t)) if value is None else float(value)
    if t.size < 2:
        return Estimate(value, np.full(RESAMPLES, value), False)
    rng = np.random.default_rng([SEED, *(zlib.crc32(str(k).encode("utf-8")) for k in key)])
    medians = np.median(t[rng.integers(0, t.size, size=(RESAMPLES, t.size))], axis=1)
    return Estimate(value, medians + (value - float(np.median(t))), True)


def ratio(num: Estimate, den: Estimate) -> Estimate:
    """``num / den`` with the quotients of their (independent) resamples."""
    return Estimate(num.value / den.value, num.boot / den.boot, num.spread or den.spread)


def verdict(r: Estimate) -> str:
    """``tie`` (the ratio's interval contains 1), ``below`` or ``above`` 1 (it does not), or
    ``undetermined`` (no interval)."""
    if r.interval is None:
        return "undetermined"
    lo, hi = r.interval
    return "tie" if lo <= 1.0 <= hi else ("below" if hi < 1.0 else "above")


def _slopes(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares slopes of the rows of ``y`` against the rows of ``x`` (broadcast, logs taken)."""
    lx, ly = np.log(x), np.log(y)
    dx = lx - lx.mean(axis=-1, keepdims=True)
    dy = ly - ly.mean(axis=-1, keepdims=True)
    return (dx * dy).sum(axis=-1) / (dx * dx).sum(axis=-1)


def exponent(x: Sequence[float] | Sequence[Estimate], y: Sequence[float] | Sequence[Estimate]) -> Estimate:
    """The slope of log ``y`` against log ``x`` (each a sequence of numbers or of ``Estimate``),
    refitted through every resample; NaN with fewer than two points."""
    if len(x) < 2:
        return Estimate(math.nan, np.full(RESAMPLES, math.nan), False)

    def values(v) -> tuple[np.ndarray, np.ndarray, bool]:
        if isinstance(v[0], Estimate):
            return np.array([e.value for e in v]), np.stack([e.boot for e in v], axis=-1), any(e.spread for e in v)
        arr = np.asarray(v, dtype=float)
        return arr, arr, False

    (x0, xb, xs), (y0, yb, ys) = values(x), values(y)
    return Estimate(float(_slopes(x0, y0)), _slopes(xb, yb) * np.ones(RESAMPLES), xs or ys)


def shifted(e: Estimate, offset: float) -> Estimate:
    """``e`` plus a constant (e.g. the assembly time added to a solve time)."""
    return Estimate(e.value + float(offset), e.boot + float(offset), e.spread)

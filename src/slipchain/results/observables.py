"""Steady-state statistics of a sampled time series: transient end, mean and standard error.

* End of the loading transient: MSER (White 1997, "An effective truncation heuristic for bias
  reduction in simulation output"): the truncation point d minimising
  sum_{j>=d}(y_j - mean_{j>=d})^2 / (n - d)^2, searched over the first half of the series.
  The series is first averaged in blocks of 5 (MSER-5).
* Standard error of the mean of a time-correlated series: non-overlapping batch means with a
  fixed number of batches (default 20); SE = std(batch means, ddof=1)/sqrt(n_batches).
* A drift check: the means of the two halves of the steady window must agree within
  ``drift_sigmas`` combined standard errors, else the window is not yet steady.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MSER_BLOCK = 5

# A contact counts as "slow" (near sticking) while |u| < SLOW_FRACTION * v_d (per-contact statistic
# ``contact_slow_fraction``; the mechanism's stick-slip criterion is built on it).
SLOW_FRACTION = 0.1


def mser_truncation(y: np.ndarray, block: int = MSER_BLOCK) -> int:
    """Index of the first sample of the steady part of ``y`` (MSER-``block``).

    Returns a sample index (a multiple of ``block``) in [0, len(y)/2].
    """
    y = np.asarray(y, dtype=float)
    nblk = y.size // block
    if nblk < 4:
        return 0
    z = y[: nblk * block].reshape(nblk, block).mean(axis=1)
    # Tail sums from each start index d: S1 = sum z[d:], S2 = sum z[d:]^2.
    s1 = np.cumsum(z[::-1])[::-1]
    s2 = np.cumsum((z * z)[::-1])[::-1]
    count = np.arange(nblk, 0, -1, dtype=float)
    sse = s2 - s1 * s1 / count
    stat = sse / count**2
    half = nblk // 2
    d = int(np.argmin(stat[: half + 1]))
    return d * block


def batch_means_sem(y: np.ndarray, n_batches: int = 20) -> float:
    """Standard error of mean(y) by non-overlapping batch means (NaN if too short)."""
    y = np.asarray(y, dtype=float)
    size = y.size // n_batches
    if size < 1 or n_batches < 2:
        return float("nan")
    means = y[: size * n_batches].reshape(n_batches, size).mean(axis=1)
    return float(means.std(ddof=1) / np.sqrt(n_batches))


@dataclass(frozen=True)
class SteadyEstimate:
    """Mean of the steady part of a series with its standard error."""

    start: int  # first steady sample
    mean: float
    sem: float
    drift_ok: bool  # halves of the steady window agree
    n_samples: int


def window_velocity(x_mean: np.ndarray, start: int, x0_mean: float, interval: float) -> float:
    """Mean interface-layer velocity from sample ``start`` to the end of the sampled mean
    displacement ``x_mean`` (sample k ends at (k+1)*interval; ``x0_mean`` is the value at t = 0)."""
    x_start = x_mean[start - 1] if start > 0 else x0_mean
    return float((x_mean[-1] - x_start) / ((x_mean.shape[0] - start) * interval))


CYCLE_BAND = 0.5  # count_cycles: the trigger levels, mean -+ CYCLE_BAND standard deviations


def count_cycles(y: np.ndarray, band: float = CYCLE_BAND) -> int:
    """Completed cycles of a fluctuating series: the falls from above mean + band*std to below
    mean - band*std (a Schmitt trigger, so that noise around the mean is not counted). For the
    sawtooth of system-wide stick-slip one per slip event; for uncorrelated noise about one per
    few samples (the run-length condition ``min_cycles``, :class:`slipchain.engine.control.UntilConverged`)."""
    return int(cycle_falls(y, band).size)


def cycle_falls(y: np.ndarray, band: float = CYCLE_BAND) -> np.ndarray:
    """The samples at which :func:`count_cycles` counts a fall: each first sample below mean - band*std
    after one above mean + band*std (indices into ``y``; one per slip event of a system-wide sawtooth)."""
    y = np.asarray(y, dtype=float)
    if y.size < 2:
        return np.zeros(0, dtype=np.int64)
    mean, std = y.mean(), y.std()
    hi, lo = y > mean + band * std, y < mean - band * std
    idx = np.flatnonzero(hi | lo)
    state = hi[idx]
    return idx[1:][state[:-1] & ~state[1:]]


def whole_cycle_mean(y: np.ndarray, band: float = CYCLE_BAND) -> float:
    """The mean of ``y`` over whole cycles: from its first fall (:func:`cycle_falls`) to the sample before its last,
    so that every cycle in it is cut at the same phase; NaN with fewer than two falls. For a run that stick-slips as
    a whole the mean over a window that ends at another phase differs from it by up to about swing/(2 cycles): at
    epsilon = 1 on 128 x 128, 0.34 % at theta = 1, six times mu_star's batch-means SE (docs/performance.md,
    "Samples of 5 ms")."""
    falls = cycle_falls(y, band)
    if falls.size < 2:
        return float("nan")
    return float(np.asarray(y, dtype=float)[falls[0]:falls[-1]].mean())


def steady_estimate(y: np.ndarray, n_batches: int = 20, drift_sigmas: float = 4.0) -> SteadyEstimate:
    """MSER truncation, then batch-means mean and SE of what remains, plus the drift check."""
    y = np.asarray(y, dtype=float)
    start = mser_truncation(y)
    tail = y[start:]
    if tail.size == 0:
        return SteadyEstimate(start, float("nan"), float("nan"), False, 0)
    sem = batch_means_sem(tail, n_batches)
    h = tail.size // 2
    drift_ok = False
    if h >= n_batches:
        first, second = tail[:h], tail[h : 2 * h]
        se_halves = np.hypot(batch_means_sem(first, n_batches // 2), batch_means_sem(second, n_batches // 2))
        drift_ok = bool(abs(first.mean() - second.mean()) <= drift_sigmas * se_halves + 1e-300)
    return SteadyEstimate(start, float(tail.mean()), sem, drift_ok, int(tail.size))

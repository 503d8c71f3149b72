"""MSER truncation and batch-means standard errors on series with known answers."""

import numpy as np
import pytest

from slipchain.results.observables import batch_means_sem, mser_truncation, steady_estimate


def _ar1(n, phi, sigma, rng):
    e = rng.normal(0, sigma, n)
    y = np.empty(n)
    y[0] = e[0] / np.sqrt(1 - phi**2)
    for i in range(1, n):
        y[i] = phi * y[i - 1] + e[i]
    return y


def test_mser_finds_the_end_of_a_loading_ramp():
    rng = np.random.default_rng(0)
    t = np.arange(4000)
    y = np.minimum(t / 1000.0, 1.0) + rng.normal(0, 0.02, t.size)  # ramp to 1 over 1000 samples
    d = mser_truncation(y)
    assert 900 <= d <= 1200


def test_batch_means_matches_ar1_theory():
    rng = np.random.default_rng(1)
    phi, sigma, n = 0.9, 1.0, 200_000
    # Var(mean) of AR(1) ~ sigma^2 / ((1 - phi)^2 n) for large n.
    true_se = sigma / (1 - phi) / np.sqrt(n)
    ses = [batch_means_sem(_ar1(n, phi, sigma, rng)) for _ in range(5)]
    assert np.mean(ses) == pytest.approx(true_se, rel=0.25)
    # The naive i.i.d. formula would be about 4x too small here.
    naive = sigma / np.sqrt(1 - phi**2) / np.sqrt(n)
    assert np.mean(ses) > 3 * naive


def test_drift_is_detected():
    rng = np.random.default_rng(2)
    flat = rng.normal(1.0, 0.01, 4000)
    assert steady_estimate(flat).drift_ok
    drifting = flat + np.linspace(0, 0.2, 4000)
    assert not steady_estimate(drifting).drift_ok

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


def _run(t, f, x, t_transient=0.0):
    import xarray as xr
    return xr.Dataset({"f_d": ("time", f), "x_mean": ("time", x)}, coords={"time": t},
                      attrs={"t_transient": t_transient})


def test_sawtooth_of_system_wide_stick_slip_and_of_steady_sliding():
    """analysis.geometry.sawtooth against series whose answer is known: a sawtooth with 11 falls that
    reloads linearly from 0 to 2 and falls at once while the interface advances only in the falls, and
    steady sliding whose f_d is white noise about a mean while the interface advances uniformly."""
    from slipchain.analysis.geometry import WHOLE_SLIP_SHARE, sawtooth, sawtooth_table

    n, per = 2990, 250  # 1-ms samples, a fall every 250 samples (0.25 s): 11 falls in 2.99 s
    i = np.arange(n) + 1
    t = i * 1e-3
    f = 2.0 * (i % per) / per  # the mean is about 1: the swing (p99 - p1)/mean is about 2
    x = np.cumsum(i % per == 0) * 1e-4  # the interface advances only in the samples where f_d falls
    s = sawtooth(_run(t, f, x))
    assert s["cycles"] == 11
    assert s["period"] == pytest.approx((t[-1] - t[0]) / 11)
    assert s["swing"] == pytest.approx(1.96, abs=0.02)
    assert s["event_share"] == pytest.approx(1.0)
    # over whole cycles the tooth 2k/per (k = 0 .. per-1) averages (per-1)/per; the window (cut mid-tooth at both
    # ends: up to 249/250 at the start, to 240/250 at the end) averages otherwise, and phase_bias is the difference
    # over that: -0.26 % here
    assert s["phase_bias"] == pytest.approx(f.mean() / ((per - 1) / per) - 1.0, rel=1e-12)
    assert abs(s["phase_bias"]) > 1e-3
    # the transient is left out: the window starts on the 6th fall (t = 1.5 s), so 5 falls remain after it
    assert sawtooth(_run(t, f, x, t_transient=1.499))["cycles"] == 5

    rng = np.random.default_rng(3)
    g = 1.0 + 0.01 * rng.standard_normal(n)
    steady = sawtooth(_run(t, g, 1e-3 * t))
    assert steady["swing"] == pytest.approx(4.65 * 0.01, rel=0.1)  # 2 x 2.326 standard deviations
    assert steady["event_share"] == pytest.approx(0.5, abs=0.03)  # half the samples fall
    assert steady["cycles"] > 200  # noise crosses the trigger levels every few samples
    assert abs(steady["phase_bias"]) < 1e-3  # noise has no phase: its mean over whole 'cycles' is its mean

    table = sawtooth_table([dict(geometry="slab", theta=1.0, v_d=1e-3, seed=k, **s) for k in (0, 1)]
                           + [dict(geometry="chain2d", theta=1.0, v_d=1e-3, seed=0, **steady)])
    assert list(table["geometry"]) == ["chain2d", "slab"] and list(table["n"]) == [1, 2]
    assert table.set_index("geometry").loc["slab", "cycles"] == 22
    assert list(table["whole"]) == [False, True] and WHOLE_SLIP_SHARE < 1.0
    assert table.set_index("geometry").loc["slab", "phase_bias"] == pytest.approx(s["phase_bias"])


def test_whole_cycle_mean_of_a_sawtooth_is_its_mean_where_a_cut_window_is_not():
    """A sawtooth y = frac(t) (mean 1/2 over whole cycles) seen through a window that starts and ends mid-cycle:
    the plain mean is biased by the partial cycles (analytically, for 0.3 ... 7.9: (sum of whole teeth 6 x 1/2 +
    the partial ones) / 7.6), the mean over whole cycles is 1/2 to the sampling; the falls are the teeth's drops,
    as many as count_cycles counts (also on noise)."""
    from slipchain.results.observables import count_cycles, cycle_falls, whole_cycle_mean

    n = 1000  # samples per tooth
    t = np.arange(int(0.3 * n), int(7.9 * n)) / n
    y = t % 1.0
    plain = (0.5 * (1 - 0.3**2) + 6 * 0.5 + 0.5 * 0.9**2) / 7.6  # exact integral of frac(t) over [0.3, 7.9] / 7.6
    assert abs(y.mean() - plain) < 1e-3 and abs(plain - 0.5) > 0.0075  # 0.0079: the partial teeth
    assert abs(whole_cycle_mean(y) - 0.5) < 1e-3
    falls = cycle_falls(y)
    assert falls.size == count_cycles(y) == 7 and np.all(y[falls] < 0.3) and np.all(y[falls - 1] > 0.7)
    rng = np.random.default_rng(3)
    for _ in range(20):
        noise = rng.standard_normal(rng.integers(2, 400))
        assert cycle_falls(noise).size == count_cycles(noise)
    assert np.isnan(whole_cycle_mean(np.ones(10))) and cycle_falls(np.ones(1)).size == 0

"""Friction-tester analysis: velocity recovery, runaway detection, uncertainties, bad data, the load test."""

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from slipchain.tester import TesterDataError
from slipchain.workflows.tester import analyze
from slipchain.tester.analysis import load_tests, maxima, mu_with_uncertainty
from slipchain.analysis.experiment import fit_scale
from slipchain.tester.synth import SynthLaw, SynthSetup, synthesize
from slipchain.results.velocity import NO_STEADY, OK, RUNAWAY, steady_velocity


def test_straight_line_velocity_and_its_standard_error():
    """White noise on x = v t: the z-scores of the fitted velocity have unit spread."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 10, 200)
    v, sigma = 2e-4, 5e-6
    z = []
    for _ in range(300):
        fit = steady_velocity(t, v * t + rng.normal(0, sigma, t.size))
        assert fit.status == OK
        z.append((fit.velocity - v) / fit.sem)
    z = np.array(z)
    assert abs(z.mean()) < 0.2 and 0.8 < z.std() < 1.2
    # the SE is the textbook OLS slope error sigma/sqrt(sum (t - mean t)^2) (window = whole record here)
    fit = steady_velocity(t, v * t + rng.normal(0, sigma, t.size))
    assert fit.sem == pytest.approx(sigma / np.sqrt(np.sum((t - t.mean()) ** 2)), rel=0.25)


def test_start_up_transient_is_excluded():
    rng = np.random.default_rng(4)
    t = np.linspace(0, 20, 400)
    v, tau = 1e-4, 2.0  # exponential approach to v
    x = v * (t - tau * (1 - np.exp(-t / tau))) + rng.normal(0, 2e-7, t.size)
    fit = steady_velocity(t, x)
    assert fit.status == OK and fit.t_start >= 2.0
    assert abs(fit.velocity - v) < 3 * fit.sem
    naive = np.polyfit(t, x, 1)[0]  # a fit over the whole record is biased by the transient
    assert abs(naive - v) > 10 * fit.sem


def test_runaway_and_no_steady_are_flagged():
    t = np.linspace(0, 5, 300)
    noise = np.random.default_rng(5).normal(0, 1e-6, t.size)
    acc = steady_velocity(t, 1e-3 * t + 0.5 * 2e-3 * t**2 + noise)
    assert acc.status == RUNAWAY and "runaway" in acc.reason and np.isnan(acc.velocity)
    dec = steady_velocity(t, 1e-3 * (1 - np.exp(-t / 1.0)) * 10 + noise)  # slowing down to a stop
    assert dec.status == NO_STEADY
    still = steady_velocity(t, noise)
    assert still.status == NO_STEADY and "does not move" in still.reason


def test_synthetic_tester_velocities_recovered_within_uncertainty_and_runaways_found():
    runs, traces, truth = synthesize(SynthSetup(seed=1))
    truth = truth.set_index("run_id")
    n_ok = 0
    for rid, g in traces.groupby("run_id"):
        fit = steady_velocity(g["time_s"].to_numpy(), g["distance_m"].to_numpy())
        tr = truth.loc[rid]
        if tr["runaway"]:
            assert fit.status == RUNAWAY, (rid, fit.reason)
        else:
            assert fit.status == OK, (rid, fit.reason)
            assert abs(fit.velocity - tr["velocity_m_s"]) <= 3 * fit.sem, (rid, fit.velocity, tr["velocity_m_s"], fit.sem)
            n_ok += 1
    assert n_ok >= 20 and truth["runaway"].sum() >= 6


def test_planted_law_and_its_maximum():
    law = SynthLaw()
    v_max, mu_max = law.maximum(law.p_ref)  # at p_ref the load term vanishes: maximum of mu0*exp(-c xi^2)
    assert v_max == pytest.approx(law.v_peak, rel=1e-4) and mu_max == pytest.approx(law.mu0, rel=1e-9)
    v = law.steady_velocity(0.8 * law.mu0, law.p_ref)
    assert v == pytest.approx(law.v_peak * 10 ** (-math.sqrt(-math.log(0.8) / law.c)), rel=1e-9)


def test_mu_uncertainty_propagation():
    mu, se = mu_with_uncertainty(10.0, 5.0, 0.01)
    assert mu == 0.5 and se == pytest.approx(0.5 * math.hypot(0.01 / 5, 0.01 / 10), rel=1e-12)
    rng = np.random.default_rng(0)  # Monte Carlo: independent method
    samples = (5.0 + rng.normal(0, 0.01, 200_000)) / (10.0 + rng.normal(0, 0.01, 200_000))
    assert samples.std() == pytest.approx(se, rel=0.02)
    assert mu_with_uncertainty(10.0, 5.0, 0.0)[1] == 0.0


RUNS_HEADER = "run_id,surface,compound,temperature_C,slider_mass_kg,hanging_mass_kg,nominal_area_m2,mass_uncertainty_kg,velocity_m_s\n"


def _trace(rid, v=1e-4, n=50, t_end=10.0):
    t = np.linspace(0, t_end, n)
    return "".join(f"{rid},{float(ti)!r},{float(v * ti)!r}\n" for ti in t)


def test_bad_data_excludes_runs_with_file_line_and_column(tmp_path):
    runs = tmp_path / "runs.csv"
    runs.write_text(RUNS_HEADER
                    + "A,s,c,20,10,5,0.004,0.001,\n"          # line 2: good
                    + "B,s,c,20,ten,5,0.004,0.001,\n"         # line 3: non-numeric mass
                    + "C,s,c,20,10,-5,0.004,0.001,\n"         # line 4: negative mass
                    + "D,s,c,20,10,5,0.004,0.001,\n"          # line 5: duplicate of line 6
                    + "D,s,c,20,10,6,0.004,0.001,\n"          # line 6
                    + "E,s,c,20,10,5,0.004,0.001,\n"          # line 7: non-increasing time
                    + "F,s,c,20,10,5,0.004,0.001,\n"          # line 8: too few points
                    + "G,s,c,20,10,5,0.004,0.001,2e-4\n"      # line 9: velocity given, no trace
                    + "H,s,c,20,10,5,0.004,-0.1,\n"           # line 10: negative uncertainty
                    + "I,s,c,20,10,5,0.004,0.001,\n")         # line 11: no trace, no velocity
    traces = tmp_path / "traces.csv"
    body = _trace("A") + _trace("B") + _trace("C") + _trace("D")
    e_lines = _trace("E").splitlines()
    e_lines[10] = e_lines[9]  # a repeated time stamp
    body += "\n".join(e_lines) + "\n" + _trace("F", n=5) + _trace("Z")
    traces.write_text("run_id,time_s,distance_m\n" + body)
    res = analyze(runs, traces, tmp_path / "out")
    t = res.runs.set_index("run_id")
    assert t.loc["A", "status"] == "ok" and t.loc["A", "velocity_m_s"] == pytest.approx(1e-4, rel=1e-9)
    assert t.loc["B", "status"] == "invalid" and "runs.csv, line 3, column slider_mass_kg: 'ten' is not a number" in t.loc["B", "reason"]
    assert "runs.csv, line 4, column hanging_mass_kg: -5; expected a number > 0" in t.loc["C", "reason"]
    d = res.runs[res.runs["run_id"] == "D"]
    assert len(d) == 2 and (d["status"] == "invalid").all()
    assert any("line 6, column run_id: duplicate of line 5" in r for r in d["reason"])
    e_line = 1 + 50 * 4 + 11  # header + four 50-row traces + the 11th row of E
    assert t.loc["E", "status"] == "invalid" and f"traces.csv, line {e_line}, column time_s" in t.loc["E", "reason"]
    assert "does not increase" in t.loc["E", "reason"]
    assert "5 points; at least 20" in t.loc["F", "reason"]
    assert t.loc["G", "status"] == "ok" and t.loc["G", "velocity_m_s"] == 2e-4 and "no trace" in t.loc["G", "reason"]
    assert "column mass_uncertainty_kg: -0.1; expected a number >= 0" in t.loc["H", "reason"]
    assert t.loc["I", "status"] == "no-velocity"
    assert t.loc["Z", "status"] == "invalid" and "not in the runs table" in t.loc["Z", "reason"]
    # nothing silently dropped: every run of the table and every orphan trace has its row on disk
    on_disk = pd.read_csv(tmp_path / "out" / "runs.csv")
    assert len(on_disk) == 10 + 1 and set(on_disk.columns) >= {"run_id", "pressure_Pa", "velocity_m_s",
                                                                "velocity_sem_m_s", "mu", "mu_sem", "status", "reason"}


@pytest.mark.parametrize("text, words", [
    ("run_id,surface,temperature_C\nA,s,20\n", ["runs.csv, line 1", "missing column(s) compound, slider_mass_kg"]),
    ("", ["runs.csv", "file is empty"]),
])
def test_unreadable_runs_table_is_an_error(tmp_path, text, words):
    runs = tmp_path / "runs.csv"
    runs.write_text(text)
    with pytest.raises(TesterDataError) as e:
        analyze(runs, None, tmp_path / "out")
    for w in words:
        assert w in str(e.value)


def test_trace_errors_name_file_line_and_column(tmp_path):
    runs = tmp_path / "runs.csv"
    runs.write_text(RUNS_HEADER + "A,s,c,20,10,5,0.004,0.001,\n")
    traces = tmp_path / "traces.csv"
    traces.write_text("run_id,time_s\nA,1\n")
    with pytest.raises(TesterDataError, match=r"traces.csv, line 1: missing column\(s\) distance_m"):
        analyze(runs, traces, tmp_path / "o")
    traces.write_text("run_id,time_s,distance_m\nA,0,0\n,1,1\n")
    with pytest.raises(TesterDataError, match="traces.csv, line 3, column run_id: empty"):
        analyze(runs, traces, tmp_path / "o")
    with pytest.raises(TesterDataError, match="does not exist"):
        analyze(tmp_path / "nope.csv", None, tmp_path / "o")


def _load_test(s, seed):
    setup = SynthSetup(seed=seed)
    runs, traces, _ = synthesize(replace(setup, law=replace(setup.law, s=s)))
    from slipchain.tester.analysis import analyze_runs
    from slipchain.tester.inputs import Run

    rs = []
    for r in runs.to_dict("records"):
        g = traces[traces["run_id"] == r["run_id"]]
        rs.append(Run(**r, time_s=g["time_s"].to_numpy(), distance_m=g["distance_m"].to_numpy()))
    table = analyze_runs(rs)
    (test,) = load_tests(table, maxima(table))
    return test


@pytest.mark.parametrize("seed", [0, 1])
def test_load_effect_detected_when_planted_and_not_when_absent(seed):
    planted = _load_test(0.15, seed)
    assert planted.near.decreasing and planted.far.consistent_with_zero and planted.claim_holds
    none = _load_test(0.0, seed)
    assert not none.near.decreasing and none.near.consistent_with_zero and not none.claim_holds


def test_fit_scale_recovers_a_known_factor():
    cv = np.geomspace(1e-5, 1e-2, 7)
    cm = 0.9 + 0.05 * np.log10(cv)
    v = np.geomspace(2e-5, 5e-3, 9)
    mu = 1.7 * np.interp(np.log10(v), np.log10(cv), cm)
    assert fit_scale(v, mu, (cv, cm)) == pytest.approx(1.7, rel=1e-12)
    assert math.isnan(fit_scale(np.array([1e-9]), np.array([1.0]), (cv, cm)))


def test_cli_synth_analyze_and_model_overlay(tmp_path, slipchain_cli, store_of_runs):
    from slipchain.sweeps.definition import make_sweep

    syn = slipchain_cli("tester", "synth", "--out", tmp_path / "syn")
    assert syn.returncode == 0 and "SYNTHETIC DATA" in syn.stderr
    assert "SYNTHETIC DATA" in (tmp_path / "syn" / "README.txt").read_text()
    ana = slipchain_cli("tester", "analyze", tmp_path / "syn" / "runs.csv", "--traces", tmp_path / "syn" / "traces.csv",
                        "--out", tmp_path / "ana")
    assert ana.returncode == 0, ana.stderr
    assert "load claim supported" in ana.stdout
    assert "supported" in (tmp_path / "ana" / "summary.md").read_text()
    assert len(pd.read_csv(tmp_path / "ana" / "maxima.csv")) == 3
    # a tiny model sweep over v_d (members run here, stored as a sweep would store them)
    sw = make_sweep({"name": "v", "base": {"N": 31, "start": "steady", "v0": 0.01, "delta": 0.2, "t_total": 3e-3},
                     "grid": {"v_d": [1e-5, 1e-4, 1e-3]}})
    store_of_runs(tmp_path / "store", sw)
    fig = slipchain_cli("figure", "tester", "--runs", tmp_path / "ana", "--store", tmp_path / "store")
    assert fig.returncode == 0, fig.stderr
    assert (tmp_path / "ana" / "model_vs_experiment_synthetic-asphalt.png").exists()


def test_bytes_that_are_not_utf8_give_one_line_and_exit_2_writing_nothing(tmp_path, slipchain_cli):
    # Before: a UnicodeDecodeError traceback, exit 1.
    bad = tmp_path / "runs.csv"
    bad.write_bytes(b"run_id,surface\nR1,\xff\xfeasphalt\n")
    proc = slipchain_cli("tester", "analyze", bad, "--out", tmp_path / "out")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip() == f"error: {bad}: not UTF-8 text: byte 0xff at byte offset 18 (line 2)"
    assert not (tmp_path / "out").exists()


def test_a_fit_whose_variance_rounds_below_zero_gives_no_nan():
    """Issue 30: a smooth 75-point trace of <X> (tests/data: the dead-weight row of
    tests/physics/test_backends.py over 2e-5 s) fits a parabola so well that the pseudo-inverse
    returns its coefficient variance as a negative round-off; the square root gave a NaN and a
    RuntimeWarning. Now that variance is zero: no warning, a finite reason, and the straight line
    x = v t (an exact fit) has a standard error of zero, not NaN."""
    import warnings
    from pathlib import Path

    data = np.load(Path(__file__).resolve().parents[1] / "data" / "velocity-negative-variance.npz")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = steady_velocity(data["t"], data["x"])
        assert fit.status == RUNAWAY and "nan" not in fit.reason.lower()
        t = np.linspace(0.0, 1.0, 101)
        line = steady_velocity(t, 1e-3 * t)
    assert line.status == OK and line.velocity == pytest.approx(1e-3) and 0.0 <= line.sem < 1e-15

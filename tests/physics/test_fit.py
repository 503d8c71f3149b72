"""The model fitted to tester data (issue 14, item 3): the closed-form rising branch against the
contact law, recovery of planted parameters from synthetic tester data, identifiability, and the
failure modes through the CLI."""

import json
import math

import numpy as np
import pandas as pd
import pytest

from slipchain import make_config
from slipchain.analysis.fit import FitError, ModelLaw, ModelMaxima, dg_dlnv, fit_runs, g, g_max, model_maxima
from slipchain.tester.synth import SynthSetup, write_synthetic
from slipchain.workflows.tester import analyze

# A planted lowering of the maximum with load (15 % from theta 0.1 to 1): strong enough to fix p_ref.
PLANTED_R = ModelMaxima(np.array([0.1, 0.3, 1.0]), np.array([1.0, 0.93, 0.85]), np.zeros(3), 0.1, "planted")


@pytest.mark.parametrize("delta", [0.0, 0.5, 1.3])
def test_closed_form_branch_equals_the_contact_law_averaged_over_vstar(delta):
    cfg = make_config(delta=delta, eta_c=0.0, dt=1e-9)
    n = 20001  # midpoints of a uniform grid in log10 v*: an independent quadrature of eq. (1)
    vstar = cfg.v0 * 10 ** (delta * (2 * (np.arange(n) + 0.5) / n - 1))
    v = np.geomspace(cfg.v0 * 1e-4, cfg.v0 * 1e3, 41)
    direct = cfg.contact_law.average(v, vstar) / cfg.contact_law.amplitude
    assert g(v, cfg.v0, delta, cfg.c) == pytest.approx(direct, rel=1e-6, abs=1e-9)
    assert g_max(delta, cfg.c) == pytest.approx(float(g(np.array(cfg.v0), cfg.v0, delta, cfg.c)), rel=1e-12)
    h = 1e-5  # the slope against a central difference in ln v
    fd = (g(v * math.exp(h), cfg.v0, delta) - g(v * math.exp(-h), cfg.v0, delta)) / (2 * h)
    assert dg_dlnv(v, cfg.v0, delta) == pytest.approx(fd, rel=1e-5, abs=1e-9)


def _synthetic(tmp_path, r: ModelMaxima, seed: int = 1):
    law = ModelLaw(r)
    write_synthetic(tmp_path / "synth", SynthSetup(law=law, runaway_factors=(1.02, 1.05, 1.1), seed=seed))
    analyze(tmp_path / "synth" / "runs.csv", tmp_path / "synth" / "traces.csv", tmp_path / "an")
    return law, pd.read_csv(tmp_path / "an" / "runs.csv")


def test_fit_recovers_the_planted_parameters_within_their_intervals(tmp_path):
    law, runs = _synthetic(tmp_path, PLANTED_R)
    (f,) = fit_runs(runs, PLANTED_R)
    assert f.converged
    for name in ("F", "v0", "delta", "p_ref"):
        e = f.params[name]
        assert e.ci_low <= getattr(law, name) <= e.ci_high, (name, e, getattr(law, name))
        assert math.isfinite(e.se) and e.se > 0
    # the run-to-run scatter the synthetic tester plants (2 %) is found, and the residuals are then normal
    assert 0.01 < f.scatter < 0.04 and f.chi2 / f.dof == pytest.approx(1.0, abs=0.5)
    # the planted fall of the maximum between the smallest and largest pressure, and the fitted one
    p = f.pressures["pressure_Pa"].to_numpy()
    truth = 1 - PLANTED_R(p[-1] / law.p_ref) / PLANTED_R(p[0] / law.p_ref)
    assert abs(f.fall_fitted.value - truth) <= 3 * f.fall_fitted.se
    assert abs(f.fall_observed.value - truth) <= 3 * f.fall_observed.se


def test_without_a_load_effect_p_ref_is_not_determined_and_the_fit_says_so(tmp_path):
    flat = ModelMaxima(np.array([0.1, 1.0]), np.array([0.97, 0.97]), np.zeros(2), 0.1, "flat")
    law, runs = _synthetic(tmp_path, flat)
    (f,) = fit_runs(runs, flat)
    e = f.params["p_ref"]
    assert not math.isfinite(e.se) or e.ci_high / e.ci_low > 1e3
    assert any("do not determine" in n for n in f.notes)
    assert f.fall_fitted.value == pytest.approx(0.0, abs=1e-12)  # a flat r predicts no fall
    for name in ("F", "v0", "delta"):  # the branch parameters are still found
        assert f.params[name].ci_low <= getattr(law, name) <= f.params[name].ci_high


def _model_dir(path, thetas=(0.1, 0.3, 1.0), r=(1.0, 0.93, 0.85)):
    path.mkdir()
    gm = g_max(0.5)
    pd.DataFrame({"theta": thetas, "mu_max": [x * gm for x in r], "mu_max_se": [0.001] * len(thetas)}).to_csv(
        path / "mu_max_summary.csv", index=False)
    (path / "plan.toml").write_text("[base]\nN = 11\n")
    return path


def test_cli_synth_analyze_fit_recovers_the_truth_and_bad_input_exits_2(tmp_path, slipchain_cli):
    model = _model_dir(tmp_path / "model")
    assert np.allclose(model_maxima(model).r, PLANTED_R.r)

    cli = slipchain_cli
    r = cli("tester", "synth", "--model", model, "--seed", 1, "--out", tmp_path / "s")
    assert r.returncode == 0, r.stderr
    assert json.loads((tmp_path / "s" / "planted.json").read_text())["p_ref"] == 60e3
    assert cli("tester", "analyze", tmp_path / "s" / "runs.csv", "--traces", tmp_path / "s" / "traces.csv",
               "--out", tmp_path / "a").returncode == 0
    r = cli("tester", "fit", tmp_path / "a" / "runs.csv", "--model", model, "--truth", tmp_path / "s" / "planted.json",
            "--out", tmp_path / "f")
    assert r.returncode == 0, r.stderr
    report = (tmp_path / "f" / "fit.md").read_text()
    assert report.count("(inside)") == 4 and "OUTSIDE" not in report
    fit = pd.read_csv(tmp_path / "f" / "fit.csv")
    assert set(fit["parameter"]) >= {"F", "v0", "delta", "p_ref", "fall_fitted", "fall_observed"}
    assert list((tmp_path / "f").glob("fit_*.png"))
    # failure modes: exit 2, one error line naming the problem, nothing written
    one_theta = _model_dir(tmp_path / "one", thetas=(0.5,), r=(0.9,))
    runs = tmp_path / "a" / "runs.csv"
    cut = tmp_path / "cut.csv"
    pd.read_csv(runs).drop(columns=["velocity_sem_m_s"]).to_csv(cut, index=False)
    text_model = _model_dir(tmp_path / "text")
    (text_model / "mu_max_summary.csv").write_text("theta,mu_max,mu_max_se\n0.1,high,0.01\n1,0.9,0.01\n")
    texty = tmp_path / "texty.csv"
    t = pd.read_csv(runs, dtype=str)
    t.loc[2, "mu"] = "abc"
    t.to_csv(texty, index=False)
    for args, words in (((runs, "--model", one_theta), "at least 2"),
                        ((runs, "--model", text_model), "column 'mu_max' has 'high' in data row 1"),
                        ((texty, "--model", model), "column 'mu' has 'abc' in data row 3"),
                        ((runs, "--model", tmp_path), "mu_max_summary.csv"),
                        ((cut, "--model", model), "velocity_sem_m_s"),
                        ((tmp_path / "none.csv", "--model", model), "none.csv")):
        bad = cli("tester", "fit", *args, "--out", tmp_path / "x")
        assert bad.returncode == 2 and bad.stderr.startswith("error:") and words in bad.stderr, bad.stderr
        assert "Traceback" not in bad.stderr and not (tmp_path / "x").exists()
    bad = cli("tester", "synth", "--model", model, "--delta", -1, "--out", tmp_path / "x")
    assert bad.returncode == 2 and "--delta" in bad.stderr and not (tmp_path / "x").exists()


def test_fit_needs_steady_runs_at_two_pressures(tmp_path):
    _, runs = _synthetic(tmp_path, PLANTED_R)
    one = runs[runs["pressure_Pa"] == runs["pressure_Pa"].min()]
    with pytest.raises(FitError, match="at least 2 pressures"):
        fit_runs(one, PLANTED_R)
    with pytest.raises(FitError, match="no steady or runaway run"):
        fit_runs(runs.assign(status="invalid"), PLANTED_R)

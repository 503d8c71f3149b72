"""A master curve fitted to Prony terms with pyvisco, and the compound's moduli (issue 28, item 3):
the fit recovers planted terms, does not depend on the file's unit, writes a valid config; bad
files are refused naming what is wrong, with nothing written; ``material show`` obeys
time-temperature superposition."""


import numpy as np
import pytest

from slipchain.model.config import load_config
from slipchain.model.master_curve import MasterCurveError, fit_master_curve, master_curve_csv
from slipchain.model.viscoelastic import DEFAULT_COMPOUND, shift_factor, storage_loss

pytest.importorskip("pyvisco")  # installed by make (requirements-nodeps.txt)

FREQ = np.geomspace(1e-4, 1e12, 161)  # wide enough to reach both plateaus of the default compound


def _write(path, E_inf, E, tau, unit="MPa", freq=FREQ):
    s, l = storage_loss(freq, E_inf, np.asarray(E), np.asarray(tau))
    path.write_text(master_curve_csv(freq, s, l, unit))
    return path


def _assert_finds_the_planted_terms(fit_tau, fit_E, E_inf, E, tau):
    """The planted times lie on the fit's decade grid: each is found with its modulus (measured: within
    0.6 %), and the terms between them carry almost nothing (measured: 3e-5 of E_0). Matched to 1e-4
    decades, not by rounding: the fitted times differ from the decades in the 6th digit on some CPUs
    (e.g. 10**-7.00000123). Which near-zero terms the optimiser leaves above the fit's NEGLIGIBLE, and
    where, depends on the CPU (an AVX-512 Zen 5 keeps three, at 8.9e-9, 1.5e-8 and 1e3 s, 2e3 to 2e4 Pa
    beside E_0 = 1 GPa; an AVX2 EPYC none), so no test counts the terms."""
    got = dict(zip(np.log10(fit_tau), fit_E))
    for t, e in zip(tau, E):
        near = min(got, key=lambda lt: abs(lt - np.log10(t)))
        assert abs(near - np.log10(t)) < 1e-4
        assert got.pop(near) == pytest.approx(e, rel=2e-2)
    assert sum(got.values()) < 1e-4 * (E_inf + sum(E))


@pytest.mark.parametrize("planted", [
    (10e6, DEFAULT_COMPOUND.E, DEFAULT_COMPOUND.tau),  # the default compound: ten terms, one per decade
    (3e6, (2e8, 5e7, 4e7, 1e6), (1e-7, 1e-5, 1e-4, 1e-1)),  # a gap of a decade, uneven moduli
])
def test_fit_recovers_planted_prony_terms(tmp_path, planted):
    E_inf, E, tau = planted
    fit = fit_master_curve(_write(tmp_path / "m.csv", E_inf, E, tau), T_ref=20.0)
    _assert_finds_the_planted_terms(fit.tau, fit.E, E_inf, E, tau)
    assert fit.E_inf == pytest.approx(E_inf, rel=1e-2)
    assert fit.err_storage < 1e-2 and fit.err_loss < 1e-2


@pytest.mark.parametrize("unit", ["kPa", "GPa"])
def test_fit_does_not_depend_on_the_unit_of_the_file(tmp_path, unit):
    """The same curve in MPa and in another unit: the same moduli, in Pa. (The optimiser's path
    differs slightly with the numbers in the file, so the terms are compared through the curves.)"""
    a = fit_master_curve(_write(tmp_path / "mpa.csv", 10e6, DEFAULT_COMPOUND.E, DEFAULT_COMPOUND.tau, "MPa"), 20.0)
    b = fit_master_curve(_write(tmp_path / "b.csv", 10e6, DEFAULT_COMPOUND.E, DEFAULT_COMPOUND.tau, unit), 20.0)
    sa, la = storage_loss(FREQ, a.E_inf, np.asarray(a.E), np.asarray(a.tau))
    sb, lb = storage_loss(FREQ, b.E_inf, np.asarray(b.E), np.asarray(b.tau))
    assert np.max(np.hypot(sa - sb, la - lb) / np.hypot(sa, la)) < 3e-3
    assert a.E_inf == pytest.approx(b.E_inf, rel=3e-3)


def test_material_fit_writes_a_config_that_runs_the_fitted_compound(tmp_path, slipchain_cli):
    master = _write(tmp_path / "m.csv", 10e6, DEFAULT_COMPOUND.E, DEFAULT_COMPOUND.tau)
    proc = slipchain_cli("material", "fit", str(master), "--T-ref", "15", "--C1", "8", "--C2", "120", "--out", str(tmp_path / "o"))
    assert proc.returncode == 0, proc.stderr
    assert {p.name for p in (tmp_path / "o").iterdir()} == {"compound.toml", "master_curve_fit.png", "master_curve_fit.pdf"}
    cfg = load_config(tmp_path / "o" / "compound.toml")
    assert cfg.material == "prony" and cfg.T_ref == 15 and (cfg.wlf_C1, cfg.wlf_C2) == (8, 120)
    assert cfg.E == pytest.approx(10e6, rel=1e-2)
    _assert_finds_the_planted_terms(cfg.prony_tau, cfg.prony_E, 10e6, DEFAULT_COMPOUND.E, DEFAULT_COMPOUND.tau)


@pytest.mark.parametrize("text, says", [
    ("f,E_stor,E_loss\nHz,MPa,psi\n1,10,1\n10,11,2\n100,12,3\n", "E_loss"),  # a unit pyvisco does not know
    ("f,E_stor,E_loss\nHz,MPa,MPa\n10,10,1\n1,11,2\n100,12,3\n", "'f' is not strictly increasing"),
    ("f,E_stor,E_loss\nHz,MPa,MPa\n1,10,1\n10,-11,2\n100,12,3\n", "column 'E_stor' has value -11.0 in data row 2"),
    ("f,E_stor,E_loss\nHz,MPa,MPa\n1,10,1\n", "1 data rows; expected at least 3"),
    ("freq,E1,E2\nHz,MPa,MPa\n1,10,1\n10,11,2\n100,12,3\n", "header rows 'f,E_stor,E_loss'"),
])
def test_material_fit_refuses_a_bad_master_curve_and_writes_nothing(tmp_path, text, says, slipchain_cli):
    (tmp_path / "bad.csv").write_text(text)
    proc = slipchain_cli("material", "fit", str(tmp_path / "bad.csv"), "--T-ref", "20", "--out", str(tmp_path / "o"))
    assert proc.returncode == 2 and proc.stderr.startswith("error: master curve") and says in proc.stderr, proc.stderr
    assert not (tmp_path / "o").exists()


def test_fit_refuses_one_wlf_constant_without_the_other(tmp_path):
    master = _write(tmp_path / "m.csv", 10e6, DEFAULT_COMPOUND.E, DEFAULT_COMPOUND.tau)
    with pytest.raises(MasterCurveError, match="C1 = 8, C2 = None; expected both or neither"):
        fit_master_curve(master, 20.0, C1=8)


def test_material_show_obeys_time_temperature_superposition(tmp_path, slipchain_cli):
    """E'(f, T) = E'(f a_T, T_ref), E'' likewise: the WLF shift of every tau_j is a shift of the
    frequency axis (an identity of the Prony formulas; a wrong sign or factor fails it)."""
    import pandas as pd

    proc = slipchain_cli("material", "show", "--T", "20", "--T", "11", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    t = pd.read_csv(tmp_path / "material.csv")
    D = DEFAULT_COMPOUND
    a = shift_factor(11.0, D.T_ref, D.C1, D.C2)
    cold = t[t["T"] == 11.0]
    s, l = storage_loss(cold["f"].to_numpy() * a, 10e6, np.asarray(D.E), np.asarray(D.tau))
    assert a > 4 and np.allclose(cold["E_storage"], s, rtol=1e-6) and np.allclose(cold["E_loss"], l, rtol=1e-6)
    assert (tmp_path / "material.png").stat().st_size > 0


@pytest.mark.parametrize("args, says", [
    (["--set", "material=elastic"], "config key 'material' has value 'elastic'; expected 'prony'"),
    (["--T", "-150"], "option --T has value -150.0; expected a temperature above T_ref - C2"),
    (["--set", "prony_E=[1e8]"], "prony_tau"),
])
def test_material_show_refuses_bad_input_and_writes_nothing(tmp_path, args, says, slipchain_cli):
    proc = slipchain_cli("material", "show", *args, "--out", str(tmp_path / "o"))
    assert proc.returncode == 2 and says in proc.stderr, proc.stderr
    assert not (tmp_path / "o").exists()

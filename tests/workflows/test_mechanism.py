"""Stick-slip classifier, slip events, spectra and field recordings."""


import numpy as np
import pandas as pd
import pytest
import xarray as xr

from slipchain import make_config, run, simulate
from slipchain.analysis.mechanism import (classify_series, median_frequency, record_field, slip_events, spectra,
                                 state_from_run, stick_slip_fraction)
from slipchain.sweeps.store import Store
from slipchain.sweeps.definition import make_sweep
from slipchain.model.system import build_system

V_D = 1e-3


def test_classifier_on_constructed_signals():
    t = np.linspace(0, 1, 10_000, endpoint=False)
    steady = V_D * (1 + 0.05 * np.sin(2 * np.pi * 7 * t))
    ss, slow, cv = classify_series(steady, V_D)
    assert not ss and slow == 0.0 and cv == pytest.approx(0.05 / np.sqrt(2), rel=1e-3)
    # periodic stick-slip: stuck 80 % of each period, slipping at 5 v_d for 20 %: mean v_d
    phase = (t * 20) % 1
    stick_slip = np.where(phase < 0.8, 0.0, 5 * V_D)
    ss, slow, cv = classify_series(stick_slip, V_D)
    assert ss and slow == pytest.approx(0.8, abs=1e-3) and cv == pytest.approx(2.0, rel=1e-3)
    # creeping slowly half the time (|u| < 0.1 v_d) counts as stuck
    assert classify_series(np.where(phase < 0.5, 0.05 * V_D, 1.95 * V_D), V_D)[0]


def test_stick_slip_fraction_and_its_error():
    ds = xr.Dataset({"contact_slow_fraction": ("contact", np.array([0.0, 0.01, 0.3, 0.9, 0.049, 0.05]))})
    p, se = stick_slip_fraction(ds)
    assert p == pytest.approx(3 / 6) and se == pytest.approx(np.sqrt(0.25 / 6))


def _field(u, interval=1e-6, v_d=V_D, K_T=66.7):
    n, nb = u.shape
    return xr.Dataset({"u": (("time", "block"), u.astype(np.float32)), "f_d_instant": ("time", np.zeros(n)),
                       "acoustic": ("time", np.zeros(n))},
                      coords={"time": (np.arange(n) + 1) * interval, "block": np.arange(nb)},
                      attrs={"interval": interval, "v_d": v_d, "K_T": K_T})


def test_slip_events_on_a_known_space_time_pattern():
    u = np.full((100, 20), 0.5 * V_D)  # background creep below the threshold
    u[10:15, 3:8] = 5 * V_D            # event A: 5 blocks x 5 samples
    u[30:32, 18:20] = 3 * V_D          # event B crosses the periodic boundary: blocks 18, 19, 0, 1
    u[30:33, 0:2] = 3 * V_D
    u[50:60, 10] = 4 * V_D             # event C: one block, 10 samples
    u[55:58, 11] = 4 * V_D             #   ...touching C in space at the same times: still C
    u[97:100, 5:7] = 6 * V_D           # event D: runs into the end of the recording
    u[70, 15] = 1.99 * V_D             # just below the threshold: not slipping
    ev = slip_events(_field(u))
    assert ev.sizes["event"] == 4
    order = np.argsort(ev["event_start"].values)
    size = ev["event_size"].values[order].tolist()
    dur = np.round(ev["event_duration"].values[order] / 1e-6).astype(int).tolist()
    assert size == [5, 4, 2, 2] and dur == [5, 3, 10, 3]
    assert ev["event_truncated"].values[order].tolist() == [False, False, False, True]
    slip_a = 25 * 5 * V_D * 1e-6
    assert ev["event_slip"].values[order][0] == pytest.approx(slip_a, rel=1e-6)
    assert ev["event_force"].values[order][0] == pytest.approx(66.7 * slip_a, rel=1e-6)
    slip_c = (10 + 3) * 4 * V_D * 1e-6
    assert ev["event_slip"].values[order][2] == pytest.approx(slip_c, rel=1e-6)


def test_slip_events_in_two_dimensions_wrap_in_x_and_y():
    """Issue 13: clusters in (t, x, y) on an 8 x 6 periodic interface (block ix*6 + iy): one event
    wrapping across both edges, one touching it only diagonally (a separate event: face
    connectivity), and their area and moment G a**2 sum(u dt)."""
    lx, ly, a, G = 8, 6, 1e-4, 3.3e6
    u = np.full((40, lx, ly), 0.5 * V_D)
    u[5:8, 7, 5] = 5 * V_D     # event A: the corner block, and its periodic neighbours in x and y
    u[6:9, 0, 5] = 5 * V_D     #   x wraps 7 -> 0
    u[6:7, 7, 0] = 5 * V_D     #   y wraps 5 -> 0
    u[20:22, 3, 3] = 4 * V_D   # event B
    u[22:23, 4, 4] = 4 * V_D   # diagonal to B, one sample later: event C
    field = _field(u.reshape(40, lx * ly)).assign_attrs(Lx=lx, Ly=ly, a=a, G=G)
    ev = slip_events(field)
    order = np.argsort(ev["event_start"].values)
    assert ev.sizes["event"] == 3
    assert ev["event_size"].values[order].tolist() == [3, 1, 1]
    slip_a = (3 + 3 + 1) * 5 * V_D * 1e-6
    assert ev["event_slip"].values[order][0] == pytest.approx(slip_a, rel=1e-6)
    assert ev["event_area"].values[order][0] == pytest.approx(3 * a * a)
    assert ev["event_moment"].values[order][0] == pytest.approx(G * a * a * slip_a, rel=1e-6)


def test_psd_of_a_sinusoid_plus_noise():
    rng = np.random.default_rng(2)
    fs, n, f0, amp, sigma = 1e6, 2**15, 37_500.0, 3e-4, 1e-4
    t = np.arange(n) / fs
    u = amp * np.sin(2 * np.pi * f0 * t)[:, None] + rng.normal(0, sigma, (n, 4))
    sp = spectra(_field(u, interval=1 / fs))
    f, p = sp["frequency"].values, sp["psd_u"].values
    k = int(np.argmax(p))
    df = f[1] - f[0]
    assert abs(f[k] - f0) <= df
    peak = slice(k - 6, k + 7)
    noise_floor = np.median(p)
    assert noise_floor == pytest.approx(2 * sigma**2 / fs, rel=0.1)  # one-sided white-noise density
    assert np.sum(p[peak] - noise_floor) * df == pytest.approx(amp**2 / 2, rel=0.05)  # Parseval: power A^2/2
    assert median_frequency(f, p) > f0 * 0.9


def test_field_recording_agrees_with_the_run_it_continues():
    """Mean instantaneous f_d over a recording = the kernel's own f_d average over the same interval."""
    cfg = make_config(N=31, theta=0.5, start="steady", v0=0.01, delta=0.2, t_total=3e-3)
    system = build_system(cfg)
    first = simulate(system)
    state = state_from_run(first)
    field = record_field(system, state, duration=1e-3, interval=1e-6)
    cont = simulate(build_system(cfg.with_updates(t_total=1e-3, output_interval=1e-6)), state)
    assert field.sizes["time"] == 1000 and field["time"].values[0] == pytest.approx(3e-3 + 1e-6)
    # sample k of the field is the state at the end of interval k: interval means vs end points differ by
    # half a sample of drive motion at most; over 1000 samples the averages agree to 1e-4
    assert field["f_d_instant"].mean().item() == pytest.approx(cont["f_d"].mean().item(), rel=1e-4)
    np.testing.assert_allclose(field["u"].values[-1], cont["u"].values, rtol=1e-5, atol=1e-9)
    law = cfg.contact_law
    u_last = field["u"].values[-1].astype(float)
    assert field["acoustic"].values[-1] == pytest.approx(np.sum(law.force(u_last[system.contact_sites], system.vstar)),
                                                         rel=1e-5)


def test_mechanism_cli_on_a_small_store(tmp_path, slipchain_cli):
    sw = make_sweep({"name": "m", "base": {"N": 31, "start": "steady", "t_total": 4e-3},
                     "grid": {"theta": [0.2, 1.0], "v_d": [1e-3, 3e-4], "seed": [0]}})
    st = Store.open(tmp_path / "s", sw)
    for m in sw.members:
        ds = run(m.config)
        ds.attrs["status"] = "completed"  # short runs: the physics checks are beside the point here
        st.write_member(m, ds)
    ana = slipchain_cli("mechanism", "--store", tmp_path / "s", "--duration", "2e-4")
    assert ana.returncode == 0, ana.stderr
    assert len(list((tmp_path / "s" / "mechanism").glob("*.nc"))) == 4
    fig = slipchain_cli("figure", "mechanism", "--store", tmp_path / "s", "--out", tmp_path / "o")
    assert fig.returncode == 0, fig.stderr
    text = (tmp_path / "o" / "mechanism.md").read_text()
    assert "Fraction of contacts that stick-slip" in text and text.count("| v_d = ") == 4
    for stem in ("mechanism_stick_slip", "mechanism_contacts_events_spectra", "mechanism_force_spectra"):
        assert (tmp_path / "o" / f"{stem}.png").stat().st_size > 5000
    missing = slipchain_cli("figure", "mechanism", "--store", tmp_path / "nope", "--out", tmp_path)
    assert missing.returncode == 2 and "not a slipchain sweep store" in missing.stderr


def _tiny_store(store_of_runs, path, grids, base=None):
    return store_of_runs(path, make_sweep({"name": path.name, "grid": grids,
                                           "base": base or {"N": 31, "start": "steady", "v0": 0.01, "delta": 0.2,
                                                            "t_total": 3e-3}}))


def test_velocity_epsilon_and_dead_weight_figures_from_stores(tmp_path, slipchain_cli, store_of_runs):
    def figure(*args):
        return slipchain_cli("figure", *args)

    _tiny_store(store_of_runs, tmp_path / "vel", {"v_d": [1e-4, 1e-3], "theta": [0.5, 1.0], "seed": [0, 1]})
    eps_store = _tiny_store(store_of_runs, tmp_path / "eps", [{"epsilon": [1e-2], "dt": [2e-8], "theta": [0.5, 1.0], "seed": [0]},
                                   {"epsilon": [5e-3], "dt": [1e-8], "theta": [0.5, 1.0], "seed": [0]}])
    _tiny_store(store_of_runs, tmp_path / "dw", {"dead_weight": [0.5, 0.9, 1.05], "theta": [1.0]},
                base={"N": 3, "theta": 1 / 3, "delta": 0.0, "t_total": 4e-3})
    vel = figure("velocity", "--store", str(tmp_path / "vel"), "--out", str(tmp_path / "o"))
    assert vel.returncode == 0, vel.stderr
    eps = figure("epsilon", "--store", str(tmp_path / "eps"), "--out", str(tmp_path / "o"))
    assert eps.returncode == 0, eps.stderr
    assert "epsilon = 0.01:" in eps.stdout and "epsilon = 0.005:" in eps.stdout and "ratio" in eps.stdout
    # issue 12: the figure extended by a store at another base epsilon (rows at v_d = v0 only) and an index CSV
    eps_store.write_index()
    _tiny_store(store_of_runs, tmp_path / "eps2", {"v_d": [0.01, 0.003], "theta": [0.5, 1.0], "seed": [0]},
                base={"N": 31, "start": "steady", "v0": 0.01, "delta": 0.2, "t_total": 3e-3, "epsilon": 2e-3})
    both = figure("epsilon", "--store", str(tmp_path / "eps2"), "--index", str(tmp_path / "eps" / "index.csv"),
                                "--out", str(tmp_path / "o2"))
    assert both.returncode == 0, both.stderr
    lines = [line for line in both.stdout.splitlines() if line.startswith("epsilon = ")]
    assert [line.split(":")[0] for line in lines] == ["epsilon = 0.002", "epsilon = 0.005", "epsilon = 0.01"]
    assert [line for line in lines if "0.01:" in line][0] in eps.stdout  # the same numbers as from the store alone
    rows = pd.read_csv(tmp_path / "o2" / "epsilon-index.csv")
    assert len(rows) == 6 and sorted(rows["epsilon"].unique()) == [0.002, 0.005, 0.01]
    assert (tmp_path / "o2" / "epsilon.png").stat().st_size > 5000
    twice = figure("epsilon", "--store", str(tmp_path / "eps"), "--index", str(tmp_path / "eps" / "index.csv"),
                                 "--out", str(tmp_path / "o3"))
    assert twice.returncode == 2 and "same (epsilon, dt, theta, seed)" in twice.stderr and not (tmp_path / "o3").exists()
    nofile = figure("epsilon", "--index", str(tmp_path / "none.csv"), "--out", str(tmp_path / "o3"))
    assert nofile.returncode == 2 and "none.csv" in nofile.stderr and not (tmp_path / "o3").exists()
    dw = figure("dead-weight", "--store", str(tmp_path / "dw"), "--out", str(tmp_path / "o"))
    assert dw.returncode == 0, dw.stderr
    for stem in ("velocity", "epsilon", "dead_weight"):
        assert (tmp_path / "o" / f"{stem}.png").stat().st_size > 5000 and (tmp_path / "o" / f"{stem}.pdf").exists()
    wrong = figure("dead-weight", "--store", str(tmp_path / "vel"), "--out", str(tmp_path / "o"))
    assert wrong.returncode == 2 and "needs dead_weight" in wrong.stderr
    # issue 29: grid stores side by side, one panel per value of a config key that one store does not
    # vary (its base value) and the other leaves absent (the weight at once); their rows in evaluations.csv
    _tiny_store(store_of_runs, tmp_path / "dw2", {"dead_weight": [0.5, 1.05], "theta": [1.0, 0.5]},
                base={"N": 3, "theta": 1 / 3, "delta": 0.0, "t_total": 4e-3, "dead_weight": 0.5, "t_ramp": 1e-3})
    grid = figure("dead-weight", "--store", str(tmp_path / "dw"), "--store", str(tmp_path / "dw2"),
                                "--by", "t_ramp", "--out", str(tmp_path / "g"))
    assert grid.returncode == 0, grid.stderr
    rows = pd.read_csv(tmp_path / "g" / "evaluations.csv")
    assert len(rows) == 3 + 4 and rows.groupby("store")["t_ramp"].unique().map(list).to_dict() == {
        "dw": ["absent"], "dw2": ["0.001"]}
    stored = Store.open(tmp_path / "dw2")
    for _, r in rows[rows["store"] == "dw2"].iterrows():  # each row is its member's own classification
        attrs = stored.member_attrs(stored.find(theta=r["theta"], dead_weight=r["mu_a"]))
        assert r["velocity_status"] == attrs["velocity_status"]
    assert (tmp_path / "g" / "dead_weight_grid.png").stat().st_size > 5000
    # a table of such rows (a grid whose store is elsewhere) beside a store: read as it was written
    rows[rows["store"] == "dw2"].drop(columns="store").to_csv(tmp_path / "dw2.csv", index=False)
    mixed = figure("dead-weight", "--table", str(tmp_path / "dw2.csv"), "--store", str(tmp_path / "dw"),
                                 "--by", "t_ramp", "--out", str(tmp_path / "g3"))
    assert mixed.returncode == 0, mixed.stderr
    again = pd.read_csv(tmp_path / "g3" / "evaluations.csv")

    def key(d):
        return sorted(map(str, d[["theta", "seed", "t_ramp", "mu_a", "velocity_status", "velocity_m_s"]].itertuples(index=False)))
    assert key(again) == key(rows) and set(again["store"]) == {"dw", "dw2.csv"}
    rows.drop(columns="t_ramp").to_csv(tmp_path / "no_ramp.csv", index=False)
    for bad, says in ((["--by", "t_rampp"], "'t_rampp' is not a config key"), ([], "several with --by"),
                      (["--by", "t_ramp", "--table", str(tmp_path / "no_ramp.csv")], "has no column 't_ramp'")):
        r = figure("dead-weight", "--store", str(tmp_path / "dw"), "--store", str(tmp_path / "dw2"),
                                 *bad, "--out", str(tmp_path / "g2"))
        assert r.returncode == 2 and says in r.stderr and not (tmp_path / "g2").exists(), r.stderr


def test_the_grid_figure_gives_a_panel_only_to_values_with_a_drawn_run():
    """A grid continued by a preset whose runs at one ramp are all still to run (tester-16-slower's
    6-s ramp): that ramp has no panel; a ramp with one drawn run among failures has one."""
    from slipchain.plots.mechanism import grid_panels

    ev = pd.DataFrame({"t_ramp": [1.0, 3.0, 3.0, 6.0, 6.0, "absent"],
                       "velocity_status": ["ok", "runaway", "error", "error", "error", "no-steady"]})
    assert grid_panels(ev, "t_ramp") == [1.0, 3.0, "absent"]

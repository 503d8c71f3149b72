"""The velocity record of a dead-weight run and mu_max read from where a slowly loaded slider runs away
(slipchain.analysis.traces): exact on polynomials, converging to the analytic maximum of identical
contacts as the ramp slows, and the CLI that draws and tables it."""

import numpy as np
import pandas as pd
import pytest

from slipchain import make_config, run
from slipchain.analysis.traces import (BRANCH_VELOCITIES, HELD_WINDOW, branch_check, branch_summary, first_crossing,
                                       is_release, last_crossing,
                                       onset_summary, protocol_brackets, ramp_branch, run_outcome, runaway_onset,
                                       seed_brackets, window_velocity)
from slipchain.sweeps.definition import make_sweep
from slipchain.workflows.dead_weight import single_contact_maximum

# Identical contacts on every block (tests/physics/test_mu_max.py): the analytic maximum f_max of eq. (1)
IDENTICAL = dict(N=11, theta=1.0, delta=0.0, start="rest")


def test_window_velocity_is_the_mean_velocity_over_each_window():
    t = np.arange(1, 1001) * 1e-3
    x = 0.3 + 2e-4 * t + 5e-3 * t**2 - 1e-3 * t**3
    tm, v = window_velocity(t, x, 0.02)  # 20 samples a window, windows every 10
    assert tm.size == (t.size - 20 - 1) // 10 + 1 and np.allclose(np.diff(tm), 0.01)
    a, b = tm - 0.01, tm + 0.01  # the mean of dx/dt over [a, b] is (x(b) - x(a)) / (b - a), cubic included
    exact = (2e-4 * (b - a) + 5e-3 * (b**2 - a**2) - 1e-3 * (b**3 - a**3)) / (b - a)
    assert np.allclose(v, exact, rtol=0, atol=1e-12)  # round-off of x ~ 0.3 over 0.02 s
    assert window_velocity(t, x, 1e-9)[1].size == t.size - 1  # at least one sample a window
    assert window_velocity(t[:1], x[:1], 0.02)[0].size == 0


def test_the_onset_is_the_last_upward_crossing():
    t = np.arange(0, 101) * 1e-3
    v = np.full(100, 1e-4)
    v[5:8] = 5.0  # an early overshoot above the threshold (the release), then back on the branch
    v[60:] = np.geomspace(1e-3, 10, 40)  # the runaway
    x = np.concatenate([[0.0], np.cumsum(v * 1e-3)])
    i = 60 + np.nonzero(v[60:] > 2e-3)[0][0]  # the runaway's first interval above 2e-3 m/s (not the overshoot's)
    assert last_crossing(t, x, 2e-3) == pytest.approx(t[i + 1])
    assert np.isnan(last_crossing(t, x, 20.0))  # never above at the end
    assert first_crossing(t, x, 2e-3) == pytest.approx(t[6]) and np.isnan(first_crossing(t, x, 20.0))  # the overshoot
    cfg = make_config(**IDENTICAL, dead_weight=1.2, t_ramp=0.2, t_total=0.3)  # v0 10**delta = 1e-3
    on = runaway_onset(cfg, t, x)
    k = 60 + np.nonzero(v[60:] > 3e-3)[0][0]
    assert on["t_onset"] == pytest.approx(t[k + 1]) and on["mu_onset"] == pytest.approx(1.2 * t[k + 1] / 0.2)
    assert on["during_ramp"] and on["resolution"] == pytest.approx(1.2 * 1e-3 / 0.2)
    assert on["mu_onset_10"] > on["mu_onset"]
    at_once = runaway_onset(cfg.with_updates(t_ramp=1e-3), t, x)  # the weight at once: nothing to read
    assert np.isnan(at_once["mu_onset"]) and not at_once["during_ramp"]
    fast = np.concatenate([[0.0], np.cumsum(np.where(v < 1e-3, 2e-3, v) * 1e-3)])  # loading alone at 2e-3 m/s
    assert np.isnan(runaway_onset(cfg, t, fast)["mu_onset"])  # above half the threshold (1.5e-3): a release


def test_a_release_is_not_read_as_a_slow_ramp():
    """is_release on records of exact velocities (v0 10**delta = 1e-3 m/s, so half the onset threshold is
    1.5e-3): the weight at once, or a top loaded at 2e-3 m/s over 10-50 % of the ramp, is a release; loaded
    at 1e-3 m/s it is a ramp. ramp_branch reads no branch where the interface's own elastic loading rate
    (at weights 0.1-0.2 of the ramp) exceeds the slowest velocity it reads, BRANCH_VELOCITIES[0], and below
    it takes that rate off exactly."""
    cfg = make_config(**IDENTICAL, dead_weight=1.0, t_ramp=0.2, t_total=0.3)
    t = np.arange(0, 301) * 1e-3
    assert not is_release(cfg, t, 1e-3 * t) and is_release(cfg, t, 2e-3 * t)
    assert is_release(cfg.with_updates(t_ramp=1e-3), t, 1e-3 * t)  # within two samples: at once
    slip = np.where(t > 0.1, 1e-4 * (t - 0.1) ** 2 / 0.1, 0.0)  # the interface slips from mu_a = 0.5 on
    for rate in (0.5 * BRANCH_VELOCITIES[0], 2.0 * BRANCH_VELOCITIES[0]):
        b = ramp_branch(cfg, t, rate * t + slip, 0.01, float("nan"))
        if rate < BRANCH_VELOCITIES[0]:
            assert len(b) > 30 and np.allclose(b["v"] - b["v_slip"], rate, rtol=1e-9, atol=1e-15)
        else:
            assert len(b) == 0 and list(b.columns) == ["t", "mu", "v", "v_slip"]


def test_the_onset_converges_to_the_analytic_maximum_as_the_ramp_slows():
    """Identical contacts loaded over 10 and 40 ms, 4000 samples a ramp: the weight at the onset is
    within 1e-3 of eq. (1)'s maximum and within one sample's rise (3e-4) at the slower ramp, read from the
    top and from the interface's first slip alike; and below the maximum the ramp traces eq. (1) itself:
    mu against the interface's velocity within 2e-4 of f(v)/(epsilon f0) from 1e-7 m/s to 0.8 of the peak's
    velocity (median within 1e-5)."""
    f_max, u_max = single_contact_maximum(make_config(**IDENTICAL, t_total=5e-3))
    errors = []
    for tr in (0.01, 0.04):
        cfg = make_config(**IDENTICAL, dead_weight=1.2 * f_max, t_ramp=tr, t_total=1.3 * tr, output_interval=tr / 4000)
        ds = run(cfg)
        assert ds.attrs["velocity_status"] == "runaway"
        on = runaway_onset(cfg, ds["time"].values, ds["X_mean"].values, ds["x_mean"].values)
        assert on["during_ramp"] and on["resolution"] == pytest.approx(1.2 * f_max / 4000)
        errors.append((on["mu_onset"] - f_max, on["mu_slip"] - f_max))
        b = ramp_branch(cfg, ds["time"].values, ds["x_mean"].values, tr / 400, on["t_slip"])
        assert b["t"].max() <= on["t_slip"] and b["mu"].max() < f_max
        on_branch = b[(b["v"] > 1e-7) & (b["v"] < 0.8 * u_max)]
        law = cfg.contact_law.force(on_branch["v"].to_numpy(), cfg.v0) / (cfg.epsilon * cfg.f0)
        assert np.abs(b["v"] - b["v_slip"]).max() < 1e-7  # every site a contact: only the slip at mu 0.1-0.2 taken off
        assert len(on_branch) > 300
        assert np.abs(on_branch["mu"] - law).max() < 2e-4 and np.median(np.abs(on_branch["mu"] - law)) < 1e-5
    assert max(map(abs, errors[0])) < 1e-3 and max(map(abs, errors[1])) <= 1.2 * f_max / 4000


def test_a_run_back_on_the_rising_branch_by_its_end_is_held():
    """The release's outcomes: a record that decelerates from the overshoot to below 3 v0 10**delta
    (here 3e-3 m/s) is held, its end velocity the exact mean over the last HELD_WINDOW; cut while still
    fast it is undecided; the tester's steady and runaway stand as they are."""
    cfg = make_config(**IDENTICAL, dead_weight=0.8, t_total=3.0)  # v0 10**delta = 1e-3 m/s
    t = np.arange(0, 3001) * 1e-3
    x = 0.02 * 0.3 * (1 - np.exp(-t / 0.3)) + 1e-5 * t  # v = 0.02 exp(-t/0.3) + 1e-5: overshoot, then creep
    outcome, v_end = run_outcome(cfg, "no-steady", t, x)
    j = t.size - 1 - int(round(HELD_WINDOW / 1e-3))
    assert outcome == "held" and v_end == pytest.approx((x[-1] - x[j]) / (t[-1] - t[j]), rel=1e-12)
    assert v_end == pytest.approx(0.02 * 0.3 * (np.exp(-2.8 / 0.3) - np.exp(-10.0)) / 0.2 + 1e-5, rel=1e-6)
    early = t <= 0.3  # still at 0.02 exp(-1) ~ 7e-3 m/s over its last 0.2 s: above the branch
    assert run_outcome(cfg, "no-steady", t[early], x[early])[0] == "undecided"
    assert run_outcome(cfg, "ok", t, x)[0] == "steady" and run_outcome(cfg, "runaway", t, x)[0] == "runaway"
    short = t <= 0.05  # shorter than the window: the whole record's mean velocity
    assert run_outcome(cfg, "no-steady", t[short], x[short])[1] == pytest.approx(x[50] / t[50], rel=1e-12)


def test_the_brackets_are_seed_by_seed_and_their_envelope():
    rows = [(0.5, 0, 0.6, "held"), (0.5, 0, 0.7, "runaway"), (0.5, 0, 0.8, "runaway"), (0.5, 1, 0.6, "steady"),
            (0.5, 1, 0.65, "undecided"), (0.5, 1, 0.75, "runaway"), (1.0, 0, 0.8, "held"), (1.0, 0, 0.75, "runaway"),
            (1.0, 1, 0.75, "held")]
    runs = pd.DataFrame([{"N": 16, "temperature": 20.0, "eta_c": 1e5, "t_ramp": 1e-3, "t_decide": 2.0, "theta": th, "seed": sd,
                          "mu_a": m, "outcome": o} for th, sd, m, o in rows])
    per_seed = seed_brackets(runs, ["theta"]).set_index(["theta", "seed"])
    assert per_seed.loc[(0.5, 0), ["lo", "hi"]].tolist() == [0.6, 0.7]
    assert per_seed.loc[(0.5, 1), ["lo", "hi"]].tolist() == [0.6, 0.75]  # the undecided 0.65 bounds nothing
    assert per_seed.loc[(1.0, 1), "hi"] == np.inf and not per_seed.loc[(1.0, 0), "consistent"]  # held above a runaway
    b = protocol_brackets(runs).set_index("theta")
    assert b.loc[0.5, ["lo", "hi", "seeds", "runs", "inconsistent"]].tolist() == [0.6, 0.75, 2, 6, 0]
    assert b.loc[1.0, "inconsistent"] == 1 and b.loc[0.5, "per_seed"] == "seed 0: [0.6, 0.7); seed 1: [0.6, 0.75)"
    # decided at another length, a run is another protocol: its own bracket, not a refutation of this one (at 0.3
    # omega0 the 16 x 16 release at theta = 0.05, 0.85 read runaway at t_decide = 0.8 s and held at 2 s)
    early = runs.iloc[[0, 1]].assign(t_decide=0.8, mu_a=[0.55, 0.6], outcome=["held", "runaway"])
    b2 = protocol_brackets(pd.concat([runs, early])).set_index(["t_decide", "theta"])
    assert b2.loc[(0.8, 0.5), ["lo", "hi", "runs", "inconsistent"]].tolist() == [0.55, 0.6, 2, 0]
    assert b2.loc[(2.0, 0.5), ["lo", "hi", "runs", "inconsistent"]].tolist() == [0.6, 0.75, 6, 0]


def test_the_summary_averages_seeds_and_divides_by_the_smallest_load():
    rows = []
    for theta, mus in ((0.1, (0.90, 0.92)), (1.0, (0.95, 0.97))):
        for seed, mu in enumerate(mus):
            rows.append({"N": 16, "temperature": 20.0, "eta_c": 1e5, "rate": 0.175, "theta": theta, "seed": seed, "mu_onset": mu,
                         "mu_onset_10": mu + 0.01, "during_ramp": True, "resolution": 2e-4})
            rows[-1]["mu_slip"] = mu - 0.002
    rows.append({**rows[0], "mu_onset": 0.5, "during_ramp": False})  # onset after the ramp: an upper bound only
    s = onset_summary(pd.DataFrame(rows)).set_index("theta")
    assert s.loc[0.1, "mu_max"] == pytest.approx(0.91) and s.loc[1.0, "mu_max"] == pytest.approx(0.96)
    assert s.loc[0.1, "mu_max_se"] == pytest.approx(0.01) and s.loc[1.0, "runs"] == 2
    assert s.loc[1.0, "R"] == pytest.approx(0.96 / 0.91) and s.loc[0.1, "R"] == 1.0
    assert s.loc[1.0, "R_se"] == pytest.approx(0.96 / 0.91 * np.hypot(0.01 / 0.96, 0.01 / 0.91))
    assert s.loc[1.0, "R_10"] == pytest.approx(0.97 / 0.92) and s.loc[1.0, "R_slip"] == pytest.approx(0.958 / 0.908)
    # another contact damping is another group: its runs neither join these means nor share their smallest load
    other = [{**r, "eta_c": 1e6, "mu_onset": r["mu_onset"] - 0.1} for r in rows if r["theta"] == 1.0 and r["during_ramp"]]
    both = onset_summary(pd.DataFrame(rows + other)).set_index(["eta_c", "theta"])
    assert both.loc[(1e5, 1.0), "mu_max"] == pytest.approx(0.96) and both.loc[(1e6, 1.0), "mu_max"] == pytest.approx(0.86)
    assert both.loc[(1e5, 1.0), "R"] == pytest.approx(0.96 / 0.91) and both.loc[(1e6, 1.0), "R"] == 1.0  # its own smallest load
    # the rate groups the runs: 1.05 over 6 s and 1.015 over 5.8 s are one rate, 1.0 over 6 s another
    from slipchain.analysis.traces import loading_rate
    cfg = make_config(**IDENTICAL, dead_weight=1.05, t_ramp=6.0, t_total=7.0)
    assert loading_rate(cfg) == loading_rate(cfg.with_updates(dead_weight=1.015, t_ramp=5.8)) == 0.175
    assert loading_rate(cfg.with_updates(dead_weight=1.0)) == pytest.approx(1 / 6, rel=1e-3)


def test_the_branch_is_read_at_a_weight_and_at_a_velocity_by_interpolation():
    """branch_check and branch_summary on a made-up branch v = 1e-4 exp(20 (mu - 0.9)) m/s: each reading is
    the exact inverse where the samples are dense (log-linear interpolation is exact on an exponential);
    the last passage counts, so an early overshoot past the level does not."""
    mu = np.linspace(0.5, 0.97, 95)
    v = 1e-4 * np.exp(20 * (mu - 0.9))
    v[3] = 1.0  # an early overshoot (the start's transient)
    rows = []
    for theta, shift in ((0.05, 0.0), (1.0, 0.01)):
        for seed in (0, 1):
            rows.append(pd.DataFrame({"N": 16, "temperature": 20.0, "eta_c": 1e5, "rate": 0.175, "theta": theta, "seed": seed,
                                      "member_id": f"{theta}-{seed}", "mu": mu + shift, "v": v + 1e-5, "v_slip": v}))
    branch = pd.concat(rows, ignore_index=True)
    steady = pd.DataFrame([{"N": 16, "temperature": 20.0, "eta_c": 1e5, "theta": 0.05, "seed": 0, "mu_a": 0.95, "velocity": 3e-4,
                            "velocity_sem": 1e-5}])
    c = branch_check(branch, steady)
    assert len(c) == 1 and c["v_ramp"].iloc[0] == pytest.approx(1e-4 * np.exp(20 * 0.05), rel=1e-9)
    assert c["ratio"].iloc[0] == pytest.approx(1e-4 * np.exp(1.0) / 3e-4, rel=1e-9)
    s = branch_summary(branch, velocities=(1e-4,)).set_index("theta")
    assert s.loc[0.05, "mu"] == pytest.approx(0.9, abs=1e-12) and s.loc[1.0, "mu"] == pytest.approx(0.91, abs=1e-12)
    assert s.loc[1.0, "R"] == pytest.approx(0.91 / 0.9) and s.loc[1.0, "seeds"] == 2 and s.loc[1.0, "mu_se"] == 0.0
    assert branch_summary(branch, velocities=(1e3,)).empty  # never reached: no row


def test_cli_traces_draws_and_tables_a_store(tmp_path, slipchain_cli, store_of_runs):
    f_max, _ = single_contact_maximum(make_config(**IDENTICAL, t_total=5e-3))
    sweep = make_sweep({"name": "ramp", "base": {**IDENTICAL, "t_ramp": 0.01, "t_total": 0.013, "output_interval": 2.5e-6,
                                 "dead_weight": 1.0},
                        "grid": {"dead_weight": [0.9 * f_max, 1.2 * f_max]}})
    st = store_of_runs(tmp_path / "s", sweep)
    r = slipchain_cli("figure", "traces", "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o"), "--window", "1e-4")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "o" / "velocity_traces.png").stat().st_size > 5000
    onsets = pd.read_csv(tmp_path / "o" / "onsets.csv").set_index("mu_a")
    for m in sweep.members:  # each row is its member's own record read again
        ds = st.read_member(m)
        own = runaway_onset(m.config, ds["time"].values, ds["X_mean"].values)
        got = onsets.iloc[int(np.argmin(abs(onsets.index - m.config.dead_weight)))]
        assert got["status"] == ds.attrs["velocity_status"]
        assert (np.isnan(own["mu_onset"]) and np.isnan(got["mu_onset"])) or got["mu_onset"] == pytest.approx(own["mu_onset"], rel=1e-5)
    assert onsets["status"].tolist() == ["ok", "runaway"] and abs(onsets["mu_onset"].iloc[1] - f_max) < 1e-3
    assert onsets["outcome"].tolist() == ["steady", "runaway"]
    b = pd.read_csv(tmp_path / "o" / "brackets.csv")  # the two weights bracket eq. (1)'s maximum
    assert b[["lo", "hi", "seeds", "runs"]].values.tolist() == [[pytest.approx(0.9 * f_max, rel=1e-5), pytest.approx(1.2 * f_max, rel=1e-5), 1, 2]]
    assert "mu_max in [" in r.stdout
    assert {"mu_slip", "t_slip", "velocity"} <= set(onsets.columns) and (tmp_path / "o" / "branches.png").stat().st_size > 5000
    branch = pd.read_csv(tmp_path / "o" / "branch.csv")  # the steady run's ramp and the runaway's, up to its first slip
    assert set(branch["member_id"]) == {m.id for m in sweep.members} and branch["mu"].max() < f_max
    check = pd.read_csv(tmp_path / "o" / "branch_check.csv")  # the steady weight 0.9 f_max read on the runaway's ramp
    assert len(check) == 1 and 0.5 < check["ratio"].iloc[0] < 2.0
    traces = pd.read_csv(tmp_path / "o" / "traces.csv")
    assert set(traces["member_id"]) == {m.id for m in sweep.members} and "theta = 1:" in r.stdout.replace("\n", " ")
    for bad, says in ((["--store", str(tmp_path / "none")], "not a slipchain sweep store"),
                      (["--store", str(tmp_path / "s"), "--window", "0"], "--window")):
        b = slipchain_cli("figure", "traces", *bad, "--out", str(tmp_path / "o2"))
        assert b.returncode == 2 and says in b.stderr and not (tmp_path / "o2").exists(), b.stderr


def test_redecide_replays_the_automatic_length_as_a_run_with_that_t_decide(tmp_path, slipchain_cli, store_of_runs):
    """analysis.traces.redecide: a stored record fed again to the automatic length (engine.control.UntilDecided)
    stops where the run stopped at its own t_decide, with its status; at an earlier t_decide it stops where, and
    says what, a run with that t_decide does (the same physics: the earlier run's record is a prefix of the later's);
    the CLI writes redecide.csv, and refuses a t_decide that is not positive, writing nothing."""
    from slipchain.analysis.traces import redecide

    f_max, _ = single_contact_maximum(make_config(**IDENTICAL, t_total=5e-3))
    base = {**IDENTICAL, "t_ramp": 1e-4, "t_decide": 2e-3, "t_max": 4e-3, "output_interval": 2.5e-6, "dead_weight": 1.0}
    sweep = make_sweep({"name": "release", "base": base, "grid": {"dead_weight": [0.9 * f_max, 1.2 * f_max]}})
    store_of_runs(tmp_path / "s", sweep)
    own, skipped = redecide([tmp_path / "s"], [2e-3])
    assert skipped == {2e-3: 0} and len(own) == 2
    assert (own["status_replay"] == own["status"]).all() and (own["t_stop"] == own["t_end"]).all() and own["agree"].all()
    early, _ = redecide([tmp_path / "s"], [1e-3])
    for m in sweep.members:
        ds = run(m.config.model_copy(update={"t_decide": 1e-3}))
        row = early[early["member_id"] == m.id].iloc[0]
        assert row["status_replay"] == ds.attrs["velocity_status"]
        assert row["t_stop"] == pytest.approx(float(ds["time"].values[-1]), abs=1e-9)
    runaway = early[early["outcome"] == "runaway"]
    assert len(runaway) == 1 and runaway["t_stop"].iloc[0] < runaway["t_end"].iloc[0]  # stopped earlier, still a runaway
    r = slipchain_cli("figure", "traces", "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o"), "--window", "1e-4",
                      "--redecide", "1e-3", "--redecide", "2e-3")
    assert r.returncode == 0, r.stderr
    table = pd.read_csv(tmp_path / "o" / "redecide.csv")
    assert sorted(set(table["t_decide_replay"])) == [1e-3, 2e-3] and table["agree"].all()
    assert "t_decide = 0.001 s replayed on 2 runs: 2 on the same side of mu_max" in r.stdout.replace("\n", " ")
    b = slipchain_cli("figure", "traces", "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o2"), "--redecide", "0")
    assert b.returncode == 2 and "--redecide" in b.stderr and not (tmp_path / "o2").exists(), b.stderr
    for flag in ("--stop-at-runaway", "--stop-when-held"):  # a replay's options, not without one
        b = slipchain_cli("figure", "traces", "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o2"), flag)
        assert b.returncode == 2 and flag in b.stderr and "--redecide" in b.stderr and not (tmp_path / "o2").exists()
    # with them on a chain, which has no rigid top to read over its ringing: the same replay, the columns say so
    r = slipchain_cli("figure", "traces", "--store", str(tmp_path / "s"), "--out", str(tmp_path / "o3"), "--window", "1e-4",
                      "--redecide", "1e-3", "--stop-at-runaway", "--stop-when-held")
    assert r.returncode == 0, r.stderr
    ruled = pd.read_csv(tmp_path / "o3" / "redecide.csv")
    assert ruled["stop_at_runaway"].all() and ruled["stop_when_held"].all()
    plain = table[table["t_decide_replay"] == 1e-3].reset_index(drop=True)
    assert ruled["t_stop"].tolist() == plain["t_stop"].tolist() and ruled["status_replay"].tolist() == plain["status_replay"].tolist()
    assert "replayed with stop_at_runaway with stop_when_held on 2 runs" in r.stdout.replace("\n", " ")


def test_traces_read_a_run_the_stop_rules_decide_on_its_checkpoint(tmp_path, checkpointed_releases):
    """velocity_traces(..., checkpoints=True): a released 4 x 4 slab (conftest's checkpointed_releases) run without the
    stop rules and checkpointed, not stored, enters the traces and the brackets as the same run made with the rules
    on: its record, bit for bit, up to where they stop it, their status and the outcome read from it; without
    the option the store holds no run and is refused; one member stored and the other only checkpointed, each is
    read once."""
    from slipchain.analysis.traces import velocity_traces
    from slipchain.sweeps.definition import SweepError

    _, sweep, st = checkpointed_releases
    with pytest.raises(SweepError, match="holds no completed run"):
        velocity_traces([tmp_path / "s"], 1e-3)
    frame, onsets, _ = velocity_traces([tmp_path / "s"], 1e-3, checkpoints=True)
    assert sorted(onsets["mu_a"]) == [0.3, 0.9] and set(onsets["source"]) == {"checkpoint"}
    ruled = {m.id: run(m.config.model_copy(update={"stop_at_runaway": True, "stop_when_held": True}))
             for m in sweep.members}
    for m in sweep.members:
        row = onsets[onsets["member_id"] == m.id].iloc[0]
        r = ruled[m.id]
        assert row["status"] == r.attrs["velocity_status"]
        np.testing.assert_array_equal([row["velocity"], row["velocity_sem"]], [r.attrs["velocity"], r.attrs["velocity_sem"]])
        want = run_outcome(m.config, r.attrs["velocity_status"], r["time"].values, r["X_mean"].values)
        assert (row["outcome"], row["v_end"]) == want
        got = frame[frame["member_id"] == m.id]
        t, v = window_velocity(r["time"].values, r["X_mean"].values, 1e-3)
        np.testing.assert_array_equal(got["t"].values, t)
        np.testing.assert_array_equal(got["v"].values, v)
    assert onsets.set_index("mu_a").loc[0.9, "outcome"] == "runaway"
    low = onsets.set_index("mu_a").loc[0.3, "outcome"]  # over 0.02 s the record still holds the release's overshoot
    b = protocol_brackets(onsets)
    assert (b["lo"].iloc[0], b["hi"].iloc[0]) == (0.3 if low in ("steady", "held") else 0.0, 0.9)
    # the held member stored (as a sweep would): read once, from the store
    held = next(m for m in sweep.members if m.config.dead_weight == 0.3)
    st.write_member(held, ruled[held.id])
    _, onsets, _ = velocity_traces([tmp_path / "s"], 1e-3, checkpoints=True)
    assert sorted(zip(onsets["mu_a"], onsets["source"])) == [(0.3, "member"), (0.9, "checkpoint")]

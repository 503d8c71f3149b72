"""mu_max under a dead weight by bisection (issue 14, first part), against the analytic maximum."""

import numpy as np
import pytest

from slipchain import make_config
from slipchain.model.config import ConfigError
from slipchain.workflows.dead_weight import TOL, BracketError, evaluate, mu_max, single_contact_maximum

# Identical contacts (delta = 0) on every block (theta = 1): every block slides at the u that
# solves f(u, v0) = mu_a epsilon f0, which exists on the rising branch up to the law's first
# maximum: the analytic mu_max.
IDENTICAL = dict(N=11, theta=1.0, delta=0.0, start="steady", t_total=5e-3)


def test_bisection_finds_the_analytic_single_contact_maximum():
    cfg = make_config(**IDENTICAL)
    f_max, u_peak = single_contact_maximum(cfg)
    # eq. (1) at u = v0 is epsilon f0 + m eta_c v0; the viscous term moves the peak only slightly
    assert f_max == pytest.approx(1.0 + cfg.m * cfg.eta_c * cfg.v0 / (cfg.epsilon * cfg.f0), abs=1e-6)
    assert u_peak == pytest.approx(cfg.v0, rel=1e-2)
    got = mu_max(cfg, lo=0.5, hi=1.5, tol=TOL)
    assert got.status == "ok" and got.hi - got.lo <= 2 * TOL
    assert abs(got.mu_max - f_max) <= TOL  # the resolution
    assert got.lo <= f_max and got.hi >= f_max - 2 * TOL  # the bracket reaches to the edge
    # v_max: the steady velocity at lo solves f(v, v0) = lo on the rising branch (below v0)
    law = cfg.contact_law
    f_at_v = law.force(got.v_max, cfg.v0) / (cfg.epsilon * cfg.f0)
    assert got.v_max < cfg.v0 and f_at_v == pytest.approx(got.lo, abs=2e-3)
    assert [e.velocity_status for e in got.evaluations[:2]] == ["ok", "runaway"]
    # Away from the peak the classification is the analytic one: steady 2 TOL below, runaway TOL above.
    # (Within a few 1e-4 of the peak a finite run calls steady points runaway: see the module docstring.)
    assert evaluate(cfg, f_max - 2 * TOL).velocity_status == "ok"
    assert evaluate(cfg, f_max + TOL).velocity_status == "runaway"


def test_a_bad_bracket_is_a_clear_error():
    cfg = make_config(**IDENTICAL)
    with pytest.raises(BracketError, match="hi = 0.9 must run away"):
        mu_max(cfg, lo=0.5, hi=0.9)
    with pytest.raises(BracketError, match="lo = 1.2 must give steady sliding"):
        mu_max(cfg, lo=1.2, hi=1.5)
    with pytest.raises(ConfigError, match="0 < lo < hi"):
        mu_max(cfg, lo=1.0, hi=0.5)


@pytest.fixture
def two_workers():
    """A client of a local cluster of two worker processes (they compile the engine once for every
    computing call of a test)."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=":0") as cluster, Client(cluster) as client:
        yield client


def test_many_bisections_on_dask_equal_serial_ones_and_resume_from_their_stores(tmp_path, two_workers):
    """Each round of the bisections is a sweep in a store (issue 30): the same numbers as serial
    bisections in-process, resumed from the stores, damaged files quarantined and rerun, a second
    driver refused, and the JSON cache of 0.2.0 still read."""
    import json
    from dataclasses import asdict

    from slipchain.sweeps.definition import SweepError, member_id
    from slipchain.sweeps.store import driver_lock
    from slipchain.workflows.dead_weight import mu_max_many

    configs = [make_config(**IDENTICAL), make_config(**{**IDENTICAL, "theta": 0.5, "seed": 1})]
    serial = [mu_max(c, lo=0.5, hi=1.5) for c in configs]
    out = tmp_path / "out"
    many = mu_max_many(configs, lo=0.5, hi=1.5, store=out, client=two_workers, progress=False)
    for a, b in zip(serial, many):  # the same runs on workers: the same numbers, bit for bit
        assert (a.status, a.mu_max, a.lo, a.hi, a.v_max) == (b.status, b.mu_max, b.lo, b.hi, b.v_max)
        assert [(e.mu_a, e.velocity_status, repr(e.velocity)) for e in a.evaluations] == \
            [(e.mu_a, e.velocity_status, repr(e.velocity)) for e in b.evaluations]  # repr: NaN equals NaN
    # one store per round (the lo/hi ends, then one per bisection step), each member one run, named by its id
    stores = sorted(p.parent for p in (out / "rounds").glob("*/sweep.toml"))
    assert len(stores) == 1 + max(len(r.evaluations) for r in many) - 2
    files = sorted((out / "rounds").glob("*/members/*.nc"))
    ids = {member_id(c.with_updates(dead_weight=e.mu_a)) for c, r in zip(configs, many) for e in r.evaluations}
    assert {f.stem for f in files} == ids and len(files) == sum(len(r.evaluations) for r in many)
    # Resumed with every run stored: nothing is computed (a client that cannot compute is not asked)...
    again = mu_max_many(configs, lo=0.5, hi=1.5, store=out, client=object(), progress=False)
    assert [(r.mu_max, r.lo, r.hi) for r in again] == [(r.mu_max, r.lo, r.hi) for r in many]
    # ...a second driver on the same output is refused, naming the first, and computes nothing...
    with driver_lock(out, "mu-max output"):
        with pytest.raises(SweepError, match="another slipchain driver"):
            mu_max_many(configs, lo=0.5, hi=1.5, store=out, client=object(), progress=False)
    # ...and after a kill that cut one member file (as a full disk would) and lost another, those
    # runs are redone: the cut file quarantined with its reason, the same results, every run stored.
    files[0].write_bytes(files[0].read_bytes()[:300])
    files[1].unlink()
    resumed = mu_max_many(configs, lo=0.5, hi=1.5, store=out, client=two_workers, progress=False)
    assert [(r.mu_max, r.lo, r.hi, r.v_max) for r in resumed] == [(r.mu_max, r.lo, r.hi, r.v_max) for r in many]
    assert sorted((out / "rounds").glob("*/members/*.nc")) == files
    assert [p.name for p in (out / "rounds").glob("*/quarantine/*.reason.txt")] == [f"{files[0].stem}.reason.txt"]
    # The JSON cache that 0.2.0 wrote (OUT/cache/<member id>.json) is read: nothing is run again.
    old = tmp_path / "old"
    (old / "cache").mkdir(parents=True)
    for c, r in zip(configs, many):
        for e in r.evaluations:
            (old / "cache" / f"{member_id(c.with_updates(dead_weight=e.mu_a))}.json").write_text(json.dumps(asdict(e)))
    legacy = mu_max_many(configs, lo=0.5, hi=1.5, store=old, client=object(), progress=False)
    assert [(r.mu_max, r.lo, r.hi, r.v_max) for r in legacy] == [(r.mu_max, r.lo, r.hi, r.v_max) for r in many]
    assert not list((old / "rounds").glob("*/members/*.nc"))


def test_a_round_is_a_sweep_whose_members_are_its_runs():
    import tomllib

    from slipchain.sweeps.definition import make_sweep, member_id
    from slipchain.workflows.dead_weight import round_sweep

    base = make_config(**IDENTICAL)
    runs = [base.with_updates(dead_weight=0.5), base.with_updates(theta=0.5, seed=3, dead_weight=1.0),
            base.with_updates(N=13, dead_weight=1.5)]
    sweep = round_sweep(runs)
    assert [m.config for m in sweep.members] == runs and [m.id for m in sweep.members] == [member_id(c) for c in runs]
    assert sweep.dims == ("theta", "seed", "dead_weight", "N")  # N differs in one run: swept too
    assert make_sweep(tomllib.loads(sweep.to_toml())).digest == sweep.digest  # the store's sweep.toml reads back


def test_cli_mu_max_writes_the_table_and_refuses_bad_input_with_exit_2(tmp_path, slipchain_cli):
    import subprocess
    import sys

    import pandas as pd

    base = ["--set", "N=11", "--set", "delta=0", "--set", "start=steady", "--set", "t_total=5e-3"]
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "slipchain", "mu-max", *base, "--theta", "1", "--seeds", "2",
                        "--lo", "0.5", "--workers", "1", "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    table, summary = pd.read_csv(out / "mu_max.csv"), pd.read_csv(out / "mu_max_summary.csv")
    cfg = make_config(**IDENTICAL)
    assert list(table["seed"]) == [0, 1] and (table["status"] == "ok").all()
    assert (abs(table["mu_max"] - single_contact_maximum(cfg)[0]) <= TOL).all()
    assert summary["seeds"].tolist() == [2] and summary["ratio_to_theta_min"].tolist() == [1.0]
    for bad, words in ((["--theta", "1.5"], "theta"), (["--set", "t_total=0"], "t_total"),
                       (["--set", "t_total=0.0", "--set", "t_decide=0.0"], "t_")):
        rej = slipchain_cli("mu-max", *base, *bad, "--out", tmp_path / "x")
        assert rej.returncode == 2 and rej.stderr.startswith("error:") and words in rej.stderr, rej.stderr
        assert not (tmp_path / "x").exists()


# The dead-weight automatic length (t_decide): from rest, identical contacts (analytic steady velocity).
AUTO = dict(N=11, theta=1.0, delta=0.0, start="rest", t_decide=2e-3, t_max=0.05)


def _analytic_velocity(cfg, mu_a: float) -> float:
    from scipy.optimize import brentq

    law = cfg.contact_law
    return brentq(lambda lv: law.force(10.0**lv, cfg.v0) / (cfg.epsilon * cfg.f0) - mu_a, -12, np.log10(cfg.v0))


def test_automatic_dead_weight_length_runs_on_while_the_velocity_drifts():
    from slipchain import run
    from slipchain.results.schema import DECIDE_DRIFT
    from slipchain.results.velocity import steady_velocity

    cfg = make_config(**AUTO, dead_weight=0.7)
    ds = run(cfg, progress=False)
    a = ds.attrs
    t_end = float(a["t_total"])
    # at t_decide the trace after the ramp still drifted by more than DECIDE_DRIFT: the run went on...
    t, X = ds["time"].values, ds["X_mean"].values
    first = (t > 0.25 * cfg.t_decide) & (t <= cfg.t_decide)
    early = steady_velocity(t[first], X[first], DECIDE_DRIFT)
    assert not (early.status == "ok" and abs(early.change) <= DECIDE_DRIFT)
    # ...and stopped, before t_max, at the first chunk where the drift was small enough
    assert cfg.t_decide < t_end < cfg.t_max and a["velocity_status"] == "ok" and a["status"] == "completed"
    late = steady_velocity(t[t > 0.25 * cfg.t_decide], X[t > 0.25 * cfg.t_decide], DECIDE_DRIFT)
    assert late.status == "ok" and abs(late.change) <= DECIDE_DRIFT and late.velocity == a["velocity"]
    # the steady velocity is the analytic one, f(v, v0) = mu_a epsilon f0, within the allowed drift
    assert a["velocity"] == pytest.approx(10.0 ** _analytic_velocity(cfg, 0.7), rel=2 * DECIDE_DRIFT)
    # a runaway beyond the rising branch is decided at t_decide
    b = run(make_config(**AUTO, dead_weight=1.2), progress=False).attrs
    assert b["velocity_status"] == "runaway" and b["t_total"] == pytest.approx(cfg.t_decide, abs=6e-4)


def test_a_runaway_still_accelerating_beyond_the_branch_is_decided_at_t_decide():
    """Without contact damping (eta_c = 0) a runaway never stops accelerating: at t_decide its fit is
    not steady, but it is already beyond the rising branch (faster than RUNAWAY_FACTOR v0 10**delta),
    where under the constant load it cannot come back (schema.accelerating_beyond_branch). The
    automatic length stops there, and the same run to t_max (fixed length) is a runaway too, faster
    still; a slider below the branch at t_decide is not stopped by this rule (the drifting run above)."""
    from slipchain import run
    from slipchain.results.schema import RUNAWAY_FACTOR

    cfg = make_config(**AUTO, dead_weight=1.2, eta_c=0.0)
    a = run(cfg, progress=False)
    assert a.attrs["velocity_status"] == "runaway" and "still rises" in a.attrs["velocity_reason"]
    assert float(a.attrs["t_total"]) == pytest.approx(cfg.t_decide, abs=6e-4)
    t, X = a["time"].values, a["X_mean"].values
    last = t >= t[-1] - 0.1 * (t[-1] - 0.25 * cfg.t_decide)
    assert np.diff(X[last]).sum() / np.diff(t[last]).sum() > RUNAWAY_FACTOR * cfg.v0 * 10.0 ** cfg.delta
    full = run(make_config(**{k: v for k, v in AUTO.items() if k not in ("t_decide", "t_max")}, dead_weight=1.2,
                           eta_c=0.0, t_total=cfg.t_max, t_ramp=0.25 * cfg.t_decide), progress=False)
    assert full.attrs["velocity_status"] == "runaway"
    assert np.array_equal(full["X_mean"].values[:X.size], X)  # the same run up to the early stop


def test_automatic_dead_weight_length_stops_at_t_max_with_no_steady_and_the_drift():
    from slipchain import run

    # t_max too short for the transient: the tester alone would call the trace steady (its change is not
    # significant in so short a record); the automatic length calls it no-steady and says by how much it drifts
    a = run(make_config(**{**AUTO, "t_max": 2.5e-3}, dead_weight=0.7), progress=False).attrs
    assert a["t_total"] == pytest.approx(2.5e-3) and a["velocity_status"] == "no-steady"
    assert "t_max = 2.5 s reached" not in a["message"] and "t_max = 0.0025 s reached" in a["message"]
    assert "still changes by" in a["velocity_reason"] and np.isnan(a["velocity"])


def test_t_ramp_sets_the_ramp_and_equals_the_default_quarter():
    from slipchain import run

    cfg = make_config(**AUTO, dead_weight=0.7)
    default = run(cfg, progress=False)
    explicit = run(cfg.with_updates(t_ramp=0.25 * cfg.t_decide), progress=False)  # the same ramp, given
    assert default.attrs["velocity"] == explicit.attrs["velocity"] and default.attrs["t_total"] == explicit.attrs["t_total"]
    assert np.array_equal(default["X_mean"].values, explicit["X_mean"].values)
    # a 4x slower ramp: the slider starts slower (a different run), and reaches the same steady velocity
    slow = run(cfg.with_updates(t_ramp=cfg.t_decide * 0.9, t_max=0.1), progress=False)
    early = slice(0, 20)  # the first 0.2 ms
    assert slow["X_mean"].values[early].max() < default["X_mean"].values[early].max()
    assert slow.attrs["velocity_status"] == "ok"
    assert slow.attrs["velocity"] == pytest.approx(default.attrs["velocity"], rel=0.1)


@pytest.mark.parametrize("extra, match", [
    (dict(t_ramp=1e-3), "t_ramp.*spring drive"),
    (dict(t_ramp=3e-3, t_decide=2e-3, dead_weight=0.5), "t_ramp.*shorter than t_decide"),
    (dict(t_ramp=0.02, t_total=0.01, dead_weight=0.5), "t_ramp.*shorter than t_total"),
    (dict(t_decide=2e-3), "t_decide.*spring drive"),
    (dict(t_decide=2e-3, dead_weight=0.5, t_total=0.01), "t_decide.*t_total"),
    (dict(t_decide=0.5, dead_weight=0.5, t_max=0.25), "t_decide.*less than t_max"),
    (dict(t_decide=1e-4, dead_weight=0.5), "t_decide.*100 output intervals"),
])
def test_t_decide_bad_combinations_are_clear_errors(extra, match):
    with pytest.raises(ConfigError, match=match):
        make_config(**{**IDENTICAL, "t_total": None, **extra})


def test_t_decide_and_t_ramp_absent_leave_member_ids_unchanged():
    from slipchain.sweeps.definition import member_id

    cfg = make_config(N=31, dead_weight=0.5, t_total=0.01, integrator="fixed", dt=2e-8)
    # the id of this config as 0.2.0 computed it (before t_decide existed, with the fixed step at
    # 2e-8 s, then the defaults): a frozen reference
    assert member_id(cfg) == "be3a6b1c23568497"


def test_cli_mu_max_plan_with_automatic_length_then_its_figure_and_report(tmp_path, slipchain_cli):
    """A plan file ([base] + [bisection] with curve points) through `slipchain mu-max`, resumed from
    its stores, then `slipchain figure mu-max` (a real figure and report) and a bad plan key."""
    import subprocess
    import sys

    import pandas as pd

    plan = tmp_path / "plan.toml"
    plan.write_text('name = "t"\n[base]\nN = 11\ndelta = 0.0\nt_decide = 1e-2\nt_max = 0.1\n'
                    "[bisection]\ntheta = [1.0]\nseeds = 2\nlo = 0.5\nhi = 1.5\ncurve = [0.3]\n")
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "slipchain", "mu-max", str(plan), "--workers", "1", "--out", str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    table, evals = pd.read_csv(out / "mu_max.csv"), pd.read_csv(out / "evaluations.csv")
    f_max = single_contact_maximum(make_config(**IDENTICAL))[0]
    assert (table["status"] == "ok").all() and (abs(table["mu_max"] - f_max) <= TOL).all()
    # every bisection run and the curve point, each a member of a round's store; the curve point on the analytic branch
    assert len(list((out / "rounds").glob("*/members/*.nc"))) == len(evals) == table["runs"].sum() + 1
    curve = evals[evals["source"] == "curve"].iloc[0]
    cfg = make_config(**AUTO, dead_weight=0.3)
    assert curve["velocity_status"] == "ok"
    assert curve["velocity_m_s"] == pytest.approx(10.0 ** _analytic_velocity(cfg, 0.3), rel=0.1)
    # (a ramp of 2.5 ms: with 0.5 ms, t_decide = 2e-3, the overshoot runs away below the peak and mu_max is 0.988)
    # a second call computes nothing (every run cached) and writes the same tables
    before = (out / "mu_max.csv").read_text()
    (out / "mu_max.csv").unlink()
    r2 = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r2.returncode == 0 and (out / "mu_max.csv").read_text() == before
    fig = tmp_path / "fig"
    r3 = slipchain_cli("figure", "mu-max", "--from", out, "--out", fig)
    assert r3.returncode == 0, r3.stderr
    assert (fig / "mu_max.png").stat().st_size > 10_000 and (fig / "mu_max.pdf").exists()
    report = (fig / "report.md").read_text()
    assert f"{table['mu_max'].mean():.4f}" in report and "| 1 | 2/2 |" in report
    # failure modes: an unknown plan key, and a result directory that is not one: exit 2, nothing written
    plan.write_text(plan.read_text().replace("seeds = 2", "seedz = 2"))
    bad = slipchain_cli(*cmd[3:-1], tmp_path / "y")
    assert bad.returncode == 2 and "seedz" in bad.stderr and not (tmp_path / "y").exists()
    good = plan.read_text().replace("seedz = 2", "seeds = 2")
    for body, words in ((good.replace("seeds = 2", "seeds = 1.5"), "'seeds' has value 1.5"),
                        (good.replace("seeds = 2", "seeds = true"), "'seeds' has value True"),
                        ("[bass]\nN = 3\n" + good, "unknown table(s)/key(s) ['bass']")):
        plan.write_text(body)
        bad = slipchain_cli(*cmd[3:-1], tmp_path / "y")
        assert bad.returncode == 2 and words in bad.stderr and not (tmp_path / "y").exists(), bad.stderr
    bad = slipchain_cli("figure", "mu-max", "--from", tmp_path, "--out", tmp_path / "z")
    assert bad.returncode == 2 and "mu_max_summary.csv" in bad.stderr and not (tmp_path / "z").exists()


def test_a_refuted_bracket_marks_that_realisation_and_the_others_go_on():
    from slipchain.workflows.dead_weight import BRACKET, _bisect

    # a run of 0.1 ms leaves 7 samples after the ramp: too few to call steady, so lo is refuted there
    configs = [make_config(**{**IDENTICAL, "t_total": 1e-4}), make_config(**IDENTICAL)]
    got = _bisect(configs, 0.5, 1.5, TOL, lambda jobs: [evaluate(c, m) for c, m in jobs], strict=False)
    assert got[0].status == BRACKET and "lo = 0.5 must give steady sliding" in got[0].message
    assert np.isnan(got[0].mu_max) and len(got[0].evaluations) == 2
    assert got[1].status == "ok" and abs(got[1].mu_max - single_contact_maximum(configs[1])[0]) <= TOL
    with pytest.raises(BracketError, match="lo = 0.5 must give steady sliding"):
        _bisect(configs, 0.5, 1.5, TOL, lambda jobs: [evaluate(c, m) for c, m in jobs])


def test_cli_mu_max_stopped_by_sigterm_keeps_its_runs_and_resumes_to_the_same_tables(tmp_path, cli_stopping_after_members):
    """SIGTERM (a batch scheduler's time limit) while a round runs, sent when the driver has stored
    its 3rd run (it stops itself there, so on any machine): exit 143 with one error line, no
    table, the runs kept; the same command then finishes, equal to an uninterrupted call."""
    import os
    import signal
    import subprocess
    import sys

    # --tol 0.05: five rounds, four of them after the interrupted one (the default 0.005 takes eight)
    args = ["mu-max", "--set", "N=11", "--set", "delta=0", "--set", "start=steady", "--set", "t_total=5e-3",
            "--theta", "1", "--seeds", "2", "--lo", "0.5", "--tol", "0.05", "--workers", "1", "--no-progress"]
    out, whole = tmp_path / "out", tmp_path / "whole"
    proc = subprocess.Popen([*cli_stopping_after_members(3), *args, "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        _, status = os.waitpid(proc.pid, os.WUNTRACED)
        assert os.WIFSTOPPED(status), proc.communicate()
        os.kill(proc.pid, signal.SIGTERM)
        os.kill(proc.pid, signal.SIGCONT)
        _, err = proc.communicate(timeout=120)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # the orphaned local-cluster processes
        except ProcessLookupError:
            pass
    assert proc.returncode == 143 and err.startswith("error: interrupted") and "rounds" in err, err
    assert len(list((out / "rounds").glob("*/members/*.nc"))) == 3 and not (out / "mu_max.csv").exists()
    for folder in (out, whole):
        r = subprocess.run([sys.executable, "-m", "slipchain", *args, "--out", str(folder)], capture_output=True,
                           text=True, timeout=300)
        assert r.returncode == 0, r.stderr
    for name in ("mu_max.csv", "evaluations.csv"):
        assert (out / name).read_text() == (whole / name).read_text()


def test_a_plan_run_in_batches_equals_one_run_per_task_and_its_sweep_store_reads_back(tmp_path, monkeypatch):
    """`--batch-size` (issue 29: one FFT per step for a batch of slab runs): the rounds' runs advanced
    together in tasks of two give the tables of one run per task, bit for bit; and a sweep over
    dead_weight reads back as the same evaluations (store_evaluations)."""
    from distributed import Client, LocalCluster

    from slipchain.sweeps import executor
    from slipchain.sweeps.executor import run_sweep
    from slipchain.sweeps.definition import make_sweep
    from slipchain.workflows.dead_weight import load_plan, run_plan, store_evaluations

    plan_file = tmp_path / "plan.toml"
    plan_file.write_text('name = "t"\n[base]\nN = 11\ndelta = 0.0\nstart = "steady"\nt_total = 5e-3\n'
                         "[bisection]\ntheta = [1.0, 0.5]\nseeds = 2\nlo = 0.5\nhi = 1.5\ntol = 0.05\n")
    plan = load_plan(plan_file)
    sizes = []
    real = executor.run_sweep

    def spy(*args, **kwargs):
        sizes.append(kwargs.get("batch_size"))
        return real(*args, **kwargs)

    monkeypatch.setattr(executor, "run_sweep", spy)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=":0") as cluster, Client(cluster) as client:
        one = run_plan(plan, tmp_path / "one", client=client, progress=False)
        two = run_plan(plan, tmp_path / "two", client=client, progress=False, batch_size=2)
        assert set(sizes) == {None, 2}  # every round of the second call went out in batches of two
        pd_one, pd_two = one.evaluations, two.evaluations
        assert pd_one.equals(pd_two) and one.table.equals(two.table)
        # the same runs as one sweep over dead_weight: the same classification and velocities
        runs = pd_one[pd_one["theta"] == 1.0]
        sweep = make_sweep({"name": "dw", "base": {"N": 11, "delta": 0.0, "start": "steady", "t_total": 5e-3,
                                                   "dead_weight": 0.5},
                            "grid": {"theta": [1.0], "seed": [0, 1], "dead_weight": sorted(set(runs["mu_a"])),
                                     "eta_c": [1e5]}})
        run_sweep(sweep, tmp_path / "store", client=client, progress=False)
    got = store_evaluations(tmp_path / "store")
    assert (got["eta_c"] == 1e5).all()  # a swept parameter besides theta, seed and dead_weight is a column
    both = runs.merge(got, on=["seed", "mu_a"], suffixes=("", "_sweep"))
    assert len(both) == len(runs) and (both["source_sweep"] == "sweep").all()
    assert (both["velocity_status"] == both["velocity_status_sweep"]).all()
    assert np.array_equal(both["velocity_m_s"].to_numpy(float), both["velocity_m_s_sweep"].to_numpy(float), equal_nan=True)


HELD_SHORT = {**AUTO, "t_max": 5e-3}  # runs too short for the transient at mu_a = 0.75: undecided at t_max


def test_held_runs_count_below_the_maximum_as_longer_runs_decide_them(tmp_path, two_workers):
    """Plan key ``held`` (workflows.dead_weight, docs/ladder rung 5): an undecided run whose record ends on
    the rising branch (analysis.traces.run_outcome: held) moves lo up as a steady one does. Runs of 5 ms
    leave mu_a = 0.75 creeping towards its steady velocity at t_max: without the rule the bisection stops
    there; with it, it goes on and finds the bracket that runs of 50 ms find with the tester's status
    alone (0.75 decided steady there), run for run the same decisions, through the stores on Dask too.
    A run that is undecided and still fast at its end is not held: it stops the bisection as before."""
    from slipchain.analysis.traces import ONSET_FACTOR
    from slipchain.results.schema import branch_scale
    from slipchain.workflows.dead_weight import HELD, mu_max_many

    short = make_config(**HELD_SHORT, dead_weight=1.0)
    long_ = mu_max(make_config(**AUTO, dead_weight=1.0), lo=0.5, hi=1.5)
    plain = mu_max(short, lo=0.5, hi=1.5)
    held = mu_max(short, lo=0.5, hi=1.5, held=True)
    assert plain.status == "no-steady" and "undecided at mu_a = 0.75" in plain.message
    assert long_.status == held.status == "ok" and (held.lo, held.hi) == (long_.lo, long_.hi)
    assert abs(held.mu_max - single_contact_maximum(short)[0]) <= 3 * TOL  # near the analytic peak
    ok_or_held = [("ok" if e.velocity_status == HELD else e.velocity_status, e.mu_a) for e in held.evaluations]
    assert ok_or_held == [(e.velocity_status, e.mu_a) for e in long_.evaluations]
    h = [e for e in held.evaluations if e.velocity_status == HELD]
    assert [e.mu_a for e in h] == [0.75] and 0 < h[0].velocity < ONSET_FACTOR * branch_scale(short)
    assert "held: " in h[0].message and "still drifted" in h[0].message
    # undecided and still fast at t_max (0.9 in 2.5 ms: the record's mean velocity above the bound): not held
    fast = evaluate(make_config(**{**AUTO, "t_max": 2.5e-3}, dead_weight=1.0), 0.9, held=True)
    assert fast.velocity_status == "no-steady" and np.isnan(fast.velocity)
    # the same through the rounds' stores on a local cluster (the record read from the member file)
    many = mu_max_many([short], lo=0.5, hi=1.5, store=tmp_path / "out", client=two_workers, progress=False, held=True)
    assert [(e.mu_a, e.velocity_status, repr(e.velocity)) for e in many[0].evaluations] == \
        [(e.mu_a, e.velocity_status, repr(e.velocity)) for e in held.evaluations]
    assert (many[0].lo, many[0].hi, many[0].v_max) == (held.lo, held.hi, held.v_max)


def test_plan_key_held_reads_writes_back_and_rejects_a_non_boolean(tmp_path):
    from slipchain.workflows.dead_weight import load_plan, plan_toml

    text = ("[base]\nN = 11\ndelta = 0.0\nt_decide = 0.002\nt_max = 0.005\n"
            "[bisection]\ntheta = [1.0]\nseeds = 1\nlo = 0.5\nhi = 1.5\n")
    off = tmp_path / "off.toml"
    off.write_text(text)
    on = tmp_path / "on.toml"
    on.write_text(text + "held = true\n")
    plan_off, plan_on = load_plan(off), load_plan(on)
    assert not plan_off.held and plan_on.held
    assert "held" not in plan_toml(plan_off)  # a plan without it writes the plan.toml it always wrote
    back = tmp_path / "back.toml"
    back.write_text(plan_toml(plan_on))
    assert load_plan(back) == plan_on
    for bad in ("1", '"yes"'):
        f = tmp_path / "bad.toml"
        f.write_text(text + f"held = {bad}\n")
        with pytest.raises(ConfigError, match=r"mu-max key 'held' has value .*; expected true or false"):
            load_plan(f)

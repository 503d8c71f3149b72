"""slipchain status / sweeps.status.store_status: where a store stands, read from its files alone.

Each state is made the way a sweep makes it (a member written by the store, a checkpoint written by a run
that was not stored, a failed file), and what the status reports is checked against that run's own
result: the simulated time a checkpoint has reached against the run's record, the outcome against the
member's attributes.
"""

from __future__ import annotations

import json
import os
import re
import socket

import numpy as np
import pytest

from slipchain import make_config, run
from slipchain.engine.checkpoint import RECENT_WINDOW
from slipchain.results.io import write_text_atomic
from slipchain.sweeps.definition import make_sweep
from slipchain.sweeps.status import FAILED, IN_FLIGHT, PENDING, STORED, store_status
from slipchain.sweeps.store import HOLDER, Store
from slipchain.workflows.dead_weight import single_contact_maximum

IDENTICAL = dict(N=11, theta=1.0, delta=0.0, start="rest")


def _sweep(f_max: float):
    base = {**IDENTICAL, "t_ramp": 1e-4, "t_decide": 2e-3, "t_max": 4e-3, "output_interval": 2.5e-6, "dead_weight": 1.0}
    return make_sweep({"name": "release", "base": base,
                       "grid": {"dead_weight": [0.8 * f_max, 0.9 * f_max, 1.2 * f_max, 1.3 * f_max]}})


def test_store_status_reports_each_state_from_the_files(tmp_path):
    f_max, _ = single_contact_maximum(make_config(**IDENTICAL, t_total=5e-3))
    sweep = _sweep(f_max)
    st = Store.open(tmp_path / "s", sweep)
    stored, flying, failed, pending = sweep.members
    ds = run(stored.config)
    st.write_member(stored, ds)
    # a run checkpointed but not stored (a task killed after its last checkpoint): the file holds its whole record
    full = run(flying.config, checkpoint=st.checkpoint_path([flying]))
    bad = run(failed.config)
    bad.attrs.update(status="diverged", message="diverged at step 7 (t = 1e-6 s): test")
    st.write_member(failed, bad)  # a status other than completed goes to failed/
    # a checkpoint of a config that is no member of this sweep (another batching, another sweep): stray
    run(flying.config.model_copy(update={"t_max": 2e-3, "t_decide": 1e-3}), checkpoint=tmp_path / "s" / "checkpoints" / "other.nc")
    (tmp_path / "s" / "checkpoints" / "broken.nc").write_bytes(b"not a netcdf file")

    s = store_status(tmp_path / "s")
    by = {m.id: m for m in s.members}
    assert [m.id for m in s.members] == [m.id for m in sweep.members]  # definition order
    assert s.counts() == {STORED: 1, IN_FLIGHT: 1, FAILED: 1, PENDING: 1, "unreadable": 0}
    a = by[stored.id]
    assert (a.state, a.status, a.outcome) == (STORED, "completed", ds.attrs["velocity_status"])
    assert a.t_simulated == pytest.approx(float(ds.attrs["t_total"])) and a.wall_time_s == ds.attrs["wall_time_s"]
    assert a.message == ds.attrs["velocity_reason"]
    f = by[flying.id]
    assert f.state == IN_FLIGHT and f.t_max == flying.config.t_max and f.written
    # the checkpoint's samples against the run's own record: two readings of how far it got
    assert f.t_simulated == pytest.approx(float(full["time"].values[-1]), rel=1e-9) and f.wall_time_s > 0
    k = round(RECENT_WINDOW / flying.config.output_interval) + 1  # the top's velocity now: the record's last 10 ms
    X, t = full["X_mean"].values[-k:], full["time"].values[-k:]
    assert f.velocity == pytest.approx((X[-1] - X[0]) / (t[-1] - t[0]), rel=1e-9) and abs(f.velocity) > 0
    b = by[failed.id]
    assert (b.state, b.status) == (FAILED, "diverged") and "step 7" in b.message
    assert by[pending.id].state == PENDING and by[pending.id].t_simulated is None
    assert s.stray_checkpoints == ["other.nc"]
    assert len(s.unreadable_checkpoints) == 1 and "broken.nc" in s.unreadable_checkpoints[0]
    assert s.driver.startswith("no driver")
    # once stored, the member is stored whatever checkpoint is left (the next sweep prunes it)
    st.write_member(flying, full)
    assert store_status(tmp_path / "s").counts()[STORED] == 2


def test_store_status_driver_record(tmp_path):
    f_max, _ = single_contact_maximum(make_config(**IDENTICAL, t_total=5e-3))
    st = Store.open(tmp_path / "s", _sweep(f_max))
    record = tmp_path / "s" / HOLDER
    write_text_atomic(record, json.dumps({"host": socket.gethostname(), "pid": os.getpid(), "started": "T0"}))
    assert store_status(st.path).driver.startswith("running (") and f"pid {os.getpid()}" in store_status(st.path).driver
    dead = 2**22 + 12345  # above Linux's default pid_max (2**22): no such process
    write_text_atomic(record, json.dumps({"host": socket.gethostname(), "pid": dead, "started": "T0"}))
    assert "was killed" in store_status(st.path).driver
    write_text_atomic(record, json.dumps({"host": "elsewhere.example", "pid": 1, "started": "T0"}))
    assert "another host" in store_status(st.path).driver
    assert store_status(st.path).counts()[PENDING] == 4


def test_cli_status_table_json_and_bad_store(tmp_path, slipchain_cli, store_of_runs):
    f_max, _ = single_contact_maximum(make_config(**IDENTICAL, t_total=5e-3))
    sweep = _sweep(f_max)
    st = store_of_runs(tmp_path / "s", sweep)
    r = slipchain_cli("status", "--store", tmp_path / "s")
    assert r.returncode == 0, r.stderr
    assert "4 members: 4 stored" in r.stdout and "runaway" in r.stdout
    j = slipchain_cli("status", "--store", tmp_path / "s", "--json")
    got = json.loads(j.stdout)
    assert got["counts"]["stored"] == 4 and got["sweep"] == "release"
    assert [m["outcome"] for m in got["members"]] == [st.member_attrs(m)["velocity_status"] for m in sweep.members]
    # a mu-max output directory: one store per round (OUT/rounds/<digest>), each reported
    small = make_sweep({"name": "round-2", "base": {**IDENTICAL, "t_ramp": 1e-4, "t_decide": 2e-3, "t_max": 4e-3,
                                                    "output_interval": 2.5e-6, "dead_weight": 1.0},
                        "grid": {"dead_weight": [f_max]}})
    store_of_runs(tmp_path / "mm" / "rounds" / "r1", sweep)
    store_of_runs(tmp_path / "mm" / "rounds" / "r2", small)
    m = slipchain_cli("status", "--store", tmp_path / "mm")
    assert m.returncode == 0, m.stderr
    assert "4 members: 4 stored" in m.stdout and "1 members: 1 stored" in m.stdout and "2 rounds" in m.stdout
    mj = json.loads(slipchain_cli("status", "--store", tmp_path / "mm", "--json").stdout)
    assert sorted(r["sweep"] for r in mj["rounds"]) == ["release", "round-2"] and mj["driver"].startswith("no driver")
    (tmp_path / "empty").mkdir()
    for bad, says in ((tmp_path / "none", "no such directory"), (tmp_path / "empty", "neither a slipchain sweep store")):
        b = slipchain_cli("status", "--store", bad)
        assert b.returncode == 2 and "--store" in b.stderr and says in b.stderr.replace("\n", " ") and str(bad) in b.stderr, b.stderr
    assert sorted(p.name for p in (tmp_path / "empty").iterdir()) == []  # nothing written


def test_store_status_says_where_the_stop_rules_decide_a_released_slab(tmp_path, checkpointed_releases):
    """A released 4 x 4 slab (tests/physics/test_dead_weight.py's RELEASE) run without the stop rules and
    checkpointed, not stored: the status says where stop_at_runaway and stop_when_held decide its record so far
    (sweeps.status.stop_rules), the time and verdict of the same run made with them on; a chain's run says
    nothing of them."""
    from slipchain.model.system import top_ringing_period
    from slipchain.results.schema import rules_start
    from slipchain.sweeps.status import stop_rules

    _, sweep, _ = checkpointed_releases
    by = {m.id: m for m in store_status(tmp_path / "s").members}
    for m in sweep.members:
        ruled = run(m.config.model_copy(update={"stop_at_runaway": True, "stop_when_held": True}))
        said = "runaway" if m.config.dead_weight == 0.9 else "held"
        assert by[m.id].state == IN_FLIGHT
        assert by[m.id].rules == f"{said} at t = {float(ruled['time'].values[-1]):.4g} s"
        # its first 2 ms, before three ringing periods (7.5 ms): not decided yet, and when each rule can decide
        start = rules_start(m.config)
        assert abs(start - (1e-5 + 3 * top_ringing_period(m.config))) < 1e-12 and 0.002 < start < 0.02
        assert stop_rules(m.config, ruled["X_mean"].values[:100]) == (
            f"not decided by t = 0.002 s; the runaway rule reads from t = {start:.4g} s, the held rule from t = 0.02 s")
        # at 6 ms (past two periods, before three): the top's period means, by interpolation of <X>(t), and the
        # wall time ahead at the pace given (3600 s of wall per simulated second: hours = simulated seconds)
        x, t = ruled["X_mean"].values[:300], ruled["time"].values[:300]
        said = stop_rules(m.config, x, wall_time_s=3600.0 * t[-1])
        period = top_ringing_period(m.config)
        v = [(np.interp(t[-1] - k * period, t, x) - np.interp(t[-1] - (k + 1) * period, t, x)) / period
             for k in (1, 0)]
        got = re.search(r"periods \(([0-9.e-]+) s each\) the top slid at ([0-9.e-]+) and then ([0-9.e-]+) m/s", said)
        assert got is not None, said
        assert float(got[1]) == pytest.approx(period, rel=5e-3)  # printed to 3 digits
        # the rule's windows start on the sample at or after t - k T: each mean may differ from the interpolated
        # one by up to one sample interval's share of the fastest velocity in it (printed to 3 digits)
        recent = t > t[-1] - 2 * period - 1e-4
        v_fast = np.max(np.abs(np.diff(x[recent]) / np.diff(t[recent])))
        slack = 2.0 * float(np.diff(t).max()) * v_fast / period
        assert [float(got[2]), float(got[3])] == pytest.approx(v, rel=5e-3, abs=slack), said
        hours = re.findall(r"t = ([0-9.e-]+) s is ([0-9.e-]+) h of wall away", said)
        assert [float(h[0]) for h in hours] == pytest.approx([start, 0.02], rel=1e-3), said
        assert [float(h[1]) for h in hours] == pytest.approx([start - t[-1], 0.02 - t[-1]], rel=0.03), said
        assert "at its pace so far" in said
        # given the recent pace from the checkpoint's last writes (here 7200 s of wall per simulated second over
        # its last 30 min), the wait is read at that pace, not the mean
        said = stop_rules(m.config, x, wall_time_s=3600.0 * t[-1], pace=(7200.0, 1800.0))
        assert "at its pace over its last 30 min of wall (7,200 s a simulated second)" in said, said
        hours = re.findall(r"t = ([0-9.e-]+) s is ([0-9.e-]+) h of wall away", said)
        assert [float(h[1]) for h in hours] == pytest.approx([2 * (start - t[-1]), 2 * (0.02 - t[-1])], rel=0.03)
    chain = make_config(**IDENTICAL, dead_weight=0.5, t_ramp=1e-4, t_decide=2e-3, t_max=4e-3)
    assert stop_rules(chain, ruled["X_mean"].values) is None


def test_recent_pace_reads_the_last_writes_that_span_its_window():
    """engine.checkpoint.recent_pace: a run that went at 10 s of wall per simulated second, then at 1000 (a
    released top ringing on fine steps after a quick start, say): over a window inside the slow stretch it
    reads 1000, over one reaching back past the change the mean of the span, over one longer than the whole
    record from the first kept write; two writes or none moved: None."""
    from slipchain.engine.checkpoint import recent_pace

    t = np.array([0.0, 1.0, 2.0, 3.0, 3.1, 3.2, 3.3])
    w = np.array([0.0, 10.0, 20.0, 30.0, 130.0, 230.0, 330.0])
    attrs = {"pace_t_simulated": t, "pace_wall_time_s": w}
    assert recent_pace(attrs, window=150.0) == pytest.approx((1000.0, 200.0))
    assert recent_pace(attrs, window=300.0) == pytest.approx((1000.0, 300.0))  # from the write 300 s back
    assert recent_pace(attrs, window=305.0) == pytest.approx((310.0 / 1.3, 310.0))
    assert recent_pace(attrs, window=1e6) == pytest.approx((100.0, 330.0))
    assert recent_pace({"pace_t_simulated": t[:1], "pace_wall_time_s": w[:1]}) is None
    assert recent_pace({"pace_t_simulated": [1.0, 1.0], "pace_wall_time_s": [5.0, 9.0]}) is None
    assert recent_pace({}) is None  # a checkpoint written before the pace was kept

"""Sweeps on a real Dask LocalCluster (loopback): results, resume, failures, killed workers and drivers."""

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from distributed import Client, LocalCluster

from slipchain import run
from slipchain.results.io import read_dataset
from slipchain.sweeps.executor import run_sweep
from slipchain.sweeps.store import Store
from slipchain.sweeps.definition import SweepError, make_sweep

# Contacts all above v_d (no stick-slip), steady start: a member completes in well under a second.
# The fixed step: the kill tests need members of a known cost (the adaptive default is ~10x faster here).
FAST = {"N": 31, "start": "steady", "v0": 0.01, "delta": 0.2, "t_total": 3e-3, "theta": 0.5, "integrator": "fixed"}
SLOW_T = 0.06  # t_total of members that take about a second each (for the kill tests)


@pytest.fixture(scope="module")
def client():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=":0") as cluster, Client(cluster) as c:
        yield c


def _sweep(name="t", **grid):
    return make_sweep({"name": name, "base": FAST, "grid": grid or {"theta": [0.5, 1.0], "seed": [0, 1]}})


def test_sweep_runs_every_member_and_matches_direct_runs(tmp_path, client):
    sw = _sweep()
    rep = run_sweep(sw, tmp_path / "s", client=client, progress=False)
    assert rep.ok and len(rep.ran) == 4 and not rep.skipped
    ds = Store.open(tmp_path / "s").dataset()
    assert (ds["status"] == "completed").all()
    # A member computed on a Dask worker is bit-identical to the same config run here.
    m = sw.members[3]
    direct = run(m.config)
    assert ds["mu_star"].sel(theta=m.coords["theta"], seed=m.coords["seed"]).item() == direct.attrs["mu_star"]
    stored = read_dataset(tmp_path / "s" / "members" / f"{m.id}.nc")
    assert (stored["f_d"].values == direct["f_d"].values).all()
    assert stored.attrs["config"] == m.config.to_toml() and stored.attrs["slipchain_version"]


def test_resume_skips_finished_and_reruns_missing_and_failed(tmp_path, client):
    sw = make_sweep({"name": "r", "base": FAST, "grid": {"start": ["steady", "rest"], "seed": [0, 1]}})
    rep = run_sweep(sw, tmp_path / "s", client=client, progress=False)
    # from rest the chain loads for about 6 ms, longer than the 3 ms run: the slider does not follow
    # the drive, a failed physics check, status diverged
    assert len(rep.ran) == 4 and len(rep.failed) == 2 and not rep.ok
    assert all(o.status == "diverged" and "steady mean interface velocity" in o.message for o in rep.failed)
    st = Store.open(tmp_path / "s")
    assert len(st.completed_ids()) == 2 and len(st.failed_ids()) == 2
    done = sorted(st.completed_ids())
    (st.path / "members" / f"{done[0]}.nc").unlink()  # a lost member
    before = (st.path / "members" / f"{done[1]}.nc").stat().st_mtime_ns
    rep2 = run_sweep(sw, tmp_path / "s", client=client, progress=False)
    assert [m.id for m in rep2.skipped] == [done[1]]
    assert sorted(o.member.id for o in rep2.ran) == sorted([done[0], *st.failed_ids()])
    assert (st.path / "members" / f"{done[1]}.nc").stat().st_mtime_ns == before  # skipped: untouched
    assert len(st.invocations()) == 2 and st.invocations()[1]["skipped"] == 1


def _stop_once(marker: str, where: str, undo: bool = False) -> None:
    """Run on every worker (``client.run``): the first of them to reach ``where`` ('task': the start of
    a task; 'checkpoint': just after a task's first checkpoint) stops its own process (SIGSTOP) and
    waits there, so that the test kills it at a known point whatever the machine's speed (issue 30:
    the test slept 0.3 s and hoped to land inside a task). ``marker`` (created exclusively) makes it
    the only one. ``undo``: put the originals back."""
    import os
    import signal

    from slipchain.engine import checkpoint as c
    from slipchain.sweeps import executor

    if undo:
        executor.run_members = getattr(executor.run_members, "original", executor.run_members)
        c.Checkpointer.save = getattr(c.Checkpointer.save, "original", c.Checkpointer.save)
        return

    def stop() -> None:
        try:
            os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            return
        os.kill(os.getpid(), signal.SIGSTOP)

    if where == "task":
        run = executor.run_members

        def gated(*args, **kwargs):
            stop()
            return run(*args, **kwargs)

        gated.original = run
        executor.run_members = gated
    else:
        save = c.Checkpointer.save

        def gated_save(self):
            save(self)
            if self.writes == 1:
                stop()

        gated_save.original = save
        c.Checkpointer.save = gated_save


def _stopped_worker(pids: dict[str, int]) -> tuple[str, int]:
    """The worker that has stopped itself: its (address, pid). A stopped process stays stopped, so this
    waits for a state, not for a moment (the time limit only guards against a hang)."""
    t_end = time.time() + 300
    while time.time() < t_end:
        for addr, pid in pids.items():
            try:
                state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
            except OSError:
                continue
            if state == "T":
                return addr, pid
        time.sleep(0.02)
    raise AssertionError("no worker stopped itself within 300 s")


def _kill_when_stopped(client, tmp_path, where: str) -> tuple[threading.Thread, dict]:
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])  # workers cannot import this test module
    marker = str(tmp_path / f"stopped-{where}")
    client.run(_stop_once, marker, where)
    pids = client.run(os.getpid)
    killed: dict = {}

    def killer():
        addr, pid = _stopped_worker(pids)
        os.kill(pid, signal.SIGKILL)
        killed.update(addr=addr)

    th = threading.Thread(target=killer)
    th.start()
    return th, killed


def test_worker_killed_mid_task_is_retried(tmp_path, client):
    sw = make_sweep({"name": "k", "base": {**FAST, "t_total": SLOW_T}, "grid": {"seed": list(range(6))}})
    th, killed = _kill_when_stopped(client, tmp_path, "task")
    try:
        rep = run_sweep(sw, tmp_path / "s", client=client, progress=False)
    finally:
        th.join()
        client.wait_for_workers(2, timeout=60)  # the nanny restarted the killed worker
        client.run(_stop_once, "", "", True)
    assert killed, "no worker stopped in a task, nothing was killed"
    assert rep.ok and len(rep.ran) == 6, [(o.status, o.message) for o in rep.failed]
    assert len(Store.open(tmp_path / "s").completed_ids()) == 6


# The sweep driver stops itself (SIGSTOP) right after storing its k-th member, so that a test acts
# on it at a known point whatever the machine's speed (issue 30: these tests slept and polled).
def _slow_sweep(tmp_path, members, stop_after=None, stopping=None, workers=2):
    """The command of a `slipchain sweep` of ``members`` one-second members on a local cluster of
    ``workers`` processes, its store, and the driver started in a new session (so its cluster can be
    killed); with ``stop_after`` = k the driver stops itself once it has stored k members
    (``stopping``: the ``cli_stopping_after_members`` fixture)."""
    definition = tmp_path / "sweep.toml"
    definition.write_text(
        'name = "slow"\n[base]\nN = 31\nstart = "steady"\nv0 = 0.01\ndelta = 0.2\ntheta = 0.5\nintegrator = "fixed"\n'
        f"t_total = {SLOW_T}\n[grid]\nseed = [{', '.join(map(str, range(members)))}]\n")
    store = tmp_path / "s"
    args = ["sweep", str(definition), "--store", str(store), "--workers", str(workers), "--no-progress"]
    cmd = [sys.executable, "-m", "slipchain", *args]
    start = cmd if stop_after is None else [*stopping(stop_after), *args]
    return cmd, store, subprocess.Popen(start, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                        start_new_session=True)


def _wait_stopped(proc) -> None:
    """Until the driver has stopped itself (SIGSTOP); fails if it ended instead."""
    _, status = os.waitpid(proc.pid, os.WUNTRACED)
    assert os.WIFSTOPPED(status), proc.communicate()


def _interrupt_sweep(tmp_path, sig, after_members, stopping, members=8, workers=2):
    """Start `slipchain sweep` of ``members`` one-second members on ``workers`` processes, send ``sig``
    to the driver right after it has stored ``after_members`` (it stops itself there), let it go on,
    then kill what is left of its process group. Returns (command, store, return code, stdout)."""
    cmd, store, proc = _slow_sweep(tmp_path, members, stop_after=after_members, stopping=stopping, workers=workers)
    try:
        _wait_stopped(proc)
        os.kill(proc.pid, sig)
        if sig != signal.SIGKILL:
            os.kill(proc.pid, signal.SIGCONT)  # the signal is handled as the driver resumes
        out, _ = proc.communicate(timeout=120)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # the orphaned local-cluster processes
        except ProcessLookupError:
            pass
    return cmd, store, proc.returncode, out


def test_driver_killed_with_sigkill_loses_only_members_in_flight(tmp_path, cli_stopping_after_members):
    # 4 members on 2 workers: when the driver is killed after storing 2, the other 2 are in flight or queued
    cmd, store, code, _ = _interrupt_sweep(tmp_path, signal.SIGKILL, 2, cli_stopping_after_members, members=4)
    members = store / "members"
    assert code == -signal.SIGKILL
    survivors = sorted(p.stem for p in members.glob("*.nc"))
    assert len(survivors) == 2  # killed right after the second was stored: the others were in flight or queued
    for mid in survivors:  # every member file that exists is complete and readable
        assert read_dataset(members / f"{mid}.nc").attrs["status"] == "completed"
    mtimes = {mid: (members / f"{mid}.nc").stat().st_mtime_ns for mid in survivors}
    # the same command again resumes: finished members skipped, the rest run
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert re.search(rf"skipped \(already in the store\)\s*│\s*{len(survivors)}\s*│", done.stdout), done.stdout
    log = Store.open(store).invocations()
    assert log[-1]["skipped"] == len(survivors) and log[-1]["ran"] == 4 - len(survivors)
    assert len(Store.open(store).completed_ids()) == 4
    assert {mid: (members / f"{mid}.nc").stat().st_mtime_ns for mid in survivors} == mtimes  # not rewritten


def test_cli_sweep_uses_an_existing_scheduler_and_refuses_a_foreign_store(tmp_path, client, slipchain_cli):
    definition = tmp_path / "a.toml"
    definition.write_text('name = "cli"\n[base]\nN = 31\nstart = "steady"\nv0 = 0.01\ndelta = 0.2\n'
                          "t_total = 3e-3\n[grid]\ntheta = [0.5, 1.0]\n")
    addr = client.scheduler.address
    cmd = [sys.executable, "-m", "slipchain", "sweep", str(definition), "--store", str(tmp_path / "s"),
           "--scheduler", addr, "--no-progress"]
    first = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert first.returncode == 0, first.stderr
    assert re.search(r"ran, completed\s*│\s*2\s*│", first.stdout), first.stdout
    other = tmp_path / "b.toml"
    other.write_text(definition.read_text().replace("[0.5, 1.0]", "[0.5, 0.9]"))
    # the refusals in this process (they happen before a scheduler is asked for anything)
    refused = slipchain_cli("sweep", other, "--store", tmp_path / "s", "--scheduler", addr, "--no-progress")
    assert refused.returncode == 2
    assert "different sweep definition" in refused.stderr and "theta" in refused.stderr
    assert len(list(Path(tmp_path / "s" / "members").glob("*.nc"))) == 2  # nothing mixed in
    # ... but a new store can take over its finished members: theta = 0.5 is copied, 0.9 computed
    bad = slipchain_cli("sweep", other, "--store", tmp_path / "t", "--reuse", tmp_path / "nowhere", "--scheduler", addr)
    assert bad.returncode == 2 and "--reuse" in bad.stderr and "nowhere" in bad.stderr
    assert not (tmp_path / "t").exists()  # refused before anything was written
    for only in ("theta", "theta=0.7"):  # malformed, or not a coordinate: exit 2, nothing written
        bad = slipchain_cli("sweep", other, "--store", tmp_path / "t", "--only", only, "--scheduler", addr)
        assert bad.returncode == 2 and "--only" in bad.stderr and not (tmp_path / "t").exists(), bad.stderr
    grown = subprocess.run([sys.executable, "-m", "slipchain", "sweep", str(other), "--store", str(tmp_path / "t"),
                            "--reuse", str(tmp_path / "s"), "--scheduler", addr, "--no-progress"],
                           capture_output=True, text=True, timeout=120)
    assert grown.returncode == 0, grown.stderr
    assert re.search(r"copied from --reuse stores\s*│\s*1\s*│", grown.stdout), grown.stdout
    assert re.search(r"ran, completed\s*│\s*1\s*│", grown.stdout), grown.stdout


def test_only_runs_the_selected_members_and_leaves_the_rest_pending(tmp_path, client):
    sw = _sweep("o", theta=[0.5, 1.0], seed=[0, 1])
    with pytest.raises(SweepError, match="'v_d' is not a dimension"):
        run_sweep(sw, tmp_path / "bad", client=client, progress=False, only={"v_d": ["1e-3"]})
    with pytest.raises(SweepError, match="not a value of dimension 'theta'"):
        run_sweep(sw, tmp_path / "bad", client=client, progress=False, only={"theta": ["0.7"]})
    assert not (tmp_path / "bad").exists()  # refused before the store was created
    # a left-out member's checkpoint (as a killed earlier invocation leaves it) is its progress: kept
    st = Store.open(tmp_path / "s", sw)
    waiting = next(m for m in sw.members if m.coords["theta"] == 0.5)
    st.checkpoint_path([waiting]).parent.mkdir(exist_ok=True)
    st.checkpoint_path([waiting]).write_bytes(b"progress of an earlier invocation")
    stale = st.checkpoint_path([waiting]).with_name("0123456789abcdef.nc")  # of no pending member: pruned
    stale.write_bytes(b"of an earlier batching")
    rep = run_sweep(sw, tmp_path / "s", client=client, progress=False, only={"theta": ["1"]})
    picked = sorted(m.id for m in sw.members if m.coords["theta"] == 1.0)
    assert sorted(o.member.id for o in rep.ran) == picked and rep.deselected == 2 and rep.ok
    assert st.checkpoint_path([waiting]).exists() and not stale.exists()
    st.checkpoint_path([waiting]).unlink()  # (not a real checkpoint: the run below would refuse it, then start over)
    ds = Store.open(tmp_path / "s").dataset()
    assert list(ds["status"].sel(theta=0.5).values) == ["missing", "missing"]
    rest = run_sweep(sw, tmp_path / "s", client=client, progress=False)  # the rest later: the whole sweep
    assert len(rest.skipped) == 2 and len(rest.ran) == 2 and rest.deselected == 0 and rest.ok


def test_reuse_copies_only_finished_members_of_the_same_physics(tmp_path, client):
    small = _sweep("a", theta=[0.5], seed=[0, 1])
    assert run_sweep(small, tmp_path / "a", client=client, progress=False).ok
    big = _sweep("b", theta=[0.5, 1.0], seed=[0, 1])
    a_ids = [m.id for m in small.members]
    assert set(a_ids) < {m.id for m in big.members}  # same config, same id
    # a file of store a under the name of a member it never ran (theta = 1, seed 0): not taken
    forged = big.members[[m.coords["theta"] for m in big.members].index(1.0)].id
    (tmp_path / "a" / "members" / f"{forged}.nc").write_bytes((tmp_path / "a" / "members" / f"{a_ids[0]}.nc").read_bytes())
    rep = run_sweep(big, tmp_path / "b", client=client, progress=False, reuse=[tmp_path / "a"])
    assert rep.ok and sorted(rep.reused) == sorted(a_ids)
    assert sorted(o.member.id for o in rep.ran) == sorted(m.id for m in big.members if m.id not in a_ids)
    for mid in a_ids:  # the copies are the members, with this sweep's digest
        a, b = (read_dataset(tmp_path / s / "members" / f"{mid}.nc") for s in "ab")
        assert (a["f_d"].values == b["f_d"].values).all() and a.attrs["mu_star"] == b.attrs["mu_star"]
        assert b.attrs["sweep_digest"] == big.digest != a.attrs["sweep_digest"]
    assert (tmp_path / "a" / "members" / f"{forged}.nc").exists()  # the other store is only read
    assert Store.open(tmp_path / "b").invocations()[-1]["reused"] == rep.reused


def test_ctrl_c_keeps_finished_members_and_exits_130(tmp_path, cli_stopping_after_members):
    _, store, code, out = _interrupt_sweep(tmp_path, signal.SIGINT, 1, cli_stopping_after_members)
    members = store / "members"
    assert code == 130, out
    assert "(interrupted)" in out
    done = list(members.glob("*.nc"))
    assert len(done) == 1 and all(read_dataset(p).attrs["status"] == "completed" for p in done)
    assert Store.open(store).invocations()[-1]["interrupted"] is True


def test_sigterm_is_handled_as_ctrl_c_and_exits_143(tmp_path, cli_stopping_after_members):
    """Issue 30: a batch scheduler's SIGTERM at the wall-time limit (it ended the sweep silently,
    exit 143 from the default action, without the store's index or log): now as Ctrl-C, with 143.
    (One worker: the driver's handling is the point, and each worker process compiles the engine
    anew; Ctrl-C on two workers is test_ctrl_c_keeps_finished_members_and_exits_130.)"""
    cmd, store, code, out = _interrupt_sweep(tmp_path, signal.SIGTERM, 1, cli_stopping_after_members, members=4,
                                             workers=1)
    assert code == 143, out
    assert "(interrupted)" in out
    done = list((store / "members").glob("*.nc"))
    assert len(done) == 1 and all(read_dataset(p).attrs["status"] == "completed" for p in done)
    assert Store.open(store).invocations()[-1]["interrupted"] is True
    assert (store / "index.csv").exists() and not list(store.rglob("*.tmp"))
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=300)  # resumes: nothing lost
    assert again.returncode == 0, again.stderr
    assert len(list((store / "members").glob("*.nc"))) == 4


def test_batched_tasks_store_the_same_members(tmp_path, client):
    from slipchain.sweeps.executor import batches

    sw = make_sweep({"name": "b", "base": FAST, "grid": {"theta": [0.5, 1.0], "seed": [0, 1], "N": [31, 41]}})
    groups = batches(sw.members, 3)
    assert sorted(len(g) for g in groups) == [1, 1, 3, 3]
    assert all(len({m.config.N for m in g}) == 1 for g in groups)
    rep = run_sweep(sw, tmp_path / "s", client=client, progress=False, batch_size=3)
    assert rep.ok and len(rep.ran) == 8
    st = Store.open(tmp_path / "s")
    for m in sw.members[:3]:
        assert st.read_member(m).attrs["mu_star"] == run(m.config).attrs["mu_star"]


class _SwallowingFinalizer:
    """Delivers SIGINT to this process from inside ``__del__``: Python then raises the
    KeyboardInterrupt inside the finalizer, prints "Exception ignored" and loses it, exactly what
    happens when a Ctrl-C lands while a Dask future is being garbage-collected."""

    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # bytecodes for the handler to run in
            pass


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")  # the swallowed Ctrl-C is the point
def test_ctrl_c_swallowed_in_a_finalizer_still_stops_the_sweep(tmp_path, client, monkeypatch):
    # Deterministic version of the Ctrl-C that CI once missed: the interrupt lands in a finalizer
    # while the first member is stored. Before the SIGINT flag, the sweep ran to the end (exit 0).
    sw = _sweep(seed=list(range(6)))
    original = Store.write_member
    calls = []

    def write_member(self, member, ds):
        calls.append(member.id)
        path = original(self, member, ds)
        if len(calls) == 1:
            _SwallowingFinalizer()  # created and collected at once
        return path

    monkeypatch.setattr(Store, "write_member", write_member)
    rep = run_sweep(sw, tmp_path / "s", client=client, progress=False)
    assert rep.interrupted and not rep.ok
    assert 1 <= len(rep.ran) < 6 and len(Store.open(tmp_path / "s").completed_ids()) == len(rep.ran)
    assert Store.open(tmp_path / "s").invocations()[-1]["interrupted"] is True


def test_a_second_driver_on_the_same_store_is_refused_naming_the_holder(tmp_path, cli_stopping_after_members):
    # Before the driver lock, both drivers ran every member (and invocations.jsonl claimed both).
    # (One worker: the lock is the driver's, and each worker process compiles the engine anew.)
    cmd, store, first = _slow_sweep(tmp_path, 3, stop_after=1, stopping=cli_stopping_after_members, workers=1)
    try:
        _wait_stopped(first)  # it holds the lock, has stored one member, and waits
        second = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        os.kill(first.pid, signal.SIGCONT)
        assert second.returncode == 2, second.stdout + second.stderr
        words = " ".join(second.stderr.split())
        assert f"store '{store}' is being run by another slipchain driver" in words
        assert f"pid {first.pid}" in words and "host " in words
        out, _ = first.communicate(timeout=180)
        assert first.returncode == 0, out
    finally:
        try:
            os.killpg(first.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    log = Store.open(store).invocations()
    assert len(log) == 1 and log[0]["ran"] == 3  # only the first driver ran, and it ran each member once
    assert not (store / "driver.json").exists()  # released on a clean exit


def test_the_lock_of_a_killed_driver_is_taken_over_with_a_note(tmp_path, client):
    sw = _sweep(seed=[0, 1])
    Store.open(tmp_path / "s", sw)
    script = ("import os, signal, sys\nfrom slipchain.sweeps.store import Store\n"
              "with Store.open(sys.argv[1]).driver_lock():\n    os.kill(os.getpid(), signal.SIGKILL)\n")
    killed = subprocess.Popen([sys.executable, "-c", script, str(tmp_path / "s")])
    assert killed.wait(timeout=60) == -signal.SIGKILL and (tmp_path / "s" / "driver.json").exists()
    rep = run_sweep(sw, tmp_path / "s", client=client, progress=False)
    assert rep.ok and len(rep.ran) == 2
    assert len(rep.notes) == 1 and "took over the driver lock" in rep.notes[0] and f"pid {killed.pid}," in rep.notes[0]
    assert not (tmp_path / "s" / "driver.json").exists()


def test_worker_killed_mid_member_resumes_it_from_its_checkpoint(tmp_path, client):
    """A long member keeps a checkpoint; its worker is SIGKILLed right after its first checkpoint (it
    stops itself there); the retried task resumes from it, and the stored member equals a direct run
    bit for bit."""
    sw = make_sweep({"name": "c", "base": {**FAST, "t_total": 3 * SLOW_T}, "grid": {"seed": [3]}})
    (m,) = sw.members
    st = Store.open(tmp_path / "s", sw)
    ckpt = st.checkpoint_path([m])
    th, killed = _kill_when_stopped(client, tmp_path, "checkpoint")
    try:
        rep = run_sweep(sw, st, client=client, progress=False, checkpoint_every=0.5)
    finally:
        th.join()
        client.wait_for_workers(2, timeout=60)
        client.run(_stop_once, "", "", True)
    assert killed, "the member's worker did not stop after its first checkpoint"
    assert rep.ok, [(o.status, o.message) for o in rep.failed]
    stored = read_dataset(st.member_path(m.id))
    assert float(stored.attrs["resumed_at"]) > 0  # the retry resumed, it did not start over
    direct = run(m.config)
    for k in ("f_d", "x_mean", "X_mean", "x", "u", "contact_force_mean"):
        assert (stored[k].values == direct[k].values).all(), k
    assert stored.attrs["mu_star"] == direct.attrs["mu_star"]
    assert not ckpt.exists() and not list((st.path / "checkpoints").iterdir())  # removed once stored


def test_stale_checkpoints_are_pruned(tmp_path, client):
    sw = _sweep()
    st = Store.open(tmp_path / "s", sw)
    stale = st.path / "checkpoints" / "0123456789abcdef.nc"
    stale.parent.mkdir()
    stale.write_bytes(b"from an earlier batching")
    rep = run_sweep(sw, st, client=client, progress=False)
    assert rep.ok and not stale.exists()


def test_a_corrupt_member_file_is_reported_by_id_then_quarantined_and_rerun(tmp_path, client):
    # Before: a truncated file in members/ made the next `slipchain sweep` (and open_sweep, and
    # every figure command) die with an h5py OSError traceback.
    from rich.console import Console

    from slipchain.cli import print_sweep_report
    from slipchain.sweeps import SweepError, SweepWarning, open_sweep
    from slipchain.workflows.figures import sweep_dataset

    sw = make_sweep({"name": "q", "base": FAST, "grid": {"theta": [0.5, 1.0], "epsilon": [0.005, 0.01]}})
    assert run_sweep(sw, tmp_path / "s", client=client, progress=False).ok
    st = Store.open(tmp_path / "s")
    before = open_sweep(st.path)
    cut, garbled = sw.members[1], sw.members[2]
    data = st.member_path(cut.id).read_bytes()
    st.member_path(cut.id).write_bytes(data[: len(data) // 2])  # a full disk / a partial copy
    st.member_path(garbled.id).write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 8)  # not a file it wrote

    ds = open_sweep(st.path)  # reports, does not crash
    bad = ds["status"].values == "unreadable"
    assert sorted(ds["member_id"].values[bad].tolist()) == sorted([cut.id, garbled.id])
    assert all(f"{m.id}.nc" in str(ds["message"].values[ds["member_id"].values == m.id][0]) for m in (cut, garbled))
    with pytest.raises(SweepError, match=cut.id):
        st.read_member(cut)
    with pytest.warns(SweepWarning, match=cut.id):
        sweep_dataset(st.path, {"theta"}, "a figure")
    fig = subprocess.run([sys.executable, "-m", "slipchain", "figure", "epsilon", "--store", str(st.path),
                          "--out", str(tmp_path / "fig")], capture_output=True, text=True, timeout=120)
    assert fig.returncode == 0 and "Traceback" not in fig.stderr, fig.stderr
    assert "warning:" in fig.stderr and cut.id in fig.stderr and garbled.id in fig.stderr

    rep = run_sweep(sw, st, client=client, progress=False)
    assert rep.ok and sorted(mid for mid, _ in rep.quarantined) == sorted([cut.id, garbled.id])
    assert sorted(o.member.id for o in rep.ran) == sorted([cut.id, garbled.id]) and len(rep.skipped) == 2
    q = st.path / "quarantine"
    assert (q / f"{cut.id}.nc").read_bytes() == data[: len(data) // 2]  # kept as found, for a post-mortem
    assert "truncated" in (q / f"{cut.id}.reason.txt").read_text()
    after = open_sweep(st.path)
    assert (after["status"] == "completed").all()
    assert (after["mu_star"].values == before["mu_star"].values).all()  # rerun: the same numbers, bit for bit
    console = Console(record=True, width=200)
    print_sweep_report(rep, console)
    text = console.export_text()
    assert re.search(r"quarantined \(unreadable file, rerun\)\s*│\s*2", text) and cut.id in text
    assert run_sweep(sw, st, client=client, progress=False).quarantined == []  # the store is healthy again

"""Checkpoints: a run stopped at any chunk and resumed gives bit for bit the uninterrupted result.

Two kinds of stop: an exception raised right after the k-th checkpoint write (in process, so the
stop lands at a known chunk), and a real SIGKILL of ``slipchain run`` once its checkpoint exists
(wherever the kill lands, the result must be the same). Compared: every variable and attribute of
the run Dataset except the wall time (and ``resumed_at``, which says that it resumed).
"""

import os
import signal
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from slipchain import read_dataset
from slipchain.engine import checkpoint as ckpt
from slipchain.engine.simulate import run, simulate_batch
from slipchain.model.config import make_config
from slipchain.model.system import build_system

VOLATILE = ("wall_time_s", "resumed_at")


def _same(a: xr.Dataset, b: xr.Dataset) -> None:
    a, b = a.copy(), b.copy()
    for ds in (a, b):
        for k in VOLATILE:
            ds.attrs.pop(k, None)
    xr.testing.assert_identical(a, b)


class Crash(Exception):
    pass


def _crash_after(monkeypatch, saves: int) -> None:
    """Make the run raise right after its ``saves``-th checkpoint write (a crash between chunks)."""
    original = ckpt.Checkpointer.save

    def save(self):
        original(self)
        if self.writes >= saves:
            raise Crash(f"injected after checkpoint {self.writes}")

    monkeypatch.setattr(ckpt.Checkpointer, "save", save)


def _crashed_run(m, cfg, path, saves: int) -> None:
    """Run ``cfg`` checkpointing to ``path`` after every chunk, crashing right after the ``saves``-th write
    (``m``: a monkeypatch context, undone by the caller)."""
    _crash_after(m, saves)
    with pytest.raises(Crash):
        run(cfg, checkpoint=path, checkpoint_every=0)


CASES = {
    "fixed length": dict(N=31, theta=0.5, t_total=2.5e-3, seed=2),
    "automatic length": dict(N=31, theta=0.5, seed=5, sem_target=0.03, t_max=0.02),
    "dead weight": dict(N=31, theta=0.5, t_total=3e-3, dead_weight=0.5, seed=1),
    # the automatic dead-weight length: 50 one-sample ramp chunks, first decision at t_decide (save 53),
    # cut after save 60 while it still drifts, on to t_max
    "dead weight, automatic length": dict(N=31, theta=0.5, dead_weight=0.7, t_decide=2e-3, t_max=0.01, seed=1),
    # stop_at_runaway: identical contacts loaded over 0.1 s to 1.2 times eq. (1)'s maximum (1.0002): the onset at
    # 0.083 s, the certain runaway at 0.093 s; one-sample ramp chunks, so the crash after save 88 falls between
    # them, and the resumed run must see the record's last 20 ms (its history restored as one array)
    "dead weight, stop at runaway": dict(N=11, theta=1.0, delta=0.0, start="rest", dead_weight=1.2003,
                                         t_ramp=0.1, t_decide=0.11, t_max=0.2, output_interval=1e-3,
                                         stop_at_runaway=True),
    # issue 13: the 2-D chains and the slab (FFT loop) resume bit for bit too
    "chain2d": dict(N=8, Ly=6, geometry="chain2d", theta=0.5, t_total=2.5e-3, seed=2),
    "slab": dict(N=8, Ly=6, geometry="slab", theta=0.5, t_total=2.5e-3, seed=2),
    # issue 12: the adaptive step (each sample starts at level 0), and the automatic length with
    # min_cycles (epsilon = 1: chunks of 0.05 s, checks when the trace has grown by 2 %, here to t_max)
    "adaptive": dict(N=31, theta=0.5, integrator="adaptive", dt=1e-7, t_total=2.5e-3, seed=2),
    "adaptive, min_cycles": dict(N=31, theta=0.5, integrator="adaptive", dt=1e-7, epsilon=1.0, start="steady",
                                 sem_target=0.03, t_max=0.3, min_cycles=3, output_interval=1e-3, seed=5),
    # issue 27: the implicit stepper (backward Euler above the explicit levels) through an event and creep
    "implicit": dict(N=31, theta=1.0, integrator="implicit", dt=1e-7, epsilon=1.0, start="steady", t_total=0.05,
                     output_interval=1e-3, seed=3),
    # ... and on the slab (Newton with conjugate gradients; its controller carried across samples and chunks)
    "implicit slab": dict(N=8, Ly=8, geometry="slab", theta=1.0, integrator="implicit", dt=1e-7, epsilon=1.0,
                          start="steady", t_total=0.03, output_interval=1e-3, seed=3),
    # ... with the additive preconditioner at a load that leaves blocks free of contacts (where it acts)
    "implicit slab, additive": dict(N=8, Ly=8, geometry="slab", theta=0.25, integrator="implicit", dt=1e-7,
                                    epsilon=1.0, start="steady", t_total=0.03, output_interval=1e-3, seed=3,
                                    krylov_preconditioner="additive"),
    # ... and TR-BDF2 above the explicit levels (its stages' states are transient: nothing more to carry)
    "implicit chain2d, trbdf2": dict(N=8, Ly=8, geometry="chain2d", theta=0.25, integrator="implicit", dt=1e-7,
                                     epsilon=1.0, start="steady", t_total=0.03, output_interval=1e-3, seed=3,
                                     implicit_scheme="trbdf2"),
}
SAVES = {"dead weight, automatic length": 60, "dead weight, stop at runaway": 88}


@pytest.mark.parametrize("case", CASES)
def test_run_crashed_after_a_checkpoint_resumes_bit_for_bit(case, tmp_path, monkeypatch):
    cfg = CASES[case]
    reference = run(cfg)
    path = tmp_path / "run.ckpt.nc"
    with monkeypatch.context() as m:
        _crashed_run(m, cfg, path, SAVES.get(case, 2))
    assert path.exists()
    resumed = run(cfg, checkpoint=path)  # (writing at the default interval: its final checkpoint, used below)
    _same(reference, resumed)
    t_resume = float(resumed.attrs["resumed_at"])
    assert 0 < t_resume < float(reference.attrs["t_total"])
    # resumed again from the final checkpoint: the same result at once, and a second resume noted
    again = run(cfg, checkpoint=path)
    _same(reference, again)
    assert len(again.attrs["resumed_at"].split(",")) == 2


def test_batch_of_rows_with_different_lengths_resumes_bit_for_bit(tmp_path, monkeypatch):
    """A GPU-style batch (what a sweep task runs): rows stop at different chunks; crash when some
    have finished and others not."""
    configs = [make_config(dict(N=31, theta=th, t_total=t, seed=s))
               for th, t, s in ((0.5, 1.2e-3, 1), (1.0, 3e-3, 2), (0.3, 2e-3, 3))]
    reference = simulate_batch([build_system(c) for c in configs])
    path = tmp_path / "batch.nc"
    with monkeypatch.context() as m:
        _crash_after(m, 4)  # chunks of 5e-4 s: row 0 has finished (3 chunks), the others not
        with pytest.raises(Crash):
            simulate_batch([build_system(c) for c in configs], checkpoint=path, checkpoint_every=0)
    resumed = simulate_batch([build_system(c) for c in configs], checkpoint=path)
    for a, b in zip(reference, resumed):
        _same(a, b)


def _checkpoint_of_a_crashed_run(path, monkeypatch) -> None:
    """Leave at ``path`` the checkpoint of a small run (N = 21, t_total = 2 ms) that crashed after its first save."""
    with monkeypatch.context() as m:
        _crash_after(m, 1)
        with pytest.raises(Crash):
            run(dict(N=21, t_total=2e-3), checkpoint=path, checkpoint_every=0)


def test_checkpoint_of_another_run_or_unreadable_is_refused(tmp_path, monkeypatch):
    path = tmp_path / "c.nc"
    _checkpoint_of_a_crashed_run(path, monkeypatch)
    with pytest.raises(ckpt.CheckpointError, match=r"belongs to another run .*seed"):
        run(dict(N=21, t_total=2e-3, seed=9), checkpoint=path)
    path.write_bytes(path.read_bytes()[:1000])  # truncated: a full disk, a partial copy
    with pytest.raises(ckpt.CheckpointError, match="unreadable"):
        run(dict(N=21, t_total=2e-3), checkpoint=path)


def _cli(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "slipchain", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kw)


def test_cli_run_killed_with_sigkill_resumes_bit_for_bit(tmp_path, cli_stopping_at_first_checkpoint):
    """The issue's test: ``slipchain run --checkpoint`` SIGKILLed, the same command again: the
    result equals an uninterrupted run. The kill lands after the first checkpoint (the run stops
    itself there and waits), which the resume must continue bit for bit."""
    args = ["run", "--set", "N=41", "--set", "theta=0.6", "--set", "t_total=0.02", "--set", "seed=7", "--json"]
    ckp, out, full = tmp_path / "run.ckpt", tmp_path / "resumed.nc", tmp_path / "full.nc"
    proc = subprocess.Popen([*cli_stopping_at_first_checkpoint, *args, "--checkpoint", str(ckp),
                             "--checkpoint-every", "0", "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    _, status = os.waitpid(proc.pid, os.WUNTRACED)  # returns once it has stopped itself (or ended)
    assert os.WIFSTOPPED(status), proc.communicate()
    proc.send_signal(signal.SIGKILL)
    assert proc.wait(timeout=60) == -signal.SIGKILL
    assert ckp.exists() and not out.exists()
    resumed = _cli(*args, "--checkpoint", str(ckp), "--out", str(out))
    _, stderr = resumed.communicate(timeout=600)
    assert resumed.returncode == 0, stderr
    assert "resuming from checkpoint" in stderr
    assert not ckp.exists()  # finished and written: the checkpoint is removed
    plain = _cli(*args, "--out", str(full))
    plain.communicate(timeout=600)
    assert plain.returncode == 0
    a, b = read_dataset(full), read_dataset(out)
    _same(a, b)
    assert np.isfinite(a.attrs["mu_star"]) and "resumed_at" in b.attrs


def test_cli_refuses_another_runs_checkpoint_with_exit_2_and_writes_nothing(tmp_path, monkeypatch):
    ckp = tmp_path / "run.ckpt"
    _checkpoint_of_a_crashed_run(ckp, monkeypatch)
    before = ckp.read_bytes()
    out = tmp_path / "out.nc"
    proc = subprocess.run([sys.executable, "-m", "slipchain", "run", "--set", "N=21", "--set", "t_total=4e-3",
                           "--checkpoint", str(ckp), "--out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert "belongs to another run" in proc.stderr and "t_total" in proc.stderr and "Traceback" not in proc.stderr
    assert not out.exists() and ckp.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["run.ckpt"]


def test_a_dead_weight_run_keeps_one_contact_record_bit_for_bit_and_resumes_from_per_chunk_records(tmp_path,
                                                                                                   monkeypatch):
    """A dead-weight ramp advances one sample per chunk; the recorder keeps one running per-contact
    sum for such a run (observers.Recorder: a 20-s ramp in 0.1-ms samples held 2 GB of per-chunk
    records). Its result equals, bit for bit, the run recorded per chunk (the whole-run average adds
    the same terms in the same order); its checkpoint holds one record; and a checkpoint written with
    a record per chunk (before) resumes to the same bits."""
    import importlib

    from slipchain.engine import observers

    simulate = importlib.import_module("slipchain.engine.simulate")  # the module (the package exports a function)
    cfg = dict(N=31, theta=0.5, dead_weight=0.7, t_ramp=3e-4, t_total=6e-4, output_interval=1e-5, seed=1)
    reference = run(cfg)

    class PerChunk(observers.Recorder):  # the recorder as it was: a record per chunk for every run
        def __init__(self, n_contacts, whole=None):
            super().__init__(n_contacts, None)

    with monkeypatch.context() as m:
        m.setattr(simulate, "Recorder", PerChunk)
        _same(reference, run(cfg))
        old = tmp_path / "old.nc"
        _crashed_run(m, cfg, old, 20)  # within the ramp (30 one-sample chunks)
    with xr.open_dataset(old) as ds:
        assert ds.sizes["chunk_0"] == 20
    _same(reference, run(cfg, checkpoint=old))
    new = tmp_path / "new.nc"
    with monkeypatch.context() as m:
        _crashed_run(m, cfg, new, 20)
    with xr.open_dataset(new) as ds:
        assert ds.sizes["chunk_0"] == 1 and int(ds["rec_chunk_samples_0"].values[0]) == 20
    _same(reference, run(cfg, checkpoint=new))


def test_contact_records_past_their_budget_are_merged_and_resume_bit_for_bit(tmp_path, monkeypatch):
    """A spring-driven run keeps a per-contact record per chunk until the records pass their byte budget
    (observers.CONTACT_SUMS_BYTES: a 128 x 128 run of 22 s held 227 MB), then merges them pairwise.
    Here the cap is 3 records, over 24 chunks. f_d, the state and mu_star are the per-chunk run's bit
    for bit; each record is the sum of its chunks; the steady window's per-contact averages are the
    per-chunk records' from the first record edge inside MSER's window; a crash and resume gives the
    same bits; and a checkpoint written before (format 2: a record per chunk, no counts) resumes to them."""
    import importlib

    from slipchain.engine import observers

    simulate = importlib.import_module("slipchain.engine.simulate")
    cfg = dict(N=31, theta=0.5, t_total=0.012, seed=2)
    recordings = []
    assemble = simulate.assemble_run

    def keep(system, rec, *a, **k):
        recordings.append(rec)
        return assemble(system, rec, *a, **k)

    with monkeypatch.context() as m:
        m.setattr(simulate, "assemble_run", keep)
        per_chunk = run(cfg)
        m.setattr(observers, "record_cap", lambda nc, budget=None: 3)
        merged = run(cfg)
    fine, coarse = recordings
    assert len(fine.contact_sums) == 24 and set(fine.chunk_samples) == {int(round(5e-4 / 1e-5))}
    assert 2 <= len(coarse.contact_sums) <= 3 and coarse.chunk_starts[0] == 0
    for k in ("f_d", "x_mean", "X_mean", "x", "u", "X", "U"):
        assert (merged[k].values == per_chunk[k].values).all(), k
    assert merged.attrs["mu_star"] == per_chunk.attrs["mu_star"] and merged.attrs["t_transient"] == per_chunk.attrs["t_transient"]
    ends = list(coarse.chunk_starts[1:]) + [sum(fine.chunk_samples)]
    for s0, s1, cs in zip(coarse.chunk_starts, ends, coarse.contact_sums):
        parts = [c for t, c in zip(fine.chunk_starts, fine.contact_sums) if s0 <= t < s1]
        np.testing.assert_allclose(cs, np.sum(parts, axis=0), rtol=1e-12, atol=0)
    start = int(round(float(per_chunk.attrs["t_transient"]) / 1e-5))
    edge = min(s for s in coarse.chunk_starts if s >= start)
    window = [(c, n) for t, n, c in zip(fine.chunk_starts, fine.chunk_samples, fine.contact_sums) if t >= edge]
    steps = sum(n for _, n in window) * (1e-5 / make_config(cfg).dt)
    expected = sum(c for c, _ in window)[:, 0] / round(steps)
    np.testing.assert_allclose(merged["contact_force_mean"].values, expected, rtol=1e-10)

    path = tmp_path / "merged.nc"
    with monkeypatch.context() as m:
        m.setattr(observers, "record_cap", lambda nc, budget=None: 3)
        _crashed_run(m, cfg, path, 9)
        with xr.open_dataset(path) as ds:
            assert ds.attrs["checkpoint_format"] == 3 and ds.sizes["chunk_0"] <= 3
            assert int(ds["rec_chunk_counts_0"].values.sum()) == 9
    with monkeypatch.context() as m:
        m.setattr(observers, "record_cap", lambda nc, budget=None: 3)
        _same(merged, run(cfg, checkpoint=path))

    old = tmp_path / "old.nc"
    with monkeypatch.context() as m:
        _crashed_run(m, cfg, old, 9)
    with xr.open_dataset(old) as ds:
        ds = ds.load().drop_vars("rec_chunk_counts_0")
    assert ds.sizes["chunk_0"] == 9
    ds.attrs["checkpoint_format"] = 2
    ds.to_netcdf(old, engine="h5netcdf")
    with monkeypatch.context() as m:
        m.setattr(observers, "record_cap", lambda nc, budget=None: 3)
        _same(merged, run(cfg, checkpoint=old))


def test_checkpoint_keeps_its_pace_over_a_resume(tmp_path, monkeypatch):
    """The checkpoint's pace (attributes pace_t_simulated, pace_wall_time_s: what `slipchain status` reads the
    recent pace from) has one point per write, the last being the checkpoint's own simulated and wall time; a
    resumed run keeps the crashed run's points and goes on from them (the wall time is summed over resumes),
    keeping the last PACE_POINTS; recent_pace reads them back (ckpt.recent_pace)."""
    cfg = CASES["fixed length"]
    path = tmp_path / "run.ckpt.nc"
    with monkeypatch.context() as m:
        _crashed_run(m, cfg, path, 3)
    a = ckpt.read_attrs(path)
    t, w = np.atleast_1d(a["pace_t_simulated"]), np.atleast_1d(a["pace_wall_time_s"])
    assert t.size == w.size == 3
    assert t[-1] == a["t_simulated"] and w[-1] == a["wall_time_s"]
    assert np.all(np.diff(t) > 0) and np.all(np.diff(w) > 0)
    with monkeypatch.context() as m:
        m.setattr(ckpt, "PACE_POINTS", 4)
        run(cfg, checkpoint=path, checkpoint_every=0)
    b = ckpt.read_attrs(path)
    t2, w2 = np.atleast_1d(b["pace_t_simulated"]), np.atleast_1d(b["pace_wall_time_s"])
    chunk = float(t[1] - t[0])
    writes = int(round(float(b["t_simulated"]) / chunk))  # one write per chunk, the crashed run's three included
    assert writes > 4 and t2.size == w2.size == 4
    np.testing.assert_allclose(t2, chunk * np.arange(writes - 3, writes + 1), rtol=1e-12)
    assert writes - 3 == 2  # the last four writes: the crashed run's last two, then the resumed run's
    np.testing.assert_array_equal(w2[:2], w[1:])
    assert w2[-1] == b["wall_time_s"] and np.all(np.diff(w2) > 0)
    rate, over = ckpt.recent_pace(b, window=0.0)  # the last two writes
    assert over == w2[-1] - w2[-2] and rate == pytest.approx(over / chunk, rel=1e-9)
    rate, over = ckpt.recent_pace(b, window=1e9)  # no write that old: from the first kept one
    assert over == w2[-1] - w2[0] and rate == pytest.approx(over / (t2[-1] - t2[0]), rel=1e-9)

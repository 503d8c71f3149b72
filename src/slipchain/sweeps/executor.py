"""Run a sweep on Dask: every member (or batch of members) a task, every finished member written
to the store at once.

On the CPU each task is one member; with ``backend = 'gpu'`` a task is a batch of up to 256
members of equal N, dt and output interval, advanced together by one kernel launch
(:func:`slipchain.engine.simulate.simulate_batch`); its members are written one by one when it returns.

The driver (this process) submits the members that the store does not hold yet, in order of
decreasing expected cost (large ``N*theta`` first, so the long runs do not end up alone at the
tail), and writes each result the moment it arrives (:meth:`slipchain.sweeps.store.Store.write_member`,
atomic). What survives what:

* the driver is killed (even SIGKILL): every member written so far stays; the ones in flight are
  lost and rerun next time; running the same command again resumes.
* a worker dies mid-task: the Dask scheduler reschedules its tasks on the other workers (at most
  ``distributed.scheduler.allowed-failures`` times, default 3, then the member fails with
  ``KilledWorker`` and the reason is recorded).
* a member raises or diverges: it is written to ``failed/`` with its reason; the others go on.
* a member file was damaged after it was written (a full disk, a partial copy): at its start the
  driver opens the header of every member file; one that cannot be read is moved to
  ``quarantine/`` with the reason and its member is rerun (:meth:`slipchain.sweeps.store.Store.check_members`).
* a long member (longer than ``checkpoint_every``, default 2 minutes) keeps a checkpoint of its
  task in ``checkpoints/``: a task rescheduled after its worker died, or submitted again by the next
  driver, resumes from it, bit for bit, instead of starting over. Workers write it to the store's
  path, so on a remote cluster the checkpoints need a shared file system (without one a write
  fails with a warning and the task simply starts over when retried).

Default scheduler: a ``LocalCluster`` of one single-threaded worker process per core on
loopback. ``scheduler="tcp://host:8786"`` uses an existing cluster instead (for example one
started by dask-jobqueue on SLURM); workers then only need slipchain installed, not the store:
results travel back to the driver, which alone writes the store.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator, Mapping, Sequence

import xarray as xr

from .._version import __version__
from ..engine import interrupts
from ..engine.backends import BackendName
from ..engine.checkpoint import CheckpointError
from ..engine.memory import check_memory
from ..engine.simulate import simulate_batch
from ..model.config import Config
from ..model.geometries import geometry_of
from ..model.system import build_system
from ..results.schema import Status
from .definition import Member, SweepDefinition, SweepError
from .store import Store, reuse_source

ERROR = Status.ERROR.value
GPU_BATCH = 256  # members per task with the GPU backend
GPU_THREADS = 4  # tasks the GPU worker runs at once (each batch on its own CUDA stream, so they overlap)
SWEEP_CHECKPOINT_EVERY = 120.0  # wall-clock s between checkpoints of a task: members shorter than this write none


def run_members(configs: list[Config], backend: str = BackendName.CPU, checkpoint: str | None = None,
                checkpoint_every: float = SWEEP_CHECKPOINT_EVERY) -> list[xr.Dataset]:
    """Sweep members (executed on a worker): build the systems, simulate them as one batch (one
    kernel launch advances all of them; a batch of one is a plain run), return the Datasets.

    ``checkpoint``: the task's checkpoint file (:mod:`slipchain.engine.checkpoint`), written every
    ``checkpoint_every`` wall-clock seconds; a task retried after its worker died, or run again
    by the next driver, resumes from it (bit for bit) instead of starting over."""
    check_memory(configs)  # a member too large for this worker fails with the reason, before allocating
    systems = [build_system(c) for c in configs]
    try:
        return simulate_batch(systems, backend=str(backend), progress=False, checkpoint=checkpoint,
                              checkpoint_every=checkpoint_every)
    except CheckpointError as e:  # unusable (e.g. cut by a failing disk): start the task over without it
        warnings.warn(f"{e}; starting the task over", RuntimeWarning, stacklevel=2)
        Path(checkpoint).unlink(missing_ok=True)
        return simulate_batch(systems, backend=str(backend), progress=False, checkpoint=checkpoint,
                              checkpoint_every=checkpoint_every)


def batches(members: list[Member], size: int) -> list[list[Member]]:
    """Members grouped for :func:`run_members`: equal N, Ly, geometry, dt and output interval, the adaptive step,
    the implicit one (and its preconditioner and scheme) or neither, the long chunks of ``min_cycles`` or not, at most ``size`` each,
    similar expected cost together (the input order, by decreasing cost, is kept)."""
    groups: dict[tuple, list[Member]] = {}
    for m in members:
        c = m.config
        groups.setdefault((c.N, c.Ly, c.geometry, c.dt, c.sample_steps, c.integrator == "adaptive",
                           c.integrator == "implicit", c.min_cycles > 0, c.material, len(c.prony_E or ()),
                           c.top_is_state, c.krylov_preconditioner, c.implicit_scheme), []).append(m)
    out = []
    for g in groups.values():
        out += [g[i:i + size] for i in range(0, len(g), size)]
    return sorted(out, key=lambda b: -max(expected_cost(m) for m in b))


def error_dataset(member: Member, exc: BaseException) -> xr.Dataset:
    """A placeholder result for a member whose task raised: status ``error`` and the reason."""
    return xr.Dataset(attrs={
        "status": ERROR,
        "message": f"{type(exc).__name__}: {exc}".strip(),
        "config": member.config.to_toml(),
        "seed": member.config.seed,
        "slipchain_version": __version__,
    })


def expected_cost(member: Member) -> float:
    """Relative run time: blocks times contacts per block (plus the FFT's share for the slab and
    half-space, about as much again), times steps per simulated second."""
    c = member.config
    fft = 0.3 if geometry_of(c).spectral else 0.0
    return c.n_blocks * (c.theta + 0.05 + fft) * (2e-8 / c.dt)


@dataclass
class Outcome:
    member: Member
    status: str
    message: str
    mu_star: float
    mu_star_sem: float
    wall_time_s: float


class StoreWriteError(SweepError):
    """The store could not be written (a full disk): the sweep stopped, keeping what it had stored."""


@dataclass
class SweepReport:
    """What one invocation of :func:`run_sweep` did."""

    store: Path
    total: int
    skipped: list[Member] = field(default_factory=list)
    ran: list[Outcome] = field(default_factory=list)
    interrupted: bool = False
    notes: list[str] = field(default_factory=list)  # e.g. a stale driver lock taken over
    quarantined: list[tuple[str, str]] = field(default_factory=list)  # (member id, reason): unreadable files moved aside, rerun
    reused: list[str] = field(default_factory=list)  # member ids copied from other stores (--reuse), also in skipped
    deselected: int = 0  # pending members outside --only: left for a later invocation, not a failure
    wall_time_s: float = 0.0

    @property
    def failed(self) -> list[Outcome]:
        return [o for o in self.ran if o.status != Status.COMPLETED]

    @property
    def not_run(self) -> int:
        return self.total - len(self.skipped) - len(self.ran) - self.deselected

    @property
    def ok(self) -> bool:
        return not self.interrupted and not self.failed and self.not_run == 0


def default_workers() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


# Dask's nanny starts every worker with MALLOC_TRIM_THRESHOLD_=65536 (its config
# ``distributed.nanny.pre-spawn-environ``), so that a worker hands freed memory back to the system. Setting
# it also fixes glibc's mmap threshold at 128 KiB (glibc adapts it only while none of its thresholds is set),
# so every allocation of 128 KiB or more is mapped afresh and unmapped when freed, its pages faulted in again,
# and the heap's top is given back after each free. The slab's compiled steps allocate their FFTs' results
# every step (about 1.3 MB at 128 x 128 with the rubber): measured from a 128 x 128 tester checkpoint in one
# process (2026-12-06, 2-core Intel Xeon with AVX-512; docs/performance.md), 1 600 us per base step with
# Dask's setting against 798 us without it, bit for bit the same state. The local cluster's workers
# therefore get glibc's defaults, as `slipchain run` does; a variable the user set in the driver's
# environment is kept. On a cluster of your own, set ``distributed.nanny.pre-spawn-environ.
# MALLOC_TRIM_THRESHOLD_`` to null in its Dask config (docs/guide/sweeps.md) for the same speed.
LOCAL_WORKER_ENVIRON = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


@contextmanager
def dask_client(scheduler: str | None = None, n_workers: int | None = None,
                threads_per_worker: int = 1, announce: Callable[[str], None] | None = None) -> Iterator["object"]:
    """A ``distributed.Client``: to ``scheduler`` if given, else to a new local cluster (every
    address on 127.0.0.1, the dashboard's too). ``announce``: called with the dashboard's address
    once the client is up (``--dashboard``)."""
    from distributed import Client, LocalCluster

    if scheduler:
        with Client(scheduler) as client:
            if announce is not None:
                announce(client.dashboard_link)
            yield client
        return
    # Logs of the local cluster: critical only. A task's failure comes back to the driver and is stored
    # with its message (failed/); what else the workers log at ERROR is noise of a shutdown (a
    # heartbeat that finds the scheduler gone after a full disk stopped the sweep; issue 30).
    # The workers start with glibc's own allocator settings (LOCAL_WORKER_ENVIRON), not Dask's.
    import dask

    with dask.config.set(LOCAL_WORKER_ENVIRON), \
            LocalCluster(n_workers=n_workers or default_workers(), threads_per_worker=threads_per_worker,
                         processes=True, host="127.0.0.1", dashboard_address="127.0.0.1:0",
                         silence_logs=logging.CRITICAL) as cluster:
        with Client(cluster) as client:
            if announce is not None:
                announce(client.dashboard_link)
            yield client


def run_sweep(sweep: SweepDefinition, store: str | os.PathLike | Store, *, scheduler: str | None = None,
              n_workers: int | None = None, client: object | None = None, progress: bool | None = None,
              backend: str | BackendName = BackendName.CPU, batch_size: int | None = None,
              checkpoint_every: float | None = SWEEP_CHECKPOINT_EVERY,
              announce: Callable[[str], None] | None = None,
              reuse: Sequence[str | os.PathLike] = (), only: Mapping[str, Sequence] | None = None) -> SweepReport:
    """Run the members of ``sweep`` that ``store`` does not hold yet; write each as it finishes.

    ``client``: an existing ``distributed.Client`` to use (tests); else ``scheduler`` (an
    address) or a new local cluster of ``n_workers`` processes (default: one per core; one with
    ``backend = 'gpu'``). ``backend``: where the members are computed ('cpu', 'gpu', 'auto'; not
    part of their identity, so CPU and GPU members share a store). ``batch_size``: members per task, advanced together by one kernel launch
    (:func:`run_members`); default 1 on the CPU, 256 with ``backend = 'gpu'``. With the GPU the
    local cluster is one worker process with GPU_THREADS threads: up to that many batches (of
    different N or dt) advance at once, each on its own CUDA stream. ``checkpoint_every``: wall-clock
    seconds between the checkpoints of a running task (None: no checkpoints; see the module docstring).
    ``announce``: called with the Dask dashboard's address when this call starts a cluster or connects.
    ``reuse``: other stores whose completed members of this sweep are copied in first instead of
    being computed (:meth:`.Store.reuse_from`; the same id is the same physics). ``only``: run only
    the pending members at these coordinates (``{dimension: [values]}``, :meth:`.SweepDefinition.selection`;
    the rest stay pending for a later invocation, counted as ``deselected``, not as failed).
    """
    threads = 1
    if backend == "gpu":  # one worker process owns the GPU; its threads run batches on separate streams
        batch_size = batch_size or GPU_BATCH
        n_workers = n_workers or 1
        threads = GPU_THREADS
    for other in reuse:  # before the store is created: a wrong path writes nothing
        reuse_source(other, store.path if isinstance(store, Store) else store)
    selected = sweep.selection(only)  # likewise: SweepError for a key or value the sweep does not have
    st = store if isinstance(store, Store) else Store.open(store, sweep)
    with st.driver_lock() as note:  # SweepError, naming the holder, if another driver runs this store
        return _run_locked(st, note, batch_size, client, scheduler, n_workers, threads, progress, backend,
                           checkpoint_every, announce, reuse, selected)


def _run_locked(st: Store, note: str | None, batch_size: int | None, client, scheduler: str | None,
                n_workers: int | None, threads: int, progress: bool | None, backend: str,
                checkpoint_every: float | None, announce: Callable[[str], None] | None = None,
                reuse: Sequence[str | os.PathLike] = (), selected: set[str] | None = None) -> SweepReport:
    t0 = time.perf_counter()
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    quarantined = st.check_members()  # unreadable member files: moved to quarantine/, their members rerun
    reused = [mid for other in reuse for mid in st.reuse_from(other)]
    done = st.completed_ids()
    report = SweepReport(store=st.path, total=len(st.sweep.members),
                         skipped=[m for m in st.sweep.members if m.id in done], notes=[note] if note else [],
                         quarantined=quarantined, reused=reused)
    pending = sorted(st.pending(), key=expected_cost, reverse=True)
    waiting: list[Member] = []
    if selected is not None:  # --only: the others wait for a later invocation (their checkpoints kept)
        waiting = [m for m in pending if m.id not in selected]
        report.deselected = len(waiting)
        pending = [m for m in pending if m.id in selected]
    bar = _SweepProgress(progress, len(pending), len(report.skipped))
    try:
        with _interrupt_flag():
            _run_groups(pending, batch_size, client, scheduler, n_workers, threads, st, report, bar, backend,
                        checkpoint_every, announce, waiting)
    except KeyboardInterrupt:
        report.interrupted = True
    finally:
        bar.close()
        report.wall_time_s = time.perf_counter() - t0
        _best_effort(st.write_index)  # on a full disk the next call rewrites them: they are derived from the members
        _best_effort(st.log_invocation, {"started": started, "wall_time_s": report.wall_time_s, "ran": len(report.ran),
                           "failed": len(report.failed), "skipped": len(report.skipped), "total": report.total,
                           "interrupted": report.interrupted, "scheduler": scheduler or ("client" if client else "local"),
                           "n_workers": n_workers or (None if scheduler or client else default_workers()),
                           "backend": str(backend), "notes": report.notes,
                           "quarantined": [mid for mid, _ in report.quarantined], "reused": report.reused, "deselected": report.deselected,
                           "slipchain_version": __version__})
    return report


def _best_effort(write, *args) -> None:
    """Write a derived file (the index, a log line); on a full disk skip it: the next call rewrites it."""
    try:
        write(*args)
    except OSError:
        pass


def _run_groups(pending: list[Member], batch_size: int | None, client, scheduler: str | None, n_workers: int | None,
                threads: int, st: Store, report: SweepReport, bar: "_SweepProgress", backend: str,
                checkpoint_every: float | None, announce: Callable[[str], None] | None = None,
                waiting: Sequence[Member] = ()) -> None:
    """Submit the pending members (in batches) to ``client`` or a new cluster and store each result.
    ``waiting``: pending members left out by ``--only``, whose checkpoints (alone or in a batch of
    them) are kept for the invocation that runs them."""
    def grouped(members):
        return batches(list(members), batch_size) if batch_size and batch_size > 1 else [[m] for m in members]

    groups = grouped(pending)
    # the checkpoints of earlier batchings or of members stored since go; a waiting member's stays
    st.prune_checkpoints([*groups, *grouped(waiting), *([m] for m in waiting)])
    if not pending:
        return
    if client is not None:
        _execute(client, st, groups, report, bar, backend, checkpoint_every)
    else:
        with dask_client(scheduler, n_workers, threads, announce) as c:
            _check_interrupt()
            _execute(c, st, groups, report, bar, backend, checkpoint_every)


def _execute(client, st: Store, groups: list[list[Member]], report: SweepReport, bar: "_SweepProgress",
             backend: str, checkpoint_every: float | None) -> None:
    from distributed import as_completed

    futures = {}
    for g in groups:
        ckpt = None if checkpoint_every is None else str(st.checkpoint_path(g).resolve())
        fut = client.submit(run_members, [m.config for m in g], str(backend), ckpt,
                            SWEEP_CHECKPOINT_EVERY if checkpoint_every is None else checkpoint_every,
                            key=f"slipchain-{g[0].id}-{len(g)}", priority=max(expected_cost(m) for m in g), pure=False)
        futures[fut] = g
    try:
        done = as_completed(list(futures))
        while not done.is_empty():
            ready = done.next_batch(block=False)
            if not ready:
                _check_interrupt()
                time.sleep(POLL_S)
            for fut in ready:
                _check_interrupt()
                group = futures.pop(fut)
                try:
                    _store_task(fut, group, st, report, bar)
                except OSError as e:  # a full disk, say: stop, keeping every member already stored
                    raise StoreWriteError(
                        f"could not write to the store {str(st.path)!r}: {e.strerror or e} ({e.filename}); the "
                        f"{len(report.ran)} member(s) stored by this call and every one before are kept and no "
                        "partial file is left; free space and run the same command again to resume") from None
        _check_interrupt()
    finally:
        if futures:  # interrupted: drop the tasks still queued or running
            client.cancel(list(futures))


POLL_S = 0.05  # the driver looks for finished tasks, and for a Ctrl-C, this often


_INTERRUPTED = threading.Event()


def _check_interrupt() -> None:
    """Raise KeyboardInterrupt if Ctrl-C arrived, even if the KeyboardInterrupt that the signal
    raised was swallowed (see :func:`_interrupt_flag`)."""
    if _INTERRUPTED.is_set():
        raise KeyboardInterrupt


@contextmanager
def _interrupt_flag() -> Iterator[None]:
    """While the sweep runs, SIGINT, and SIGTERM as a batch scheduler sends it at a job's time limit
    (:mod:`slipchain.engine.interrupts`), raise KeyboardInterrupt and set a flag that the driver
    checks between tasks.

    Python runs a signal handler in the main thread at the next bytecode, wherever that is; when it
    is inside a finalizer (a Dask future's ``__del__``, say) the KeyboardInterrupt it raises is
    printed as "Exception ignored" and lost, and the sweep went on to the end (seen once in CI
    under load). The flag cannot be lost: the driver polls it every POLL_S and after every task.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _INTERRUPTED.clear()
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}

    def handler(signum, frame):
        _INTERRUPTED.set()
        interrupts.raise_interrupt(signum, frame)

    for sig in previous:
        signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
        _INTERRUPTED.clear()


def _store_task(fut, group: list[Member], st: Store, report: SweepReport, bar: "_SweepProgress") -> None:
    """Write the members of one finished task (or its error) to the store and the report."""
    try:
        results = fut.result()
    except Exception as exc:  # the task raised, or its workers kept dying (KilledWorker)
        results = [error_dataset(m, exc) for m in group]
    for m, ds in zip(group, results):
        st.write_member(m, ds)
        a = ds.attrs
        report.ran.append(Outcome(m, str(a.get("status", ERROR)), str(a.get("message", "")),
                                  float(a.get("mu_star", float("nan"))), float(a.get("mu_star_sem", float("nan"))),
                                  float(a.get("wall_time_s", float("nan")))))
        bar.advance(report)
    st.checkpoint_path(group).unlink(missing_ok=True)  # its members are stored: the task's state is done with
    fut.release()


class _SweepProgress:
    """Rich progress bar with counts and an ETA (on a terminal by default)."""

    def __init__(self, enabled: bool | None, total: int, skipped: int):
        self.enabled = (sys.stderr.isatty() if enabled is None else enabled) and total > 0
        self._bar = None
        if self.enabled:
            from rich.console import Console
            from rich.progress import (BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn,
                                       TimeRemainingColumn)

            self._bar = Progress(TextColumn("[bold]slipchain sweep"), BarColumn(), MofNCompleteColumn(),
                                 TextColumn("{task.fields[info]}"), TimeElapsedColumn(), TextColumn("ETA"),
                                 TimeRemainingColumn(), console=Console(stderr=True))
            self._bar.start()
            self._task = self._bar.add_task("sweep", total=total, info=f"skipped {skipped} (in store)")
            self._skipped = skipped

    def advance(self, report: SweepReport) -> None:
        if self._bar is not None:
            n_failed = len(report.failed)
            self._bar.update(self._task, advance=1,
                             info=f"completed {len(report.ran) - n_failed}, failed {n_failed}, skipped {self._skipped}")

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()


__all__ = ["GPU_BATCH", "GPU_THREADS", "SWEEP_CHECKPOINT_EVERY", "batches", "run_members", "Outcome", "StoreWriteError", "SweepReport", "dask_client", "default_workers", "error_dataset", "expected_cost",
           "run_sweep"]

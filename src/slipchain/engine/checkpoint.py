"""Checkpoints: the full state of a run in progress, written atomically between compiled chunks.

A checkpoint holds everything the time loop (:func:`slipchain.engine.driver.drive`) carries from
one chunk to the next, so that a run resumed from it continues **bit for bit** as if it had never
stopped:

* the batch (:class:`~slipchain.engine.backends.base.Batch`): positions and velocities of both
  chains, the step counter, the kernel parameters, the contacts, and the contact solver's warm
  start (``ysolve``: log10 of each contact's velocity and its two Taylor factors; the implicit
  contact solve starts from it, so it is state, not a cache);
* each row's control (:class:`~slipchain.engine.control.RowControl`): samples done, limit (a
  limit above the config's says the run was extended by its slip cycles), active/status/message, the automatic length's f_d and <x> series and its last SE (the
  dead-weight ramp is a function of the samples done);
* the recorder (:class:`~slipchain.engine.observers.Recorder`): every sample so far, the per-contact
  sums in records of whole chunks (a record per chunk until they pass CONTACT_SUMS_BYTES, then merged
  pairwise; one running sum for a dead-weight run) with each record's first sample, samples and chunks,
  and the work sums;
* the start values the result needs (<x> and the stored energy at the start), the wall time so far
  and the simulated times of earlier resumes;
* the pace (attributes ``pace_t_simulated`` and ``pace_wall_time_s``: the simulated and the wall time at each of
  the last :data:`PACE_POINTS` writes, over resumes), from which ``slipchain status`` reads how fast the run
  goes now rather than on average (:func:`recent_pace`); not state, nothing in the run reads it.

There is no random number generator in the time loop (the disorder is drawn from the seed when
the system is built), so none is stored. The checkpoint is written only where this state is
consistent: after the run controls have seen a chunk (never from a Ctrl-C handler). It is a
NetCDF file written with :func:`slipchain.results.io.write_dataset` (temporary file and
``os.replace``): a kill while writing leaves the previous checkpoint whole.

A checkpoint names its configs; resuming with another config is refused (:class:`CheckpointError`).
"""

from __future__ import annotations

import time
import tomllib
import warnings
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np
import xarray as xr

from .._version import __version__
from ..model.system import System
from ..results.io import read_attrs, read_dataset, write_dataset
from ..results.schema import Status
from . import scheme as S
from .backends.base import Batch
from .control import RowControl
from .observers import Recorder

FORMAT = 3  # bumped whenever the layout below changes; a checkpoint of another format is refused
READS = (1, 2, 3)  # formats this version reads: 1 lacks the bulk's state and the bulk's work (both zero then);
# 1 and 2 lack the chunks per contact record (one record per chunk, or one running record: replayed)
CHECKPOINT_EVERY = 60.0  # default wall-time seconds between checkpoints (slipchain run --checkpoint-every)
PACE_POINTS = 64  # writes whose (simulated, wall) times a checkpoint keeps (attributes pace_*): the recent pace
PACE_WINDOW = 1800.0  # wall s over which recent_pace reads the pace (the last writes that span at least this)
# The batch's arrays; geometry, shape, the elastic kernel, the adaptive step's folds and control, the
# preconditioner and the implicit scheme follow from the configs (Batch.pack).
_BATCH_FIELDS = [f.name for f in fields(Batch)
                 if f.name not in ("geometry", "shape", "kernel", "folds", "step_control", "material", "twoport",
                                   "preconditioner", "implicit_scheme")]


class CheckpointError(ValueError):
    """A checkpoint that cannot be used: unreadable, another format, or another run's."""


@dataclass
class Restored:
    """What :meth:`Checkpointer.restore` gives back besides the objects it fills in."""

    x0: list[float]
    e0: list[float]
    wall: float
    resumed_at: list[float] = field(default_factory=list)


class Checkpointer:
    """Write the run's state to ``path`` every ``every`` wall-clock seconds (0: after every chunk).

    Made by :func:`slipchain.engine.simulate.simulate_batch`, which calls :meth:`restore` before
    the loop (if ``path`` exists) and :meth:`attach` to give it the live objects; the driver calls
    :meth:`after_chunk` once per chunk, after the run controls. A failed write (a full disk, say)
    warns and the run goes on: the previous checkpoint is still whole.
    """

    def __init__(self, path: str | Path, every: float = CHECKPOINT_EVERY):
        if not every >= 0:
            raise ValueError(f"checkpoint interval must be >= 0 seconds, got {every!r}")
        self.path = Path(path)
        self.every = float(every)
        self._last = time.monotonic()
        self._live: tuple | None = None
        self.writes = 0
        self.pace: list[tuple[float, float]] = []  # (simulated s, wall s) at the last PACE_POINTS writes

    # --- writing ---------------------------------------------------------------------------
    def attach(self, systems: list[System], batch: Batch, controls: list[RowControl], recorder: Recorder,
               x0: list[float], e0: list[float], wall0: float, wall_before: float, resumed_at: list[float],
               backend: str, interval: float) -> None:
        self._live = (systems, batch, controls, recorder, x0, e0, wall0, wall_before, resumed_at, backend, interval)
        self._last = time.monotonic()

    def after_chunk(self) -> None:
        """Called by the driver after every chunk: write if ``every`` seconds have passed."""
        if time.monotonic() - self._last >= self.every:
            self.save()

    def save(self) -> None:
        """Write the state now (atomically)."""
        if self._live is None:
            raise RuntimeError("Checkpointer.save before attach")
        systems, batch, controls, rec, x0, e0, wall0, wall_before, resumed_at, backend, interval = self._live
        wall = wall_before + time.perf_counter() - wall0
        pace = (self.pace + [(float(max(c.n for c in controls) * interval), wall)])[-PACE_POINTS:]
        try:
            write_dataset(_to_dataset(systems, batch, controls, rec, x0, e0, wall, resumed_at, backend, interval, pace),
                          self.path)
            self.writes += 1
            self.pace = pace
        except OSError as e:
            warnings.warn(f"could not write checkpoint {str(self.path)!r} ({e}); the run goes on and the previous "
                          "checkpoint, if any, is kept", RuntimeWarning, stacklevel=2)
        self._last = time.monotonic()

    # --- reading ---------------------------------------------------------------------------
    def restore(self, systems: list[System], batch: Batch, controls: list[RowControl], recorder: Recorder) -> Restored:
        """Fill ``batch``, ``controls`` and ``recorder`` (made fresh for ``systems``) from the file."""
        try:
            ds = read_dataset(self.path)
        except Exception as e:  # h5py's OSError, a ValueError of xarray: the file is not a whole checkpoint
            raise CheckpointError(f"checkpoint {str(self.path)!r} is unreadable ({type(e).__name__}: {e}); "
                                  "delete it to start the run over") from None
        a = ds.attrs
        if a.get("checkpoint_format") not in READS:
            raise CheckpointError(f"checkpoint {str(self.path)!r} has format {a.get('checkpoint_format')!r} "
                                  f"(written by slipchain {a.get('slipchain_version', '?')}); this version reads "
                                  f"formats {', '.join(map(str, READS))}. Delete it to start the run over")
        configs = [str(c) for c in np.atleast_1d(ds["config"].values)]
        mine = [s.config.to_toml() for s in systems]
        if configs != mine:
            if len(configs) != len(mine):
                which = "the number of runs differs"
            else:
                row = next(i for i, (p, q) in enumerate(zip(configs, mine)) if p != q)
                which = f"row {row}: {_first_difference(configs[row], mine[row])}"
            raise CheckpointError(f"checkpoint {str(self.path)!r} belongs to another run ({which}); give another "
                                  "--checkpoint path, or delete it to start over")
        for name in _BATCH_FIELDS:
            target = getattr(batch, name)
            if f"batch_{name}" not in ds and target.size == 0:  # nothing to restore (an elastic bulk; format 1)
                continue
            value = ds[f"batch_{name}"].values
            if value.shape != target.shape:
                raise CheckpointError(f"checkpoint {str(self.path)!r}: batch array {name!r} has shape {value.shape}, "
                                      f"this run needs {target.shape}")
            target[...] = value
        for r, c in enumerate(controls):
            c.limit = int(ds["limit"].values[r])  # a cap extended by slip cycles is kept (RowControl.extend)
            c.n = int(ds["samples_done"].values[r])
            c.active = bool(ds["active"].values[r])
            c.status = Status(str(ds["row_status"].values[r]))
            c.message = str(ds["row_message"].values[r])
            if c.converge is not None:
                c.converge.f_d = [ds[f"conv_f_d_{r}"].values.copy()]
                c.converge.x_mean = [ds[f"conv_x_mean_{r}"].values.copy()]
                c.converge.reached = bool(ds["conv_reached"].values[r])
                c.converge.sem = float(ds["conv_sem"].values[r])
                c.converge.extended = c.limit > c.base_limit  # the cap only grows past the config's by extend()
            samples = ds[f"rec_samples_{r}"].values
            lengths = ds[f"rec_chunk_samples_{r}"].values.astype(int)
            cuts = np.cumsum(lengths)[:-1]
            recorder.samples[r] = [s.copy() for s in np.split(samples, cuts)] if lengths.size else []
            if c.decide is not None:  # its history is the recorded trace of <X>
                c.decide.X_mean = [samples[:, S.O_XUMEAN].copy()]
                c.decide.reached = bool(ds["conv_reached"].values[r])
            counts = ds[f"rec_chunk_counts_{r}"].values if f"rec_chunk_counts_{r}" in ds else None  # format < 3: per chunk
            recorder.restore(r, ds[f"rec_chunk_starts_{r}"].values, lengths,
                             list(ds[f"rec_contact_sums_{r}"].values) if lengths.size else [], counts)
            recorder.n[r] = int(ds["rec_n"].values[r])
        works = ds["rec_works"].values
        recorder.works[...] = 0.0
        recorder.works[:, :works.shape[1]] = works  # format 1: no bulk work column (zero)
        resumed = [float(v) for v in np.atleast_1d(ds["resumed_at"].values)] if "resumed_at" in ds else []
        self.pace = _pace(a)
        return Restored(x0=[float(v) for v in ds["x0_mean"].values], e0=[float(v) for v in ds["e0"].values],
                        wall=float(a["wall_time_s"]), resumed_at=resumed)


def _to_dataset(systems, batch: Batch, controls: list[RowControl], rec: Recorder, x0, e0, wall: float,
                resumed_at: list[float], backend: str, interval: float,
                pace: list[tuple[float, float]] = ()) -> xr.Dataset:
    data: dict[str, tuple] = {}
    for name in _BATCH_FIELDS:
        v = getattr(batch, name)
        if v.size:  # (an elastic bulk has no state)
            data[f"batch_{name}"] = ([f"batch_{name}_{k}" for k in range(v.ndim)], v)
    data["config"] = ("row", np.array([s.config.to_toml() for s in systems], dtype=object))
    data["limit"] = ("row", np.array([c.limit for c in controls], dtype=np.int64))
    data["samples_done"] = ("row", np.array([c.n for c in controls], dtype=np.int64))
    data["active"] = ("row", np.array([int(c.active) for c in controls], dtype=np.int8))
    data["row_status"] = ("row", np.array([str(c.status.value) for c in controls], dtype=object))
    data["row_message"] = ("row", np.array([c.message for c in controls], dtype=object))
    data["conv_reached"] = ("row", np.array([int(bool((c.converge and c.converge.reached) or (c.decide and c.decide.reached)))
                                             for c in controls], dtype=np.int8))
    data["conv_sem"] = ("row", np.array([c.converge.sem if c.converge else np.nan for c in controls]))
    data["x0_mean"] = ("row", np.asarray(x0, dtype=float))
    data["e0"] = ("row", np.asarray(e0, dtype=float))
    data["rec_n"] = ("row", np.asarray(rec.n, dtype=np.int64))
    data["rec_works"] = (("row", "acc"), rec.works)
    data["resumed_at"] = ("resume", np.asarray(resumed_at, dtype=float))
    for r, c in enumerate(controls):
        if c.converge is not None:
            data[f"conv_f_d_{r}"] = (f"conv_{r}", _cat(c.converge.f_d))
            data[f"conv_x_mean_{r}"] = (f"conv_{r}", _cat(c.converge.x_mean))
        samples = rec.samples[r]
        data[f"rec_samples_{r}"] = ((f"sample_{r}", "out"), np.concatenate(samples) if samples else
                                    np.zeros((0, S.N_OUT)))
        data[f"rec_chunk_samples_{r}"] = (f"chunk_{r}", np.asarray(rec.chunk_samples[r], dtype=np.int64))
        data[f"rec_chunk_starts_{r}"] = (f"chunk_{r}", np.asarray(rec.chunk_starts[r], dtype=np.int64))
        data[f"rec_chunk_counts_{r}"] = (f"chunk_{r}", np.asarray(rec.chunk_counts[r], dtype=np.int64))
        sums = rec.contact_sums[r]
        nc = rec.n_contacts[r]
        data[f"rec_contact_sums_{r}"] = ((f"chunk_{r}", f"contact_{r}", "cacc"),
                                         np.stack(sums) if sums else np.zeros((0, nc, S.N_CACC)))
    return xr.Dataset(data, attrs={
        "title": "slipchain run checkpoint (state between chunks; see slipchain.engine.checkpoint)",
        "checkpoint_format": FORMAT, "slipchain_version": __version__, "backend": backend,
        "wall_time_s": wall, "t_simulated": float(max(c.n for c in controls) * interval),
        "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "pace_t_simulated": np.array([p[0] for p in pace], dtype=float),
        "pace_wall_time_s": np.array([p[1] for p in pace], dtype=float)})


def _pace(attrs: dict) -> list[tuple[float, float]]:
    """A checkpoint's (simulated s, wall s) at its last writes (none before this was kept, or where unreadable)."""
    try:
        t = np.atleast_1d(np.asarray(attrs["pace_t_simulated"], dtype=float))
        w = np.atleast_1d(np.asarray(attrs["pace_wall_time_s"], dtype=float))
    except (KeyError, ValueError, TypeError):
        return []
    return [(float(a), float(b)) for a, b in zip(t, w)] if t.shape == w.shape else []


def recent_pace(attrs: dict, window: float = PACE_WINDOW) -> tuple[float, float] | None:
    """The run's recent pace from a checkpoint's attributes: (wall s per simulated s, wall s it is read over),
    from its last write back to the latest earlier write at least ``window`` wall seconds before it (or its
    first kept write, if none is that old); None where fewer than two writes are kept or the simulated time did
    not move between them. A run's pace changes as its slip does (a released top rings on fine steps, then
    creeps on long ones), so this says more of what is ahead than the mean over the whole run."""
    pace = _pace(attrs)
    if len(pace) < 2:
        return None
    t1, w1 = pace[-1]
    older = [p for p in pace[:-1] if p[1] <= w1 - window]
    t0, w0 = older[-1] if older else pace[0]
    if not t1 > t0:
        return None
    return (w1 - w0) / (t1 - t0), w1 - w0


def _cat(parts: list[np.ndarray]) -> np.ndarray:
    return np.concatenate(parts) if parts else np.zeros(0)


def _first_difference(a: str, b: str) -> str:
    la, lb = a.splitlines(), b.splitlines()
    for p, q in zip(la, lb):
        if p != q:
            return f"checkpoint has '{p.strip()}', this run '{q.strip()}'"
    return "configs differ"


def simulated_time(path: str | Path) -> float:
    """The simulated time (s) a checkpoint has reached (for messages)."""
    try:
        return float(read_attrs(path)["t_simulated"])
    except Exception:  # noqa: BLE001 - only for a message
        return float("nan")


@dataclass(frozen=True)
class CheckpointRow:
    """What a checkpoint says of one of its runs (:func:`checkpoint_rows`), without its state."""

    config: str  # the run's config TOML (as the run's System wrote it)
    samples_done: int  # output samples so far: the run has reached samples_done * output_interval s
    status: str  # the row's status so far ("completed" while it runs)
    message: str
    active: bool  # False once the row's run has ended (its batch goes on for the others)
    velocity: float  # d<X>/dt over the record's last RECENT_WINDOW s (m/s; the rigid top's under a dead weight), nan if < 2 samples
    samples: np.ndarray  # the record so far: one row per output sample from the first, columns scheme.O_* (mean f_d, <x>, <X>); no rows where it cannot be read

    @property
    def X_mean(self) -> np.ndarray:
        """The upper layer's record <X>(t) so far (the tester's top under a dead weight)."""
        return self.samples[:, S.O_XUMEAN]

    @property
    def x_mean(self) -> np.ndarray:
        """The interface layer's record <x>(t) so far."""
        return self.samples[:, S.O_XMEAN]


RECENT_WINDOW = 0.01  # s: the stretch of the record over which checkpoint_rows reads the upper layer's velocity


def _record(ds: xr.Dataset, r: int) -> np.ndarray:
    """Row ``r``'s record so far, samples by columns O_* (no rows where the checkpoint holds none)."""
    try:
        rec = np.asarray(ds[f"rec_samples_{r}"].values, dtype=float)
    except (KeyError, ValueError, TypeError):
        rec = np.zeros((0, 0))
    return rec if rec.ndim == 2 and rec.shape[1] > S.O_XUMEAN else np.zeros((0, S.O_XUMEAN + 1))


def _recent_velocity(X: np.ndarray, config: str) -> float:
    """d<X>/dt of a record over its last RECENT_WINDOW s (nan where the record cannot say)."""
    try:
        interval = float(tomllib.loads(config)["output_interval"])  # the samples' spacing (s)
    except (KeyError, ValueError, TypeError, tomllib.TOMLDecodeError):
        return float("nan")
    tail = X[-(max(1, int(round(RECENT_WINDOW / interval))) + 1):]
    return float((tail[-1] - tail[0]) / ((tail.size - 1) * interval)) if tail.size >= 2 else float("nan")


def checkpoint_rows(path: str | Path) -> tuple[dict, list[CheckpointRow]]:
    """The attributes of a checkpoint (wall_time_s, t_simulated, written, ...) and one
    :class:`CheckpointRow` per run in it, reading only those variables and each record's <X>(t) (for
    ``slipchain status``: how far a run has got, how fast its upper layer, or the tester's top, moves now:
    whether a dead weight is running away or coming back, and what the stop rules say of its record; and for
    ``slipchain figure traces --checkpoints``: a run the stop rules decide on its record, read before it is
    stored).

    Safe beside a running task: a checkpoint is replaced atomically, never written in place.
    Raises :class:`CheckpointError` for a file that is not a readable checkpoint.
    """
    from ..results.io import ENGINE

    try:
        with xr.open_dataset(path, engine=ENGINE) as ds:
            attrs = dict(ds.attrs)
            cols = [np.atleast_1d(ds[v].values) for v in ("config", "samples_done", "row_status", "row_message", "active")]
            records = [_record(ds, r) for r in range(cols[0].size)]
    except Exception as e:  # noqa: BLE001 - h5py's OSError, xarray's ValueError, a KeyError: not a whole checkpoint
        raise CheckpointError(f"checkpoint {str(path)!r} is unreadable ({type(e).__name__}: {e})") from None
    rows = [CheckpointRow(str(c), int(n), str(st), str(msg), bool(a), _recent_velocity(rec[:, S.O_XUMEAN], str(c)), rec)
            for c, n, st, msg, a, rec in zip(*cols, records)]
    return attrs, rows


__all__ = ["CHECKPOINT_EVERY", "PACE_POINTS", "PACE_WINDOW", "RECENT_WINDOW", "CheckpointError", "CheckpointRow", "Checkpointer", "Restored",
           "checkpoint_rows", "recent_pace", "simulated_time"]

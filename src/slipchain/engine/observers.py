"""Observers of the time loop: called by the driver after every compiled chunk.

An observer has ``chunk(batch, out, live, n)`` (``out`` the :class:`~.backends.base.ChunkOutput`,
``live`` the rows that ran, ``n`` the samples they ran; called before the run controls decide
whether a row stops) and ``close()``. Three ship:
:class:`Recorder` (the run's time series and per-contact sums, for the result Dataset),
:class:`FieldRecorder` (instantaneous fields after every chunk, for the mechanism) and
:class:`ProgressBar` (a rich bar on a terminal).
"""

from __future__ import annotations

import sys
import time
from typing import Protocol

import numpy as np

from ..model.geometries import GEOMETRIES
from ..results.schema import Recording
from . import scheme as S
from .backends.base import Batch, ChunkOutput


class Observer(Protocol):
    def chunk(self, batch: Batch, out: ChunkOutput, live: list[int], n: int) -> None: ...

    def close(self) -> None: ...


CONTACT_SUMS_BYTES = 32 * 2**20
"""Per row, the most bytes the per-contact records of a spring-driven run may hold (32 MiB: 64 records on a
128 x 128 interface, 3 483 for a chain of 301 contacts). Past it, adjacent records are merged pairwise
(:meth:`Recorder.halve`): the steady window's per-contact averages then start at the first record edge
inside MSER's window instead of the first chunk edge. f_d, mu_star and the state are unaffected."""


def record_cap(n_contacts: int, budget: int | None = None) -> int:
    """Records a row of ``n_contacts`` contacts may keep within ``budget`` bytes (CONTACT_SUMS_BYTES), at least 2."""
    budget = CONTACT_SUMS_BYTES if budget is None else budget
    return max(2, int(budget) // (max(n_contacts, 1) * S.N_CACC * 8))


class Recorder:
    """Collects every row's chunk outputs: per-sample f_d and mean displacements, per-contact sums
    in records of whole chunks, and the work sums.

    A spring-driven row keeps a record per chunk (its steady window, chosen by MSER only at the end,
    averages the records that lie wholly in it) until the records would pass CONTACT_SUMS_BYTES
    (:func:`record_cap`); then adjacent records are merged pairwise and each record holds twice as many
    chunks (:meth:`width`), so a record is ``width`` chunks long except the last, which fills up before a
    new one starts. A run of 22 s on a 128 x 128 interface (455 chunks of 50 ms) thus keeps 57 records
    of 8 chunks (29 MB) instead of 455 (227 MB, and as much in each checkpoint). Every step is a
    function of the chunk sequence alone, so a resumed run keeps the uninterrupted run's records.

    A row in ``whole`` (a dead-weight run: its per-contact averages are over the whole run,
    :func:`~slipchain.results.schema.contacts_over_whole_run`) keeps one per-contact record, the running sum
    over its chunks in their order (the sum the whole-run average adds up, bit for bit), instead of
    one per chunk: its force ramp advances one sample per chunk, so a ramp of 20 s in 0.1-ms samples
    would otherwise hold 200 000 records (2 GB for 301 contacts, and as much in each checkpoint)."""

    def __init__(self, n_contacts: list[int], whole: list[bool] | None = None, budget: int | None = None):
        self.n_contacts = n_contacts
        self.whole = list(whole) if whole is not None else [False] * len(n_contacts)
        self.cap = [record_cap(nc, budget) for nc in n_contacts]
        self.samples: list[list[np.ndarray]] = [[] for _ in n_contacts]
        self.contact_sums: list[list[np.ndarray]] = [[] for _ in n_contacts]
        self.chunk_starts: list[list[int]] = [[] for _ in n_contacts]  # first sample of each record
        self.chunk_samples: list[list[int]] = [[] for _ in n_contacts]  # samples per record
        self.chunk_counts: list[list[int]] = [[] for _ in n_contacts]  # chunks per record
        self.works = np.zeros((len(n_contacts), S.N_ACC))
        self.n = [0] * len(n_contacts)

    def chunk(self, batch: Batch, out: ChunkOutput, live: list[int], n: int) -> None:
        for i in live:
            nc = self.n_contacts[i]
            ns = out.out.shape[1]
            self.samples[i].append(out.out[i].copy())
            self.add(i, self.n[i], ns, out.cacc[i, :, :nc].T)
            self.works[i] += out.acc[i]
            self.n[i] += ns

    def width(self, row: int) -> int:
        """Chunks per full record of row ``row``: the first record's (it is full once a merge has run; 1 before)."""
        counts = self.chunk_counts[row]
        return counts[0] if counts else 1

    def add(self, row: int, start: int, ns: int, sums: np.ndarray) -> None:
        """One chunk's per-contact sums (starting at sample ``start``, ``ns`` samples) into row ``row``'s records."""
        records = self.contact_sums[row]
        if records and (self.whole[row] or self.chunk_counts[row][-1] < self.width(row)):
            records[-1] += sums
            self.chunk_samples[row][-1] += ns
            self.chunk_counts[row][-1] += 1
        else:
            self.chunk_starts[row].append(start)
            records.append(np.array(sums, dtype=float, order="C"))
            self.chunk_samples[row].append(ns)
            self.chunk_counts[row].append(1)
        if len(records) > self.cap[row]:
            self.halve(row)

    def halve(self, row: int) -> None:
        """Merge row ``row``'s records pairwise (records 0 + 1, 2 + 3, ...; a trailing odd one kept as it
        is): full records are then twice as wide."""
        def pairs(xs):
            return [xs[k] + xs[k + 1] if k + 1 < len(xs) else xs[k] for k in range(0, len(xs), 2)]

        self.contact_sums[row] = pairs(self.contact_sums[row])
        self.chunk_starts[row] = self.chunk_starts[row][::2]
        self.chunk_samples[row] = pairs(self.chunk_samples[row])
        self.chunk_counts[row] = pairs(self.chunk_counts[row])

    def restore(self, row: int, starts, samples, sums, counts=None) -> None:
        """Row ``row``'s records from a checkpoint. With ``counts`` (chunks per record) they are
        this recorder's own; without (a checkpoint written before records were merged: one record per
        chunk), or for a ``whole`` row, they are replayed through :meth:`add` in their order, which gives
        the records an uninterrupted run would hold (a ``whole`` row's: their running sum)."""
        self.contact_sums[row], self.chunk_starts[row], self.chunk_samples[row], self.chunk_counts[row] = [], [], [], []
        if counts is None or self.whole[row]:
            for s0, ns, cs in zip(starts, samples, sums):
                self.add(row, int(s0), int(ns), cs)
            if counts is not None and self.chunk_counts[row]:  # a whole row's one record: its chunks
                self.chunk_counts[row] = [int(np.sum(counts))]
            return
        self.contact_sums[row] = [np.array(s, dtype=float, order="C") for s in sums]
        self.chunk_starts[row] = [int(v) for v in starts]
        self.chunk_samples[row] = [int(v) for v in samples]
        self.chunk_counts[row] = [int(v) for v in counts]
        while len(self.contact_sums[row]) > self.cap[row]:  # written under a larger budget
            self.halve(row)

    def recording(self, row: int) -> Recording:
        """Row ``row``'s recording in the run schema's plain form."""
        series = np.concatenate(self.samples[row]) if self.samples[row] else np.zeros((0, S.N_OUT))
        return Recording(f_d=series[:, S.O_FD], x_mean=series[:, S.O_XMEAN], X_mean=series[:, S.O_XUMEAN],
                         chunk_starts=list(self.chunk_starts[row]), chunk_samples=list(self.chunk_samples[row]),
                         contact_sums=list(self.contact_sums[row]),
                         works=self.works[row][[S.A_WDRIVE, S.A_WDAMP, S.A_WCONTACT, S.A_WVISC]])

    def close(self) -> None:
        pass


class FieldRecorder:
    """Instantaneous fields of one row after every chunk: the interface velocities u_i(t), the
    driving force f_d(t) = K_d (v_d t - <X>) (a**2 k(0) (v_d t - <x>) for the slab and half-space)
    and the acoustic proxy A(t) = sum_i f(u_i, v*_i); with ``positions``, also x_i - v_d t."""

    def __init__(self, system, n_max: int, row: int = 0, positions: bool = False):
        self.system = system
        self.row = row
        cfg = system.config
        self.t = np.empty(n_max)
        self.u = np.empty((n_max, cfg.n_blocks), dtype=np.float32)
        self.x = np.empty((n_max, cfg.n_blocks)) if positions else None
        self.f_d = np.empty(n_max)
        self.acoustic = np.empty(n_max)
        self.k = 0

    def chunk(self, batch: Batch, out: ChunkOutput, live: list[int], n: int) -> None:
        if self.row not in live or batch.status[self.row] >= 0:  # not run, or went non-finite
            return
        cfg = self.system.config
        law = cfg.contact_law
        sites, vstar = self.system.contact_sites, self.system.vstar
        uk = batch.u[self.row]
        k = self.k
        self.t[k] = batch.step[self.row] * cfg.dt
        self.u[k] = uk
        if self.x is not None:
            self.x[k] = batch.x[self.row] - cfg.v_d * self.t[k]
        if GEOMETRIES[batch.geometry].spectral:  # slab, half-space: the uniform mode of the elastic force
            self.f_d[k] = batch.kernel[self.row, 0, 0] * (cfg.v_d * self.t[k] - batch.x[self.row].mean())
        else:
            self.f_d[k] = cfg.K_d * (cfg.v_d * self.t[k] - batch.X[self.row].mean())
        self.acoustic[k] = float(np.sum(law.force(uk[sites], vstar))) if sites.size else 0.0
        self.k += 1

    def close(self) -> None:
        pass


class ProgressBar:
    """A rich progress bar for one run, shown on a terminal once it has taken more than 2 s."""

    def __init__(self, enabled: bool | None, control, interval: float):
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.control = control
        self.interval = interval
        self.total = control.limit * interval
        self._bar = None
        self._task = None
        self._t0 = time.perf_counter()

    def chunk(self, batch: Batch, out: ChunkOutput, live: list[int], n: int) -> None:
        if not self.enabled or time.perf_counter() - self._t0 < 2.0:
            return
        if self._bar is None:
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            self._bar = Progress(TextColumn("[bold]slipchain run"), BarColumn(),
                                 TextColumn("{task.completed:.4f}/{task.total:.4f} s simulated"),
                                 TextColumn("{task.fields[info]}"), TimeElapsedColumn(), TimeRemainingColumn())
            self._bar.start()
            auto = self.control.converge is not None
            self._task = self._bar.add_task("run", total=self.total,
                                            info="up to t_max; stops at sem_target" if auto else "")
        if self.control.limit * self.interval != self.total:  # extended past t_max by its slip cycles
            self.total = self.control.limit * self.interval
            self._bar.update(self._task, total=self.total)
        sem = self.control.converge.sem if self.control.converge is not None else float("nan")
        info = f"SE(mu*) = {sem:.4f}" if np.isfinite(sem) else ""
        self._bar.update(self._task, completed=(self.control.n + n) * self.interval, info=info)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()


__all__ = ["FieldRecorder", "Observer", "ProgressBar", "Recorder"]

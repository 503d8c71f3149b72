"""Run realisations: the public entry points :func:`run`, :func:`simulate` and :func:`simulate_batch`.

config -> system (disorder from the seed) -> start state -> batch -> the one time loop
(:func:`.driver.drive`, with :class:`.control.RowControl` per row and the
:class:`.observers.Recorder`) -> the run Dataset (:func:`slipchain.results.schema.assemble_run`:
MSER transient, mu_star with its batch-means error, physics checks).

mu_star = <f_d>_t / (epsilon*f0*theta), theta = N_c/N (docs/model.md, "Drive, start and measurement").
Where the run is computed is an argument (``backend``: 'cpu', 'gpu', 'auto' or a backend object),
never part of the config: the same config gives the same physics on every backend.
"""

from __future__ import annotations

import os
import time
from typing import Any, Mapping

import numpy as np
import xarray as xr

from ..model.config import Config, make_config
from ..model.system import State, System, build_system, initial_state
from ..results.checks import arm_energy, stored_energy
from ..results.schema import assemble_run, contacts_over_whole_run
from .backends import BackendName, Batch, get_backend
from .checkpoint import CHECKPOINT_EVERY, Checkpointer
from .control import chunk_samples, row_control
from .driver import drive
from .memory import check_memory, extension_refusal
from .observers import ProgressBar, Recorder
from .threads import one_blas_thread


def run(config: Config | Mapping[str, Any] | None = None, *, backend: str | BackendName = BackendName.CPU,
        progress: bool | None = None, checkpoint: str | os.PathLike | None = None,
        checkpoint_every: float = CHECKPOINT_EVERY) -> xr.Dataset:
    """Run the model for ``config`` (a Config, a mapping of overrides, or None for the defaults).

    ``checkpoint``: a file for the run's state, written every ``checkpoint_every`` wall-clock
    seconds and at the end; if it exists, the run resumes from it and gives bit for bit the result
    of an uninterrupted run (:mod:`slipchain.engine.checkpoint`; CheckpointError if it belongs to
    another config). Delete it once the result is saved. A run that would not fit in memory is
    refused before anything is allocated (:class:`.memory.MemoryEstimateError`, a ConfigError).

    **Returns:** the run Dataset (docs/run-schema.md).
    """
    cfg = config if isinstance(config, Config) else make_config(dict(config or {}))
    check_memory([cfg])
    return simulate(build_system(cfg), backend=backend, progress=progress, checkpoint=checkpoint,
                    checkpoint_every=checkpoint_every)


def simulate(system: System, state: State | None = None, *, backend: str | BackendName = BackendName.CPU,
             progress: bool | None = None, checkpoint: str | os.PathLike | None = None,
             checkpoint_every: float = CHECKPOINT_EVERY) -> xr.Dataset:
    """Integrate one realisation from ``state`` (default: the config's start) to a run Dataset."""
    return simulate_batch([system], None if state is None else [state], backend=backend, progress=progress,
                          checkpoint=checkpoint, checkpoint_every=checkpoint_every)[0]


def simulate_batch(systems: list[System], states: list[State] | None = None, *,
                   backend: str | BackendName = BackendName.CPU, progress: bool | None = None,
                   checkpoint: str | os.PathLike | None = None,
                   checkpoint_every: float = CHECKPOINT_EVERY) -> list[xr.Dataset]:
    """Integrate several realisations together (one backend call advances all of them).

    They must share N, dt, the output interval and whether ``min_cycles`` is set (one kernel launch
    runs them in lock-step, in chunks of :func:`.control.chunk_samples`);
    each row has its own length control (fixed, automatic, dead-weight ramp) and stops on its
    own: a finished row is skipped by the kernel. On the GPU this is how a sweep fills the device.
    The wall time recorded for every row is the batch's. ``checkpoint``: see :func:`run` (one file
    for the whole batch). The BLAS library runs on one thread meanwhile (:func:`.threads.one_blas_thread`),
    so a run gives the same bits in this process as in a sweep's worker, on any number of cores.
    """
    with one_blas_thread():
        return _simulate_batch(systems, states, backend, progress, checkpoint, checkpoint_every)


def _simulate_batch(systems, states, backend, progress, checkpoint, checkpoint_every) -> list[xr.Dataset]:
    cfg0 = systems[0].config
    for s in systems:
        c = s.config
        if (c.N, c.dt, c.sample_steps, bool(c.min_cycles)) != (cfg0.N, cfg0.dt, cfg0.sample_steps, bool(cfg0.min_cycles)):
            raise ValueError("a batch needs equal N, dt, output_interval and min_cycles > 0 or not; got "
                             f"{(c.N, c.dt, c.output_interval, c.min_cycles)} and {(cfg0.N, cfg0.dt, cfg0.output_interval, cfg0.min_cycles)}")
    check_memory([s.config for s in systems])  # MemoryEstimateError before the batch is allocated
    engine = get_backend(backend, [s.config for s in systems])
    states0 = [initial_state(s) if states is None or states[i] is None else states[i].copy()
               for i, s in enumerate(systems)]
    batch = Batch.pack(systems, states0)
    sample_steps = cfg0.sample_steps
    interval = sample_steps * cfg0.dt
    x0 = [float(np.mean(st.x)) for st in states0]
    e0 = [stored_energy(s, st) for s, st in zip(systems, states0)]
    a0 = [arm_energy(s, st) for s, st in zip(systems, states0)]  # material 'prony': the arms' energy at the start
    controls = [row_control(s, x0[i], interval, extension_refusal) for i, s in enumerate(systems)]
    recorder = Recorder([s.n_contacts for s in systems], [contacts_over_whole_run(s.config) for s in systems])
    saver, wall_before, resumed_at = None, 0.0, []
    if checkpoint is not None:
        saver = Checkpointer(checkpoint, checkpoint_every)
        if saver.path.exists():
            got = saver.restore(systems, batch, controls, recorder)
            x0, e0, wall_before = got.x0, got.e0, got.wall
            resumed_at = got.resumed_at + [max(c.n for c in controls) * interval]
    observers = [recorder, ProgressBar(progress if len(systems) == 1 else False, controls[0], interval)]
    wall0 = time.perf_counter()
    if saver is not None:
        saver.attach(systems, batch, controls, recorder, x0, e0, wall0, wall_before, resumed_at, engine.name, interval)
    drive(engine, batch, controls, sample_steps=sample_steps, chunk=chunk_samples(cfg0, interval),
          interval=interval, observers=observers, checkpoint=saver)
    wall = wall_before + time.perf_counter() - wall0
    out = [assemble_run(s, recorder.recording(i), batch.state(i), x0_mean=x0[i], e0=e0[i], a0=a0[i], interval=interval,
                        steps_per_sample=sample_steps, status=c.status,
                        message=c.final_message(s.config.t_max, s.config.sem_target), sem_reached=c.sem_reached,
                        wall=wall, backend=engine.name)
           for i, (s, c) in enumerate(zip(systems, controls))]
    if resumed_at:
        for ds in out:
            ds.attrs["resumed_at"] = ", ".join(f"{t:.6e}" for t in resumed_at)
    return out


__all__ = ["run", "simulate", "simulate_batch"]

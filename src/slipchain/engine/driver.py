"""The one time loop: compiled chunks, then run control and observers, until every row is done.

Loop order (each chunk), as in hoomd's ``Simulation.run``:

1. the rows still active and the chunk length: at most ``chunk`` samples (a row extended past
   t_max by its slip cycles allows long chunks), at most what any live row has left, one sample
   while a dead-weight ramp is rising (:mod:`.control`);
2. the dead-weight force of each ramping row is written into its parameters;
3. the backend advances every live row by ``n`` samples of ``sample_steps`` steps in compiled
   code (finished rows are skipped by the kernel);
4. the work of the constant dead-weight forces is added (F_b times the upper layer's displacement);
5. every observer sees the chunk (:mod:`.observers`: recorder, field recorder, progress bar);
6. each live row's control decides: ``diverged`` if the kernel flagged a non-finite state, else
   stop at its length limit or once converged; a finished row is marked for the kernel to skip;
7. the checkpointer, if any, writes the state when its interval has passed (:mod:`.checkpoint`):
   here, and only here, the batch, the controls and the recorder agree;
8. a stop asked for by a signal (:func:`.interrupts.check`) ends the loop as Ctrl-C does.

Ctrl-C (KeyboardInterrupt) during the loop stops every active row with status ``interrupted``:
what was simulated is kept and returned like a finished run. So does SIGTERM where
:func:`.interrupts.sigterm_as_interrupt` is installed (the command line).
"""

from __future__ import annotations

import numpy as np

from ..results.schema import Status
from . import interrupts
from . import scheme as S
from .backends.base import Backend, Batch
from .control import RowControl
from .observers import Observer


def drive(backend: Backend, batch: Batch, controls: list[RowControl], *, sample_steps: int, chunk: int,
          interval: float, observers: list[Observer] = (), checkpoint=None) -> None:
    """Advance ``batch`` until every row's control says stop (loop order: module docstring).

    **Arguments:** ``backend`` advances the batch; ``controls`` one :class:`RowControl` per row
    (updated in place: status, message, samples done); ``sample_steps`` steps per output sample;
    ``chunk`` samples per compiled call at most; ``interval`` the output interval (s, for
    messages); ``observers`` see every chunk; ``checkpoint`` (a
    :class:`~.checkpoint.Checkpointer`) is told after every chunk, and writes a final checkpoint
    when every row has finished (not when interrupted: the last periodic one stays).
    """
    interrupts.REQUESTED.clear()  # a signal of an earlier run in this process is not this run's
    try:
        while any(c.active for c in controls):
            live = [i for i, c in enumerate(controls) if c.active]
            n = min(controls[i].next_samples(chunk) for i in live)
            f_now = np.zeros(len(controls))
            sum_x0 = batch.X.sum(axis=1)
            for i in live:
                ramp = controls[i].ramp
                if ramp is not None:
                    f_now[i] = ramp.force(controls[i].n)
                    batch.params[i, S.P_FCONST] = f_now[i]
            co = backend.advance(batch, n, sample_steps)
            co.acc[:, S.A_WDRIVE] += f_now * (batch.X.sum(axis=1) - sum_x0)  # work of the constant forces
            for obs in observers:
                obs.chunk(batch, co, live, n)
            for i in live:
                c = controls[i]
                if batch.status[i] >= 0:
                    step = int(batch.status[i])
                    c.n += n
                    c.stop(Status.DIVERGED, f"non-finite state at step {step} (t = {step * batch.params[i, S.P_DT]:.6e} s)")
                    continue
                c.after_chunk(n, co.out[i])
                if not c.active:
                    batch.status[i] = batch.step[i]  # finished: the kernel skips this row from now on
            if checkpoint is not None:
                if any(c.active for c in controls):
                    checkpoint.after_chunk()
                else:
                    checkpoint.save()
            interrupts.check()  # a Ctrl-C or SIGTERM whose KeyboardInterrupt a finalizer swallowed
    except KeyboardInterrupt:
        for c in controls:
            if c.active:
                c.stop(Status.INTERRUPTED, f"interrupted by {interrupts.who()} at t = {c.n * interval:.6e} s")
    finally:
        for obs in observers:
            obs.close()


__all__ = ["drive"]

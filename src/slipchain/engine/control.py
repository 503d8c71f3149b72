"""Run control: how long each realisation runs, and the dead-weight force schedule.

Every row of a batch has a :class:`RowControl`: a length limit in output samples (``t_total``,
else ``t_max``), optionally :class:`UntilConverged` (the automatic length: stop once mu_star is
known to ``sem_target``) and optionally :class:`DeadWeightRamp` (the dead-weight force rising over
the first :data:`~slipchain.model.system.DEAD_WEIGHT_RAMP` of the run). The driver
(:func:`slipchain.engine.driver.drive`) asks them, between compiled chunks, how many samples to
run next and whether a row is done.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model.system import DEAD_WEIGHT_RAMP, System, dead_weight_force, mu_star_norm
from ..results.checks import DISPLACEMENT_RTOL
from ..results.observables import steady_estimate, window_velocity
from ..results.schema import Status
from . import scheme as S

CHUNK_TIME = 5e-4  # simulated seconds per compiled chunk (about 25 000 steps at the default dt)
MIN_STEADY_SAMPLES = 400  # automatic mode: at least this many steady samples before stopping
MIN_STEADY_SLIDE = 1e-6  # ...and a steady window in which the drive has moved at least this far (m):
# at very low v_d a steady start can look converged (tiny SE, no drift) long before it has settled


@dataclass
class UntilConverged:
    """The automatic run length: stop once the standard error of mu_star is at most ``sem_target``,
    the steady window (MSER) holds at least MIN_STEADY_SAMPLES samples, shows no drift, has seen
    the drive move MIN_STEADY_SLIDE, and the slider follows the drive there (within half the
    after-run displacement check's tolerance)."""

    system: System
    x0_mean: float
    interval: float
    f_d: list[np.ndarray] = field(default_factory=list)
    x_mean: list[np.ndarray] = field(default_factory=list)
    reached: bool = False
    sem: float = float("nan")

    def converged(self, out_row: np.ndarray) -> bool:
        """Append one chunk's samples (N_OUT columns) and say whether the run may stop."""
        cfg = self.system.config
        self.f_d.append(out_row[:, S.O_FD])
        self.x_mean.append(out_row[:, S.O_XMEAN])
        fd = np.concatenate(self.f_d)
        est = steady_estimate(fd / mu_star_norm(self.system))
        self.sem = est.sem
        if (est.n_samples >= MIN_STEADY_SAMPLES and est.drift_ok and est.sem <= cfg.sem_target
                and est.n_samples * self.interval * cfg.v_d >= MIN_STEADY_SLIDE
                and self._follows_drive(np.concatenate(self.x_mean), est.start)):
            self.reached = True
        return self.reached

    def _follows_drive(self, x_mean: np.ndarray, start: int) -> bool:
        v = window_velocity(x_mean, start, self.x0_mean, self.interval)
        return abs(v / self.system.config.v_d - 1.0) <= 0.5 * DISPLACEMENT_RTOL


@dataclass
class DeadWeightRamp:
    """The dead-weight force F_b rising linearly, a sample at a time, over the first ``n_ramp``
    samples of the run, then constant."""

    f_b: float
    n_ramp: int

    def force(self, n_done: int) -> float:
        return self.f_b * min(1.0, (n_done + 1) / self.n_ramp)

    def max_samples(self, n_done: int) -> int:
        return 1 if n_done < self.n_ramp else 1 << 62


@dataclass
class RowControl:
    """Length control and outcome of one row of a batch."""

    limit: int  # samples
    converge: UntilConverged | None = None
    ramp: DeadWeightRamp | None = None
    n: int = 0  # samples done
    active: bool = True
    status: Status = Status.COMPLETED
    message: str = ""

    @property
    def remaining(self) -> int:
        return self.limit - self.n

    @property
    def sem_reached(self) -> bool:
        return self.converge.reached if self.converge is not None else True

    def stop(self, status: Status, message: str) -> None:
        self.status, self.message, self.active = status, message, False

    def after_chunk(self, n: int, out_row: np.ndarray) -> None:
        """Account for ``n`` samples just run (``out_row`` holds them) and decide whether to stop."""
        self.n += n
        if self.converge is not None and self.converge.converged(out_row):
            self.active = False
        if self.n >= self.limit:
            self.active = False

    def final_message(self, t_max: float, sem_target: float) -> str:
        if self.converge is not None and self.status == Status.COMPLETED and not self.converge.reached:
            return (f"t_max = {t_max:g} s reached before the standard error fell below "
                    f"sem_target = {sem_target:g}")
        return self.message


def row_control(system: System, x0_mean: float, interval: float) -> RowControl:
    """The control of one realisation from its config: fixed length (``t_total``), automatic
    (``t_total`` absent: until converged, at most ``t_max``), and the dead-weight ramp (dead-weight
    runs always have a fixed length, ``t_total`` else ``t_max``; their velocity is measured after)."""
    c = system.config
    limit = max(1, int(round((c.t_total if c.t_total is not None else c.t_max) / interval)))
    dead_weight = c.dead_weight is not None
    auto = c.t_total is None and not dead_weight
    return RowControl(
        limit=limit,
        converge=UntilConverged(system, x0_mean, interval) if auto else None,
        ramp=DeadWeightRamp(dead_weight_force(system), max(1, int(round(DEAD_WEIGHT_RAMP * limit)))) if dead_weight else None,
    )


__all__ = ["CHUNK_TIME", "MIN_STEADY_SAMPLES", "MIN_STEADY_SLIDE", "DeadWeightRamp", "RowControl", "UntilConverged",
           "row_control"]

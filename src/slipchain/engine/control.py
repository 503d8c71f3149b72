"""Run control: how long each realisation runs, and the dead-weight force schedule.

Every row of a batch has a :class:`RowControl`: a length limit in output samples (``t_total``,
else ``t_max``), optionally :class:`UntilConverged` (the automatic length: stop once mu_star is
known to ``sem_target``) or :class:`UntilDecided` (the dead-weight automatic length: stop once the
velocity is steady or has left the rising branch), and optionally :class:`DeadWeightRamp` (the
dead-weight force rising over the first :data:`~slipchain.model.system.DEAD_WEIGHT_RAMP` of the
run, or of ``t_decide``). The driver
(:func:`slipchain.engine.driver.drive`) asks them, between compiled chunks, how many samples to
run next and whether a row is done.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple

import numpy as np

from ..model.config import Config
from ..model.system import DEAD_WEIGHT_RAMP, System, dead_weight_force, dead_weight_ramp_time, mu_star_norm
from ..results.checks import DISPLACEMENT_RTOL
from ..results.observables import count_cycles, steady_estimate, window_velocity
from ..results.schema import (Status, accelerating_beyond_branch, after_ramp, certain_held, certain_runaway,
                              dead_weight_status, dead_weight_velocity, runaway_window, velocity_decided)
from ..results.velocity import VelocityStatus
from . import scheme as S

DECIDE_EVERY = 0.02  # the dead-weight automatic length classifies the trace each time it has grown by 2 %
# (each classification fits the whole trace: checking every chunk would cost as much as the run)
CHUNK_TIME = 5e-4  # simulated seconds per compiled chunk (about 25 000 steps at the default dt)
LONG_CHUNK_TIME = 0.05  # ... for runs with min_cycles (epsilon = 1: runs of tens of seconds, 1 ms samples)
FEW_CYCLES = 5  # at t_max with fewer cycles than this in the steady window, the run stick-slips as a whole in
# cycles as long as the run: it is extended (t_max_cycles), or the message says how to converge it
DEFAULT_MIN_CYCLES = 20  # an extended run's steady window must hold this many cycles (min_cycles, if given, instead)
MIN_STEADY_SAMPLES = 400  # automatic mode: at least this many steady samples before stopping
MIN_STEADY_SLIDE = 1e-6  # ...and a steady window in which the drive has moved at least this far (m):
# at very low v_d a steady start can look converged (tiny SE, no drift) long before it has settled


def chunk_time(cfg) -> float:
    """Simulated seconds per compiled chunk: CHUNK_TIME, or LONG_CHUNK_TIME with ``min_cycles`` (runs
    of tens of seconds: the per-contact sums are kept in records of whole chunks, and the checkpoint
    holds them; observers.CONTACT_SUMS_BYTES bounds them)."""
    return LONG_CHUNK_TIME if cfg.min_cycles else CHUNK_TIME


def chunk_samples(cfg, interval: float) -> int:
    """Output samples per compiled chunk (:func:`chunk_time`), at least one."""
    return max(1, int(round(chunk_time(cfg) / interval)))


def geometric_check_index(n: int, n_first: int) -> int:
    """Checks at n_first*(1 + DECIDE_EVERY)**k samples: the index k of the last one passed by ``n``
    (-1 before the first). A function of the sample count alone, so a resumed run checks where
    the uninterrupted one did."""
    if n < n_first:
        return -1
    return int(np.floor(np.log(n / n_first) / np.log1p(DECIDE_EVERY) + 1e-12))


@dataclass
class UntilConverged:
    """The automatic run length: stop once the standard error of mu_star is at most ``sem_target``,
    the steady window (MSER) holds at least MIN_STEADY_SAMPLES samples, shows no drift, has seen
    the drive move MIN_STEADY_SLIDE, and the slider follows the drive there (within half the
    after-run displacement check's tolerance).

    With ``min_cycles`` > 0 (issue 12: the long slip cycles at epsilon = 1) the steady window must
    also hold that many cycles of f_d (:func:`~slipchain.results.observables.count_cycles`: for
    system-wide stick-slip, slip events; the batch-means SE of a window of a few cycles is not to be
    trusted) unless its standard deviation is below ``sem_target`` (steady sliding), and the
    conditions are checked each time the trace has grown by DECIDE_EVERY (runs of 10**5 samples and
    more: checking every chunk would cost more than the run). Without it the checks run after
    every chunk, as before.
    """

    system: System
    x0_mean: float
    interval: float
    f_d: list[np.ndarray] = field(default_factory=list)
    x_mean: list[np.ndarray] = field(default_factory=list)
    reached: bool = False
    sem: float = float("nan")
    extended: bool = False  # past t_max by the slip-cycle rule (:meth:`RowControl.extend`)

    @property
    def cycles_required(self) -> int:
        """Cycles of f_d the steady window must hold: ``min_cycles``; once extended past t_max by its
        slip cycles, DEFAULT_MIN_CYCLES where ``min_cycles`` is not given; else none."""
        return self.system.config.min_cycles or (DEFAULT_MIN_CYCLES if self.extended else 0)

    def converged(self, out_row: np.ndarray) -> bool:
        """Append one chunk's samples (N_OUT columns) and say whether the run may stop."""
        cfg = self.system.config
        self.f_d.append(out_row[:, S.O_FD])
        self.x_mean.append(out_row[:, S.O_XMEAN])
        if self.cycles_required:
            n = sum(a.shape[0] for a in self.f_d)
            if (geometric_check_index(n, MIN_STEADY_SAMPLES)
                    == geometric_check_index(n - out_row.shape[0], MIN_STEADY_SAMPLES)):
                return self.reached
            self.f_d, self.x_mean = [np.concatenate(self.f_d)], [np.concatenate(self.x_mean)]
        fd = np.concatenate(self.f_d) / mu_star_norm(self.system)
        est = steady_estimate(fd)
        self.sem = est.sem
        if (est.n_samples >= MIN_STEADY_SAMPLES and est.drift_ok and est.sem <= cfg.sem_target
                and est.n_samples * self.interval * cfg.v_d >= MIN_STEADY_SLIDE
                and self._follows_drive(np.concatenate(self.x_mean), est.start)
                and (not self.cycles_required or self._cycles_ok(fd[est.start:]))):
            self.reached = True
        return self.reached

    def window_cycles(self) -> tuple[int, int, bool]:
        """The steady window now: its first sample (MSER), the cycles of f_d it holds, and whether it
        slides steadily (varies less than sem_target and follows the drive: no cycles to count)."""
        if not self.f_d:
            return 0, 0, False
        fd = np.concatenate(self.f_d) / mu_star_norm(self.system)
        start = steady_estimate(fd).start
        window = fd[start:]
        steady_sliding = (window.size > 0 and window.std() <= self.system.config.sem_target
                          and self._follows_drive(np.concatenate(self.x_mean), start))
        return start, count_cycles(window), bool(steady_sliding)

    def few_cycles_advice(self) -> str:
        """At the cap without convergence: if the steady window holds fewer cycles of f_d than the run
        needs (FEW_CYCLES, or :attr:`cycles_required` once extended: the whole interface
        stick-slipping in cycles as long as the run, as at epsilon = 1), say so and what lets such a
        run converge; else nothing."""
        _, cycles, steady_sliding = self.window_cycles()
        if cycles >= max(FEW_CYCLES, self.cycles_required if self.extended else 0) or steady_sliding or not self.f_d:
            return ""
        cfg = self.system.config
        if self.extended:
            return (f"; the steady window holds only {cycles} cycle(s) of f_d at t_max_cycles = {cfg.t_max_cycles:g} s "
                    "(slip cycles as long as the run): raise t_max_cycles, with output_interval = 1e-3 and "
                    "start = 'steady' as presets/fig6-eps1.toml does for epsilon = 1")
        return (f"; the steady window holds only {cycles} cycle(s) of f_d (slip cycles as long as the run): give "
                "t_max_cycles (the cap that follows slip cycles), or t_max long enough for tens of cycles with "
                "min_cycles = 20, output_interval = 1e-3 and start = 'steady', as presets/fig6-eps1.toml does for "
                "epsilon = 1")

    def _cycles_ok(self, window: np.ndarray) -> bool:
        """:attr:`cycles_required` cycles in the steady window, or a window that varies less than
        sem_target (steady sliding: no cycles to count, and no sample farther from the mean than the target)."""
        cfg = self.system.config
        return bool(window.std() <= cfg.sem_target or count_cycles(window) >= self.cycles_required)

    def _follows_drive(self, x_mean: np.ndarray, start: int) -> bool:
        v = window_velocity(x_mean, start, self.x0_mean, self.interval)
        return abs(v / self.system.config.v_d - 1.0) <= 0.5 * DISPLACEMENT_RTOL


@dataclass
class UntilDecided:
    """The dead-weight automatic length (config ``t_decide``): from ``t_decide`` on, after every
    chunk that has lengthened the trace by DECIDE_EVERY since the last check, the velocity after
    the ramp is classified exactly as at the end of the run
    (:func:`~slipchain.results.schema.dead_weight_velocity`, the tester's algorithm). The run stops
    once it is decided (:func:`~slipchain.results.schema.velocity_decided`): steady with a velocity
    change across the window of at most DECIDE_DRIFT, or a runaway beyond the rising branch (faster
    than RUNAWAY_FACTOR*v0*10**delta: sliding steadily there, or still accelerating beyond it,
    :func:`~slipchain.results.schema.accelerating_beyond_branch`). While the slider still accelerates
    or slows down it goes on, at most ``t_max``; there a tester's ``ok`` that still drifts becomes ``no-steady``, with the
    drift in its reason, and an accelerating slider stays ``runaway``. It reads only the run's config and
    its record, so a stored record can be fed to it again with another ``t_decide``
    (:func:`slipchain.analysis.traces.redecide`). With config ``stop_when_held`` a decision also stops a
    released slab whose top is back on the rising branch for good
    (:func:`~slipchain.results.schema.certain_held`)."""

    config: Config
    interval: float
    n_first: int  # samples before the first decision (t_decide)
    X_mean: list[np.ndarray] = field(default_factory=list)
    reached: bool = False

    def decided(self, n_done: int, out_row: np.ndarray) -> bool:
        """Append one chunk's samples; say whether the velocity is decided (``n_done`` samples so far).
        Before t_decide, with config ``stop_at_runaway``, decided where the record's last stretch shows a
        certain runaway (:func:`~slipchain.results.schema.certain_runaway`), checked after every chunk
        (a sample at a time while the weight rises)."""
        self.X_mean.append(out_row[:, S.O_XUMEAN])
        if n_done < self.n_first:
            if self.config.stop_at_runaway and self._runaway(n_done):
                self.reached = True
                return True
            return False
        if self._check_index(n_done) == self._check_index(n_done - out_row.shape[0]):
            return False
        time = (np.arange(n_done) + 1) * self.interval
        X = np.concatenate(self.X_mean)
        after = after_ramp(self.config, time)
        status, _, fit = dead_weight_velocity(self.config, time[after], X[after])
        self.reached = (velocity_decided(status, fit) or accelerating_beyond_branch(self.config, time[after], X[after], fit)
                        or bool(self.config.stop_when_held and status != VelocityStatus.RUNAWAY
                                and certain_held(self.config, time, X)))
        return self.reached

    def _runaway(self, n_done: int) -> bool:
        """certain_runaway on the record's last runaway_window (the chunks that hold it, from the end; a
        released run's two ringing periods)."""
        need = int(np.ceil(runaway_window(self.config) / self.interval)) + 1
        parts, have = [], 0
        for part in reversed(self.X_mean):
            parts.append(part)
            have += part.size
            if have >= need:
                break
        X = np.concatenate(parts[::-1])
        time = (np.arange(n_done - X.size, n_done) + 1) * self.interval
        return certain_runaway(self.config, time, X) is not None

    def _check_index(self, n: int) -> int:
        """Checks fall at n_first*(1 + DECIDE_EVERY)**k: a chunk end checks when it passes the next one."""
        return geometric_check_index(n, self.n_first)


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
    decide: UntilDecided | None = None
    n: int = 0  # samples done
    active: bool = True
    status: Status = Status.COMPLETED
    message: str = ""
    base_limit: int = 0  # the limit the config sets (t_total or t_max); past it only by :meth:`extend`
    long_chunk: int = 1  # samples per chunk once extended (LONG_CHUNK_TIME)
    note: str = ""  # why the run was not extended, for the final message
    # (cfg, t_now, t_new) -> why an extension to t_new would not fit in memory, or None
    # (:func:`.memory.extension_refusal`, given by the caller: memory's estimate builds on this module)
    memory_refusal: Callable[[Any, float, float], str | None] | None = None

    @property
    def remaining(self) -> int:
        return self.limit - self.n

    @property
    def sem_reached(self) -> bool:
        return self.converge.reached if self.converge is not None else True

    def stop(self, status: Status, message: str) -> None:
        self.status, self.message, self.active = status, message, False

    @property
    def extended(self) -> bool:
        return self.converge is not None and self.converge.extended

    def chunk_cap(self, chunk: int) -> int:
        """Samples this row may run in the next chunk: ``chunk``, or the long chunk once extended
        (slip cycles of seconds: the per-contact sums are kept in records of whole chunks)."""
        return max(chunk, self.long_chunk) if self.extended else chunk

    def next_samples(self, chunk: int) -> int:
        """Samples this row may run in the next compiled call: :meth:`chunk_cap`, at most what it has left,
        one while its dead weight rises (:meth:`DeadWeightRamp.max_samples`). The driver runs a batch for
        the least of its live rows'; a replay of a stored record (:func:`slipchain.analysis.traces.redecide`)
        follows the same chunks."""
        n = min(self.chunk_cap(chunk), self.remaining)
        return n if self.ramp is None else min(n, self.ramp.max_samples(self.n))

    def after_chunk(self, n: int, out_row: np.ndarray) -> None:
        """Account for ``n`` samples just run (``out_row`` holds them) and decide whether to stop."""
        self.n += n
        if self.converge is not None and self.converge.converged(out_row):
            self.active = False
        if self.decide is not None and self.decide.decided(self.n, out_row):
            self.active = False
        if self.n >= self.limit and not (self.active and self.extend()):
            self.active = False

    def extend(self) -> bool:
        """At the cap, unconverged: extend the cap if the run stick-slips as a whole in cycles as long
        as the run (config ``t_max_cycles``; issue 26). Returns whether it did.

        The rule: the steady window (MSER) holds fewer cycles of f_d than FEW_CYCLES (at t_max; or
        than :attr:`UntilConverged.cycles_required` with ``min_cycles`` or once extended) and does
        not slide steadily. The new cap follows the cycles: with two or more counted, the window's
        start plus (cycles_required + 2) periods, and at least two periods past now; with fewer,
        twice the time so far; at most ``t_max_cycles``. From then on the steady window must hold
        :attr:`UntilConverged.cycles_required` cycles, the conditions are checked each time the
        trace has grown by DECIDE_EVERY, and chunks are long (as with ``min_cycles``). Each choice
        is a function of the samples alone, so a resumed run extends where the uninterrupted one
        did. The extension is refused, and the final message says why, where its memory estimate
        does not fit in what the machine has available (``memory_refusal``).
        """
        cv = self.converge
        if cv is None or cv.reached:
            return False
        cfg = cv.system.config
        ceiling = int(round(cfg.t_max_cycles / cv.interval))
        if not cfg.t_max_cycles or self.limit >= ceiling:
            return False
        start, cycles, steady_sliding = cv.window_cycles()
        need = cv.cycles_required if (cv.extended or cfg.min_cycles) else FEW_CYCLES
        if steady_sliding or cycles >= need:
            return False
        target = cfg.min_cycles or DEFAULT_MIN_CYCLES
        if cycles >= 2:
            period = (self.n - start) / cycles
            new = max(start + (target + 2) * period, self.n + 2 * period)
        else:
            new = 2.0 * self.n
        new_limit = min(ceiling, max(self.limit + 1, int(np.ceil(new))))
        why = self.memory_refusal(cfg, self.n * cv.interval, new_limit * cv.interval) if self.memory_refusal else None
        if why is not None:
            self.note = why
            return False
        self.limit = new_limit
        cv.extended = True
        return True

    def final_message(self, t_max: float, sem_target: float) -> str:
        if self.converge is not None and self.status == Status.COMPLETED and not self.converge.reached:
            cap = (f"the cap {self.limit * self.converge.interval:g} s (extended past t_max = {t_max:g} s by its slip "
                   "cycles)" if self.extended else f"t_max = {t_max:g} s")
            return (f"{cap} reached before the standard error fell below sem_target = {sem_target:g}"
                    + self.converge.few_cycles_advice() + (f"; {self.note}" if self.note else ""))
        if self.extended and self.status == Status.COMPLETED:
            return (f"converged at t = {self.n * self.converge.interval:g} s, past t_max = {t_max:g} s: the run "
                    "stick-slips as a whole and its automatic length followed its slip cycles (t_max_cycles)")
        if self.decide is not None and self.status == Status.COMPLETED and not self.decide.reached:
            return f"t_max = {t_max:g} s reached while the dead-weight velocity still drifted (see velocity_reason)"
        return self.message


def replay_decision(cfg: Config, X_mean: np.ndarray) -> int:
    """How many samples of the record ``X_mean`` (<X> at every output sample, from the first) a dead-weight run
    with config ``cfg`` (``t_decide`` given) runs before its automatic length stops it: the record fed in the
    run's own chunks (:func:`chunk_samples`, a sample at a time while the weight rises:
    :meth:`RowControl.next_samples`) to :class:`UntilDecided`, as the run's driver feeds it
    (:func:`slipchain.engine.driver.drive`); the record's length if nothing stops it there. It reads the
    config and the record alone, so a stored or checkpointed record can be replayed with other ``t_decide``,
    ``t_ramp``, ``stop_at_runaway`` or ``stop_when_held`` (:func:`slipchain.analysis.traces.redecide`,
    ``slipchain status``)."""
    interval = cfg.output_interval
    ramp = dead_weight_ramp_time(cfg)
    row = RowControl(limit=X_mean.size, ramp=DeadWeightRamp(0.0, max(1, int(round(ramp / interval)))),
                     decide=UntilDecided(cfg, interval, max(1, int(round(cfg.t_decide / interval)))))
    chunk = chunk_samples(cfg, interval)
    while row.active:  # the chunks the run's driver gives it, each checked at its end
        k = row.next_samples(chunk)
        out_row = np.zeros((k, S.O_XUMEAN + 1))
        out_row[:, S.O_XUMEAN] = X_mean[row.n:row.n + k]
        row.after_chunk(k, out_row)
    return row.n


class RulesDecision(NamedTuple):
    """What the released slab's stop rules say of a record (:func:`rules_decision`)."""

    config: Config  # the run's config with both rules on (stop_at_runaway, stop_when_held)
    time: np.ndarray  # the record's sample times (s): the run's own, (i + 1) * sample_steps * dt
    n: int  # samples up to where the rules stop the run; the record's length if they do not stop it on it
    verdict: tuple[str, str, Any] | None  # (velocity status, its reason, the tester's fit) there; None if undecided


def rules_decision(cfg: Config, X_mean: np.ndarray) -> RulesDecision | None:
    """What the stop rules of a released slab (configs ``stop_at_runaway`` and ``stop_when_held``, both on; the
    run's own ``t_decide``) say of a record <X>(t) so far (every output sample from the first), also for a run
    made without them: :func:`replay_decision` with the rules on, and where it stops the run the status the run
    would record there (:func:`~slipchain.results.schema.dead_weight_status`). The rules do not change the
    dynamics before they stop a run, so the record up to there is the ruled run's. None where they do not apply
    (no dead weight, no ``t_decide``, not the slab, fewer than two samples). What ``slipchain status`` prints
    of a checkpointed run and what ``slipchain figure traces --checkpoints`` reads."""
    if cfg.dead_weight is None or cfg.t_decide is None or cfg.geometry != "slab" or X_mean.size < 2:
        return None
    c = cfg.model_copy(update={"stop_at_runaway": True, "stop_when_held": True})
    n = replay_decision(c, X_mean)
    time = (np.arange(X_mean.size) + 1) * (c.sample_steps * c.dt)  # as engine.simulate writes a run's times
    verdict = dead_weight_status(c, time[:n], X_mean[:n]) if n < X_mean.size else None
    return RulesDecision(c, time, n, verdict)


def row_control(system: System, x0_mean: float, interval: float,
                memory_refusal: Callable[[Any, float, float], str | None] | None = None) -> RowControl:
    """The control of one realisation from its config: fixed length (``t_total``), automatic
    (``t_total`` absent: until converged, at most ``t_max``), and the dead-weight ramp. Dead-weight
    runs have a fixed length (``t_total``, else ``t_max``; ramp over its first DEAD_WEIGHT_RAMP),
    or with ``t_decide`` the automatic length :class:`UntilDecided` (ramp over
    DEAD_WEIGHT_RAMP*t_decide); ``t_ramp``, if given, is the ramp's duration instead. Their
    velocity is measured after the ramp."""
    c = system.config
    limit = max(1, int(round((c.t_total if c.t_total is not None else c.t_max) / interval)))
    long_chunk = max(1, int(round(LONG_CHUNK_TIME / interval)))
    dead_weight = c.dead_weight is not None
    auto = c.t_total is None and not dead_weight
    decide = dead_weight and c.t_decide is not None
    ramp_time = dead_weight_ramp_time(c)
    n_ramp = max(1, int(round(ramp_time / interval if ramp_time is not None else DEAD_WEIGHT_RAMP * limit)))
    return RowControl(
        limit=limit, base_limit=limit, long_chunk=long_chunk, memory_refusal=memory_refusal,
        converge=UntilConverged(system, x0_mean, interval) if auto else None,
        ramp=DeadWeightRamp(dead_weight_force(system), n_ramp) if dead_weight else None,
        decide=UntilDecided(c, interval, max(1, int(round(c.t_decide / interval)))) if decide else None,
    )


__all__ = ["CHUNK_TIME", "DEFAULT_MIN_CYCLES", "FEW_CYCLES", "LONG_CHUNK_TIME", "chunk_samples", "chunk_time", "geometric_check_index", "DECIDE_EVERY", "MIN_STEADY_SAMPLES", "MIN_STEADY_SLIDE", "DeadWeightRamp", "RowControl", "UntilConverged", "UntilDecided", "RulesDecision", "replay_decision",
           "row_control", "rules_decision"]

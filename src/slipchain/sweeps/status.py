"""Where a sweep store stands: each member stored, failed, in flight (checkpointed) or pending.

A long sweep (hours a member) is run in parts, often by different sessions or batch jobs: one
invocation is stopped (Ctrl-C, SIGTERM, a time limit) and the next resumes from the store. Between
them a researcher wants to know, without starting anything, what is finished and what it found, how
far each checkpointed run has got and at what cost, and whether a driver is running it now.
:func:`store_status` reads only what the store already holds:

* ``members/<id>.nc`` and ``failed/<id>.nc``: their attributes (status, the run's length ``t_total``,
  its ``wall_time_s``; for a dead-weight run its ``velocity_status``, e.g. runaway or held);
* ``checkpoints/<key>.nc``: each run's config and samples done
  (:func:`~slipchain.engine.checkpoint.checkpoint_rows`), matched to its member by the config text,
  and the wall time the task has spent so far (summed over resumes);
* ``driver.json``: the driver that holds the store, if any;
* for a checkpointed release of the slab (the tester's block), what the stop rules (configs
  ``stop_at_runaway``, ``stop_when_held``) say of its record so far (:func:`stop_rules`), also for a run
  started without them: whether it is decided already.

It takes no lock and writes nothing, so it is safe beside a running sweep: member files and
checkpoints are replaced atomically, never written in place. ``slipchain status --store PATH`` prints it.
"""

from __future__ import annotations

import json
import os
import socket
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..engine.checkpoint import CheckpointError, CheckpointRow, checkpoint_rows, recent_pace
from ..engine.control import rules_decision
from ..results.schema import Status
from .definition import Member, SweepError
from .store import CHECKPOINTS, HOLDER, Store, holder_text, read_holder

STORED, FAILED, IN_FLIGHT, PENDING, UNREADABLE = "stored", "failed", "in flight", "pending", "unreadable"


@dataclass(frozen=True)
class MemberStatus:
    """One member of the sweep, as the store shows it now."""

    id: str
    label: str  # its sweep coordinates, e.g. "theta=1, dead_weight=0.75, seed=1"
    state: str  # stored | failed | in flight | pending | unreadable
    status: str | None  # the run's recorded status (completed, diverged, ...); None while in flight or pending
    outcome: str | None  # a dead-weight run's velocity_status (ok, runaway, no-steady, ...), else None
    message: str  # the run's message or velocity_reason; a checkpointed row's message so far
    t_simulated: float | None  # simulated s reached (stored: t_total; in flight: from the checkpoint)
    t_max: float  # the config's t_max (a run may stop earlier: automatic length, a decided dead weight)
    wall_time_s: float | None  # wall s spent (in flight: the task's, over all its resumes)
    written: str | None  # when the checkpoint was written (in flight only)
    velocity: float | None  # in flight: d<X>/dt over the record's last 10 ms (m/s; the tester's top under a dead weight)
    rules: str | None = None  # in flight, a released slab: what the stop rules say of its record so far (stop_rules)


@dataclass(frozen=True)
class StoreStatus:
    """A store's members (:class:`MemberStatus`, in definition order), its driver and stray checkpoints."""

    path: str
    sweep: str
    members: list[MemberStatus]
    driver: str  # who runs the store now, in words
    stray_checkpoints: list[str]  # checkpoint files of no member of this sweep (the next sweep prunes them)
    unreadable_checkpoints: list[str]  # checkpoint files that could not be read, with the reason

    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {s: 0 for s in (STORED, IN_FLIGHT, FAILED, PENDING, UNREADABLE)}
        for m in self.members:
            out[m.state] += 1
        return out

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "counts": self.counts()}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1, default=str)


def store_status(path: str | os.PathLike) -> StoreStatus:
    """The status of the sweep store at ``path`` (see the module docstring).

    Raises :class:`~slipchain.sweeps.definition.SweepError` if ``path`` is not a sweep store.
    """
    path = Path(path)
    if not path.is_dir():
        raise SweepError(f"--store {str(path)!r}: no such directory; expected a slipchain sweep store "
                         "(a directory with sweep.toml, written by slipchain sweep)")
    try:
        st = Store.open(path)  # refuses a directory without sweep.toml, or one it cannot read
    except SweepError as e:
        raise SweepError(f"--store: {e}") from None
    flying, stray, unreadable = checkpointed(st)
    done, failed = st.completed_ids(), st.failed_ids()
    members = [_member_status(st, m, m.id in done, m.id in failed, flying.get(m.id)) for m in st.sweep.members]
    return StoreStatus(str(path), st.sweep.name, members, driver_status(path), stray, unreadable)


def checkpointed(st: Store) -> tuple[dict[str, tuple[CheckpointRow, dict]], list[str], list[str]]:
    """The store's checkpoints, read (:func:`~slipchain.engine.checkpoint.checkpoint_rows`): per member id the row
    that holds its run and its checkpoint's attributes (a member's run matched by its config text); the names of
    checkpoint files that hold no member of the sweep; and why each unreadable one could not be read. A write in
    progress (a temporary file) is skipped. What :func:`store_status` reports and what
    ``slipchain figure traces --checkpoints`` reads (:func:`slipchain.analysis.traces.velocity_traces`)."""
    by_config = {m.config.to_toml(): m for m in st.sweep.members}
    flying: dict[str, tuple[CheckpointRow, dict]] = {}
    stray, unreadable = [], []
    for ck in sorted((st.path / CHECKPOINTS).glob("*.nc")):
        if ck.name.startswith("."):  # a write in progress (temporary file)
            continue
        try:
            attrs, rows = checkpoint_rows(ck)
        except CheckpointError as e:
            unreadable.append(str(e))
            continue
        mine = [r for r in rows if r.config in by_config]
        if not mine:
            stray.append(ck.name)
        for r in mine:
            flying[by_config[r.config].id] = (r, attrs)
    return flying, stray, unreadable


def _member_status(st: Store, m: Member, done: bool, failed: bool, flying) -> MemberStatus:
    t_max = float(m.config.t_max)
    if done or (failed and flying is None):
        a = st.member_attrs(m) or {}
        if a.get("status") == Status.UNREADABLE.value:
            return MemberStatus(m.id, m.label(), UNREADABLE, None, None, str(a.get("message", "")), None, t_max, None, None,
                                None)
        outcome = a.get("velocity_status")
        # a completed dead-weight run: why it is steady, held or a runaway; anything else: why it failed
        message = a.get("velocity_reason") if outcome and a.get("status") == Status.COMPLETED.value else a.get("message")
        return MemberStatus(m.id, m.label(), STORED if done else FAILED, a.get("status"), outcome, str(message or ""),
                            _float(a.get("t_total")), t_max, _float(a.get("wall_time_s")), None, None)
    if flying is not None:
        row, attrs = flying
        t = row.samples_done * float(m.config.output_interval)
        return MemberStatus(m.id, m.label(), IN_FLIGHT, None, None, row.message, t, t_max,
                            _float(attrs.get("wall_time_s")), attrs.get("written"), row.velocity,
                            stop_rules(m.config, row.X_mean, _float(attrs.get("wall_time_s")), recent_pace(attrs)))
    return MemberStatus(m.id, m.label(), PENDING, None, None, "", None, t_max, None, None, None)


def stop_rules(cfg, X_mean: np.ndarray, wall_time_s: float | None = None,
               pace: tuple[float, float] | None = None) -> str | None:
    """What the stop rules of a released slab (configs ``stop_at_runaway`` and ``stop_when_held``, both on; the
    run's own ``t_decide``) say of its record <X>(t) so far (:func:`~slipchain.engine.control.rules_decision`):
    where they stop it and its status there (runaway; no-steady with a "held" reason; ok), or that they have not
    stopped it yet; None for any other run (no dead weight, no ``t_decide``, not the slab). For a run started
    without them: how far it would have had to go. Not decided yet, it adds what the rules read so far (the top's
    mean velocity over its last two ringing periods against their bounds), from when each can stop the run, and,
    given the run's recent pace (``pace``: wall s per simulated s and the wall s it was read over, from the
    checkpoint's last writes, :func:`~slipchain.engine.checkpoint.recent_pace`) or else its wall time so far
    (``wall_time_s``, its mean pace), how much more wall time the run needs to get there (an estimate: a run's
    pace changes as its slip does)."""
    from ..results.schema import RUNAWAY_RISE, _beyond_branch, _period_velocities, branch_scale, rules_start

    decision = rules_decision(cfg, X_mean)
    if decision is None:
        return None
    c, time, n, verdict = decision
    if verdict is not None:
        status, reason, _ = verdict
        said = "held" if reason.startswith("held") else status
        return f"{said} at t = {time[n - 1]:.4g} s"
    t = time[-1]
    out = f"not decided by t = {t:.4g} s"
    got = _period_velocities(c, time, X_mean, early=True)
    if got is not None:
        v1, v2, period = got
        out += (f"; over its last two ringing periods ({period:.3g} s each) the top slid at {v1:.3g} and then "
                f"{v2:.3g} m/s (a runaway: both beyond {_beyond_branch(c):.3g} m/s and {RUNAWAY_RISE - 1:.0%} faster; "
                f"held: both below {branch_scale(c):.3g} m/s and slower)")
    start = rules_start(c)
    runaway_from, held_from = start, max(start, float(c.t_decide))
    out += f"; the runaway rule reads from t = {runaway_from:.4g} s, the held rule from t = {held_from:.4g} s"
    ahead = [x for x in (runaway_from, held_from) if x > t]
    if pace is not None:
        rate, over = pace
        span = f"{over / 60.0:.0f} min" if over >= 120.0 else f"{over:.0f} s"
        said = f"at its pace over its last {span} of wall ({rate:,.0f} s a simulated second), "
    elif wall_time_s:
        rate, said = wall_time_s / t, "at its pace so far, "
    else:
        return out
    if ahead:
        out += f" ({said}" + " and ".join(
            f"t = {x:.4g} s is {(x - t) * rate / 3600.0:.2g} h of wall away" for x in dict.fromkeys(ahead)) + ")"
    return out


def _float(v: Any) -> float | None:
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def driver_status(path: str | os.PathLike) -> str:
    """Who runs the folder now (a sweep store, or a mu-max output directory: both hold their driver's
    record), in words, from driver.json (present while a driver runs, or after one was killed)."""
    record = Path(path) / HOLDER
    if not record.exists():
        return "no driver (none is running it)"
    holder = read_holder(record)
    if holder is None:
        return "a driver is starting (its record is not complete yet)"
    host, pid, _ = holder
    who = holder_text(holder)
    if host != socket.gethostname():
        return f"recorded driver on another host ({who}): running unless it was killed there"
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return f"no driver: the last one ({who}) was killed; the next slipchain sweep resumes from the checkpoints"
    except PermissionError:  # alive, another user's
        pass
    return f"running ({who})"


__all__ = ["FAILED", "IN_FLIGHT", "PENDING", "STORED", "UNREADABLE", "MemberStatus", "StoreStatus", "checkpointed", "driver_status",
           "stop_rules", "store_status"]

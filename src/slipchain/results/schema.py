"""The run schema: the status of a run, the run Dataset's variables and attributes, and its assembly.

One table (:data:`RUN_VARIABLES`, :data:`RUN_ATTRIBUTES`) says what a run's ``xarray.Dataset``
holds; the assembly (:func:`assemble_run`), the sweep store's per-member summary
(:data:`SWEEP_VARIABLES`), the CLI's summary (:data:`SUMMARY_KEYS`) and the docs
(:func:`schema_markdown`, docs/run-schema.md) all read it.

mu_star = <f_d>_t / (epsilon*f0*theta), theta = N_c/N (docs/model.md, "Drive, start and measurement"),
averaged over the steady window found by MSER (:mod:`slipchain.results.observables`).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np
import xarray as xr

from .._version import __version__
from ..model.system import (DEAD_WEIGHT_RAMP, RING_START, State, System, dead_weight_force, dead_weight_ramp_time,
                            mu_star_norm, top_ringing_period)
from .checks import CheckResult, arm_energy, displacement_check, energy_check, stored_energy
from .observables import SLOW_FRACTION, steady_estimate, window_velocity
from .velocity import N_STARTS, REL_TOL, VelocityFit, VelocityStatus, steady_velocity, window_start


class Status(StrEnum):
    """Status of a run (the first four) or of a point of a sweep grid (``missing``, ``absent``, ``unreadable``).

    str-valued: files hold the plain words, and ``ds.attrs["status"] == Status.COMPLETED`` works
    on files written before the enum existed.
    """

    COMPLETED = "completed"  # ran to its end; every physics check passed
    DIVERGED = "diverged"  # a non-finite state, or a failed physics check (the message names it)
    INTERRUPTED = "interrupted"  # stopped by the user (Ctrl-C); what was simulated is kept
    ERROR = "error"  # the run raised (a sweep task that failed; the message holds the exception)
    MISSING = "missing"  # sweep grid: a member not run yet
    ABSENT = "absent"  # sweep grid: a combination that no grid of the sweep contains
    UNREADABLE = "unreadable"  # sweep grid: the member's file cannot be read (quarantined and rerun by the next sweep)


# A dead-weight run faster than this times v0*10**delta has left the rising branch of mu(v).
RUNAWAY_FACTOR = 10.0
# A released top's mean velocity over its last ringing period at least this times the one before: accelerating beyond
# the ringing's residual (_released_runaway). A top that slid at 1.1 times the bound, 1.4 % faster over its last period,
# came back after 1.3 s (tester-16-long-etac-3-check); the stored runaways were 4.1 % faster or more where the rule
# first read them beyond the bound (the two below 5 % passed it within a ringing period and, run on without the rules,
# ran away: tester-16-long-etac-seeds-check), and no other run was ever faster there than 1.4 % (docs/tester-3d,
# "Stopping a released run early", "The rule's margin").
RUNAWAY_RISE = 1.05


@dataclass(frozen=True)
class Entry:
    """One variable or attribute of the run Dataset.

    ``dims``: the dimension of a variable ('' for an attribute); ``summary``: shown by the CLI's
    summary (and ``--json``); ``sweep``: the name under which the sweep store gathers this
    attribute into its per-member grid ('' if it does not).
    """

    name: str
    dims: str
    units: str
    meaning: str
    summary: bool = False
    sweep: str = ""


RUN_VARIABLES: tuple[Entry, ...] = (
    Entry("f_d", "time", "N", "driving force per block f_d, mean over the output interval ending at time"),
    Entry("x_mean", "time", "m", "mean interface-layer displacement"),
    Entry("X_mean", "time", "m", "mean upper-layer displacement"),
    Entry("contact_site", "contact", "", "interface block carrying the contact"),
    Entry("vstar", "contact", "m/s", "contact velocity scale v*_i"),
    Entry("contact_force_mean", "contact", "N", "time-averaged contact force, steady window"),
    Entry("contact_velocity_mean", "contact", "m/s", "time-averaged contact velocity, steady window"),
    Entry("contact_velocity_std", "contact", "m/s", "standard deviation of the contact velocity, steady window"),
    Entry("contact_slow_fraction", "contact", "", f"fraction of steady steps with |u| < {SLOW_FRACTION:g} v_d"),
    Entry("x", "block", "m", "final interface-layer displacements"),
    Entry("u", "block", "m/s", "final interface-layer velocities"),
    Entry("X", "block", "m", "final upper-layer displacements"),
    Entry("U", "block", "m/s", "final upper-layer velocities"),
    Entry("xi", "layer, term, block", "m", "material 'prony' only: final fields of the Maxwell arms (issue 28)"),
)

RUN_ATTRIBUTES: tuple[Entry, ...] = (
    Entry("title", "", "", "what the file is"),
    Entry("slipchain_version", "", "", "package version that wrote the run"),
    Entry("status", "", "", "completed, diverged, interrupted or error (Status)", summary=True),
    Entry("message", "", "", "why a run did not complete, or a note (t_max reached)", summary=True),
    Entry("config", "", "", "the full config as TOML"),
    Entry("seed", "", "", "seed of the disorder", summary=True),
    Entry("mu_star", "", "", "mu_star = <f_d>/(epsilon f0 theta), steady window", summary=True, sweep="mu_star"),
    Entry("mu_star_sem", "", "", "standard error of mu_star (batch means over time)", summary=True,
          sweep="mu_star_sem"),
    Entry("t_transient", "", "s", "loading transient excluded from the average", summary=True, sweep="t_transient"),
    Entry("t_steady", "", "s", "steady window", sweep="t_steady"),
    Entry("sem_target_reached", "", "", "1 if the automatic length reached sem_target"),
    Entry("theta", "", "", "realised theta = N_c/N", summary=True, sweep="theta_realised"),
    Entry("n_contacts", "", "", "number of contacts N_c", summary=True, sweep="n_contacts"),
    Entry("N", "", "", "blocks per chain (along x, Lx, in 2-D)", summary=True),
    Entry("geometry", "", "", "chain, chain2d, slab or halfspace (issue 13)"),
    Entry("Ly", "", "", "blocks across the sliding direction (1 for the chain)"),
    Entry("v_d", "", "m/s", "drive velocity", summary=True),
    Entry("eta_c", "", "1/s", "contact damping", summary=True),
    Entry("epsilon", "", "", "contact-force scale", summary=True),
    Entry("dt", "", "s", "time step", summary=True),
    Entry("t_total", "", "s", "simulated time", summary=True, sweep="t_total"),
    Entry("steps", "", "", "time steps", summary=True, sweep="steps"),
    Entry("wall_time_s", "", "s", "wall time of the run", summary=True, sweep="wall_time_s"),
    Entry("backend", "", "", "where the run was computed (cpu or gpu); not part of a member's identity"),
    Entry("resumed_at", "", "s", "runs resumed from a checkpoint only: the simulated times of the resumes"),
    Entry("mu_star_norm", "", "N", "epsilon f0 theta, the unit of mu_star"),
    Entry("W_drive", "", "J", "work of the drive"),
    Entry("W_damping", "", "J", "work of the inter-block damping (negative)"),
    Entry("W_contacts", "", "J", "work of the contact forces (negative)"),
    Entry("W_bulk", "", "J", "material 'prony' only: work of the viscoelastic bulk, what its Maxwell arms dissipated "
          "(negative)"),
    Entry("check_<name>", "", "", "value of each physics check (energy_balance, slider_follows_drive)"),
    Entry("check_<name>_passed", "", "", "1 if that check passed"),
    Entry("drive", "", "", "dead-weight drive only: 'dead-weight'"),
    Entry("dead_weight_force", "", "N", "dead-weight drive: the force F_b on every upper block"),
    Entry("velocity", "", "m/s", "dead-weight drive: steady velocity (NaN otherwise or if runaway)", summary=True,
          sweep="velocity"),
    Entry("velocity_sem", "", "m/s", "dead-weight drive: standard error of the velocity", summary=True,
          sweep="velocity_sem"),
    Entry("velocity_status", "", "", "dead-weight drive: ok, runaway or no-steady (VelocityStatus)", summary=True),
    Entry("velocity_reason", "", "", "dead-weight drive: why the velocity is not ok"),
)

_VARIABLES = {e.name: e for e in RUN_VARIABLES}

# Gathered by the sweep store into one grid per name: name -> (attribute of the member file, meaning).
SWEEP_VARIABLES: dict[str, tuple[str, str]] = {
    e.sweep: (e.name, e.meaning + (f", {e.units}" if e.units else "")) for e in RUN_ATTRIBUTES if e.sweep
}
# The run's headline numbers (the CLI's summary and --json), in this order.
SUMMARY_KEYS: tuple[str, ...] = tuple(e.name for e in RUN_ATTRIBUTES if e.summary)


def schema_markdown() -> str:
    """The run schema as Markdown tables (docs/run-schema.md is this text)."""
    lines = ["# The run Dataset", "",
             "Generated from `slipchain.results.schema` (`python -m slipchain.results.schema`); a test keeps "
             "this file equal to the code.", "",
             "## Variables", "", "| name | dimension | units | meaning |", "|---|---|---|---|"]
    lines += [f"| `{e.name}` | {e.dims} | {e.units} | {e.meaning} |" for e in RUN_VARIABLES]
    lines += ["", "## Attributes", "",
              "| name | units | meaning | CLI summary | sweep grid variable |", "|---|---|---|---|---|"]
    lines += [f"| `{e.name}` | {e.units} | {e.meaning} | {'yes' if e.summary else ''} | "
              f"{('`' + e.sweep + '`') if e.sweep else ''} |" for e in RUN_ATTRIBUTES]
    lines += ["", "## Status", "", "| value | meaning |", "|---|---|"]
    lines += [f"| `{s.value}` | {_STATUS_MEANING[s]} |" for s in Status]
    return "\n".join(lines) + "\n"


_STATUS_MEANING = {
    Status.COMPLETED: "ran to its end; every physics check passed",
    Status.DIVERGED: "a non-finite state, or a failed physics check (the message names it)",
    Status.INTERRUPTED: "stopped by the user; what was simulated is kept",
    Status.ERROR: "the run raised (a failed sweep task; the message holds the exception)",
    Status.MISSING: "sweep grid: a member not run yet",
    Status.ABSENT: "sweep grid: a combination that no grid of the sweep contains",
    Status.UNREADABLE: "sweep grid: the member's file cannot be read (the message says why); the next sweep "
                       "moves it to quarantine/ and reruns the member",
}


@dataclass
class Recording:
    """What the engine recorded for one realisation, in plain named arrays.

    Per output sample k (ending at (k+1)*interval): ``f_d`` mean driving force per block over the
    sample, ``x_mean``/``X_mean`` mean layer displacements at its end. Per record c of whole
    chunks (a chunk each, until :data:`slipchain.engine.observers.CONTACT_SUMS_BYTES` merges them
    pairwise; starting at sample ``chunk_starts[c]``, ``chunk_samples[c]`` samples long):
    ``contact_sums[c]``, an (N_c, 4) array of per-contact sums over its steps (force, velocity,
    velocity**2, slow steps). The steady window's per-contact averages add the records that lie
    wholly in MSER's window.
    ``works``: (W_drive, W_damping, W_contacts, W_visc) [J], W_visc the Maxwell arms' work on the
    blocks (material 'prony'; 0 otherwise).
    """

    f_d: np.ndarray
    x_mean: np.ndarray
    X_mean: np.ndarray
    chunk_starts: list[int]
    chunk_samples: list[int]
    contact_sums: list[np.ndarray]
    works: np.ndarray


def contacts_over_whole_run(cfg) -> bool:
    """Whether a run's per-contact averages are over the whole run rather than the steady window of
    f_d: a dead-weight run (its f_d, the drive springs' force, is zero, so MSER's window is the whole
    run anyway). The recorder keeps such a run's per-contact sums as one running record
    (:class:`slipchain.engine.observers.Recorder`), which only this window can read."""
    return cfg.dead_weight is not None


def assemble_run(system: System, rec: Recording, final: State, *, x0_mean: float, e0: float, interval: float,
                 a0: float = 0.0,
                 steps_per_sample: int, status: Status, message: str, sem_reached: bool, wall: float,
                 backend: str) -> xr.Dataset:
    """The run Dataset (the schema above) from a recording: MSER transient, mu_star and its error,
    per-contact steady averages, the physics checks after the run (a failed check turns a
    completed run into ``diverged``), and the dead-weight velocity."""
    cfg = system.config
    norm = mu_star_norm(system)
    fd = rec.f_d
    n = fd.size
    est = steady_estimate(fd / norm) if n else None
    start = est.start if est else 0
    checks: list[CheckResult] = []
    prony = cfg.material == "prony"
    # the bulk's dissipation: the arms' work on the blocks plus the change of their energy (a0 at the start)
    w_bulk = float(rec.works[3] + arm_energy(system, final) - a0) if prony else None
    if status != Status.DIVERGED and n:
        checks.append(energy_check(stored_energy(system, final) - e0, *rec.works[:3], w_bulk))
        if est is not None and est.n_samples >= 2 and cfg.dead_weight is None:
            checks.append(displacement_check(window_velocity(rec.x_mean, start, x0_mean, interval), cfg.v_d))
        failed = [c for c in checks if not c.passed]
        if failed and status == Status.COMPLETED:
            status = Status.DIVERGED
            message = "physics check failed at the end of the run (t = %.6e s): %s" % (
                n * interval, "; ".join(c.message for c in failed)) + (f" (and: {message})" if message else "")

    # Per-contact averages over the records that lie wholly in the steady window (or the whole run)
    contact_start = 0 if contacts_over_whole_run(cfg) else start
    sums = np.zeros((system.n_contacts, 4))
    steady_steps = 0
    for s0, ns, cs in zip(rec.chunk_starts, rec.chunk_samples, rec.contact_sums):
        if s0 >= contact_start:
            sums += cs
            steady_steps += ns * steps_per_sample
    with np.errstate(invalid="ignore", divide="ignore"):
        denom = steady_steps if steady_steps else np.nan
        f_mean = sums[:, 0] / denom
        u_mean = sums[:, 1] / denom
        u_std = np.sqrt(np.maximum(sums[:, 2] / denom - u_mean**2, 0.0))
        slow = sums[:, 3] / denom

    time = (np.arange(n) + 1) * interval
    values = {"f_d": fd, "x_mean": rec.x_mean, "X_mean": rec.X_mean, "contact_site": system.contact_sites,
              "vstar": system.vstar, "contact_force_mean": f_mean, "contact_velocity_mean": u_mean,
              "contact_velocity_std": u_std, "contact_slow_fraction": slow, "x": final.x, "u": final.u, "X": final.X,
              "U": final.U}
    ds = xr.Dataset(
        data_vars={k: (_VARIABLES[k].dims, v, _var_attrs(_VARIABLES[k])) for k, v in values.items()},
        coords={"time": ("time", time, {"units": "s"}), "contact": np.arange(system.n_contacts), "block": np.arange(cfg.n_blocks)},
    )
    if prony and final.xi is not None:  # the arms' fields: a run continued from this state goes on exactly
        ds["xi"] = (("layer", "term", "block"), final.xi, _var_attrs(_VARIABLES["xi"]))
    has_contacts = est is not None and system.n_contacts > 0
    attrs: dict[str, Any] = {
        "title": "slipchain two-chain friction model run",
        "slipchain_version": __version__,
        "status": Status(status).value,
        "message": message,
        "config": cfg.to_toml(),
        "seed": cfg.seed,
        "mu_star": est.mean if has_contacts else np.nan,
        "mu_star_sem": est.sem if has_contacts else np.nan,
        "t_transient": start * interval,
        "t_steady": (n - start) * interval,
        "sem_target_reached": int(sem_reached),
        "theta": system.theta_realised,
        "n_contacts": system.n_contacts,
        "N": cfg.N,
        "geometry": cfg.geometry,
        "Ly": cfg.Ly,
        "v_d": cfg.v_d,
        "eta_c": cfg.eta_c,
        "epsilon": cfg.epsilon,
        "dt": cfg.dt,
        "t_total": n * interval,
        "steps": int(final.step),
        "wall_time_s": wall,
        "backend": backend,
        "mu_star_norm": norm,
        "W_drive": rec.works[0],
        "W_damping": rec.works[1],
        "W_contacts": rec.works[2],
    }
    if prony:
        attrs["W_bulk"] = w_bulk
    if cfg.dead_weight is not None:
        attrs.update(dead_weight_attrs(system, time, rec.X_mean))
    for c in checks:
        attrs[f"check_{c.name}"] = c.value
        attrs[f"check_{c.name}_passed"] = int(c.passed)
    ds.attrs.update(attrs)
    return ds


def _var_attrs(e: Entry) -> dict[str, str]:
    out = {"units": e.units} if e.units else {}
    out["long_name"] = e.meaning
    return out


def after_ramp(cfg, time: np.ndarray) -> np.ndarray:
    """The samples after the dead-weight force ramp, where the velocity is measured
    (:func:`~slipchain.model.system.dead_weight_ramp_time`; a fixed-length run: DEAD_WEIGHT_RAMP of it)."""
    if not time.size:
        return np.zeros(0, bool)
    ramp_time = dead_weight_ramp_time(cfg)
    return time > (ramp_time if ramp_time is not None else DEAD_WEIGHT_RAMP * time[-1])


def branch_scale(cfg) -> float:
    """v0 10**delta (m/s): the velocity of the last contact's maximum of eq. (1) (the paper's v* at its upper
    end): below it a slider is on the rising branch of mu(v). The scale of the dead-weight thresholds here and in
    :mod:`slipchain.analysis.traces` (ONSET_FACTOR, ONSET_CHECK times it)."""
    return cfg.v0 * 10.0 ** cfg.delta


def _beyond_branch(cfg) -> float:
    """RUNAWAY_FACTOR*v0*10**delta: a velocity far above the last contact's maximum of eq. (1). (Not
    RUNAWAY_FACTOR * branch_scale(cfg): that rounds differently, 0.03162277660168379 against this 0.0316227766016838
    at v0 = 1e-3, delta = 0.5, and every stored decision was taken against this bound.)"""
    return RUNAWAY_FACTOR * cfg.v0 * 10.0**cfg.delta


def dead_weight_velocity(cfg, time: np.ndarray, X_mean: np.ndarray) -> tuple[str, str, VelocityFit | None]:
    """The tester's classification of the slider's trace <X>(t) after the ramp (status, reason,
    fit; :func:`dead_weight_attrs`); with the automatic length (``t_decide``) a window is steady
    if its velocity changes by at most DECIDE_DRIFT (instead of the tester's REL_TOL). A status
    ``runaway`` with a fit of status ``ok`` is a slider that slides steadily beyond the rising branch.
    ``cfg``: the run's config."""
    rel_tol = REL_TOL if cfg.t_decide is None else DECIDE_DRIFT
    fit = steady_velocity(time, X_mean, rel_tol) if time.size >= 20 else None
    status, reason = (fit.status, fit.reason) if fit else (VelocityStatus.NO_STEADY, "fewer than 20 samples after the ramp")
    v_branch = _beyond_branch(cfg)
    if fit and fit.status == VelocityStatus.OK and fit.velocity > v_branch:
        status = VelocityStatus.RUNAWAY
        reason = (f"runaway: the slider left the rising branch of mu(v) and slides at {fit.velocity:.3g} m/s "
                  f"(> {RUNAWAY_FACTOR:g} v0 10**delta = {v_branch:.3g} m/s), where only the contact damping "
                  "m eta_c u holds it")
    elif fit and fit.status == VelocityStatus.RUNAWAY and time.size >= 2:
        # "still rises" read over the fit's last window (its last 40 % of the record): a slider there slower on
        # average than v0 10**delta, the last contact's maximum of eq. (1), creeps on the rising branch, below the
        # maximum; its rise (a released top's ringing residual, or a creep that speeds up) is no runaway by itself
        i = int(np.searchsorted(time, window_start(time, N_STARTS - 1)))
        v_mean = (X_mean[-1] - X_mean[i]) / (time[-1] - time[i]) if i < time.size - 1 else float("nan")
        v_top = branch_scale(cfg)
        if v_mean < v_top:
            status = VelocityStatus.NO_STEADY
            reason = (f"no steady sliding: the slider creeps on the rising branch of mu(v) at {v_mean:.3g} m/s over "
                      f"the last {time[-1] - time[i]:.3g} s (< v0 10**delta = {v_top:.3g} m/s), not a runaway; "
                      f"the tester's fit: {fit.reason}")
    return str(VelocityStatus(status)), reason, fit


RUNAWAY_WINDOW = 0.02  # s: config stop_at_runaway reads the top's velocity over this last stretch of the record


def slowly_loaded(cfg) -> bool:
    """A dead-weight run with ``t_decide`` whose weight rises over at least half of it (``t_ramp``): read where
    it runs away as the weight rises. Anything faster is a release, after which the tester's heavy top
    overshoots and rings (docs/tester-3d)."""
    return cfg.t_decide is not None and cfg.t_ramp is not None and cfg.t_ramp >= 0.5 * cfg.t_decide


def runaway_window(cfg) -> float:
    """The stretch at the record's end that :func:`certain_runaway` reads (s): RUNAWAY_WINDOW for a slowly
    loaded run, two of the top's ringing periods for a release (:func:`~slipchain.model.system.top_ringing_period`)."""
    period = None if slowly_loaded(cfg) else top_ringing_period(cfg)
    return RUNAWAY_WINDOW if period is None else 2.0 * period


def _released_runaway(cfg, time: np.ndarray, X_mean: np.ndarray) -> str | None:
    """:func:`certain_runaway` for a released run on the slab's rigid top (issue 29's tester, the weight hanging
    at once or let go fast). The top rings on the rubber's shear with the period T of
    :func:`~slipchain.model.system.top_ringing_period`, through zero and far beyond the rising branch, so a
    short stretch cannot tell a runaway from an overshoot that comes back. Over a whole period the ringing
    cancels and the top's mean velocity is the interface's mean slip velocity (the layer's shear swings, it
    does not grow): a top whose mean velocity over each of the last two periods is beyond the rising branch
    (faster than RUNAWAY_FACTOR*v0*10**delta) and over the last at least RUNAWAY_RISE = 1.05 times as fast as
    over the one before slides, on average, where eq. (1)'s forces fall with velocity below a load that no longer
    grows, and cannot come back. The margin matters: eq. (1) falls slowly past its maximum (c = 0.1: a contact at
    ten times its vstar still carries 90 % of its peak) and the rubber's own dissipation rises with the slip rate, so
    a top just beyond the bound and barely faster can slow down and come back; one did (theta = 0.05 at 0.85,
    eta_c = 0.3 omega0, 16 x 16: 0.0352 then 0.0356 m/s at 0.18 s, slowing from 0.3 s, 0.028 m/s at 1.4 s,
    tester-16-long-etac-3-check), while every stored runaway was 4.1 % faster or more where the rule first read
    it beyond the bound (the slowest two, below 5 %, were stopped within a ringing period and ran away when run on:
    tester-16-long-etac-seeds-check). The first period after the ramp holds the release's own rise from rest (its mean velocity
    rises by construction), so the check starts at RING_START = 3 periods after the ramp: the two windows
    are the second and third periods. Measured on the stored release runs (16 x 16 to 128 x 128, three
    seeds, 20 and 11 deg C, eta_c 0.1, 0.3 and 1 omega0; docs/tester-3d "Stopping a released run early"): every
    held or steady run fails the test from 2.04 T on, every runaway passes it from 2.67 T on, and
    ``slipchain figure traces --redecide T --stop-at-runaway`` replays the rule on a store."""
    got = _period_velocities(cfg, time, X_mean)
    if got is None:
        return None
    v1, v2, period = got
    t = time[-1]
    v_branch = _beyond_branch(cfg)
    if not (v1 > v_branch and v2 > RUNAWAY_RISE * v1):
        return None
    return (f"runaway: by t = {t:.6g} s the released top slid at {v1:.3g} and then {v2:.3g} m/s over its last two "
            f"ringing periods ({period:.3g} s each; > {RUNAWAY_FACTOR:g} v0 10**delta = {v_branch:.3g} m/s, and "
            f"{RUNAWAY_RISE - 1:.0%} faster or more), "
            "beyond the maximum of mu(v) under a load that no longer grows: stopped there (stop_at_runaway)")


def rules_start(cfg) -> float | None:
    """The time (s) from which the released slab's stop rules (:func:`_released_runaway`, :func:`certain_held`)
    read the top's ringing periods: RING_START periods after the ramp; None where there is no such top."""
    period = top_ringing_period(cfg)
    return None if period is None else (dead_weight_ramp_time(cfg) or 0.0) + RING_START * period


def _period_velocities(cfg, time: np.ndarray, X_mean: np.ndarray,
                       early: bool = False) -> tuple[float, float, float] | None:
    """The top's mean velocities over the record's last two ringing periods (the one before the last, the
    last) and that period, once the record reaches RING_START periods after the ramp (``early``: once it
    holds two periods, for a look at a record the rules do not read yet); else None."""
    period = top_ringing_period(cfg)
    if period is None or time.size < 3:
        return None
    first = 2.0 * period * (1.0 - 1e-9) if early else (dead_weight_ramp_time(cfg) or 0.0) + RING_START * period * (1.0 - 1e-9)
    if time[-1] < first:
        return None
    t = time[-1]
    i0, i1 = np.searchsorted(time, (t - 2.0 * period * (1.0 + 1e-9), t - period * (1.0 + 1e-9)))
    if i1 <= i0 or i1 >= time.size - 1:
        return None
    return ((X_mean[i1] - X_mean[i0]) / (time[i1] - time[i0]), (X_mean[-1] - X_mean[i1]) / (t - time[i1]), period)


def certain_held(cfg, time: np.ndarray, X_mean: np.ndarray) -> str | None:
    """Config ``stop_when_held``: whether the released slab's top is back on the rising branch of mu(v) for good,
    and why (None if it is not). Its mean velocity over each of its last two ringing periods
    (:func:`~slipchain.model.system.top_ringing_period`; the ringing cancels over a period, as in
    :func:`_released_runaway`) is below v0 10**delta, the last contact's maximum of eq. (1), and over the
    last period below the one before: the slider slides, on average, where the contacts' forces rise with
    velocity, and slows down under a load that no longer grows, towards the steady velocity where they carry
    it (or to rest), as every such run of the stored release runs did to t_max (docs/tester-3d "Stopping a
    released run early"). While the top still rings, its period mean carries a residual of the ringing (up to
    9e-4 m/s on the tester's 64 x 64 block, where the interface creeps at 2-6e-5 m/s), so the bound is what the
    rule rests on, and "slower" mostly reads that residual's decay. Checked from RING_START periods after the
    ramp on, as the runaway."""
    got = _period_velocities(cfg, time, X_mean)
    if got is None:
        return None
    v1, v2, period = got
    v_top = branch_scale(cfg)
    if not (v1 < v_top and v2 < v1):
        return None
    return (f"held: by t = {time[-1]:.6g} s the released top slid at {v1:.3g} and then {v2:.3g} m/s over its last two "
            f"ringing periods ({period:.3g} s each; < v0 10**delta = {v_top:.3g} m/s, and slower): back on the rising "
            "branch of mu(v) under a load that no longer grows, below the maximum: stopped there (stop_when_held)")


def certain_runaway(cfg, time: np.ndarray, X_mean: np.ndarray) -> str | None:
    """Config ``stop_at_runaway``: whether the record's last RUNAWAY_WINDOW says the slider has run away
    for good before ``t_decide`` (while the weight still rises, or after), and why (None if it does not).
    The top's mean velocity over each half of that stretch is beyond the rising branch
    (faster than RUNAWAY_FACTOR*v0*10**delta, the bound :func:`accelerating_beyond_branch` uses) and
    over the second half faster than over the first: under a load that only grows or stays, such a slider cannot come back
    (the argument of :func:`accelerating_beyond_branch`). A released run (not :func:`slowly_loaded`) on the
    slab's rigid top is read over its last two ringing periods instead (:func:`_released_runaway`).
    ``time``, ``X_mean``: the record so far (only its last :func:`runaway_window` is read)."""
    if time.size < 3:
        return None
    if not slowly_loaded(cfg):
        return _released_runaway(cfg, time, X_mean)
    start = np.searchsorted(time, time[-1] - RUNAWAY_WINDOW * (1.0 + 1e-9))
    t, x = time[start:], X_mean[start:]
    if t.size < 3 or t[-1] - t[0] < 0.5 * RUNAWAY_WINDOW:
        return None
    mid = t.size // 2
    v, v1, v2 = ((x[b] - x[a]) / (t[b] - t[a]) for a, b in ((0, -1), (0, mid), (mid, -1)))
    v_branch = _beyond_branch(cfg)
    if not (v1 > v_branch and v2 > v1):  # beyond the branch over the whole stretch, and faster in its second half
        return None
    return (f"runaway: by t = {time[-1]:.6g} s the slider slid at {v:.3g} m/s over the last {RUNAWAY_WINDOW:g} s "
            f"(> {RUNAWAY_FACTOR:g} v0 10**delta = {v_branch:.3g} m/s) and still accelerated ({v1:.3g} -> {v2:.3g} m/s), "
            "beyond the maximum of mu(v) under a load that does not fall: stopped there (stop_at_runaway)")


DECIDE_DRIFT = 0.05  # dead-weight automatic length: a steady window may change its velocity by at most this
# (the tester's REL_TOL is 1 %; under a dead weight the model creeps towards its steady velocity with a
# relaxation time of ~0.1-0.3 s at theta = 0.1-0.2, and 1 % would need seconds of simulated time)


def velocity_decided(status: str, fit: VelocityFit | None) -> bool:
    """The dead-weight automatic length's stop rule (config ``t_decide``): the tester's ``ok`` with
    a velocity change across the steady window of at most DECIDE_DRIFT (the tester alone accepts
    any change that is not significant, which a short, noisy record allows), or a slider that
    slides beyond the rising branch (``runaway`` with a steady fit; still accelerating beyond it:
    :func:`accelerating_beyond_branch`)."""
    if fit is None:
        return False
    if status == VelocityStatus.OK:
        return abs(fit.change) <= DECIDE_DRIFT
    return status == VelocityStatus.RUNAWAY and fit.status == VelocityStatus.OK


def accelerating_beyond_branch(cfg, time: np.ndarray, X_mean: np.ndarray, fit: VelocityFit | None) -> bool:
    """The dead-weight automatic length's early runaway: the tester's fit says the slider still
    accelerates (``runaway`` without a steady window) and its mean velocity over the last tenth of the
    trace after the ramp is already beyond the rising branch (faster than RUNAWAY_FACTOR*v0*10**delta).
    Under the constant load after the ramp such a slider cannot come back: there eq. (1)'s forces are
    far below the load, and it accelerates until the contact damping m*eta_c*u alone balances it. Its
    classification at t_max would be ``runaway`` too (still accelerating, or steady beyond the branch),
    so the run stops here (on the tester's block a runaway's fast sliding cost most of a run)."""
    if fit is None or fit.status != VelocityStatus.RUNAWAY or time.size < 20:
        return False
    last = time >= time[0] + 0.9 * (time[-1] - time[0])
    if last.sum() < 2:
        return False
    tl, xl = time[last], X_mean[last]
    return bool((xl[-1] - xl[0]) / (tl[-1] - tl[0]) > _beyond_branch(cfg))


def dead_weight_status(cfg, time: np.ndarray, X_mean: np.ndarray) -> tuple[str, str, VelocityFit | None]:
    """The velocity status, its reason and the tester's fit that a dead-weight run records for its
    whole record <X>(t) (``time`` and ``X_mean`` from the first sample on; the classification reads the
    samples after the force ramp, :func:`after_ramp`): :func:`dead_weight_velocity`; with the automatic
    length (``t_decide``) an ``ok`` that still drifts by more than DECIDE_DRIFT is ``no-steady``, and a
    run that stopped before ``t_decide`` at a certain runaway (config ``stop_at_runaway``,
    :func:`certain_runaway`) is ``runaway``. The run's attrs (:func:`dead_weight_attrs`) and the replay of
    the automatic length on a stored record (:func:`slipchain.analysis.traces.redecide`) both read it."""
    after = after_ramp(cfg, time)
    status, reason, fit = dead_weight_velocity(cfg, time[after], X_mean[after])
    if cfg.t_decide is not None and status == VelocityStatus.OK and not velocity_decided(status, fit):
        status = str(VelocityStatus.NO_STEADY)
        reason = (f"no steady sliding by t_max = {cfg.t_max:g} s: the velocity still changes by {fit.change:+.1%} "
                  f"across the best window (automatic length: at most {DECIDE_DRIFT:.0%}); {fit.reason}")
    stopped = (certain_runaway(cfg, time, X_mean) if cfg.stop_at_runaway and time.size
               and time[-1] < cfg.t_decide - 0.5 * cfg.output_interval else None)
    if stopped is not None:  # the run stopped before t_decide at a certain runaway (control.UntilDecided)
        status, reason, fit = str(VelocityStatus.RUNAWAY), stopped, None
    held = (certain_held(cfg, time, X_mean) if cfg.stop_when_held and status != VelocityStatus.RUNAWAY and time.size
            and cfg.t_decide - 0.5 * cfg.output_interval <= time[-1] < cfg.t_max - 0.5 * cfg.output_interval else None)
    if held is not None and status != VelocityStatus.OK:  # stopped at a decision once back on the branch for good
        status, reason = str(VelocityStatus.NO_STEADY), f"{held}; {reason}"
    return status, reason, fit


def dead_weight_attrs(system: System, time: np.ndarray, X_mean: np.ndarray) -> dict[str, Any]:
    """Dead-weight drive: the applied mu_star, and the velocity measured from the slider's position
    trace <X>(t) after the force ramp (``time``, ``X_mean``: the whole record), exactly as the friction
    tester measures it (:func:`slipchain.results.velocity.steady_velocity`; :func:`dead_weight_status`).

    ``runaway``: still accelerating at the end, or sliding faster than RUNAWAY_FACTOR*v0*10**delta:
    above the maximum of mu(v) the model slider does not stop accelerating until the contact
    damping m*eta_c*u alone balances the load, at about a metre per second (with eta_c = 0 it never
    stops).

    With the automatic length (``t_decide``) a run that reached ``t_max`` undecided
    (:func:`velocity_decided`) while the tester would call it ``ok`` is ``no-steady``: its velocity
    still drifted by more than DECIDE_DRIFT across the window (the reason says by how much)."""
    cfg = system.config
    status, reason, fit = dead_weight_status(cfg, time, X_mean)
    ok = status == VelocityStatus.OK
    return {
        "drive": "dead-weight",
        "mu_star": float(cfg.dead_weight),
        "mu_star_sem": 0.0,
        "dead_weight_force": dead_weight_force(system),
        "velocity": fit.velocity if ok else np.nan,
        "velocity_sem": fit.sem if ok else np.nan,
        "velocity_status": status,
        "velocity_reason": reason,
    }


def summary(ds: xr.Dataset) -> dict[str, Any]:
    """The run's headline numbers (:data:`SUMMARY_KEYS`) as plain Python values (the CLI's --json)."""
    out: dict[str, Any] = {}
    for key in SUMMARY_KEYS:
        if key.startswith("velocity") and key not in ds.attrs:
            continue
        v = ds.attrs.get(key)
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, float) and not np.isfinite(v):
            v = None
        out[key] = v
    return out


__all__ = ["DECIDE_DRIFT", "RUN_ATTRIBUTES", "RUN_VARIABLES", "RUNAWAY_FACTOR", "RUNAWAY_RISE", "SUMMARY_KEYS", "SWEEP_VARIABLES", "Entry", "Recording",
           "Status", "accelerating_beyond_branch", "certain_runaway", "after_ramp", "branch_scale", "rules_start", "assemble_run", "contacts_over_whole_run", "dead_weight_attrs", "dead_weight_velocity", "velocity_decided", "schema_markdown", "summary"]

if __name__ == "__main__":  # pragma: no cover - regenerates docs/run-schema.md
    print(schema_markdown(), end="")

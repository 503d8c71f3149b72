"""Run one realisation: compiled chunks, observables between chunks, checks, an xarray result.

Loop order (each chunk): the backend advances ``chunk`` samples of ``sample_steps`` steps each
in compiled code, accumulating per sample the mean driving force f_d and the mean layer
displacements, and per contact the sums of force, velocity, velocity squared and slow steps.
Python then (1) appends these, (2) stops with status ``diverged`` if a row went non-finite,
(3) in automatic mode, estimates mu_star on what has been sampled so far (MSER transient, batch
means) and stops once its standard error is below ``sem_target``, the steady window shows no
drift and the drive has moved at least MIN_STEADY_SLIDE (1 um) through it, or at ``t_max``.
After the loop: energy balance and displacement checks, then the Dataset.

mu_star = <f_d>_t / (epsilon*f0*theta), theta = N_c/N (MODEL.md, "Start and measurement").
"""

from __future__ import annotations

import sys
import time as _time
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
import xarray as xr

from . import kernel as K
from ._version import __version__
from .backend import SLOW_FRACTION, Batch, dead_weight_force, get_backend
from .checks import DISPLACEMENT_RTOL, CheckResult, displacement_check, energy_check, stored_energy
from .config import Config, make_config
from .observables import steady_estimate
from .system import State, System, build_system, initial_state

CHUNK_TIME = 5e-4  # simulated seconds per compiled chunk (about 25 000 steps at the default dt)
MIN_STEADY_SAMPLES = 400  # automatic mode: at least this many steady samples before stopping
MIN_STEADY_SLIDE = 1e-6  # ...and a steady window in which the drive has moved at least this far (m):
# at very low v_d a steady start can look converged (tiny SE, no drift) long before it has settled
DEAD_WEIGHT_RAMP = 0.25  # dead-weight drive: the force rises linearly over this fraction of the run
RUNAWAY_FACTOR = 10.0  # dead-weight drive: faster than this times v0*10**delta is off the rising branch

COMPLETED, DIVERGED, INTERRUPTED = "completed", "diverged", "interrupted"


@dataclass
class _Recorder:
    """Collects chunk outputs of one realisation."""

    samples: list[np.ndarray] = field(default_factory=list)
    contact_sums: list[np.ndarray] = field(default_factory=list)
    chunk_starts: list[int] = field(default_factory=list)
    works: np.ndarray = field(default_factory=lambda: np.zeros(K.N_ACC))
    n: int = 0

    def add(self, out: np.ndarray, acc: np.ndarray, cacc: np.ndarray) -> None:
        self.chunk_starts.append(self.n)
        self.samples.append(out.copy())
        self.contact_sums.append(cacc.copy())
        self.works += acc
        self.n += out.shape[0]

    def series(self) -> np.ndarray:
        if not self.samples:
            return np.zeros((0, K.N_OUT))
        return np.concatenate(self.samples)


def mu_star_norm(system: System) -> float:
    """epsilon*f0*theta with the realised theta = N_c/N: f_d / this = mu_star.

    Without contacts mu_star is undefined; the series is then normalised by epsilon*f0 alone
    (for the transient and error estimates) and mu_star is reported as NaN.
    """
    cfg = system.config
    return cfg.epsilon * cfg.f0 * (system.theta_realised if system.n_contacts else 1.0)


def run(config: Config | Mapping[str, Any] | None = None, *, progress: bool | None = None) -> xr.Dataset:
    """Run the model for ``config`` (a Config, a mapping of overrides, or None for defaults)."""
    cfg = config if isinstance(config, Config) else make_config(dict(config or {}))
    return simulate(build_system(cfg), progress=progress)


def simulate(system: System, state: State | None = None, *, progress: bool | None = None) -> xr.Dataset:
    """Integrate one realisation from ``state`` (default: the config's start) to a result Dataset."""
    return simulate_batch([system], None if state is None else [state], progress=progress)[0]


@dataclass
class _Row:
    """The run control of one realisation of a batch."""

    system: System
    e0: float
    norm: float
    limit: int
    auto: bool
    f_b: float
    x0_mean: float
    rec: _Recorder = field(default_factory=_Recorder)
    active: bool = True
    status: str = COMPLETED
    message: str = ""
    sem_reached: bool = False
    sem: float = float("nan")


def simulate_batch(systems: list[System], states: list[State] | None = None, *,
                   progress: bool | None = None) -> list[xr.Dataset]:
    """Integrate several realisations together (one backend call advances all of them).

    They must share N, dt and the output interval (one kernel launch runs them in lock-step);
    each row has its own length control (fixed, automatic, dead-weight ramp) and stops on its
    own: a finished row is skipped by the kernel. On the GPU this is how a sweep fills the device.
    The wall time recorded for every row is the batch's.
    """
    cfg0 = systems[0].config
    for s in systems:
        c = s.config
        if (c.N, c.dt, c.sample_steps) != (cfg0.N, cfg0.dt, cfg0.sample_steps):
            raise ValueError("a batch needs equal N, dt and output_interval; got "
                             f"{(c.N, c.dt, c.output_interval)} and {(cfg0.N, cfg0.dt, cfg0.output_interval)}")
    backend = get_backend(cfg0.backend)
    states0 = [initial_state(s) if states is None or states[i] is None else states[i].copy()
               for i, s in enumerate(systems)]
    batch = Batch.pack(systems, states0)
    steps_per_sample = cfg0.sample_steps
    interval = steps_per_sample * cfg0.dt
    chunk = max(1, int(round(CHUNK_TIME / interval)))
    rows = []
    for s, st in zip(systems, states0):
        c = s.config
        dead_weight = c.dead_weight is not None  # fixed length (t_total, else t_max); velocity measured after
        rows.append(_Row(system=s, e0=stored_energy(s, st), norm=mu_star_norm(s),
                         limit=max(1, int(round((c.t_total if c.t_total is not None else c.t_max) / interval))),
                         auto=c.t_total is None and not dead_weight, f_b=dead_weight_force(s) if dead_weight else 0.0,
                         x0_mean=float(np.mean(st.x)), sem_reached=not (c.t_total is None and not dead_weight)))
    wall0 = _time.perf_counter()
    single = len(rows) == 1
    bar = _Progress(progress if single else False, rows[0].limit * interval, rows[0].auto)
    try:
        while any(r.active for r in rows):
            live = [i for i, r in enumerate(rows) if r.active]
            n = min(chunk, min(rows[i].limit - rows[i].rec.n for i in live))
            f_now = np.zeros(len(rows))
            sum_x0 = batch.X.sum(axis=1)
            for i in live:  # dead weight: F_b ramps up over the first DEAD_WEIGHT_RAMP of the run, a sample at a time
                r = rows[i]
                if r.system.config.dead_weight is not None:
                    n_ramp = max(1, int(round(DEAD_WEIGHT_RAMP * r.limit)))
                    f_now[i] = r.f_b * min(1.0, (r.rec.n + 1) / n_ramp)
                    batch.params[i, K.P_FCONST] = f_now[i]
                    if r.rec.n < n_ramp:
                        n = 1
            co = backend.advance(batch, n, steps_per_sample)
            co.acc[:, K.A_WDRIVE] += f_now * (batch.X.sum(axis=1) - sum_x0)  # work of the constant forces
            for i in live:
                r = rows[i]
                nc = r.system.n_contacts
                r.rec.add(co.out[i], co.acc[i], co.cacc[i, :, :nc].T)
                cfg = r.system.config
                if batch.status[i] >= 0:
                    step = int(batch.status[i])
                    r.status, r.active = DIVERGED, False
                    r.message = f"non-finite state at step {step} (t = {step * cfg.dt:.6e} s)"
                    continue
                if r.auto:
                    series = r.rec.series()
                    est = steady_estimate(series[:, K.O_FD] / r.norm)
                    r.sem = est.sem
                    if (est.n_samples >= MIN_STEADY_SAMPLES and est.drift_ok and est.sem <= cfg.sem_target
                            and est.n_samples * interval * cfg.v_d >= MIN_STEADY_SLIDE
                            and _follows_drive(series, est.start, r.x0_mean, interval, cfg.v_d)):
                        r.sem_reached = True
                        r.active = False
                if r.rec.n >= r.limit:
                    r.active = False
                if not r.active:
                    batch.status[i] = batch.step[i]  # finished: the kernel skips this row from now on
            bar.update(rows[0].rec.n * interval, rows[0].sem, _time.perf_counter() - wall0)
    except KeyboardInterrupt:
        for r in rows:
            if r.active:
                r.status, r.active = INTERRUPTED, False
                r.message = f"interrupted by the user at t = {r.rec.n * interval:.6e} s"
    finally:
        bar.close()
    wall = _time.perf_counter() - wall0
    results = []
    for i, r in enumerate(rows):
        cfg = r.system.config
        if r.auto and r.status == COMPLETED and not r.sem_reached:
            r.message = (f"t_max = {cfg.t_max:g} s reached before the standard error fell below "
                         f"sem_target = {cfg.sem_target:g}")
        results.append(_assemble(r.system, r.rec, batch.state(i), r.x0_mean, r.e0, r.norm, interval, steps_per_sample,
                                 r.status, r.message, r.sem_reached, wall))
    return results


def _window_velocity(series: np.ndarray, start: int, x0_mean: float, interval: float) -> float:
    """Mean interface-layer velocity from sample ``start`` to the end of ``series``."""
    x_start = series[start - 1, K.O_XMEAN] if start > 0 else x0_mean
    return float((series[-1, K.O_XMEAN] - x_start) / ((series.shape[0] - start) * interval))


def _follows_drive(series: np.ndarray, start: int, x0_mean: float, interval: float, v_d: float) -> bool:
    """Automatic stop only once the window is past loading: the slider moves at v_d within half
    the tolerance of the after-run displacement check."""
    return abs(_window_velocity(series, start, x0_mean, interval) / v_d - 1.0) <= 0.5 * DISPLACEMENT_RTOL


def _assemble(system: System, rec: _Recorder, final: State, x0_mean: float, e0: float, norm: float, interval: float,
              steps_per_sample: int, status: str, message: str, sem_reached: bool, wall: float) -> xr.Dataset:
    cfg = system.config
    series = rec.series()
    fd = series[:, K.O_FD]
    n = fd.size
    est = steady_estimate(fd / norm) if n else None
    start = est.start if est else 0
    checks: list[CheckResult] = []
    if status != DIVERGED and n:
        checks.append(energy_check(stored_energy(system, final) - e0, *rec.works))
        if est is not None and est.n_samples >= 2 and cfg.dead_weight is None:
            checks.append(displacement_check(_window_velocity(series, start, x0_mean, interval), cfg.v_d))
        failed = [c for c in checks if not c.passed]
        if failed and status == COMPLETED:
            status = DIVERGED
            message = "physics check failed at the end of the run (t = %.6e s): %s" % (
                n * interval, "; ".join(c.message for c in failed))

    # Per-contact averages over the chunks that lie wholly in the steady window.
    sums = np.zeros((system.n_contacts, K.N_CACC))
    steady_steps = 0
    for s0, cs, smp in zip(rec.chunk_starts, rec.contact_sums, rec.samples):
        if s0 >= start:
            sums += cs
            steady_steps += smp.shape[0] * steps_per_sample
    with np.errstate(invalid="ignore", divide="ignore"):
        denom = steady_steps if steady_steps else np.nan
        f_mean = sums[:, K.C_F] / denom
        u_mean = sums[:, K.C_U] / denom
        u_std = np.sqrt(np.maximum(sums[:, K.C_U2] / denom - u_mean**2, 0.0))
        slow = sums[:, K.C_SLOW] / denom

    time = (np.arange(n) + 1) * interval
    ds = xr.Dataset(
        data_vars={
            "f_d": ("time", fd, {"units": "N", "long_name": "driving force per block f_d, mean over the output interval ending at time"}),
            "x_mean": ("time", series[:, K.O_XMEAN], {"units": "m", "long_name": "mean interface-layer displacement"}),
            "X_mean": ("time", series[:, K.O_XUMEAN], {"units": "m", "long_name": "mean upper-layer displacement"}),
            "contact_site": ("contact", system.contact_sites, {"long_name": "interface block carrying the contact"}),
            "vstar": ("contact", system.vstar, {"units": "m/s", "long_name": "contact velocity scale v*_i"}),
            "contact_force_mean": ("contact", f_mean, {"units": "N", "long_name": "time-averaged contact force, steady window"}),
            "contact_velocity_mean": ("contact", u_mean, {"units": "m/s"}),
            "contact_velocity_std": ("contact", u_std, {"units": "m/s"}),
            "contact_slow_fraction": ("contact", slow, {"long_name": f"fraction of steady steps with |u| < {SLOW_FRACTION:g} v_d"}),
            "x": ("block", final.x, {"units": "m", "long_name": "final interface-layer displacements"}),
            "u": ("block", final.u, {"units": "m/s", "long_name": "final interface-layer velocities"}),
            "X": ("block", final.X, {"units": "m", "long_name": "final upper-layer displacements"}),
            "U": ("block", final.U, {"units": "m/s", "long_name": "final upper-layer velocities"}),
        },
        coords={"time": ("time", time, {"units": "s"}), "contact": np.arange(system.n_contacts), "block": np.arange(cfg.N)},
    )
    attrs: dict[str, Any] = {
        "title": "slipchain two-chain friction model run",
        "slipchain_version": __version__,
        "status": status,
        "message": message,
        "config": cfg.to_toml(),
        "seed": cfg.seed,
        "mu_star": est.mean if est and system.n_contacts else np.nan,
        "mu_star_sem": est.sem if est and system.n_contacts else np.nan,
        "t_transient": start * interval,
        "t_steady": (n - start) * interval,
        "sem_target_reached": int(sem_reached),
        "theta": system.theta_realised,
        "n_contacts": system.n_contacts,
        "N": cfg.N,
        "v_d": cfg.v_d,
        "eta_c": cfg.eta_c,
        "epsilon": cfg.epsilon,
        "dt": cfg.dt,
        "t_total": n * interval,
        "steps": int(final.step),
        "wall_time_s": wall,
        "mu_star_norm": norm,
        "W_drive": rec.works[K.A_WDRIVE],
        "W_damping": rec.works[K.A_WDAMP],
        "W_contacts": rec.works[K.A_WCONTACT],
    }
    if cfg.dead_weight is not None:
        after = time > DEAD_WEIGHT_RAMP * time[-1] if n else np.zeros(0, bool)
        attrs.update(_dead_weight_attrs(system, time[after], series[after, K.O_XUMEAN]))
    for c in checks:
        attrs[f"check_{c.name}"] = c.value
        attrs[f"check_{c.name}_passed"] = int(c.passed)
    ds.attrs.update(attrs)
    return ds


def _dead_weight_attrs(system: System, time: np.ndarray, X_mean: np.ndarray) -> dict[str, Any]:
    """Dead-weight drive: the applied mu_star, and the velocity measured from the slider's position
    trace <X>(t) after the force ramp, exactly as the friction tester measures it
    (:func:`slipchain.tester.velocity.steady_velocity`).

    The force rises linearly over the first quarter of the run (a heavy slider accepts its load
    gradually; a step load makes the light model slider overshoot past the maximum of mu(v)).
    ``runaway``: still accelerating at the end, or sliding faster than RUNAWAY_FACTOR*v0*10**delta:
    above the maximum of mu(v) the model slider does not stop accelerating until the contact
    damping m*eta_c*u alone balances the load, at about a metre per second (with eta_c = 0 it never
    stops)."""
    from .tester.velocity import steady_velocity

    cfg = system.config
    fit = steady_velocity(time, X_mean) if time.size >= 20 else None
    status, reason = (fit.status, fit.reason) if fit else ("no-steady", "fewer than 20 samples after the ramp")
    v_branch = RUNAWAY_FACTOR * cfg.v0 * 10.0**cfg.delta  # far above the last contact's maximum
    if fit and fit.status == "ok" and fit.velocity > v_branch:
        status = "runaway"
        reason = (f"runaway: the slider left the rising branch of mu(v) and slides at {fit.velocity:.3g} m/s "
                  f"(> {RUNAWAY_FACTOR:g} v0 10**delta = {v_branch:.3g} m/s), where only the contact damping "
                  "m eta_c u holds it")
    return {
        "drive": "dead-weight",
        "mu_star": float(cfg.dead_weight),
        "mu_star_sem": 0.0,
        "dead_weight_force": dead_weight_force(system),
        "velocity": fit.velocity if status == "ok" else np.nan,
        "velocity_sem": fit.sem if status == "ok" else np.nan,
        "velocity_status": status,
        "velocity_reason": reason,
    }


SUMMARY_KEYS = ("mu_star", "mu_star_sem", "theta", "n_contacts", "N", "v_d", "eta_c", "epsilon", "seed",
                "dt", "t_total", "t_transient", "steps", "wall_time_s", "status", "message", "velocity",
                "velocity_sem", "velocity_status")


def summary(ds: xr.Dataset) -> dict[str, Any]:
    """The run's headline numbers as plain Python values (the CLI's --json)."""
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


class _Progress:
    """A rich progress bar, shown on a terminal once a run has taken more than a few seconds."""

    def __init__(self, enabled: bool | None, total_time: float, auto: bool):
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.total = total_time
        self.auto = auto
        self._bar = None
        self._task = None

    def update(self, t: float, sem: float, elapsed: float) -> None:
        if not self.enabled or elapsed < 2.0:
            return
        if self._bar is None:
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            self._bar = Progress(TextColumn("[bold]slipchain run"), BarColumn(),
                                 TextColumn("{task.completed:.4f}/{task.total:.4f} s simulated"),
                                 TextColumn("{task.fields[info]}"), TimeElapsedColumn(), TimeRemainingColumn())
            self._bar.start()
            label = "up to t_max; stops at sem_target" if self.auto else ""
            self._task = self._bar.add_task("run", total=self.total, info=label)
        info = f"SE(mu*) = {sem:.4f}" if np.isfinite(sem) else ""
        self._bar.update(self._task, completed=t, info=info)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()

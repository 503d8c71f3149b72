"""Validated, frozen run configuration: every parameter of docs/model.md under its name, SI units.

A config is read from a flat TOML file and overridden by ``name=value`` strings (the CLI's
``--set``). Anything wrong (an unknown key, a non-number, a value out of range) raises
:class:`ConfigError`, whose message names the key, the value and what is allowed.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any, Literal, Mapping, Sequence

from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator, model_validator

from .contact_law import ContactLaw
from .geometries import geometry_of

# What each key accepts, in words; used in every error message.
ALLOWED: dict[str, str] = {
    "a": "a number > 0 (block size, m)",
    "rho": "a number > 0 (mass density, kg/m^3)",
    "E": "a number > 0 (Young modulus, Pa)",
    "nu": "a number in (-1, 0.5] (Poisson ratio)",
    "N_L": "an integer >= 1 (upper-layer height in blocks)",
    "N": "an integer >= 3 (blocks per chain; blocks along the sliding direction x, Lx, in 2-D)",
    "Ly": "an integer >= 1 (blocks across the sliding direction, y; 1 for the chain)",
    "geometry": "one of 'chain', 'chain2d', 'slab', 'halfspace'",
    "integrator": "one of 'adaptive' (the default: fold-aware contacts and a step that doubles up to the stable "
                  "step), 'fixed' (dt below the unique-root limit), 'fold' (fold-aware contacts, issue 12), "
                  "'implicit' (the adaptive step, and backward Euler through creep above the stable step; issue 27)",
    "step_tol": "a number > 0 (integrator = 'adaptive' or 'implicit': largest local velocity error per step, in "
                "units of v_d)",
    "krylov_preconditioner": "one of 'jacobi' (the default: the diagonal), 'additive' (by site: the diagonal on "
                             "the contact blocks, the body's (chain2d: both layers') exact Fourier inverse on "
                             "the free ones; fewer conjugate-gradient iterations at low load, each dearer), only with "
                             "integrator = 'implicit' on the slab, half-space or chain2d",
    "energy_tol": "a number in (0, 0.1] (integrator = 'implicit': largest energy residual of a backward-Euler step, "
                  "its numerical dissipation, as a fraction of the magnitudes of the step's works; default 1e-4)",
    "implicit_scheme": "one of 'backward-euler' (the default) or 'trbdf2' (the second-order L-stable TR-BDF2 step "
                       "above the explicit levels; only with integrator = 'implicit' on the slab, half-space or "
                       "chain2d with material = 'elastic')",
    "min_cycles": "an integer >= 0 (automatic length: slip cycles the steady window must hold; 0 for none)",
    "tau_f": "a number > 0 (frictional shear stress, Pa)",
    "c": "a number >= 0",
    "v0": "a number > 0 (m/s)",
    "delta": "a number >= 0 (decades)",
    "epsilon": "a number > 0",
    "eta": "a number >= 0 (1/s)",
    "eta_c": "a number >= 0 (1/s)",
    "theta": "a number in (0, 1]",
    "v_d": "a number > 0 (m/s)",
    "start": "one of 'rest', 'steady'",
    "dead_weight": "a number > 0 (applied force per block in units of epsilon*f0*theta), or absent for the spring drive",
    "top_mass": "a number > 0 (kg per interface block: what the slab's rigid top carries besides the slab, the "
                "plate and what sits on it), or 'tester' ((1 + dead_weight) theta p_theta1 a**2 / g: the normal load's "
                "mass and the hanging weight, issue 29), only with dead_weight on the slab; or absent (the slab alone)",
    "p_theta1": "a number > 0 (Pa: the nominal pressure theta = 1 stands for), only with top_mass = 'tester'; or "
                "absent (epsilon tau_f: the model's own normal stress, whose force mu_star is normalised by)",
    "dt": "a number > 0 (s), or absent for the default of the integrator (Config.default_dt)",
    "t_total": "a number > 0 (s), or absent for an automatic run length",
    "t_max": "a number > 0 (s)",
    "t_max_cycles": "a number >= 0 (s): the cap of the automatic length of a run that stick-slips as a whole in "
                    "cycles as long as the run follows its cycles up to this (0: no extension past t_max); more than "
                    "t_max, absent with t_total or dead_weight",
    "t_decide": "a number > 0 (s), less than t_max, only with dead_weight and without t_total; or absent",
    "t_ramp": "a number > 0 (s), only with dead_weight, shorter than t_decide (else than the run); or absent",
    "stop_at_runaway": "true or false (only with dead_weight, t_decide and t_ramp >= t_decide/2, or with dead_weight, "
                       "t_decide and geometry = 'slab' for a release: stop before t_decide once the slider has run "
                       "away for good, its velocity over each half of the last 20 ms, or over each of the slab top's "
                       "last two ringing periods from three after the ramp, beyond 10 v0 10**delta and rising)",
    "stop_when_held": "true or false (only with dead_weight, t_decide and geometry = 'slab': from t_decide on, and "
                      "three of the slab top's ringing periods after the ramp, stop once the top's mean velocity over "
                      "each of its last two ringing periods is below v0 10**delta, the rising branch's top, and falls)",
    "sem_target": "a number > 0",
    "output_interval": "a number > 0 (s), at least dt",
    "seed": "an integer >= 0",
    "material": "one of 'elastic' (the paper's springs, with the pair damping eta), 'prony' (a viscoelastic bulk: "
                "a Prony series, issue 28; the chains)",
    "prony_E": "a list of numbers > 0 (Pa): the Maxwell arms' moduli E_j (material = 'prony'; absent: the default "
               "compound, slipchain.model.viscoelastic)",
    "prony_tau": "a list of numbers > 0 (s), as long as prony_E: the relaxation times tau_j at T_ref",
    "temperature": "a number (°C), with material = 'prony' (absent: T_ref), where C2 + T - T_ref > 0",
    "T_ref": "a number (°C): the temperature of prony_tau (material = 'prony'; absent: 20)",
    "wlf_C1": "a number >= 0: WLF's C1 at T_ref (material = 'prony'; absent: the default compound's)",
    "wlf_C2": "a number > 0 (K): WLF's C2 at T_ref (material = 'prony'; absent: the default compound's)",
}
PRONY_KEYS = ("prony_E", "prony_tau", "temperature", "T_ref", "wlf_C1", "wlf_C2")

# Keys that older versions wrote into configs (stored run attrs, a store's sweep.toml) and that are
# no longer part of what is simulated. Accepted and dropped when reading stored files (legacy=True);
# rejected with this explanation in new input.
LEGACY_KEYS: dict[str, str] = {
    "backend": "how a run is executed is not part of what is simulated: give the backend to run(..., backend=...), "
               "simulate(), run_sweep() or the CLI's --backend instead",
}


# Keys added after 0.2, with the value that their absence meant before they existed: left out of sweep
# member ids at that value (so stores written before stay valid), filled in where a stored config
# (legacy=True) lacks them, and left out of the TOML text while that is also today's default.
# integrator: 'fixed' was the default until issue 26 made it 'adaptive'; a stored config or store
# without the key ran with the fixed step and keeps that meaning.
# t_max_cycles: 0 (no extension past t_max) until issue 26 made the automatic length follow slip cycles.
# krylov_preconditioner: 'jacobi', the implicit stepper's only preconditioner on the slab before it existed.
# energy_tol: ENERGY_TOL, the implicit stepper's fixed energy tolerance before it was a key.
# stop_at_runaway: False, a dead-weight run went on to t_decide before it existed.
# stop_when_held: False, a held dead-weight run went on to t_max before it existed.
# implicit_scheme: 'backward-euler', the implicit stepper's only step above the explicit levels before it existed.
ENERGY_TOL = 1e-4
OFF: dict[str, Any] = {"geometry": "chain", "Ly": 1, "integrator": "fixed", "step_tol": 0.01, "min_cycles": 0,
                       "t_max_cycles": 0.0, "material": "elastic", "krylov_preconditioner": "jacobi",
                       "energy_tol": ENERGY_TOL, "stop_at_runaway": False, "stop_when_held": False,
                       "implicit_scheme": "backward-euler"}
_NOT_OFF = object()

# The adaptive step's largest step stays below this fraction of the stable step (Config.dt_stable).
STABLE_FRACTION = 0.9
DEFAULT_DT_LEVELS = 2  # dt absent: the base step lies at least 2**2 below the adaptive step's ceiling
MAX_IMPLICIT_LEVELS = 24  # integrator = 'implicit': dt ... dt 2**24 (1.7 s at 1e-7 s), within a sample
STANDARD_GRAVITY = 9.80665  # m/s**2
PRONY_STEP_TOL = 1e-3  # material = 'prony', integrator = 'adaptive': the default step_tol (_prony_defaults says why)
MAX_STEP_LEVELS = 6  # integrator = 'adaptive': the step doubles at most this often (dt ... 64 dt)
# t_max_cycles absent: the automatic length of a run that stick-slips as a whole may follow its slip
# cycles up to this many seconds (the cap of presets/fig6-eps1.toml, 20 cycles of 1.1 s at epsilon = 1,
# theta = 1, v_d = v0, plus its transient); where it has no effect (a fixed length, a dead weight, or
# t_max already at least this), absent means 0.
DEFAULT_T_MAX_CYCLES = 30.0


class ConfigError(ValueError):
    """A rejected configuration; the message names key, value and what is allowed."""


class Config(BaseModel):
    """All parameters of one run (docs/model.md names; defaults are the paper's values).

    Model: ``a`` (a), ``rho`` (rho), ``E`` (E), ``nu`` (nu), ``N_L`` (N_L), ``N`` (N),
    ``tau_f`` (tau_f), ``c`` (c), ``v0`` (v_0), ``delta`` (delta), ``epsilon`` (varepsilon),
    ``eta`` (eta, 0.3*omega0), ``eta_c`` (eta_c; default 0.1*omega0), ``theta`` (theta),
    ``v_d`` (v, the drive velocity), ``start`` ('rest' or 'steady', docs/model.md, "Drive, start and measurement").
    ``dead_weight``: None (default) drives the upper layer through the springs K_d at v_d; a
    number mu_a replaces them by a constant force F_b = mu_a*epsilon*f0*theta on every upper block
    (a hanging weight, as in the experiment): mu_a is the applied mu_star, and the run measures
    the velocity (``v_d`` then only sets the steady start and the "slow" threshold).

    Run control: ``dt`` time step; ``t_total`` fixed run length, or None for automatic
    (run until the standard error of mu_star is below ``sem_target``, at most ``t_max``);
    ``t_decide`` (dead-weight drive only, with ``t_total`` absent): the dead-weight automatic
    length: the force ramps up over DEAD_WEIGHT_RAMP*t_decide, the velocity is first classified at
    t_decide, and the run goes on while it still drifts (neither steady nor beyond the rising
    branch), at most ``t_max`` (:class:`slipchain.engine.control.UntilDecided`); ``t_ramp``
    (dead weight only): the duration of the force's linear ramp instead of a quarter of
    ``t_decide`` (or of the run). The ramp must be slow against the creep relaxation, or the
    slider overshoots past the maximum (docs/guide/mechanism.md);
    ``integrator``: 'adaptive' (the default since issue 26: the fold scheme with a step dt*2**k up
    to 0.9 of the stable step, error-controlled by ``step_tol`` in units of v_d:
    :mod:`slipchain.engine.backends.adaptive`), 'fixed' (the scheme of slipchain.engine.scheme, dt
    below the unique-root limit; the default before, and what a stored config without the key
    means), 'fold' (fold-aware contacts: dt bounded by the explicit springs and dampers only) or
    'implicit' (issue 27: the adaptive step up to its top level, and above it backward Euler with
    springs, damping and contacts implicit while every contact is on the rising branch of eq. (1),
    the step bounded by ``step_tol`` and the output samples alone, up to dt 2**24:
    :mod:`slipchain.engine.backends.implicit`; every geometry and material: with 'prony' the Maxwell
    arms are in the backward-Euler system and the explicit steps are the fold step at dt);
    ``krylov_preconditioner`` (integrator = 'implicit' on the slab, half-space and chain2d): 'jacobi' (the
    default) or 'additive', the conjugate gradients' preconditioner in each backward-Euler solve
    (:meth:`slipchain.engine.backends.implicit.SlabSystem.precondition`,
    :meth:`slipchain.engine.backends.implicit.LatticeSystem.precondition`);
    ``stop_at_runaway`` (dead weight with ``t_decide`` and a ramp ``t_ramp`` of at least half of it: a
    slowly loaded run; or on the slab, released: with the weight at once or released within a few of the
    tester top's ringing periods the top overshoots to 0.03-0.15 m/s and comes back, docs/tester-3d): the run
    stops before ``t_decide`` once the slider has run away for good
    (:func:`slipchain.results.schema.certain_runaway`: the top's velocity over each half of the last 20 ms,
    or, released, over each of the top's last two ringing periods from three periods after the ramp on,
    beyond RUNAWAY_FACTOR v0 10**delta and rising), classified ``runaway``; for runs that read mu_max where
    the block runs away as the weight rises, or bracket it where a released block runs away (the runaway
    after it costs most of such a run and tells nothing more);
    ``stop_when_held`` (dead weight with ``t_decide`` on the slab): the run stops at a decision from
    ``t_decide`` on once the released top is back on the rising branch for good
    (:func:`slipchain.results.schema.certain_held`: its mean velocity over each of its last two ringing
    periods below v0 10**delta and falling), instead of going on to ``t_max`` while it creeps or rings;
    for runs that bracket mu_max (the tester's ringing top at theta = 1 costs most of such a run);
    ``energy_tol`` (integrator = 'implicit'): a backward-Euler step is accepted only if its energy
    residual (its numerical dissipation) is at most this fraction of the magnitudes of its works, and
    the step doubles only below half of it (default ENERGY_TOL = 1e-4, the value before it was a key;
    where the heavy tester top creeps under a slowly rising weight this, not ``step_tol``, bounds the
    step: docs/numerics.md);
    ``implicit_scheme`` (integrator = 'implicit' on the slab, half-space and chain2d, material 'elastic'):
    'backward-euler' (the default) or 'trbdf2', the step taken above the explicit levels: TR-BDF2
    (a trapezoidal stage to t + gamma h, then BDF2 to t + h, gamma = 2 - sqrt(2); second order and
    L-stable, its numerical dissipation of a resolved oscillation ~ (h omega)**4 against backward
    Euler's (h omega)**2), each stage a backward-Euler-like solve from a shifted base state
    (:func:`slipchain.engine.backends.implicit.krylov_trbdf2_try`; issue 27);
    ``dt`` absent: :attr:`default_dt`; every dt must lie below :attr:`dt_stable`;
    ``min_cycles``: the automatic length also needs this many cycles of f_d in its steady window
    (:class:`slipchain.engine.control.UntilConverged`; for the long slip cycles at epsilon = 1);
    ``t_max_cycles``: a run that reaches ``t_max`` unconverged with fewer than FEW_CYCLES slip cycles in
    its steady window (the whole interface stick-slipping in cycles as long as the run) goes on, its
    cap following its cycles (``min_cycles``, else DEFAULT_MIN_CYCLES, plus two), at most this
    (:meth:`slipchain.engine.control.RowControl.extend`); absent: DEFAULT_T_MAX_CYCLES where it can
    act, else 0 (no extension; also what a stored config without the key means);
    ``output_interval`` sampling interval of f_d(t) (each sample is the average over the
    interval); ``seed`` for the disorder. Where a run is executed (CPU or GPU) is not part of the
    config: it is an argument of :func:`slipchain.run` and the CLI's ``--backend``.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)

    a: float = Field(1e-4, gt=0)
    rho: float = Field(1e3, gt=0)
    E: float = Field(1e7, gt=0)
    nu: float = Field(0.5, gt=-1, le=0.5)
    N_L: int = Field(5, ge=1)
    N: int = Field(301, ge=3)
    tau_f: float = Field(6.5e6, gt=0)
    c: float = Field(0.1, ge=0)
    v0: float = Field(1e-3, gt=0)
    delta: float = Field(0.5, ge=0)
    epsilon: float = Field(1e-2, gt=0)
    eta: float = Field(3e5, ge=0)
    eta_c: float = Field(1e5, ge=0)
    theta: float = Field(1.0, gt=0, le=1)
    v_d: float = Field(1e-3, gt=0)
    start: Literal["rest", "steady"] = "rest"
    dead_weight: float | None = Field(None, gt=0)
    top_mass: float | Literal["tester"] | None = None
    p_theta1: float | None = Field(None, gt=0)
    geometry: Literal["chain", "chain2d", "slab", "halfspace"] = "chain"
    Ly: int = Field(1, ge=1)
    integrator: Literal["fixed", "fold", "adaptive", "implicit"] = "adaptive"
    step_tol: float = Field(0.01, gt=0)
    krylov_preconditioner: Literal["jacobi", "additive"] = "jacobi"
    energy_tol: float = Field(ENERGY_TOL, gt=0, le=0.1)
    implicit_scheme: Literal["backward-euler", "trbdf2"] = "backward-euler"
    min_cycles: int = Field(0, ge=0)

    dt: float = Field(2e-8, gt=0)  # absent from the input: Config.default_dt (the 2e-8 is never used)
    t_total: float | None = Field(None, gt=0)
    t_max: float = Field(0.25, gt=0)
    t_max_cycles: float = Field(DEFAULT_T_MAX_CYCLES, ge=0)  # absent from the input: see _default_step
    t_decide: float | None = Field(None, gt=0)
    stop_at_runaway: bool = False
    stop_when_held: bool = False
    t_ramp: float | None = Field(None, gt=0)
    sem_target: float = Field(0.01, gt=0)
    output_interval: float = Field(1e-5, gt=0)
    seed: int = Field(0, ge=0)
    material: Literal["elastic", "prony"] = "elastic"
    prony_E: list[float] | None = None
    prony_tau: list[float] | None = None
    temperature: float | None = None
    T_ref: float | None = None
    wlf_C1: float | None = Field(None, ge=0)
    wlf_C2: float | None = Field(None, gt=0)

    _dt_auto: bool = PrivateAttr(default=False)

    def __eq__(self, other: object) -> bool:
        """Equal values, equal configs (whether dt was given or chosen by default does not matter)."""
        return isinstance(other, Config) and self.model_dump() == other.model_dump()

    def __hash__(self) -> int:
        return hash(tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in self.model_dump().items()))

    @model_validator(mode="wrap")
    @classmethod
    def _default_step(cls, data: Any, handler: Any) -> "Config":
        """dt absent (or None): :attr:`default_dt` of the config with every other value as given.
        t_max_cycles absent (or None): DEFAULT_T_MAX_CYCLES where the slip-cycle extension can act
        (the spring drive's automatic length with t_max below it), else 0."""
        if isinstance(data, Mapping) and data.get("t_max_cycles") is None:
            data = {**data, "t_max_cycles": _default_t_max_cycles(data)}
        if isinstance(data, Mapping) and data.get("material") == "prony":
            data = _prony_defaults(data)
        if not isinstance(data, Mapping) or data.get("dt") is not None:
            return handler(data)
        probe = handler({**data, "dt": 1e-15})  # the fields alone (the checks below run on the result)
        try:
            dt = probe.default_dt
        except (ArithmeticError, LookupError, TypeError, ValueError):  # an invalid combination: the checks name it
            dt = 1e-15
        cfg = handler({**data, "dt": dt})
        cfg._dt_auto = True
        return cfg

    @model_validator(mode="after")
    def _check_combinations(self) -> "Config":
        for key in ALLOWED:
            value = getattr(self, key)
            if isinstance(value, float) and not math.isfinite(value):
                raise ValueError(_message(key, value, ALLOWED[key] + ", finite"))
        if round(self.theta * self.n_blocks) < 1:
            n = "N" if self.Ly == 1 else "N*Ly"
            raise ValueError(
                _message("theta", self.theta, f"theta*{n} >= 0.5 so that N_c = round(theta*{n}) >= 1 (N = {self.N}"
                         + (f", Ly = {self.Ly})" if self.Ly > 1 else ")"))
            )
        self._check_geometry()
        self._check_top()
        self._check_material()
        if self.output_interval < self.dt:
            raise ValueError(_message("output_interval", self.output_interval, f"at least dt = {self.dt:g}"))
        if abs(math.log10(self.v0)) + self.delta > 290:  # v* = v0*10**(+-delta) must be ordinary floats
            raise ValueError(_message("delta", self.delta, f"v0*10**-delta and v0*10**delta between 1e-290 and 1e290 "
                                      f"m/s (v0 = {self.v0:g})"))
        if self.t_decide is not None:
            if self.dead_weight is None:
                raise ValueError(_message("t_decide", self.t_decide, "absent with the spring drive (it sets the "
                                          "dead-weight automatic length; give dead_weight = mu_a)"))
            if self.t_total is not None:
                raise ValueError(_message("t_decide", self.t_decide, f"absent when t_total = {self.t_total:g} is "
                                          "given (a fixed length); remove one of them"))
            if not self.t_decide < self.t_max:
                raise ValueError(_message("t_decide", self.t_decide, f"less than t_max = {self.t_max:g}"))
            if self.t_decide < 100 * self.output_interval:
                raise ValueError(_message("t_decide", self.t_decide, "at least 100 output intervals (the velocity is "
                                          f"fitted to the samples after the ramp): {100 * self.output_interval:g} s"))
        if self.t_ramp is not None:
            if self.dead_weight is None:
                raise ValueError(_message("t_ramp", self.t_ramp, "absent with the spring drive (it is the dead-weight "
                                          "force's ramp; give dead_weight = mu_a)"))
            end, name = ((self.t_decide, "t_decide") if self.t_decide is not None else
                         (self.t_total, "t_total") if self.t_total is not None else (self.t_max, "t_max"))
            if not self.t_ramp < end:
                raise ValueError(_message("t_ramp", self.t_ramp, f"shorter than {name} = {end:g} (the velocity is "
                                          "measured after the ramp)"))
        if self.integrator not in ("adaptive", "implicit") and self.step_tol != OFF["step_tol"]:
            raise ValueError(_message("step_tol", self.step_tol, "absent unless integrator = 'adaptive' or 'implicit' "
                                      "(it is the adaptive step's tolerance)"))
        if self.stop_at_runaway and (self.dead_weight is None or self.t_decide is None or (
                (self.t_ramp is None or self.t_ramp < 0.5 * self.t_decide) and self.geometry != "slab")):
            raise ValueError(_message("stop_at_runaway", self.stop_at_runaway, "absent (or false) unless dead_weight "
                                      "and t_decide are given with a ramp t_ramp of at least half of t_decide (a slowly "
                                      "loaded run, read where it runs away) or with geometry = 'slab' (a release of "
                                      "the slab's rigid top, read over its ringing periods; released faster, any other "
                                      "slider's top overshoots beyond the rising branch and comes back, which would stop it)"))
        if self.stop_when_held and (self.dead_weight is None or self.t_decide is None or self.geometry != "slab"):
            raise ValueError(_message("stop_when_held", self.stop_when_held, "absent (or false) unless dead_weight and "
                                      "t_decide are given with geometry = 'slab' (the rigid top whose ringing periods "
                                      "the velocity is read over)"))
        if self.integrator != "implicit" and self.energy_tol != OFF["energy_tol"]:
            raise ValueError(_message("energy_tol", self.energy_tol, "absent unless integrator = 'implicit' (it bounds "
                                      f"the backward-Euler steps' numerical dissipation; here integrator = '{self.integrator}')"))
        if self.implicit_scheme != OFF["implicit_scheme"] and (
                self.integrator != "implicit" or self.geometry not in ("slab", "halfspace", "chain2d")
                or self.material != "elastic"):
            raise ValueError(_message("implicit_scheme", self.implicit_scheme, "absent (or 'backward-euler') unless "
                                      "integrator = 'implicit' with geometry = 'slab', 'halfspace' or 'chain2d' and "
                                      "material = 'elastic' (TR-BDF2 is built for their Newton-Krylov step; here "
                                      f"integrator = '{self.integrator}', geometry = '{self.geometry}', material = "
                                      f"'{self.material}')"))
        if self.krylov_preconditioner != OFF["krylov_preconditioner"] and (
                self.integrator != "implicit" or self.geometry not in ("slab", "halfspace", "chain2d")):
            raise ValueError(_message("krylov_preconditioner", self.krylov_preconditioner, "absent (or 'jacobi') unless "
                                      "integrator = 'implicit' with geometry = 'slab', 'halfspace' or 'chain2d' (it preconditions "
                                      "their backward-Euler solves; here integrator = "
                                      f"'{self.integrator}', geometry = '{self.geometry}')"))
        if self.t_max_cycles and (self.t_total is not None or self.dead_weight is not None
                                  or not self.t_max_cycles > self.t_max):
            raise ValueError(_message("t_max_cycles", self.t_max_cycles, f"more than t_max = {self.t_max:g}, and 0 "
                                      "(absent) with t_total or dead_weight: it caps the spring drive's automatic "
                                      "length past t_max"))
        if self.min_cycles and (self.t_total is not None or self.dead_weight is not None):
            raise ValueError(_message("min_cycles", self.min_cycles, "0 (absent) with t_total or dead_weight: it is a "
                                      "condition of the spring drive's automatic run length"))
        self._check_stable_step()
        if self.integrator in ("fold", "adaptive", "implicit"):
            return self
        dt_max = self.dt_unique_root_limit
        if self.dt >= dt_max:
            raise ValueError(
                _message(
                    "dt",
                    self.dt,
                    f"dt < {dt_max:.3g} s: above it the per-contact implicit equation "
                    "m*u + dt*f(u) = r has several roots on the weakening branch of the slowest "
                    "contact (v* = v0*10**-delta) and the dynamics are not those of the model; "
                    "integrator = 'adaptive' (the default) or 'fold' keep each contact on its branch and allow "
                    f"dt up to the stable step, {self.dt_stable:.3g} s",
                )
            )
        return self

    def _check_geometry(self) -> None:
        """The geometry: Ly only off the chain (issue 13), and a combination that runs somewhere (the
        capability table, :mod:`slipchain.model.capabilities`)."""
        if not geometry_of(self).two_d:
            if self.Ly != 1:
                raise ValueError(_message("Ly", self.Ly, "1 with geometry = 'chain' (a 2-D interface is geometry = "
                                          "'chain2d', 'slab' or 'halfspace')"))
            return
        from .capabilities import drive_of, refusal

        why = refusal(self.geometry, self.integrator, drive_of(self), "cpu")  # the capability table: what runs nowhere
        if why is not None:
            key = "dead_weight" if self.dead_weight is not None else "integrator"
            raise ValueError(_message(key, getattr(self, key), f"a combination that runs: {why}"))

    @field_validator("top_mass", mode="before")
    @classmethod
    def _top_mass_value(cls, value: Any) -> Any:
        """A number or 'tester' (one message naming both, instead of one per member of the union)."""
        if value is None or value == "tester" or (isinstance(value, (int, float)) and not isinstance(value, bool)):
            return value
        raise ValueError("neither a number nor 'tester'")

    def _check_top(self) -> None:
        """top_mass: with the dead weight on the slab only (its rigid top); p_theta1 with 'tester' only."""
        if self.top_mass is not None:
            if isinstance(self.top_mass, float) and not (math.isfinite(self.top_mass) and self.top_mass > 0):
                raise ValueError(_message("top_mass", self.top_mass, ALLOWED["top_mass"]))
            if self.dead_weight is None or self.geometry != "slab":
                raise ValueError(_message("top_mass", self.top_mass, "absent unless dead_weight is given with geometry "
                                          f"= 'slab' (the rigid top the weight rests on; here geometry = "
                                          f"'{self.geometry}', dead_weight = {self.dead_weight})"))
        if self.p_theta1 is not None and self.top_mass != "tester":
            raise ValueError(_message("p_theta1", self.p_theta1, "absent unless top_mass = 'tester' (it sets the "
                                      "tester's load mass)"))

    def _check_material(self) -> None:
        """material = 'prony': a valid Prony series and temperature; 'elastic': no Prony key."""
        if self.material == "elastic":
            given = [k for k in PRONY_KEYS if getattr(self, k) is not None]
            if given:
                raise ValueError(_message(given[0], getattr(self, given[0]), "absent unless material = 'prony' (it "
                                          "describes the viscoelastic bulk)"))
            return
        for key in ("prony_E", "prony_tau"):
            values = getattr(self, key)
            if not values or not all(math.isfinite(v) and v > 0 for v in values):
                raise ValueError(_message(key, values, ALLOWED[key]))
        if len(self.prony_E) != len(self.prony_tau):
            raise ValueError(_message("prony_tau", self.prony_tau, f"as many terms as prony_E ({len(self.prony_E)})"))
        for key in ("temperature", "T_ref", "wlf_C1", "wlf_C2"):
            if not math.isfinite(getattr(self, key)):
                raise ValueError(_message(key, getattr(self, key), ALLOWED[key] + ", finite"))
        if not self.wlf_C2 + self.temperature - self.T_ref > 0:
            raise ValueError(_message("temperature", self.temperature, f"above T_ref - C2 = "
                                      f"{self.T_ref - self.wlf_C2:g} °C (WLF's range)"))
        from .capabilities import config_refusal

        why = config_refusal(self, "cpu")
        if why is not None:
            raise ValueError(_message("material", self.material, f"a combination that runs: {why}"))

    @property
    def dt_stable(self) -> float:
        """The largest stable step [s] of the explicit springs and damping together, from the scheme's
        linear analysis per Fourier mode (:func:`slipchain.model.stability.stable_step`; issue 26).
        Every integrator's dt must be below it; the adaptive step's largest level stays below
        STABLE_FRACTION of it."""
        from .stability import stable_step

        return stable_step(self)

    @property
    def default_dt(self) -> float:
        """The base step used when dt is not given [s]: the largest value of the 1-2-5 series at most
        STABLE_FRACTION * dt_stable / 2**DEFAULT_DT_LEVELS (so the adaptive step can double at least
        twice) and at most 0.1/omega0 (an interface block's period in 60 steps: the step's first-order
        error at slip events; 1e-7 s at the paper's values in every geometry), for integrator =
        'fixed' also at most STABLE_FRACTION of the unique-root limit (2e-8 s at epsilon = 1e-2, the
        paper's step). Measured (16 x 8 slab, 1 ms of stick-slip): the energy balance's residual is
        2.4e-4, 1.2e-3 and 5.9e-3 at a base step of 5e-8, 1e-7 and 2e-7 s. With material = 'prony'
        and any integrator but 'adaptive' (its default is 'fold') no headroom for doubling: 1e-7 s with
        the default compound at 20 and 11 °C, fold (measured, N = 301, theta = 1, 20 ms from the steady
        start: mu_star 0.8085, 0.8099, 0.8111 at 1e-7, 5e-8, 2e-8 s, each +- 0.0067); with 'adaptive'
        the same headroom as the elastic material (2e-8 s at 20 °C, levels up to 1.6e-7 s)."""
        doubles = self.material != "prony" or self.integrator == "adaptive"
        headroom = 2**DEFAULT_DT_LEVELS if doubles else 1
        bound = min(STABLE_FRACTION * self.dt_stable / headroom, self.dt_accurate)
        if self.integrator == "fixed":
            bound = min(bound, STABLE_FRACTION * self.dt_unique_root_limit)
        decade = 10.0 ** math.floor(math.log10(bound))
        return max(f * decade for f in (1.0, 2.0, 5.0) if f * decade <= bound * (1 + 1e-12))

    @property
    def dt_accurate(self) -> float:
        """0.1/omega0 [s]: an interface block's period in 60 steps, the largest step whose first-order
        error at slip events :attr:`default_dt` accepts (1e-7 s at the paper's values), and with
        material = 'prony' also the adaptive step's largest level (:attr:`step_levels`)."""
        return 0.1 / self.omega0

    @property
    def dt_is_default(self) -> bool:
        """True where dt was not given (:attr:`default_dt`): :meth:`with_updates` then chooses it again."""
        return self._dt_auto

    @property
    def step_levels(self) -> int:
        """integrator = 'adaptive': how often the step may double, dt * 2**k, while the largest step
        stays within STABLE_FRACTION of the stable step :attr:`dt_stable`, at most MAX_STEP_LEVELS.
        integrator = 'implicit' with material = 'prony': 0, its explicit steps the fold step at dt (chosen
        before the adaptive levels were validated with the Prony bulk, and kept so that its results stay
        as committed: docs/guide/viscoelastic.md)."""
        if self.integrator == "implicit" and self.material == "prony":
            return 0
        top = STABLE_FRACTION * self.dt_stable
        if self.material == "prony":  # the arms' work is first order in the step: no step beyond fold's bound
            top = min(top, self.dt_accurate * (1 + 1e-12))
        k = 0
        while k < MAX_STEP_LEVELS and self.dt * 2.0 ** (k + 1) <= top:
            k += 1
        return k

    @property
    def implicit_levels(self) -> int:
        """integrator = 'implicit' (issue 27): how often the step may double, dt * 2**k, above
        :attr:`step_levels` by backward Euler (:mod:`slipchain.engine.backends.implicit`), which
        has no stability bound: MAX_IMPLICIT_LEVELS, the output samples bounding each step too."""
        return max(self.step_levels, MAX_IMPLICIT_LEVELS)

    def _check_stable_step(self) -> None:
        """dt below :attr:`dt_stable` (every geometry and integrator: the explicit part is the same)."""
        bound = self.dt_stable
        if not self.dt < bound:
            drive = "dead weight" if self.dead_weight is not None else "spring drive"
            raise ValueError(_message("dt", self.dt, f"dt < {bound:.4g} s, the largest stable step of the explicit "
                                      f"springs and damping together (linear analysis of the scheme per mode; "
                                      f"geometry = '{self.geometry}', {drive}); leave dt out for the default"))

    # --- derived quantities (docs/model.md tables) -------------------------------------------
    @property
    def n_blocks(self) -> int:
        """Interface blocks: N for the chain, N*Ly (Lx = N along x) for the 2-D geometries."""
        return self.N * self.Ly

    @property
    def H(self) -> float:
        """Slab thickness H = N_L*a [m] (geometry 'slab')."""
        return self.N_L * self.a

    @property
    def kappa_d(self) -> float:
        """Drive springs per area kappa_d = K_d/a**2 [Pa/m] (slab, halfspace)."""
        return self.K_d / self.a**2

    @property
    def top_is_state(self) -> bool:
        """The slab's top is a state of its own: material 'prony' on the slab under the drive springs (the
        slab as a two-port per mode, model.elastic.slab_twoport; State.top, engine.backends.viscoelastic)."""
        return self.material == "prony" and self.geometry == "slab" and self.dead_weight is None

    @property
    def top_stiffness(self) -> float | None:
        """What holds the top of the slab [Pa/m]: the drive springs kappa_d, or None under the dead
        weight (the top is the rigid plate that carries the weight: clamped for every q != 0)."""
        return None if self.dead_weight is not None else self.kappa_d

    @property
    def c_s(self) -> float:
        """Shear-wave speed c_s = sqrt(G/rho) [m/s]."""
        return math.sqrt(self.G / self.rho)

    @property
    def radiation_damping_rate(self) -> float:
        """gamma = a**2 (G/c_s)/m = c_s/a [1/s]: the slab's radiation damping G/c_s per area on a block of
        mass m (slab, halfspace; the quasi-dynamic approximation, Rice 1993, as in QDYN)."""
        return self.c_s / self.a

    @property
    def omega_max(self) -> float:
        """Upper bound of the undamped angular frequencies [1/s] (Gershgorin for the chains; for the
        slab and half-space a**2 max k / m, k at the largest |q| of the grid, where k is largest)."""
        if geometry_of(self).body == "lattice":
            il = 2.0 * (2.0 * self.K + 2.0 * self.K_Y + self.K_T) / self.m
            ul = 2.0 * (2.0 * self.K_L + 2.0 * self.K_LY + self.K_T) / (self.N_L * self.m) + self.K_d / (self.N_L * self.m)
            return math.sqrt(max(il, ul))
        from .elastic import config_kernel

        qx = math.pi / self.a if self.N > 1 else 0.0
        qy = math.pi / self.a if self.Ly > 1 else 0.0
        k = float(config_kernel(self, qx, qy))
        return math.sqrt(self.a**2 * k / self.m)

    @property
    def K_Y(self) -> float:
        """IL spring along y, K_Y = G*a [N/m] (chain2d; 0 for the other geometries)."""
        g = geometry_of(self)
        return self.G * self.a if g.body == "lattice" and g.two_d else 0.0

    @property
    def K_LY(self) -> float:
        """UL spring along y, K_LY = N_L*G*a [N/m] (chain2d; 0 for the other geometries)."""
        return self.N_L * self.K_Y

    @property
    def m(self) -> float:
        """Interface-block mass m = rho*a**3 [kg]."""
        return self.rho * self.a**3

    @property
    def p_nominal(self) -> float:
        """The nominal pressure p0 = theta p_theta1 [Pa] the load stands for (top_mass = 'tester'; issue 29:
        the contact density is proportional to p0, paper p. 2). p_theta1 absent: epsilon tau_f, so that p0 a**2
        is the normal force per block epsilon f0 theta by which mu_star and the dead weight mu_a are
        normalised (the model's friction force and its load in one scale: 65 kPa at theta = 1 with the
        paper's epsilon = 1e-2, the testers' range; 6.5 MPa at epsilon = 1)."""
        return self.theta * (self.p_theta1 if self.p_theta1 is not None else self.epsilon * self.tau_f)

    @property
    def upper_mass(self) -> float:
        """Mass per upper block [kg]: the chains' upper-layer block N_L m; the slab's rigid top under the dead
        weight carries the slab, N_L m per interface block, plus ``top_mass``: with 'tester' the normal load's
        mass p0 a**2/g (the plate and what sits on it) and the hanging weight's, dead_weight p0 a**2/g, which
        the string moves with the slider (issue 29)."""
        if self.top_mass is None:
            return self.N_L * self.m
        extra = (self.top_mass if self.top_mass != "tester"
                 else (1.0 + self.dead_weight) * self.p_nominal * self.a**2 / STANDARD_GRAVITY)
        return self.N_L * self.m + extra

    @property
    def K(self) -> float:
        """IL spring K = E*a [N/m]."""
        return self.E * self.a

    @property
    def K_L(self) -> float:
        """UL spring K_L = N_L*E*a [N/m]."""
        return self.N_L * self.E * self.a

    @property
    def G(self) -> float:
        """Shear modulus G = E/(2(1+nu)) [Pa]."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def K_T(self) -> float:
        """IL-UL transverse spring K_T = G*a/N_L [N/m]."""
        return self.G * self.a / self.N_L

    @property
    def K_d(self) -> float:
        """Drive spring K_d = K/(2(1+nu)) [N/m]."""
        return self.K / (2.0 * (1.0 + self.nu))

    @property
    def f0(self) -> float:
        """f0 = a**2*tau_f [N]."""
        return self.a**2 * self.tau_f

    @property
    def omega0(self) -> float:
        """omega0 = sqrt(K/m) [1/s]."""
        return math.sqrt(self.K / self.m)

    @property
    def n_contacts(self) -> int:
        """N_c = round(theta*N*Ly) (Ly = 1 for the chain)."""
        return int(round(self.theta * self.n_blocks))

    @property
    def contact_law(self) -> ContactLaw:
        return ContactLaw(epsilon=self.epsilon, f0=self.f0, c=self.c, m=self.m, eta_c=self.eta_c)

    @property
    def dt_unique_root_limit(self) -> float:
        """Largest dt for which m(1+dt*eta_c)*u + dt*f(u) = r has one root for every contact."""
        slope = self.contact_law.max_weakening_slope(self.v0 * 10.0 ** (-self.delta))
        if slope == 0.0:
            return math.inf
        return self.m / max(slope - self.m * self.eta_c, 1e-300)

    @property
    def sample_steps(self) -> int:
        """Time steps per output sample."""
        return max(1, int(round(self.output_interval / self.dt)))

    def with_updates(self, **updates: Any) -> "Config":
        """A new validated config with some values replaced; a default dt is chosen again."""
        data = self.model_dump()
        if self._dt_auto:
            data.pop("dt")
        if "t_max_cycles" not in updates and self.t_max_cycles == _default_t_max_cycles(data):
            data.pop("t_max_cycles")  # the default: chosen again for the new values
        return make_config({**data, **updates})

    def to_toml(self) -> str:
        """The config as flat TOML (None values omitted), readable by :func:`load_config`."""
        lines = []
        data = self.model_dump()
        for key, value in data.items():
            absent = (_default_t_max_cycles(data) if key == "t_max_cycles"
                      else Config.model_fields[key].default)  # what the key's absence means today
            if value is None or (OFF.get(key, _NOT_OFF) == value and absent == value):
                continue
            lines.append(f"{key} = {_toml_value(value)}")
        return "\n".join(lines) + "\n"


def _prony_defaults(data: Mapping[str, Any]) -> dict[str, Any]:
    """material = 'prony' with keys absent: the default compound's Prony terms (both lists absent)
    and WLF constants, T_ref = 20 °C, temperature = T_ref, and eta = 0 (the pair damping was a
    stand-in for the bulk's loss, which the Prony series now carries; give eta to keep it), and
    integrator = 'fold' (the adaptive step runs with this material, but its stable step, 1.9e-7 s
    with the default compound, leaves it at most one doubling above fold's 1e-7 s: it buys accuracy
    at events, not speed; docs/guide/viscoelastic.md); with integrator = 'adaptive', step_tol =
    PRONY_STEP_TOL (the energy balance's residual with the default compound, N = 8 chain and 4 x 4 slab
    under the dead weight, 1.2 ms: 1.8e-3 and 2.0e-3 of the works at step_tol = 1e-2, at the check's
    limit, against 1.1e-5 and 5.0e-4 at 1e-3; the fold step at the adaptive step's top level 2.5e-4
    and 3.1e-4)."""
    from .viscoelastic import DEFAULT_COMPOUND as D

    out = dict(data)
    if out.get("prony_E") is None and out.get("prony_tau") is None:
        out["prony_E"], out["prony_tau"] = list(D.E), list(D.tau)
    for key, value in (("T_ref", D.T_ref), ("wlf_C1", D.C1), ("wlf_C2", D.C2)):
        if out.get(key) is None:
            out[key] = value
    if out.get("temperature") is None:
        out["temperature"] = out["T_ref"]
    if out.get("eta") is None:
        out["eta"] = 0.0
    if out.get("integrator") is None:
        out["integrator"] = "fold"
    if out.get("integrator") == "adaptive" and out.get("step_tol") is None:
        out["step_tol"] = PRONY_STEP_TOL
    return out


def _default_t_max_cycles(data: Mapping[str, Any]) -> float:
    """t_max_cycles where the input does not give it: DEFAULT_T_MAX_CYCLES for the spring drive's
    automatic length with t_max below it, else 0 (the extension could not act: a fixed length, a
    dead weight, or a t_max already at least as long)."""
    t_max = data.get("t_max", Config.model_fields["t_max"].default)
    if data.get("t_total") is not None or data.get("dead_weight") is not None:
        return 0.0
    try:
        return DEFAULT_T_MAX_CYCLES if float(t_max) < DEFAULT_T_MAX_CYCLES else 0.0
    except (TypeError, ValueError):  # a bad t_max: its own check names it
        return 0.0


def _toml_value(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _message(key: str, value: Any, allowed: str) -> str:
    return f"config key '{key}' has value {value!r}; expected {allowed}"


def _format_validation_error(err: ValidationError) -> str:
    lines = []
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"])
        if e["type"] == "extra_forbidden":
            known = ", ".join(sorted(Config.model_fields))
            lines.append(f"unknown config key '{loc}' (value {e['input']!r}); known keys: {known}")
        elif not loc:  # raised by the model validator: already a full message
            lines.append(str(e["ctx"]["error"]) if "ctx" in e else e["msg"])
        else:
            lines.append(f"{_message(loc, e['input'], ALLOWED.get(loc, 'a valid value'))} ({e['msg']})")
    return "invalid configuration:\n  " + "\n  ".join(lines)


def _coerce_numbers(data: Mapping[str, Any]) -> dict[str, Any]:
    """TOML integers are accepted for float keys; bools and strings are not numbers."""
    out = dict(data)
    for key, value in data.items():
        field = Config.model_fields.get(key)
        if field is not None and field.annotation in (float, float | None):
            if isinstance(value, int) and not isinstance(value, bool):
                out[key] = float(value)
        elif field is not None and field.annotation == list[float] | None and isinstance(value, (list, tuple)):
            out[key] = [float(v) if isinstance(v, int) and not isinstance(v, bool) else v for v in value]
    return out


def make_config(data: Mapping[str, Any] | None = None, *, legacy: bool = False, **kwargs: Any) -> Config:
    """Build a validated :class:`Config` from a mapping and/or keyword arguments.

    ``legacy=True`` (for stored files only) drops the keys of :data:`LEGACY_KEYS` that older
    versions wrote (otherwise such a key is an error that says where it went) and reads a key of
    :data:`OFF` that is missing as its value there (what its absence meant when the file was written).
    """
    merged = {**(data or {}), **kwargs}
    if legacy:  # a stored config without a key added since means what its absence meant then
        merged = {**OFF, **merged}
    for key, why in LEGACY_KEYS.items():
        if key in merged:
            if not legacy:
                raise ConfigError(f"invalid configuration:\n  config key '{key}' (value {merged[key]!r}) is no longer "
                                  f"accepted: {why}")
            merged.pop(key)
    try:
        return Config(**_coerce_numbers(merged))
    except ValidationError as err:
        raise ConfigError(_format_validation_error(err)) from None


def parse_override(item: str) -> tuple[str, Any]:
    """Parse one ``name=value``; the value is read as a TOML literal, else as a bare string."""
    if "=" not in item:
        raise ConfigError(f"override {item!r} is not of the form name=value")
    key, raw = item.split("=", 1)
    key, raw = key.strip(), raw.strip()
    if not key:
        raise ConfigError(f"override {item!r} has an empty key")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key, value


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file into a dict, with a clear error for a missing or malformed file."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"config file {str(path)!r} does not exist") from None
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"config file {str(path)!r} is not valid TOML: {err}") from None
    except UnicodeDecodeError as err:
        raise ConfigError(f"config file {str(path)!r} is not UTF-8 text: byte 0x{err.object[err.start]:02x} at byte "
                          f"offset {err.start}") from None
    except (IsADirectoryError, PermissionError) as err:
        raise ConfigError(f"config file {str(path)!r} cannot be read: {err.strerror}") from None


def config_from_toml(text: str) -> Config:
    """The config stored as TOML in a result file (a run's ``config`` attribute); keys that older
    versions wrote (:data:`LEGACY_KEYS`) are dropped."""
    return make_config(tomllib.loads(text), legacy=True)


def load_config(path: str | Path | None = None, overrides: Sequence[str] = ()) -> Config:
    """Defaults, then the TOML file at ``path`` (if any), then ``name=value`` overrides."""
    data: dict[str, Any] = read_toml(path) if path is not None else {}
    for item in overrides:
        key, value = parse_override(item)
        data[key] = value
    return make_config(data)


__all__ = ["ALLOWED", "DEFAULT_T_MAX_CYCLES", "LEGACY_KEYS", "OFF", "PRONY_KEYS", "STABLE_FRACTION", "Config", "ConfigError", "config_from_toml", "load_config", "make_config", "parse_override", "read_toml"]

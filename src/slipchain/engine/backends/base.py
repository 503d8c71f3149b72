"""What every backend shares: the batch layout and the backend protocol.

A backend has one method, ``advance(batch, n_samples, sample_steps)``, over a :class:`Batch` of
realisations packed into (B, N) / (B, C) / (B, P) arrays (column layout in
:mod:`slipchain.engine.scheme`); it returns a :class:`ChunkOutput`. The CPU backend
(:mod:`.cpu`) and the CUDA backend (:mod:`.cuda`) import this module and never each other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ...model.elastic import twoport_kernel
from ...model.system import State, System, dead_weight_force, elastic_kernel
from ...model.geometries import geometry_of
from ...results.observables import SLOW_FRACTION
from .. import scheme as S

N_CONTROL = 7  # Batch.step_control's columns (.compose's CTRL_ names the last three)
N_CARRY = 4  # Batch.carry's head: level, have (an error estimate's memory), wait, back-off (.compose's CT_ columns 1, 3, 4, 5)


@dataclass
class Batch:
    """Realisations packed into (B, N) / (B, C) arrays for a kernel (N*Ly blocks per row in 2-D).

    ``geometry`` and ``shape`` = (Lx, Ly) are the batch's (all rows share them); ``kernel`` holds
    a**2 k(q) on the rfft2 grid of each row, (B, Lx, Ly//2 + 1), for 'slab' and 'halfspace'.
    With integrator = 'adaptive' (all rows or none), ``folds`` (B, levels + 1, 2, C) holds each
    contact's folds at dt * 2**k and ``step_control`` (B, N_CONTROL) the tolerance in m/s (step_tol*v_d),
    the number of doublings, counts of the steps taken and rejected (:mod:`.adaptive`), the implicit
    stepper's top level (integrator = 'implicit'; the number of doublings otherwise), the last
    step's error estimate (:mod:`.compose`) and the implicit stepper's energy tolerance (energy_tol).
    """

    x: np.ndarray
    u: np.ndarray
    X: np.ndarray
    U: np.ndarray
    step: np.ndarray
    params: np.ndarray
    sites: np.ndarray
    vstar: np.ndarray
    n_contacts: np.ndarray
    ysolve: np.ndarray
    status: np.ndarray
    geometry: str = "chain"
    shape: tuple[int, int] = (0, 1)
    kernel: np.ndarray | None = None
    folds: np.ndarray | None = None
    step_control: np.ndarray | None = None
    bstate: np.ndarray | None = None  # (B, 2J + 4, N): the bulk's internal fields (material 'prony'; J = 0: elastic)
    material: np.ndarray | None = None  # (B, 2, J): r_j and tau_j of each row's Prony series
    # (B, N_CARRY + 2N) with integrator = 'implicit', else (B, 0): the stepper's level, error memory and back-off
    # (:data:`.compose.CT_LEVEL` ...) and the last step's accelerations, carried from one output sample to the next
    carry: np.ndarray | None = None
    # material 'prony' on the slab under the drive springs: (B, 6, Lx, Ly//2 + 1), the slab's two-port
    # (model.elastic.twoport_kernel), whose top is then a state of its own (State.top); else None
    twoport: np.ndarray | None = None
    # integrator = 'implicit' on the slab and half-space: the conjugate gradients' preconditioner
    # (Config.krylov_preconditioner, one per batch; :meth:`.implicit.SlabSystem.precondition`)
    preconditioner: str = "jacobi"
    # integrator = 'implicit' on the slab, half-space and chain2d: the step above the explicit levels
    # (Config.implicit_scheme, one per batch: 'backward-euler' or 'trbdf2'; :func:`.implicit.krylov_trbdf2_try`)
    implicit_scheme: str = "backward-euler"

    @property
    def implicit(self) -> bool:
        """integrator = 'implicit' (issue 27): the adaptive step's levels and backward Euler above them
        (the implicit top level, ``step_control`` column 4, above the adaptive top, column 1)."""
        return self.step_control is not None and bool(np.any(self.step_control[:, 4] > self.step_control[:, 1]))

    @property
    def material_name(self) -> str:
        """'prony' where the rows carry a Prony series, else 'elastic'."""
        return "prony" if self.material is not None and self.material.shape[2] > 0 else "elastic"

    @classmethod
    def pack(cls, systems: list[System], states: list[State]) -> "Batch":
        c0 = systems[0].config
        if any((s.config.N, s.config.Ly, s.config.geometry) != (c0.N, c0.Ly, c0.geometry) for s in systems):
            raise ValueError("all realisations of a batch must have the same N, Ly and geometry")
        adaptive = c0.integrator in ("adaptive", "implicit")  # the implicit stepper is the adaptive one with more levels
        if adaptive and {s.config.integrator for s in systems} != {c0.integrator}:
            raise ValueError("a batch runs integrator = 'adaptive' or 'implicit' in all its rows or in none")
        n_terms = {len(s.config.prony_E or ()) for s in systems}
        if len(n_terms) > 1 or {s.config.material for s in systems} != {c0.material}:
            raise ValueError("a batch needs one material and as many Prony terms in every row")
        if {s.config.krylov_preconditioner for s in systems} != {c0.krylov_preconditioner}:
            raise ValueError("a batch needs one krylov_preconditioner in every row")
        if {s.config.implicit_scheme for s in systems} != {c0.implicit_scheme}:
            raise ValueError("a batch needs one implicit_scheme in every row")
        b = len(systems)
        cmax = max(1, max(s.n_contacts for s in systems))
        params = np.zeros((b, S.N_PARAMS))
        sites = np.zeros((b, cmax), dtype=np.int64)
        vstar = np.ones((b, cmax))
        ncon = np.zeros(b, dtype=np.int64)
        ysolve = np.zeros((b, S.N_YS, cmax))
        levels = max(s.config.step_levels for s in systems) if adaptive else 0
        folds = np.zeros((b, levels + 1, 2, cmax)) if adaptive else None
        step_control = np.zeros((b, N_CONTROL)) if adaptive else None
        for r, s in enumerate(systems):
            params[r] = kernel_params(s)
            c = s.n_contacts
            sites[r, :c] = s.contact_sites
            vstar[r, :c] = s.vstar
            ncon[r] = c
            st = states[r]
            # Warm start for the contact solver: the current contact velocities (y = 0 at rest);
            # 10**y and exp(-c y^2) are recomputed by the kernel at every sample.
            uc = np.abs(st.u[s.contact_sites])
            with np.errstate(divide="ignore"):
                ysolve[r, S.Y_LOG, :c] = np.where(uc > 0, np.log10(uc / s.vstar), 0.0)
            ysolve[r, S.Y_FA], ysolve[r, S.Y_FB] = np.inf, -np.inf  # no folds (integrator 'fixed')
            if s.config.integrator == "fold":
                cf = s.config
                ysolve[r, S.Y_FA, :c], ysolve[r, S.Y_FB, :c] = S.fold_points(
                    cf.m * (1.0 + cf.dt * cf.eta_c) * s.vstar, cf.dt * cf.epsilon * cf.f0, cf.c)
            if adaptive:
                cf = s.config
                top = cf.implicit_levels if cf.integrator == "implicit" else cf.step_levels
                step_control[r] = cf.step_tol * cf.v_d, cf.step_levels, 0.0, 0.0, top, 0.0, cf.energy_tol
                folds[r, :, 0], folds[r, :, 1] = np.inf, -np.inf
                for k in range(cf.step_levels + 1):
                    h = cf.dt * 2.0**k
                    folds[r, k, 0, :c], folds[r, k, 1, :c] = S.fold_points(
                        cf.m * (1.0 + h * cf.eta_c) * s.vstar, h * cf.epsilon * cf.f0, cf.c)
        J = n_terms.pop()
        n = c0.n_blocks
        material = np.zeros((b, 2, J))
        top = c0.top_is_state
        if any(s.config.top_is_state != top for s in systems):
            raise ValueError("a batch of the viscoelastic slab is under the drive springs in all its rows or in none")
        bstate = np.zeros((b, 2 * J + S.BODY_ROWS + (S.top_rows(J) if top else 0) if J else 0, n))
        if J:
            from ...model.viscoelastic import terms

            for r, s in enumerate(systems):
                material[r, 0], material[r, 1] = terms(s.config)
                if states[r].xi is not None:
                    bstate[r, :2 * J] = states[r].xi.reshape(2 * J, n)
                if top:
                    t0 = 2 * J + S.BODY_ROWS
                    if states[r].top is not None:
                        bstate[r, t0:] = states[r].top
                    else:
                        bstate[r, -1, 1] = -1.0  # never solved: the relaxed equilibrium at the first step
        return cls(
            x=np.stack([s.x for s in states]).astype(float),
            u=np.stack([s.u for s in states]).astype(float),
            X=np.stack([s.X for s in states]).astype(float),
            U=np.stack([s.U for s in states]).astype(float),
            step=np.array([s.step for s in states], dtype=np.int64),
            params=params,
            sites=sites,
            vstar=vstar,
            n_contacts=ncon,
            ysolve=ysolve,
            status=np.full(b, -1, dtype=np.int64),
            geometry=c0.geometry,
            shape=(c0.N, c0.Ly),
            kernel=_kernels(systems),
            folds=folds,
            step_control=step_control,
            bstate=bstate,
            material=material,
            carry=np.zeros((b, N_CARRY + 2 * n) if c0.integrator == "implicit" else (b, 0)),
            twoport=np.stack([twoport_kernel(s.config) for s in systems]) if top else None,
            preconditioner=c0.krylov_preconditioner,
            implicit_scheme=c0.implicit_scheme,
        )

    def state(self, row: int) -> State:
        J = self.material.shape[2] if self.material is not None else 0
        xi = self.bstate[row, :2 * J].reshape(2, J, -1).copy() if J else None
        top = self.bstate[row, 2 * J + S.BODY_ROWS:].copy() if self.twoport is not None else None
        return State(self.x[row].copy(), self.u[row].copy(), self.X[row].copy(), self.U[row].copy(), int(self.step[row]),
                     xi, top)


def _kernels(systems: list[System]) -> np.ndarray | None:
    """a**2 k(q) per row for the slab and half-space (None for the chains); rows with equal
    elastic parameters share one computation."""
    if not geometry_of(systems[0].config).spectral:
        return None
    cache: dict[tuple, np.ndarray] = {}
    rows = []
    for s in systems:
        c = s.config
        key = (c.a, c.E, c.nu, c.N_L, c.geometry)
        if key not in cache:
            cache[key] = elastic_kernel(c)
        rows.append(cache[key])
    return np.stack(rows)


def kernel_params(system: System) -> np.ndarray:
    """The (P,) parameter row for one realisation (column names in :mod:`slipchain.engine.scheme`)."""
    cfg = system.config
    p = np.zeros(S.N_PARAMS)
    p[S.P_K] = cfg.K
    p[S.P_KL] = cfg.K_L
    p[S.P_KT] = cfg.K_T
    p[S.P_KD] = cfg.K_d
    p[S.P_M] = cfg.m
    p[S.P_ML] = cfg.upper_mass
    p[S.P_META] = cfg.m * cfg.eta
    p[S.P_VD] = cfg.v_d
    p[S.P_DT] = cfg.dt
    p[S.P_AMP] = cfg.epsilon * cfg.f0
    p[S.P_C] = cfg.c
    p[S.P_ETAC] = cfg.eta_c
    p[S.P_SLOW] = SLOW_FRACTION * cfg.v_d
    p[S.P_LY] = cfg.Ly
    p[S.P_FOLD] = 0.0 if cfg.integrator == "fixed" else 1.0  # fold-aware contacts: fold, adaptive
    g = geometry_of(cfg)
    if g.body == "lattice" and g.two_d:  # chain2d
        p[S.P_LAT] = 1.0
        p[S.P_KY] = cfg.K_Y
        p[S.P_KLY] = cfg.K_LY
    elif g.spectral:  # no upper layer: the kernel couples; radiation damping
        p[S.P_KL] = p[S.P_KT] = 0.0
        p[S.P_META] = cfg.m * cfg.radiation_damping_rate
    if cfg.dead_weight is not None:  # constant force per upper block instead of the drive springs
        p[S.P_KD] = 0.0
        p[S.P_FCONST] = dead_weight_force(system)
    return p


def gpu_refusal(batch: Batch) -> str | None:
    """Why the GPU paths (the CUDA kernel, the array code) cannot run a batch, from its integrator and
    drives (:func:`slipchain.model.capabilities.refusal`), or None."""
    from ...model.capabilities import refusal

    integrator = ("implicit" if batch.implicit else "adaptive") if batch.folds is not None else "fold" if np.any(batch.params[:, S.P_FOLD] > 0) else "fixed"
    drives = {"dead_weight" if kd == 0.0 else "spring" for kd in batch.params[:, S.P_KD]}
    return next((w for w in (refusal(batch.geometry, integrator, d, "gpu", batch.material_name)
                             for d in sorted(drives)) if w), None)


@dataclass
class ChunkOutput:
    out: np.ndarray  # (B, n_samples, N_OUT)
    acc: np.ndarray  # (B, N_ACC)
    cacc: np.ndarray  # (B, N_CACC, C)


class Backend(Protocol):
    """The protocol of a backend (CPU, CUDA): advance every row of ``batch`` by
    ``n_samples * sample_steps`` steps in place and return the chunk's outputs."""

    name: str

    def advance(self, batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput: ...


__all__ = ["Backend", "Batch", "ChunkOutput", "gpu_refusal", "kernel_params"]

"""Backends: one method, ``advance``, over a :class:`Batch` of realisations.

The CPU backend runs :func:`slipchain.kernel.advance` (numba). A GPU backend provides the same
method on the same arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import kernel as K
from .system import State, System


@dataclass
class Batch:
    """Realisations packed into (B, N) / (B, C) arrays for a kernel."""

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

    @classmethod
    def pack(cls, systems: list[System], states: list[State]) -> "Batch":
        n = systems[0].config.N
        if any(s.config.N != n for s in systems):
            raise ValueError("all realisations of a batch must have the same N")
        b = len(systems)
        cmax = max(1, max(s.n_contacts for s in systems))
        params = np.zeros((b, K.N_PARAMS))
        sites = np.zeros((b, cmax), dtype=np.int64)
        vstar = np.ones((b, cmax))
        ncon = np.zeros(b, dtype=np.int64)
        ysolve = np.zeros((b, K.N_YS, cmax))
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
                ysolve[r, K.Y_LOG, :c] = np.where(uc > 0, np.log10(uc / s.vstar), 0.0)
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
        )

    def state(self, row: int) -> State:
        return State(self.x[row].copy(), self.u[row].copy(), self.X[row].copy(), self.U[row].copy(), int(self.step[row]))


def kernel_params(system: System) -> np.ndarray:
    """The (P,) parameter row for one realisation (column names in :mod:`slipchain.kernel`)."""
    cfg = system.config
    p = np.zeros(K.N_PARAMS)
    p[K.P_K] = cfg.K
    p[K.P_KL] = cfg.K_L
    p[K.P_KT] = cfg.K_T
    p[K.P_KD] = cfg.K_d
    p[K.P_M] = cfg.m
    p[K.P_ML] = cfg.N_L * cfg.m
    p[K.P_META] = cfg.m * cfg.eta
    p[K.P_VD] = cfg.v_d
    p[K.P_DT] = cfg.dt
    p[K.P_AMP] = cfg.epsilon * cfg.f0
    p[K.P_C] = cfg.c
    p[K.P_ETAC] = cfg.eta_c
    p[K.P_SLOW] = SLOW_FRACTION * cfg.v_d
    if cfg.dead_weight is not None:  # constant force per upper block instead of the drive springs
        p[K.P_KD] = 0.0
        p[K.P_FCONST] = dead_weight_force(system)
    return p


def dead_weight_force(system: System) -> float:
    """F_b = mu_a*epsilon*f0*theta (theta = N_c/N realised): the hanging weight's share per upper block."""
    cfg = system.config
    return float(cfg.dead_weight) * cfg.epsilon * cfg.f0 * system.theta_realised if cfg.dead_weight else 0.0


# A contact counts as "slow" (near sticking) while |u| < SLOW_FRACTION * v_d.
SLOW_FRACTION = 0.1


@dataclass
class ChunkOutput:
    out: np.ndarray  # (B, n_samples, N_OUT)
    acc: np.ndarray  # (B, N_ACC)
    cacc: np.ndarray  # (B, N_CACC, C)


class CPUBackend:
    """numba kernel on one CPU core."""

    name = "cpu"

    def advance(self, batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
        b = batch.x.shape[0]
        out = np.zeros((b, n_samples, K.N_OUT))
        acc = np.zeros((b, K.N_ACC))
        cacc = np.zeros((b, K.N_CACC, batch.sites.shape[1]))
        K.advance(batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites, batch.vstar,
                  batch.n_contacts, batch.ysolve, n_samples, sample_steps, out, acc, cacc, batch.status)
        return ChunkOutput(out, acc, cacc)


def get_backend(name: str):
    """The backend for a config's ``backend``: 'cpu', 'gpu' (numba.cuda; error without a GPU) or
    'auto' (the GPU when numba.cuda finds one, else the CPU)."""
    if name == "cpu":
        return CPUBackend()
    from .gpu import GPUBackend, cuda_available

    if name == "gpu" or (name == "auto" and cuda_available()):
        return GPUBackend()
    if name == "auto":
        return CPUBackend()
    raise ValueError(f"config key 'backend' has value {name!r}; expected one of 'cpu', 'gpu', 'auto'")

"""Physics checks after a run: energy balance and the slider following the drive.

Energy balance: the stored energy E = kinetic + elastic (all springs, drive springs included, and
with material 'prony' the energy held by the Maxwell arms) changes by the work of the drive point
minus what damping, contacts and the viscoelastic bulk dissipate,
``E(t) - E(0) = W_drive + W_damping + W_contacts (+ W_bulk)`` (the last ones are negative; W_bulk
is the arms' work on the blocks plus the change of their energy, issue 28). The scheme is first order, so the balance holds to O(dt) relative to the stored energy; over a
long run it is a small fraction of the drive work. Tolerance: ENERGY_RTOL of W_drive.

Displacement: in steady sliding the mean interface-layer velocity over the steady window
equals v_d within DISPLACEMENT_RTOL (the spring stretch can only fluctuate, not grow).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.system import State, System
from ..model.geometries import geometry_of

ENERGY_RTOL = 2e-3
DISPLACEMENT_RTOL = 0.1


def stored_energy(system: System, state: State) -> float:
    """Kinetic plus elastic energy of one realisation [J], the Maxwell arms' included (material
    'prony': :func:`arm_energy`)."""
    cfg = system.config
    x, u, X, U = state.x, state.u, state.X, state.U
    drive = cfg.v_d * state.step * cfg.dt
    kinetic = 0.5 * cfg.m * np.sum(u * u) + 0.5 * cfg.upper_mass * np.sum(U * U)
    if cfg.top_is_state:  # the viscoelastic slab under the drive springs
        el, arms = top_energies(cfg, state)
        return float(kinetic + el + arms)
    if geometry_of(cfg).spectral:  # the quasi-static body: (1/2) sum (x - d) . (-F_el)
        from ..model.elastic import elastic_force
        from ..model.system import elastic_kernel

        d = (x - (X if cfg.dead_weight is not None else drive)).reshape(cfg.N, cfg.Ly)  # X: the plate
        body = -0.5 * np.sum(d * elastic_force(d, 0.0, elastic_kernel(cfg), 1.0))
        return float(kinetic + body + arm_energy(system, state))
    elastic = bulk_energy(cfg, x, X)
    if cfg.dead_weight is None:  # the drive springs (none under the dead weight)
        elastic += 0.5 * cfg.K_d * np.sum((drive - X) ** 2)
    return float(kinetic + elastic + arm_energy(system, state))


def bulk_energy(cfg, x: np.ndarray, X: np.ndarray) -> float:
    """Elastic energy of the chains' bulk springs (K, K_L, K_T; on chain2d's lattice also K_Y, K_LY;
    not the drive springs) for displacement fields x, X [J]."""
    if geometry_of(cfg).two_d:  # chain2d: the (Lx, Ly) lattice, row-major (model.system)
        g = (cfg.N, cfg.Ly)
        xg, Xg = x.reshape(g), X.reshape(g)
        elastic = sum(0.5 * k * np.sum((np.roll(f, -1, axis=ax) - f) ** 2)
                      for k, f, ax in ((cfg.K, xg, 0), (cfg.K_L, Xg, 0), (cfg.K_Y, xg, 1), (cfg.K_LY, Xg, 1)))
        return float(elastic + 0.5 * cfg.K_T * np.sum((X - x) ** 2))
    return float(0.5 * cfg.K * np.sum((np.roll(x, -1) - x) ** 2) + 0.5 * cfg.K_L * np.sum((np.roll(X, -1) - X) ** 2)
                 + 0.5 * cfg.K_T * np.sum((X - x) ** 2))


def arm_energy(system: System, state: State) -> float:
    """Energy held by the Maxwell arms of a Prony bulk, sum_j r_j U_bulk(xi_j) [J]
    (:mod:`slipchain.model.viscoelastic`; U_bulk the chains' bulk springs, or the slab's kernel
    for the fields relative to the plate); 0 for material 'elastic'."""
    cfg = system.config
    if cfg.material != "prony" or state.xi is None:
        return 0.0
    r = np.asarray(cfg.prony_E) / cfg.E
    if cfg.top_is_state:
        return top_energies(cfg, state)[1]
    if geometry_of(cfg).spectral:  # xi relative to the plate (dead weight), U = (1/2) xi . a^2 k xi, k the arms' kernel
        from ..model.elastic import elastic_force
        from ..model.system import elastic_kernel
        from ..model.viscoelastic import arm_kernel

        kern = arm_kernel(elastic_kernel(cfg), cfg.dead_weight is not None)
        g = state.xi[0].reshape(r.size, cfg.N, cfg.Ly)
        return float(sum(-0.5 * r[j] * np.sum(g[j] * elastic_force(g[j], 0.0, kern, 1.0)) for j in range(r.size)))
    return float(sum(r[j] * bulk_energy(cfg, state.xi[0, j], state.xi[1, j]) for j in range(r.size)))


def top_energies(cfg, state: State) -> tuple[float, float]:
    """(elastic energy of slab and drive springs, energy held by the Maxwell arms) [J] of the viscoelastic
    slab under the drive springs, whose top is a state of its own (the two-port of
    :func:`slipchain.model.elastic.slab_twoport`; :mod:`slipchain.engine.backends.viscoelastic`). Per mode
    and channel c, with W_c = w_c**2 (the top's displacement is w_c Z_c)::

        U_el  = 1/2 [A |x|^2 + sum_c W_c (2 K12c Re(x* Z_c) + (K22c + kappa) |Z_c|^2)]   (uniform mode: kappa |Z_P - n X_d|^2)
        U_arm = sum_j r_j/2 [A |xi_bj|^2 + sum_c W_c (2 K12c Re(xi_bj* xi_cj) + K22c |xi_cj|^2)]

    summed with Parseval's weights. A state without the top's (``state.top`` None: a run's start) has
    its top in the relaxed equilibrium, as the first step puts it."""
    from ..model.elastic import parseval_weights, twoport_energy, twoport_kernel

    tp = twoport_kernel(cfg)
    A, W = tp[0], np.stack([tp[1], 1.0 - tp[1]])
    K12, K22 = tp[2:4], tp[4:6]
    kap = cfg.K_d
    g = (cfg.N, cfg.Ly)
    wgt = parseval_weights(*g)
    r = np.asarray(cfg.prony_E) / cfg.E
    J = r.size
    xh = np.fft.rfft2(state.x.reshape(g))
    xib = np.fft.rfft2(state.xi[0].reshape((J,) + g)) if state.xi is not None else np.zeros((J,) + xh.shape, complex)
    xd = cfg.v_d * state.step * cfg.dt * cfg.n_blocks
    if state.top is not None:
        spec = np.fft.rfft2(state.top[:2 + 2 * J].reshape((2 + 2 * J,) + g))
        Z, xit = spec[:2], spec[2:].reshape((2, J) + xh.shape)
    else:  # the relaxed equilibrium with the top's arms at zero
        xit = np.zeros((2, J) + xh.shape, complex)
        ub = xh + np.tensordot(r, xib, 1)
        rhs = np.zeros((2,) + xh.shape, complex)
        rhs[0, 0, 0] = kap * xd
        Z = (rhs - K12 * ub) / (K22 + kap)
    arms = 0.0
    for j in range(J):
        q = A * abs(xib[j]) ** 2 + np.sum(W * (2 * K12 * (np.conj(xib[j]) * xit[:, j]).real + K22 * abs(xit[:, j]) ** 2), axis=0)
        arms += r[j] * np.sum(wgt * q)
    return twoport_energy(tp, kap, xh, Z, xd, wgt), float(0.5 * arms)


@dataclass(frozen=True)
class CheckResult:
    name: str
    passed: bool
    value: float
    tolerance: float
    message: str


def energy_check(delta_e: float, w_drive: float, w_damp: float, w_contact: float, w_bulk: float | None = None,
                 rtol: float = ENERGY_RTOL) -> CheckResult:
    """The balance dE = W_drive + W_damp + W_contact (+ W_bulk, the Prony bulk's dissipation: a
    material 'prony' run gives it, and the message names it)."""
    residual = delta_e - (w_drive + w_damp + w_contact + (w_bulk or 0.0))
    scale = max(abs(w_drive), abs(delta_e), 1e-300)
    rel = abs(residual) / scale
    bulk = (" + W_bulk", f", W_bulk = {w_bulk:.4e} J") if w_bulk is not None else ("", "")
    return CheckResult(
        "energy_balance", bool(rel <= rtol), float(rel), rtol,
        f"energy balance: |dE - (W_drive + W_damp + W_contact{bulk[0]})| / W_drive = {rel:.2e} (tolerance {rtol:g}); "
        f"dE = {delta_e:.4e} J, W_drive = {w_drive:.4e} J, W_damp = {w_damp:.4e} J, W_contact = {w_contact:.4e} J"
        + bulk[1],
    )


def displacement_check(mean_velocity: float, v_d: float, rtol: float = DISPLACEMENT_RTOL) -> CheckResult:
    rel = abs(mean_velocity / v_d - 1.0)
    return CheckResult(
        "slider_follows_drive", bool(rel <= rtol), float(rel), rtol,
        f"steady mean interface velocity {mean_velocity:.4e} m/s vs v_d = {v_d:.4e} m/s "
        f"(relative difference {rel:.2e}, tolerance {rtol:g})",
    )

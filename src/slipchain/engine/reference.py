"""An independent reference: the same equations of motion integrated by scipy.integrate.solve_ivp.

State vector [x (N), X (N), u (N), U (N), F], with F(t) = integral of f_d from 0 to t, so that the
mean driving force over any output interval is a difference of F: exactly what the kernel
records. Written directly from the equations of motion in :mod:`slipchain.engine.scheme`'s docstring,
sharing no code with the kernel (the contact law comes from :class:`ContactLaw`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp

from ..model.system import State, System


class ReferenceModel:
    """Right-hand side, analytic Jacobian and sparsity pattern of the two-chain model."""

    def __init__(self, system: System):
        cfg = system.config
        if cfg.geometry != "chain":
            raise ValueError(f"the reference integrator is the chain's; geometry = '{cfg.geometry}' has none")
        self.system = system
        self.n = cfg.N
        self.law = cfg.contact_law
        self.sites = system.contact_sites
        self.vstar = system.vstar
        n = self.n
        eye = sp.identity(n, format="csr")
        ring = sp.diags([np.ones(n - 1), np.ones(n - 1)], [1, -1], shape=(n, n), format="lil")
        ring[0, n - 1] = 1.0
        ring[n - 1, 0] = 1.0
        ring = ring.tocsr()
        lap = ring - 2.0 * eye
        m, mL, meta = cfg.m, cfg.N_L * cfg.m, cfg.m * cfg.eta
        # Linear part: d[u]/dt and d[U]/dt as functions of [x, X, u, U].
        self.Axx = (cfg.K * lap - cfg.K_T * eye) / m
        self.AxX = cfg.K_T * eye / m
        self.Axu = meta * (ring - 3.0 * eye) / m
        self.AxU = meta * eye / m
        self.AXx = cfg.K_T * eye / mL
        self.AXX = (cfg.K_L * lap - (cfg.K_T + cfg.K_d) * eye) / mL
        self.AXu = meta * eye / mL
        self.AXU = meta * (ring - 3.0 * eye) / mL
        self.cfg = cfg
        z = sp.csr_matrix((n, n))
        lin = sp.bmat([
            [z, z, eye, z],
            [z, z, z, eye],
            [self.Axx, self.AxX, self.Axu, self.AxU],
            [self.AXx, self.AXX, self.AXu, self.AXU],
        ], format="csr")
        # Row for F: dF/dt = f_d = K_d (v_d t - mean X).
        f_row = sp.hstack([sp.csr_matrix((1, n)), sp.csr_matrix(np.full((1, n), -cfg.K_d / n)),
                           sp.csr_matrix((1, 2 * n))])
        self.linear = sp.bmat([[lin, sp.csr_matrix((4 * n, 1))], [f_row, sp.csr_matrix((1, 1))]], format="csr")

    def y0(self, state: State) -> np.ndarray:
        return np.concatenate([state.x, state.X, state.u, state.U, [0.0]])

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        cfg, n = self.cfg, self.n
        dy = self.linear @ y
        dy[3 * n : 4 * n] += cfg.K_d * cfg.v_d * t / (cfg.N_L * cfg.m)
        dy[4 * n] += cfg.K_d * cfg.v_d * t
        u = y[2 * n : 3 * n]
        dy[2 * n + self.sites] -= self.law.force(u[self.sites], self.vstar) / cfg.m
        return dy

    def jac(self, t: float, y: np.ndarray) -> sp.csr_matrix:
        n = self.n
        u = y[2 * n : 3 * n]
        d = np.zeros(4 * n + 1)
        d[2 * n + self.sites] = -self.law.derivative(u[self.sites], self.vstar) / self.cfg.m
        return (self.linear + sp.diags(d)).tocsr()

    def sparsity(self) -> sp.csr_matrix:
        pattern = self.jac(0.0, np.zeros(4 * self.n + 1))
        pattern = pattern + sp.diags(np.ones(4 * self.n + 1))
        pattern.data[:] = 1.0
        return pattern


def reference_fd(system: System, state: State, interval: float, n_samples: int, *, method: str = "Radau",
                 rtol: float = 1e-10, atol: float | None = None, analytic_jacobian: bool = True) -> tuple[np.ndarray, object]:
    """Mean driving force over each of ``n_samples`` intervals from ``state``, by solve_ivp.

    Returns (f_d means, solve_ivp result). With ``analytic_jacobian=False`` the solver estimates
    the Jacobian by finite differences on its sparsity pattern (what a typical user would do).
    """
    model = ReferenceModel(system)
    t_eval = np.arange(n_samples + 1) * interval
    t0 = state.step * system.config.dt
    if atol is None:
        scale = np.concatenate([np.full(2 * model.n, 1e-12), np.full(2 * model.n, 1e-9), [1e-15]])
        atol = scale
    kwargs = {"jac": model.jac} if analytic_jacobian else {"jac_sparsity": model.sparsity()}
    res = solve_ivp(lambda t, y: model.rhs(t + t0, y), (0.0, t_eval[-1]), model.y0(state), method=method,
                    t_eval=t_eval, rtol=rtol, atol=atol, **kwargs)
    if not res.success:
        raise RuntimeError(f"solve_ivp failed: {res.message}")
    F = res.y[-1]
    return np.diff(F) / interval, res

"""The slider of Fig. 4 plus one disorder realisation, built from an explicit seed.

Interface layer (IL): N cubes of mass m, displacements x_i, velocities u_i.
Upper layer (UL): N parallelepipeds of mass N_L*m, displacements X_i, velocities U_i.
N_c = round(theta*N) distinct IL blocks carry one frictional contact each, with
log10(v*_i) uniform on [log10 v0 - delta, log10 v0 + delta] (docs/model.md, "Frictional contacts").

The 2-D geometries (``config.geometry``, issue 13) have N*Ly interface blocks on an (Lx = N, Ly)
periodic grid, stored flat in row-major order: block (ix, iy) is index ix*Ly + iy, so x-neighbours
are Ly apart and Ly = 1 is the chain's numbering. 'chain2d' has an upper layer of N*Ly columns;
'slab' and 'halfspace' have none (X, U stay zero): the elastic body is quasi-static, its force on
the blocks a Fourier-space kernel (:mod:`.elastic`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .config import Config
from .elastic import elastic_kernel, uniform_stiffness  # noqa: F401 (a config's kernels; imported from here too)
from .geometries import geometry_of


@dataclass(frozen=True)
class System:
    """A configuration plus its disorder realisation (contact sites and their v*)."""

    config: Config
    contact_sites: np.ndarray  # sorted IL indices carrying a contact, int64, shape (N_c,)
    vstar: np.ndarray  # v*_i of each contact [m/s], shape (N_c,)

    @property
    def n_contacts(self) -> int:
        return int(self.contact_sites.size)

    @property
    def theta_realised(self) -> float:
        """theta = N_c/N (N*Ly in 2-D), the realised contact fraction used in mu_star."""
        return self.n_contacts / self.config.n_blocks

    def steady_friction_per_block(self) -> float:
        """(1/N) sum_contacts f(v_d, v*_i): the mean force per block in uniform sliding [N]."""
        if self.n_contacts == 0:
            return 0.0
        f = self.config.contact_law.force(self.config.v_d, self.vstar)
        return float(np.sum(f)) / self.config.n_blocks


def build_system(config: Config, contact_sites: np.ndarray | None = None, vstar: np.ndarray | None = None) -> System:
    """Draw the disorder from ``config.seed`` (or take explicit sites and v*, for tests).

    The draw is: sites = rng.choice(N*Ly, N_c, replace=False), sorted; then
    log10(v*) = log10(v0) + rng.uniform(-delta, delta, N_c), in site order, with
    ``rng = numpy.random.default_rng(seed)``. Same config and seed, same realisation.
    """
    cfg = config
    if contact_sites is None:
        rng = np.random.default_rng(cfg.seed)
        sites = np.sort(rng.choice(cfg.n_blocks, size=cfg.n_contacts, replace=False)).astype(np.int64)
        vs = cfg.v0 * 10.0 ** rng.uniform(-cfg.delta, cfg.delta, size=sites.size)
    else:
        sites = np.asarray(contact_sites, dtype=np.int64)
        vs = np.asarray(vstar, dtype=float) if vstar is not None else np.full(sites.size, cfg.v0)
        if sites.ndim != 1 or vs.shape != sites.shape:
            raise ValueError(f"contact_sites {sites.shape} and vstar {vs.shape} must be 1-d and equal in length")
        if sites.size and (sites.min() < 0 or sites.max() >= cfg.n_blocks or np.unique(sites).size != sites.size):
            raise ValueError(f"contact_sites must be distinct indices in [0, {cfg.n_blocks}); got {sites.tolist()}")
        if np.any(vs <= 0) or not np.all(np.isfinite(vs)):
            raise ValueError("vstar must be finite and > 0")
        order = np.argsort(sites)
        sites, vs = sites[order], vs[order]
    return System(config=cfg, contact_sites=sites, vstar=vs)


# Dead-weight drive: the force rises linearly over this fraction of the run (a heavy slider accepts
# its load gradually; a step load makes the light model slider overshoot past the maximum of mu(v)).
DEAD_WEIGHT_RAMP = 0.25


def dead_weight_ramp_time(cfg: Config) -> float | None:
    """How long the dead-weight force ramps up (s): ``t_ramp``, else DEAD_WEIGHT_RAMP*``t_decide``;
    None for a fixed-length run, whose ramp is DEAD_WEIGHT_RAMP of its length."""
    if cfg.t_ramp is not None:
        return cfg.t_ramp
    return DEAD_WEIGHT_RAMP * cfg.t_decide if cfg.t_decide is not None else None


RING_START = 3  # top_ringing_period: a released run's stop rules (certain runaway, certain held) start this many periods after the ramp


def top_ringing_period(cfg: Config) -> float | None:
    """T = 2 pi sqrt(M / (a**2 k(0))) (s): the period with which the slab's rigid top under the dead weight
    rings on the layer's shear while the interface holds (issue 29's tester: M the top's mass per interface
    block, :attr:`Config.upper_mass`; k(0) = G/H the uniform mode's stiffness per area,
    :func:`~slipchain.model.elastic.uniform_stiffness`, with the relaxed modulus: a rubber stiffer at the
    ringing frequency rings faster, so this is the longest period). 0.06 s at theta = 0.05 and 0.26 s at
    theta = 1 on the tester's block (H = 50 a, p_theta1 = 6.5 MPa), as the stored release runs ring
    (docs/tester-3d). None where there is no such top (the chains, the half-space, the spring drive)."""
    if cfg.dead_weight is None or cfg.geometry != "slab":
        return None
    return 2.0 * np.pi * float(np.sqrt(cfg.upper_mass / (cfg.a**2 * uniform_stiffness(cfg))))


def dead_weight_force(system: System) -> float:
    """F_b = mu_a*epsilon*f0*theta (theta = N_c/N realised): the hanging weight's share per upper
    block in the dead-weight drive (``config.dead_weight`` = mu_a); 0 with the spring drive."""
    cfg = system.config
    return float(cfg.dead_weight) * cfg.epsilon * cfg.f0 * system.theta_realised if cfg.dead_weight else 0.0


def mu_star_norm(system: System) -> float:
    """epsilon*f0*theta with the realised theta = N_c/N: f_d / this = mu_star (docs/model.md).

    Without contacts mu_star is undefined; the series is then normalised by epsilon*f0 alone
    (for the transient and error estimates) and mu_star is reported as NaN.
    """
    cfg = system.config
    return cfg.epsilon * cfg.f0 * (system.theta_realised if system.n_contacts else 1.0)


@dataclass
class State:
    """Dynamic state of one realisation: displacements from the lattice sites and velocities."""

    x: np.ndarray  # IL displacements
    u: np.ndarray  # IL velocities
    X: np.ndarray  # UL displacements
    U: np.ndarray  # UL velocities
    step: int = 0  # time steps taken; t = step*dt
    xi: np.ndarray | None = None  # material 'prony': the Maxwell arms' fields (2 layers, J terms, n); None: zero
    # material 'prony' on the slab under the drive springs: the top's state (2 J + 3, n), rows Z_P, Z_S, the
    # top's arms (J of channel P, J of S), then [drive force sum, step of the top's last solve] (backends.viscoelastic,
    # scheme.top_rows); None: the top in equilibrium with relaxed arms, solved at the first step
    top: np.ndarray | None = None

    def copy(self) -> "State":
        return State(self.x.copy(), self.u.copy(), self.X.copy(), self.U.copy(), self.step,
                     None if self.xi is None else self.xi.copy(), None if self.top is None else self.top.copy())


def initial_state(system: System) -> State:
    """The start chosen by ``config.start`` (docs/model.md, "Drive, start and measurement").

    rest: every block at rest at its site; the drive starts at 0 and moves at v_d.
    steady: every block moves at v_d; X_i = -F/K_d and x_i = X_i - F/K_T with
    F = (1/N) sum_contacts f(v_d, v*_i), so that drive and transverse springs carry the mean
    steady-sliding friction per block. Slab and half-space: x_i = -F/(a**2 k(0)) (the uniform mode
    of the elastic kernel carries it), X = U = 0 (no upper layer; under the dead weight the plate,
    at X = 0 moving at U = v_d).
    """
    cfg = system.config
    n = cfg.n_blocks
    if cfg.start == "rest":
        zeros = np.zeros(n)
        return State(zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy(), 0)
    force = system.steady_friction_per_block()
    if geometry_of(cfg).spectral:
        zeros = np.zeros(n)
        plate = np.full(n, cfg.v_d) if cfg.dead_weight is not None else zeros.copy()
        return State(np.full(n, -force / (cfg.a**2 * uniform_stiffness(cfg))), np.full(n, cfg.v_d), zeros.copy(),
                     plate, 0)
    X = np.full(n, -force / cfg.K_d)
    x = X - force / cfg.K_T
    v = np.full(n, cfg.v_d)
    return State(x, v.copy(), X, v.copy(), 0)

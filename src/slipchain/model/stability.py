"""The largest stable time step of the explicit part of the scheme, from its own linear analysis (issue 26).

The scheme (:mod:`slipchain.engine.scheme`) is symplectic Euler with the springs and the damping
both explicit; the contact force is implicit (backward Euler) and L-stable, so the bound comes from
the contact-free system. It is linear and periodic, so its Fourier modes decouple; per mode the
equations are ``M dv/dt = -K x - C v`` with 2 x 2 matrices for the two chains (IL, UL) and 1 x 1
for the slab and half-space. One step h maps (x, v) to::

    v' = v - h M^-1 (K x + C v),     x' = x + h v'.

With xi = x/h (so that every entry is of order one) the amplification matrix of a mode is::

    A = [[I - h^2 B, I - h D], [-h^2 B, I - h D]],   B = M^-1 K, D = M^-1 C,

and the step is stable when every eigenvalue of every mode's A lies in the unit disk. For a scalar
mode (the slab: B = omega^2, D = gamma) Jury's criterion gives it in closed form,
``h^2 omega^2 + 2 h gamma < 4``, i.e. ``h < (sqrt(gamma^2 + 4 omega^2) - gamma)/omega^2``: the
springs and the damping together, not each alone (the chain's stiffest mode is also its most
damped, which is why bounding ``h omega_max`` and ``h 2 z eta`` separately overestimated it).

Modes, with s = 2 - 2 cos(q a) along each axis (q on the periodic grid):

* chain, chain2d (docs/model.md, Fig. 4 of the paper; chain2d adds the y springs)::

      K = [[K s_x + K_Y s_y + K_T, -K_T], [-K_T, K_L s_x + K_LY s_y + K_T + K_d]]
      C = m eta [[1 + s_x + s_y, -1], [-1, 1 + s_x + s_y]],   M = diag(m, N_L m)

  (K_d = 0 under the dead weight: its uniform mode, both chains translating together, is then
  marginal for every h, an eigenvalue 1 of a Jordan pair, and is not a limit);
* slab, halfspace: B = a^2 k(q)/m on the rfft2 grid, D = gamma = c_s/a (radiation damping);
  under the dead weight the slab's uniform mode couples the blocks' mean x to the plate X (mass
  M = N_L m per block, :mod:`slipchain.engine.backends.spectral`), a 2 x 2 mode with
  kappa = a^2 G/H::

      B = [[kappa/m, -kappa/m], [-kappa/M, kappa/M]],   D = gamma [[1, -1], [-m/M, m/M]]

:func:`stable_step` is what :class:`slipchain.model.config.Config` checks every ``dt`` against
and what bounds the adaptive step's largest level. tests/physics/test_stability.py runs the engine
just inside and just outside it.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .elastic import elastic_kernel, uniform_stiffness
from .geometries import geometry_of

RADIUS_TOL = 1e-7  # |lambda| above 1 + this is growth (a Jordan pair at 1 is computed to ~1e-8)


MAX_MODES = 2049  # per axis: above, the modes are sampled (the first and last, q = 0 and pi, always)


def _wavenumbers(n: int) -> np.ndarray:
    """The distinct wave numbers k = 0 ... n//2 of a periodic axis of n blocks, or MAX_MODES of them
    evenly spread (both ends kept) for larger n, so that a huge config is refused by its memory
    estimate instead of by this analysis; s(k) is smooth, and the stiffest mode is always included."""
    if n // 2 + 1 <= MAX_MODES:
        return np.arange(n // 2 + 1, dtype=float)
    return np.unique(np.round(np.linspace(0, n // 2, MAX_MODES)))


def chain_modes(N: int, Ly: int, m: float, N_L: int, K: float, K_L: float, K_T: float, K_d: float, K_Y: float,
                K_LY: float, eta: float, uniform: bool | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(B, D) = (M^-1 K, M^-1 C), shape (modes, 2, 2), of the chains' distinct Fourier modes (module
    docstring); modes with the same (cos qx, cos qy) are counted once. The dead weight's
    translation mode (K_d = 0, q = 0) is left out (``uniform``: keep it or not, whatever K_d)."""
    sx = 2.0 - 2.0 * np.cos(2.0 * np.pi * _wavenumbers(N) / N)
    sy = 2.0 - 2.0 * np.cos(2.0 * np.pi * _wavenumbers(Ly) / Ly)
    sx, sy = (s.ravel() for s in np.meshgrid(sx, sy, indexing="ij"))
    if not (K_d != 0.0 if uniform is None else uniform):
        sx, sy = sx[1:], sy[1:]
    k = np.empty((sx.size, 2, 2))
    k[:, 0, 0] = K * sx + K_Y * sy + K_T
    k[:, 0, 1] = k[:, 1, 0] = -K_T
    k[:, 1, 1] = K_L * sx + K_LY * sy + K_T + K_d
    c = np.empty_like(k)
    c[:, 0, 0] = c[:, 1, 1] = m * eta * (1.0 + sx + sy)
    c[:, 0, 1] = c[:, 1, 0] = -m * eta
    minv = np.array([1.0 / m, 1.0 / (N_L * m)])[None, :, None]
    return minv * k, minv * c


def amplification(B: np.ndarray, D: np.ndarray, h: float) -> np.ndarray:
    """The step's amplification matrices (modes, 2d, 2d) in (x/h, v) for (modes, d, d) B and D."""
    n, d, _ = B.shape
    eye = np.broadcast_to(np.eye(d), B.shape)
    A = np.empty((n, 2 * d, 2 * d))
    A[:, :d, :d] = eye - h * h * B
    A[:, :d, d:] = eye - h * D
    A[:, d:, :d] = -h * h * B
    A[:, d:, d:] = eye - h * D
    return A


def spectral_radius(B: np.ndarray, D: np.ndarray, h: float) -> float:
    """Largest |eigenvalue| over the modes' amplification matrices at step h."""
    return float(np.abs(np.linalg.eigvals(amplification(B, D, h))).max())


def be_amplification(B: np.ndarray, D: np.ndarray, h: float) -> np.ndarray:
    """Backward Euler's amplification matrices (modes, 2d, 2d) in (x/h, v), the implicit stepper's
    linear part (integrator = 'implicit', :mod:`slipchain.engine.backends.implicit`, issue 27)::

        v' = v - h (B x' + D v'),  x' = x + h v'   =>   v' = S (v - h^2 B xi),  xi' = xi + v',

    S = (I + h D + h^2 B)^-1, xi = x/h. For B, D positive semidefinite every eigenvalue lies in the
    unit disk for every h (A-stable) and A -> 0 as h -> inf for B > 0 (L-stable): a scalar mode is
    damped by 1/|1 + h gamma + h^2 omega^2|^(1/2) per step and more."""
    n, d, _ = B.shape
    eye = np.broadcast_to(np.eye(d), B.shape)
    S = np.linalg.inv(eye + h * D + h * h * B)
    SB = h * h * S @ B
    A = np.empty((n, 2 * d, 2 * d))
    A[:, :d, :d] = eye - SB
    A[:, :d, d:] = S
    A[:, d:, :d] = -SB
    A[:, d:, d:] = S
    return A


TRBDF2_GAMMA = 2.0 - math.sqrt(2.0)  # TR-BDF2's stage fraction: L-stable, and both stages share one matrix form


def trbdf2_weights(h: float, gamma: float = TRBDF2_GAMMA) -> tuple[float, float, float, float]:
    """TR-BDF2's step sizes and BDF2 weights for a step h: (h1, h2, w1, w0) with h1 = gamma h/2 the
    trapezoidal stage's backward-Euler-like step, h2 = (1 - gamma)/(2 - gamma) h the BDF2 stage's, and
    the BDF2 base y_g w1 - y_n w0, w1 = 1/(gamma (2 - gamma)), w0 = (1 - gamma)^2/(gamma (2 - gamma)).
    The one statement of them: :func:`trbdf2_amplification` and the stepper
    (:func:`slipchain.engine.backends.implicit.krylov_trbdf2_try`) both read them here."""
    return (0.5 * gamma * h, (1.0 - gamma) / (2.0 - gamma) * h, 1.0 / (gamma * (2.0 - gamma)),
            (1.0 - gamma) ** 2 / (gamma * (2.0 - gamma)))


def trbdf2_amplification(B: np.ndarray, D: np.ndarray, h: float, gamma: float = TRBDF2_GAMMA) -> np.ndarray:
    """TR-BDF2's amplification matrices (modes, 2d, 2d) in (x, v) for the linear part
    y' = J y, J = [[0, I], [-B, -D]] (Bank et al. 1985; Hosea and Shampine 1996): a trapezoidal stage
    to t + gamma h, then BDF2 through t, t + gamma h, t + h::

        (I - gamma h/2 J) y_g = (I + gamma h/2 J) y_n
        (I - (1 - gamma)/(2 - gamma) h J) y_1 = y_g / (gamma (2 - gamma)) - (1 - gamma)^2 / (gamma (2 - gamma)) y_n

    Each stage is a backward-Euler-like solve (the implicit stepper's, with a shifted base state and
    step gamma h/2 or (1 - gamma)/(2 - gamma) h), so the stepper's Newton-Krylov solve would serve both.
    Second order, A-stable and, with gamma = 2 - sqrt(2), L-stable (radius ~ 4.8/(h omega) as h -> inf).
    Its numerical dissipation on a resolved undamped mode is ~7e-3 (h omega)^4 of the energy per step,
    against (h omega)^2 for backward Euler (:func:`be_amplification`); on motion linear in time (creep)
    the trapezoidal stage is exact. The analysis of ``Config.implicit_scheme = 'trbdf2'`` (issue 27,
    docs/numerics.md "TR-BDF2"), whose stepper takes the same weights (:func:`trbdf2_weights`)."""
    n, d, _ = B.shape
    eye = np.broadcast_to(np.eye(2 * d), (n, 2 * d, 2 * d))
    J = np.zeros((n, 2 * d, 2 * d))
    J[:, :d, d:] = np.eye(d)
    J[:, d:, :d] = -B
    J[:, d:, d:] = -D
    c1, c2, w1, w0 = trbdf2_weights(h, gamma)
    stage = np.linalg.solve(eye - c1 * J, eye + c1 * J)
    return np.linalg.solve(eye - c2 * J, w1 * stage - w0 * eye)


def largest_stable_step(B: np.ndarray, D: np.ndarray, rel: float = 1e-10) -> float:
    """The largest h with spectral radius <= 1 + RADIUS_TOL, by doubling then bisection to ``rel``.

    Stability regions of these damped oscillators are intervals [0, h*) (for scalar modes exactly,
    by Jury's criterion): the first unstable h found by doubling from far below bounds h* above."""
    scale = math.sqrt(max(float(np.abs(B).max()), 1e-300)) + float(np.abs(D).max())
    lo, hi = 0.0, 1e-3 / scale
    while spectral_radius(B, D, hi) <= 1.0 + RADIUS_TOL:
        lo, hi = hi, 2.0 * hi
    while hi - lo > rel * hi:
        mid = 0.5 * (lo + hi)
        if spectral_radius(B, D, mid) <= 1.0 + RADIUS_TOL:
            lo = mid
        else:
            hi = mid
    return lo


def scalar_stable_step(omega2: np.ndarray, gamma: float) -> float:
    """min over scalar modes of the closed-form bound h < (sqrt(gamma^2 + 4 omega^2) - gamma)/omega^2
    (Jury: h^2 omega^2 + 2 h gamma < 4; a mode with omega = 0 needs h gamma < 2)."""
    w2 = float(np.max(omega2))
    if w2 <= 0.0:
        return 2.0 / gamma if gamma > 0.0 else math.inf
    # 4 / (sqrt(gamma^2 + 4 w2) + gamma): the same number without cancellation when gamma >> omega
    return 4.0 / (math.sqrt(gamma * gamma + 4.0 * w2) + gamma)


@functools.lru_cache(maxsize=256)
def _chain_stable_step(*args: float) -> float:
    return largest_stable_step(*chain_modes(*args))


def prony_amplification(B: np.ndarray, D: np.ndarray, Bb: np.ndarray, r: np.ndarray, tau: np.ndarray,
                        h: float) -> np.ndarray:
    """The step's amplification matrices with a Prony bulk (issue 28), (modes, (2 + J) d, (2 + J) d) in
    (x/h, v, xi_1/h ... xi_J/h): the explicit step with the Maxwell arms' force -h^2 r_j Bb xi_j/h
    (Bb = M^-1 K_bulk, the springs without the drive's) and their exponential update
    ``xi_j' = a_j xi_j + tau_j (1 - a_j) v'`` (:mod:`slipchain.model.viscoelastic`)."""
    n, d, _ = B.shape
    J = len(r)
    a = np.exp(-h / np.asarray(tau))
    c = np.asarray(tau) * -np.expm1(-h / np.asarray(tau)) / h
    eye = np.broadcast_to(np.eye(d), B.shape)
    vrow = np.empty((n, d, (2 + J) * d))  # v' in terms of the old state
    vrow[:, :, :d] = -h * h * B
    vrow[:, :, d:2 * d] = eye - h * D
    for j in range(J):
        vrow[:, :, (2 + j) * d:(3 + j) * d] = -h * h * r[j] * Bb
    A = np.zeros((n, (2 + J) * d, (2 + J) * d))
    A[:, :d] = vrow
    A[:, :d, :d] += eye  # x/h' = x/h + v'
    A[:, d:2 * d] = vrow
    for j in range(J):
        rows = slice((2 + j) * d, (3 + j) * d)
        A[:, rows] = c[j] * vrow
        A[:, rows, rows] += a[j] * eye
    return A


def _largest(radius, scale: float, rel: float = 1e-10) -> float:
    """The largest h with radius(h) <= 1 + RADIUS_TOL, by doubling from 1e-3/scale then bisection."""
    lo, hi = 0.0, 1e-3 / scale
    while radius(hi) <= 1.0 + RADIUS_TOL:
        lo, hi = hi, 2.0 * hi
    while hi - lo > rel * hi:
        mid = 0.5 * (lo + hi)
        if radius(mid) <= 1.0 + RADIUS_TOL:
            lo = mid
        else:
            hi = mid
    return lo


PRONY_SCAN = 64  # steps below the bound at which a Prony bulk's stability is checked as well


@functools.lru_cache(maxsize=64)
def _prony_stable_step(args: tuple, r: tuple, tau: tuple) -> float:
    """The largest stable step of the chains with a Prony bulk (:func:`prony_stable_step` of their modes)."""
    B, D = chain_modes(*args)
    K_d = args[7]
    Bb, _ = chain_modes(*args[:7], 0.0, *args[8:], uniform=K_d != 0.0)
    return prony_stable_step(B, D, Bb, np.asarray(r), np.asarray(tau))


def prony_stable_step(B: np.ndarray, D: np.ndarray, Bb: np.ndarray, r: np.ndarray, tau: np.ndarray) -> float:
    """The largest stable step of modes (B, D) with the Maxwell arms acting through Bb
    (:func:`prony_amplification`); below it the spectral radius is checked on PRONY_SCAN steps spread
    over four decades, and the bound lowered below any unstable one found (the region need not be an
    interval with the arms' exponentials in it)."""
    glassy = B + np.asarray(r).sum() * Bb

    def radius(h: float) -> float:
        return float(np.abs(np.linalg.eigvals(prony_amplification(B, D, Bb, r, tau, h))).max())

    scale = math.sqrt(max(float(np.abs(glassy).max()), 1e-300)) + float(np.abs(D).max())
    h = _largest(radius, scale)
    for trial in np.geomspace(h * 1e-4, h, PRONY_SCAN)[::-1]:
        if radius(trial) > 1.0 + RADIUS_TOL:
            h = _largest(lambda x: radius(x) if x < trial else 2.0, scale)  # below the unstable island
    return h


def stable_step(cfg) -> float:
    """The largest stable step dt [s] of ``cfg``'s geometry and drive (module docstring); the
    scheme is stable for every dt below it."""
    if geometry_of(cfg).body == "lattice":
        K_d = 0.0 if cfg.dead_weight is not None else cfg.K_d
        args = (cfg.N, cfg.Ly, cfg.m, cfg.N_L, cfg.K, cfg.K_L, cfg.K_T, K_d, cfg.K_Y, cfg.K_LY, cfg.eta)
        if cfg.material == "prony":
            from .viscoelastic import terms

            r, tau = terms(cfg)
            return _prony_stable_step(args, tuple(r), tuple(tau))
        return _chain_stable_step(*args)
    # the slab's and half-space's stiffest mode is at the grid's largest |q| (Config.omega_max), and the
    # scalar bound falls with omega: that mode alone (tests/physics/test_stability.py checks every mode)
    if cfg.material == "prony":
        return _slab_prony_stable_step(cfg)
    h = scalar_stable_step(np.array(cfg.omega_max**2), cfg.radiation_damping_rate)
    if cfg.dead_weight is not None:
        h = min(h, largest_stable_step(*plate_mode(cfg)))
    return h


def _slab_prony_stable_step(cfg) -> float:
    """The slab under the dead weight with a Prony bulk (issue 28): the whole kernel is the bulk's,
    so the arms act through the mode's own stiffness (Bb = B); the stiffest Fourier mode and the
    plate's uniform mode (radiation damping at the relaxed modulus, as the elastic slab's). Memoised
    on those numbers (a sweep's members share them; each scan costs about 100 eigenvalue problems)."""
    from .viscoelastic import terms

    r, tau = terms(cfg)
    plate = None
    if cfg.dead_weight is not None:
        plate = tuple(tuple(map(float, a.ravel())) for a in plate_mode(cfg))
    return _slab_prony_step(float(cfg.omega_max**2), float(cfg.radiation_damping_rate), tuple(map(float, r)),
                            tuple(map(float, tau)), plate)


@functools.lru_cache(maxsize=256)
def _slab_prony_step(w2: float, gamma: float, r: tuple, tau: tuple, plate: tuple | None) -> float:
    B = np.array([[[w2]]])
    D = np.array([[[gamma]]])
    h = prony_stable_step(B, D, B, np.asarray(r), np.asarray(tau))
    if plate is not None:
        Bp, Dp = (np.asarray(a).reshape(1, 2, 2) for a in plate)
        h = min(h, prony_stable_step(Bp, Dp, Bp, np.asarray(r), np.asarray(tau)))
    return h


def plate_mode(cfg) -> tuple[np.ndarray, np.ndarray]:
    """(B, D), shape (1, 2, 2), of the slab's uniform mode under the dead weight (module docstring)."""
    kappa = cfg.a**2 * uniform_stiffness(cfg)
    m, M, g = cfg.m, cfg.upper_mass, cfg.radiation_damping_rate
    B = np.array([[[kappa / m, -kappa / m], [-kappa / M, kappa / M]]])
    D = g * np.array([[[1.0, -1.0], [-m / M, m / M]]])
    return B, D


def slab_modes(cfg) -> tuple[np.ndarray, np.ndarray]:
    """(B, D) of the slab's or half-space's Fourier modes as (modes, 1, 1) arrays (for the generic
    eigenvalue test of the closed form); under the dead weight without the uniform mode
    (:func:`plate_mode`)."""
    w2 = (elastic_kernel(cfg) / cfg.m).ravel()
    if cfg.dead_weight is not None:
        w2 = w2[1:]
    return w2[:, None, None], np.full((w2.size, 1, 1), cfg.radiation_damping_rate)


__all__ = ["RADIUS_TOL", "TRBDF2_GAMMA", "trbdf2_amplification", "trbdf2_weights", "amplification", "prony_amplification", "prony_stable_step", "chain_modes", "largest_stable_step", "plate_mode", "scalar_stable_step",
           "slab_modes", "spectral_radius", "stable_step"]

"""Quasi-static Fourier-space stiffness of an elastic slab on its bottom face (issue 13, first part).

The 2-D interface of issue 13 is the bottom face z = 0 of an isotropic elastic slab (shear modulus
``G``, Poisson ratio ``nu``) of thickness ``H = N_L a``. A tangential displacement along x,
``u_x(x, y) = u_q exp(i q.r)``, with the blocks moving along x only (``u_y = 0``) and the normal
stress free at the bottom face, needs the traction ``t_x = k(q) u_q`` with (the scalar model)::

    k(q) = (qx/q)**2 k_PSV(q) + (qy/q)**2 k_SH(q)

k_SH: the anti-plane (SH) part, displacement perpendicular to q; k_PSV: the in-plane (P-SV) part,
displacement along q. With x = qH and the top **clamped** (u = 0 at z = H)::

    k_SH  = G q coth(x)
    k_PSV = G q [(3-4nu) cosh 2x + 2x**2 + 8nu**2 - 12nu + 5] / {(1-nu) [(3-4nu) sinh 2x + 2x]}

(normal displacement also zero at the top). With the top held by the drive springs instead,
``kappa_d = K_d / a**2`` per area on u_x(H) (the normal displacement still zero there)::

    k_SH = G q (G q tanh x + kappa_d) / (G q + kappa_d tanh x),

and k_PSV from the exact solution of the layer's boundary-value problem (:func:`k_psv_bvp`).
Limits: q -> 0 gives ``G/H`` (clamped) and ``(H/G + 1/kappa_d)**-1`` (springs: the layer's shear
in series with the springs); qH -> inf the half-space values ``G q/(1-nu)`` (PSV, normal stress
free) and ``G q`` (SH), used above ``x = QH_HALFSPACE`` where the layer's correction,
~ x**2 exp(-2x), is below 1e-15 (and sinh would overflow from x ~ 355 on). nu = 1/2 (rubber) is
regular in every form here. A slider on a rigid base has twice the stiffness of a fault between
two half-spaces (QDYN's ``fault_stress.f90`` uses ``G q / 2``).

:func:`k_psv_bvp` integrates the plane-strain Navier equations across the layer in the
variables ``y = (U, W, S, T)`` (u_x = i U e^{iqx}, u_z = W e^{iqx}, sigma_xz = i S e^{iqx},
sigma_zz = T e^{iqx}), whose coefficients stay finite at nu = 1/2::

    U' = -q W + S/G,              W' = nu/(1-nu) q U + (1-2nu)/(2G(1-nu)) T,
    S' = 2G q**2 U/(1-nu) - nu/(1-nu) q T,     T' = q S,

``y(H) = expm(A H) y(0)`` with U(0) = 1, T(0) = 0 and two conditions at the top; the stiffness is
``-S(0)``. It reproduces the clamped closed form to 2e-13 for qH up to 25 and nu from 0 to 1/2
(tests/unit/test_elastic.py): the closed forms above were checked against it, not copied.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

QH_HALFSPACE = 20.0  # above this qH the slab is a half-space to round-off


def k_halfspace(q: ArrayLike, G: float, nu: float) -> tuple[np.ndarray, np.ndarray]:
    """(k_PSV, k_SH) of a half-space with the normal stress free: G q/(1-nu), G q."""
    q = np.asarray(q, float)
    return G * q / (1.0 - nu), G * q


def k_sh(q: ArrayLike, H: float, G: float, kappa_d: float | None = None) -> np.ndarray:
    """Anti-plane stiffness of the slab (module docstring): top clamped, or on springs kappa_d per area."""
    q = np.asarray(q, float)
    x = q * H
    small = x < 1e-12
    xs = np.where(small, 1.0, np.minimum(x, QH_HALFSPACE))
    t = np.tanh(xs)
    Gq = G * q
    if kappa_d is None:
        k = Gq / t
        k0 = G / H
    else:
        k = Gq * (Gq * t + kappa_d) / (Gq + kappa_d * t)
        k0 = 1.0 / (H / G + 1.0 / kappa_d)
    k = np.where(x > QH_HALFSPACE, Gq, k)
    return np.where(small, k0, k)


def k_psv(q: ArrayLike, H: float, G: float, nu: float, kappa_d: float | None = None) -> np.ndarray:
    """In-plane stiffness of the slab with the normal stress free (module docstring): the closed
    form with the top clamped, the boundary-value problem with the top on springs."""
    q = np.asarray(q, float)
    x = q * H
    small = x < 1e-12
    far = x > QH_HALFSPACE
    if kappa_d is None:
        xs = np.where(small | far, 1.0, x)
        num = (3 - 4 * nu) * np.cosh(2 * xs) + 2 * xs**2 + 8 * nu**2 - 12 * nu + 5
        den = (1 - nu) * ((3 - 4 * nu) * np.sinh(2 * xs) + 2 * xs)
        k = G * np.where(small | far, 1.0, q) * num / den
        k0 = G / H
    else:
        mid = ~(small | far)
        k = np.empty_like(q)
        if mid.any():
            k[mid] = k_psv_bvp(q[mid], H, G, nu, kappa_d)
        k0 = 1.0 / (H / G + 1.0 / kappa_d)
    k = np.where(far, G * q / (1 - nu), k)
    return np.where(small, k0, k)


def _propagator(q: ArrayLike, H: float, G: float, nu: float) -> np.ndarray:
    """expm(A H) of the plane-strain equations in y = (U, W, S, T) (module docstring), per q."""
    from scipy.linalg import expm

    q = np.asarray(q, float)
    A = np.zeros(q.shape + (4, 4))
    c1, c2 = nu / (1 - nu), (1 - 2 * nu) / (2 * G * (1 - nu))
    A[..., 0, 1], A[..., 0, 2] = -q, 1.0 / G
    A[..., 1, 0], A[..., 1, 3] = c1 * q, c2
    A[..., 2, 0], A[..., 2, 3] = 2 * G * q * q / (1 - nu), -c1 * q
    A[..., 3, 2] = q
    return expm(A * H)


def k_psv_bvp(q: ArrayLike, H: float, G: float, nu: float, kappa_d: float | None = None) -> np.ndarray:
    """k_PSV from the layer's boundary-value problem (module docstring), for qH up to ~25; top
    clamped (``kappa_d`` None) or on tangential springs kappa_d per area, normal displacement zero."""
    P = _propagator(q, H, G, nu)  # y(H) = P y(0), y(0) = (1, W0, S0, 0)
    r1 = P[..., 1, :]  # W(H) = 0
    r2 = P[..., 0, :] if kappa_d is None else P[..., 2, :] + kappa_d * P[..., 0, :]  # U(H) = 0, or S(H) = -kappa_d U(H)
    M = np.stack([np.stack([r1[..., 1], r1[..., 2]], -1), np.stack([r2[..., 1], r2[..., 2]], -1)], -2)
    rhs = -np.stack([r1[..., 0], r2[..., 0]], -1)
    sol = np.linalg.solve(M, rhs[..., None])[..., 0]
    return -sol[..., 1]


def k_psv_twoport_bvp(q: ArrayLike, H: float, G: float, nu: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(K11, K12, K22) of the layer's in-plane (P-SV) two-port (:func:`slab_twoport`) from its
    boundary-value problem (module docstring), for qH up to ~25: the bottom's traction
    ``-(K11 u_b + K12 u_t)`` and the top's ``-(K12 u_b + K22 u_t)`` for tangential displacements u_b
    (normal stress free there) and u_t (normal displacement zero there). K21 = K12 (reciprocity) is
    checked by the tests, not assumed: the solve gives it separately (:func:`_psv_twoport_full`)."""
    k11, k12, k21, k22 = _psv_twoport_full(q, H, G, nu)
    return k11, 0.5 * (k12 + k21), k22


def _psv_twoport_full(q: ArrayLike, H: float, G: float, nu: float):
    P = _propagator(q, H, G, nu)  # y(H) = P y(0), y(0) = (U0, W0, S0, 0)
    M = np.stack([np.stack([P[..., 1, 1], P[..., 1, 2]], -1), np.stack([P[..., 0, 1], P[..., 0, 2]], -1)], -2)
    out = []
    for ub, ut in ((1.0, 0.0), (0.0, 1.0)):  # W(H) = 0, U(H) = u_t
        rhs = np.stack([-ub * P[..., 1, 0], ut - ub * P[..., 0, 0]], -1)
        w0, s0 = np.moveaxis(np.linalg.solve(M, rhs[..., None])[..., 0], -1, 0)
        sh = ub * P[..., 2, 0] + w0 * P[..., 2, 1] + s0 * P[..., 2, 2]
        out.append((-s0, sh))  # the body's force on the bottom is S(0), on the top -S(H)
    (k11, k21), (k12, k22) = out
    return k11, k12, k21, k22


def slab_twoport(qx: ArrayLike, qy: ArrayLike, H: float, G: float, nu: float) -> tuple[np.ndarray, ...]:
    """The slab as a two-port per Fourier mode (issue 28: the viscoelastic slab under the drive springs).

    The slab's bottom (the interface, tangential displacement u_b along x, normal stress free) and its
    top (tangential displacement u_t, normal displacement zero) carry the tractions, per area and per
    channel c (P-SV: along q; SH: across q)::

        t_b = -(K11c u_b + K12c u_t),   t_t = -(K12c u_b + K22c u_t)

    SH in closed form (K11 = K22 = G q coth x, K12 = -G q / sinh x, x = qH), P-SV from the
    boundary-value problem (:func:`k_psv_twoport_bvp`); q -> 0: G/H (1, -1; -1, 1); qH above
    QH_HALFSPACE: the half-space values and K12 = 0 (|K12| ~ x exp(-x) there, and what it changes in
    the bottom's force, K12**2 / K22, is below 1e-15 of it). Every entry is G times a function of q:
    linear in the modulus, as the Maxwell arms need. With the bottom moving along x only, the top's
    displacement in channel c is ``w_c Z_c`` with ``w_P = qx/q``, ``w_S = qy/q`` (the scalar model of
    the module docstring), and the top field Z_c is real in space. Returns, on the (qx, qy) grid::

        A = w_P**2 K11P + w_S**2 K11S   (the clamped kernel, :func:`slab_kernel` with the top held)
        B_P, B_S = w_c**2 K12c          (the top's pull on the bottom)
        D_P, D_S = K22c                 (the top's own stiffness)

    so that the bottom's force is ``-(A u + B_P Z_P + B_S Z_S)`` and channel c's top, held by springs
    kappa per area, is in equilibrium where ``K12c u + K22c Z_c + kappa Z_c = 0`` (q != 0; the
    drive's displacement enters the uniform mode, channel P). Eliminating Z gives back
    :func:`slab_kernel` with the springs (tests/unit/test_elastic.py). At q = 0: w_P = 1, w_S = 0.
    """
    qx, qy = np.broadcast_arrays(np.asarray(qx, float), np.asarray(qy, float))
    q = np.hypot(qx, qy)
    x = q * H
    small = x < 1e-12
    far = x > QH_HALFSPACE
    mid = ~(small | far)
    xs = np.where(mid, x, 1.0)
    Gq = G * q
    s11 = np.where(mid, Gq / np.tanh(xs), np.where(far, Gq, G / H))
    s12 = np.where(mid, -Gq / np.sinh(xs), np.where(far, 0.0, -G / H))
    p11 = np.where(far, Gq / (1 - nu), G / H)
    p12 = np.where(far, 0.0, -G / H)
    p22 = p11.copy()
    if mid.any():
        p11[mid], p12[mid], p22[mid] = k_psv_twoport_bvp(q[mid], H, G, nu)
    with np.errstate(invalid="ignore", divide="ignore"):
        wp = np.where(q > 0, qx * qx / (q * q), 1.0)
    ws = 1.0 - wp
    return wp * p11 + ws * s11, wp * p12, ws * s12, p22, s11.copy()


def _mix(qx: ArrayLike, qy: ArrayLike, kp: np.ndarray, ks: np.ndarray, k0: float) -> np.ndarray:
    qx, qy = np.broadcast_arrays(np.asarray(qx, float), np.asarray(qy, float))
    q2 = qx * qx + qy * qy
    with np.errstate(invalid="ignore", divide="ignore"):
        k = (qx * qx * kp + qy * qy * ks) / q2
    return np.where(q2 > 0, k, k0)


def slab_kernel(qx: ArrayLike, qy: ArrayLike, H: float, G: float, nu: float, kappa_d: float | None = None) -> np.ndarray:
    """k(qx, qy) of the slab (module docstring); at q = 0 the uniform shear, G/H or (H/G + 1/kappa_d)**-1."""
    q = np.hypot(*np.broadcast_arrays(np.asarray(qx, float), np.asarray(qy, float)))
    k0 = G / H if kappa_d is None else 1.0 / (H / G + 1.0 / kappa_d)
    return _mix(qx, qy, k_psv(q, H, G, nu, kappa_d), k_sh(q, H, G, kappa_d), k0)


def halfspace_kernel(qx: ArrayLike, qy: ArrayLike, G: float, nu: float, kappa_d: float) -> np.ndarray:
    """The limit H -> inf: the half-space values, with k(0) = kappa_d (the drive springs alone hold
    the uniform mode)."""
    q = np.hypot(*np.broadcast_arrays(np.asarray(qx, float), np.asarray(qy, float)))
    kp, ks = k_halfspace(q, G, nu)
    return _mix(qx, qy, kp, ks, kappa_d)


def interface_kernel(geometry: str, qx: ArrayLike, qy: ArrayLike, H: float, G: float, nu: float,
                     kappa_d: float | None) -> np.ndarray:
    """k(qx, qy) of the body above the interface for a config's ``geometry``: :func:`slab_kernel`
    (top on the drive springs kappa_d, or clamped to the rigid plate of the dead weight where
    kappa_d is None) for 'slab', :func:`halfspace_kernel` for 'halfspace'."""
    if geometry == "slab":
        return slab_kernel(qx, qy, H, G, nu, kappa_d)
    if geometry == "halfspace":
        return halfspace_kernel(qx, qy, G, nu, kappa_d)
    raise ValueError(f"geometry {geometry!r} has no elastic kernel (only 'slab' and 'halfspace')")


def config_kernel(cfg, qx: ArrayLike, qy: ArrayLike) -> np.ndarray:
    """k(qx, qy) [Pa/m] of the body of a :class:`~slipchain.model.config.Config`: its geometry, H = N_L a,
    G, nu, and what holds its top (``Config.top_stiffness``: the drive springs, or the dead weight's
    rigid plate)."""
    return interface_kernel(cfg.geometry, qx, qy, cfg.H, cfg.G, cfg.nu, cfg.top_stiffness)


def uniform_stiffness(cfg) -> float:
    """k(0) [Pa/m]: the stiffness per area of the uniform mode of the slab, (H/G + 1/kappa_d)**-1 (G/H
    under the dead weight: the layer's shear against the plate), or of the half-space, kappa_d (the
    drive springs alone)."""
    return float(config_kernel(cfg, 0.0, 0.0))


def elastic_kernel(cfg) -> np.ndarray:
    """a**2 k(q) [N/m] on the rfft2 grid of a config's (N, Ly) interface (slab, halfspace): the block
    force is -IFFT[a**2 k FFT(x - v_d t)]."""
    return cfg.a**2 * config_kernel(cfg, *wavenumbers(cfg.N, cfg.Ly, cfg.a))


def twoport_kernel(cfg) -> np.ndarray:
    """a**2 times the slab's two-port (:func:`slab_twoport`) on the rfft2 grid of a config's (N, Ly)
    interface, stacked (6, Lx, Ly//2 + 1): A, w_P**2 (not scaled), K12P, K12S, K22P, K22S [N/m]."""
    A, bp, bs, dp, ds = slab_twoport(*wavenumbers(cfg.N, cfg.Ly, cfg.a), cfg.H, cfg.G, cfg.nu)
    qx, qy = wavenumbers(cfg.N, cfg.Ly, cfg.a)
    q2 = qx * qx + qy * qy
    with np.errstate(invalid="ignore", divide="ignore"):
        wp = np.where(q2 > 0, qx * qx / q2, 1.0)
        k12p = np.where(wp > 0, bp / wp, 0.0)
        k12s = np.where(wp < 1, bs / (1.0 - wp), 0.0)
    a2 = cfg.a**2
    return np.stack([a2 * A, wp, a2 * k12p, a2 * k12s, a2 * dp, a2 * ds])


def twoport_energy(tp: np.ndarray, kappa: float, xh: np.ndarray, Z: np.ndarray, xd: float, wgt: np.ndarray) -> float:
    """The elastic energy of the slab under the drive springs, its top a state of its own [J]: per mode and
    channel c, with W_c = w_c**2 (:func:`twoport_kernel`'s ``tp``; the top's displacement is w_c Z_c),

        1/2 [A |x|^2 + sum_c W_c (2 K12c Re(x* Z_c) + (K22c + kappa) |Z_c|^2)]   (uniform mode: kappa |Z_P - X_d|^2)

    summed with Parseval's weights ``wgt``; ``xh`` the blocks' transform, ``Z`` (2, ...) the top's, ``xd``
    the drive's displacement times the number of blocks (the uniform mode of its transform)."""
    A, W = tp[0], np.stack([tp[1], 1.0 - tp[1]])
    K12, K22 = tp[2:4], tp[4:6]
    el = A * abs(xh) ** 2 + np.sum(W * (2 * K12 * (np.conj(xh) * Z).real + (K22 + kappa) * abs(Z) ** 2), axis=0)
    el[0, 0] += kappa * (abs(Z[0, 0, 0] - xd) ** 2 - abs(Z[0, 0, 0]) ** 2)
    return float(0.5 * np.sum(wgt * el))


def parseval_weights(Lx: int, Ly: int) -> np.ndarray:
    """w on the rfft2 grid with sum_r f g = sum_q w Re(F conj G) for real (Lx, Ly) fields f, g of
    transforms F, G: 2/n on the columns that stand for two of the full grid, 1/n on ky = 0 (and on
    ky = Ly/2 for even Ly), n = Lx Ly."""
    n = Lx * Ly
    w = np.full((Lx, Ly // 2 + 1), 2.0 / n)
    w[:, 0] = 1.0 / n
    if Ly % 2 == 0:
        w[:, -1] = 1.0 / n
    return w


def wavenumbers(Lx: int, Ly: int, a: float) -> tuple[np.ndarray, np.ndarray]:
    """(qx, qy) on the grid of ``rfft2`` of an (Lx, Ly) periodic field of spacing a (1/m), shapes
    (Lx, Ly//2 + 1): the full axis first, the half axis last."""
    qx = 2 * np.pi * np.fft.fftfreq(Lx, a)
    qy = 2 * np.pi * np.fft.rfftfreq(Ly, a)
    return np.meshgrid(qx, qy, indexing="ij")


def elastic_force(u: np.ndarray, X: float | np.ndarray, k_half: np.ndarray, a: float, fft=None) -> np.ndarray:
    """The slab's force on the interface blocks, ``-a**2 IFFT[k(q) FFT(u - X)]`` (N), for an (Lx, Ly)
    periodic field ``u`` of block displacements and the drive's displacement ``X`` (scalar or
    field); ``k_half`` is k on the rfft2 grid (:func:`wavenumbers`). One rfft2/irfft2 pair.
    ``fft``: the FFT module of the arrays' namespace (scipy.fft by default; with CuPy arrays and
    cupyx.scipy.fft the same code runs on a GPU)."""
    if fft is None:
        import scipy.fft as fft
    d = u - X
    return -(a * a) * fft.irfft2(k_half * fft.rfft2(d), s=d.shape)


__all__ = ["QH_HALFSPACE", "k_psv_twoport_bvp", "parseval_weights", "slab_twoport", "twoport_energy", "twoport_kernel", "config_kernel", "elastic_force", "elastic_kernel", "uniform_stiffness", "interface_kernel", "wavenumbers", "halfspace_kernel", "k_halfspace", "k_psv", "k_psv_bvp", "k_sh", "slab_kernel"]

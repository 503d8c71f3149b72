"""The numerical scheme of the two-chain model, written once: the per-block update and the contact solve.

The functions here are plain Python; each backend compiles them for its target
(:func:`compile_for`): the CPU backend with ``numba.njit`` (:mod:`.backends.cpu`), the CUDA backend
with ``numba.cuda.jit(device=True)`` (:mod:`.backends.cuda`). The batch loops that call them live
in the backends.

Equations of motion (docs/model.md; Fig. 4 of the paper), periodic in i:

    m   du_i/dt = K  (x_{i+1} + x_{i-1} - 2 x_i) + K_T (X_i - x_i)
                  - m eta (3 u_i - u_{i+1} - u_{i-1} - U_i) - f(u_i, v*_i) [if i carries a contact]
    N_L m dU_i/dt = K_L (X_{i+1} + X_{i-1} - 2 X_i) + K_T (x_i - X_i) + K_d (v_d t - X_i)
                  - m eta (3 U_i - U_{i+1} - U_{i-1} - u_i)

With the dead-weight drive the term K_d (v_d t - X_i) is replaced by a constant force F_b on every
UL block (K_d = 0 and the P_FCONST parameter = F_b).

Scheme (one step n -> n+1, dt):
 1. All spring, drive and inter-block damping forces from (x^n, X^n, u^n, U^n, t^n).
 2. Velocities: U^{n+1} = U^n + dt F/(N_L m); IL blocks without a contact likewise.
 3. IL blocks with a contact: backward Euler in the contact force alone, a scalar equation
    ``m u + dt f(u, v*) = r``, ``r = m u^n + dt F_i``, solved by Newton's method in y = log10(|u|/v*), warm-started from the previous step: two
    branch-free, vectorised steps for all contacts (the CPU's ``newton_pass``), accepted when the second
    is below NEWTON_TOL = 1e-5
    decades (error left < 3e-10 decades); the others continue in :func:`solve_contact`, whose
    last resort is bisection-safeguarded Newton on a bracket that always contains the root.
 4. Positions: x^{n+1} = x^n + dt u^{n+1}, X^{n+1} = X^n + dt U^{n+1}.

Without contacts and damping this is symplectic Euler: first order in the velocities
(second order for positions, being leapfrog with velocities at half steps), with a bounded
energy error. The springs and the explicit damping together bound the step: per Fourier mode
h**2 omega**2 + 2 h gamma < 4 in the scalar case, the eigenvalues of each mode's amplification
matrix in general (:mod:`slipchain.model.stability`; 6.87e-7 s at the paper's values), which
:class:`slipchain.model.config.Config` enforces for every integrator (issue 26). The contact term is
L-stable (backward Euler), so the ~1e-15 s relaxation times of f near sticking (docs/model.md,
numerical facts) impose no limit; the fixed step's only other limit is that the scalar equation
keep one root, dt*max|df/du|_weakening < m (integrator = 'fold' and 'adaptive' lift it).
Overall order: 1 (checked by tests/test_convergence.py).

Batch layout: arrays of shape (B, N) for the state, (B, C) for contacts (padded; ``n_contacts``
gives each row's count), (B, P) for the parameters. Rows are independent.
"""

from __future__ import annotations

import math

import types
from typing import Callable

LN10 = math.log(10.0)
LOG10_2 = math.log10(2.0)

# Parameter columns in the (B, P) parameter array.
P_K, P_KL, P_KT, P_KD, P_M, P_ML, P_META, P_VD, P_DT, P_AMP, P_C, P_ETAC, P_SLOW, P_FCONST = range(14)
P_KY, P_KLY, P_LY, P_LAT, P_FOLD = range(14, 19)
N_PARAMS = 19  # P_FCONST: constant force on every UL block (dead-weight drive; 0 with the spring drive)
# P_KY, P_KLY: IL and UL springs along y (G a, N_L G a; chain2d); P_LY: Ly; P_LAT: 1 for the 2-D
# lattice stencil (chain2d), 0 for the chain. With the slab and half-space, P_META is m*gamma, gamma
# the radiation damping rate (Config.radiation_damping_rate). P_FOLD: 1 for integrator = 'fold'.

# Output columns per sample and accumulator columns.
O_FD, O_XMEAN, O_XUMEAN = range(3)  # mean f_d over the sample; mean x and mean X at its end
N_OUT = 3
A_WDRIVE, A_WDAMP, A_WCONTACT, A_WVISC = range(4)  # work by drive point, damping, contacts, the bulk's Maxwell arms
N_ACC = 4
BODY_ROWS = 4  # material 'prony': work rows of a row's body state after its 2 J internal fields (backends.viscoelastic)
# material 'prony' on the slab under the drive springs: the top's rows after those (State.top; backends.viscoelastic):
# Z_P, Z_S, J arms of channel P, J of S, and one row [drive force sum, step of the last solve], the body state's last


def top_rows(J: int) -> int:
    """Rows of the top's state in the body state (2 J + 3; they start at row 2 J + BODY_ROWS)."""
    return 2 * J + 3
C_F, C_U, C_U2, C_SLOW = range(4)  # per-contact sums over steps: force, u, u^2, steps with |u| < slow
N_CACC = 4
Y_LOG, Y_P, Y_Q = range(3)  # per-contact solver state: y = log10(|u|/v*), p = 10**y, q = exp(-c y^2)
N_YS_STATE = 3  # the rows above are the solver's state; the rows below are inputs
Y_FA, Y_FB = 3, 4  # integrator 'fold' (issue 12): the contact equation's folds (local max, min of H in y)
N_YS = 5

# LLVM may contract to FMA, reassociate sums and use reciprocals; never assume finite values
# (the non-finite checks must keep working).
FASTMATH = {"contract", "reassoc", "nsz", "arcp"}

NEWTON_TOL = 1e-5  # accept after a Newton step in y (decades) below this: the error left,
# ~|H''/2H'|*d**2 < 3e-10 decades, is a relative velocity error below 1e-9
TAYLOR_MAX = 2e-3  # largest |z| for which the vectorised pass updates exp by its Taylor series



def exp_taylor(z):
    """exp(z) for |z| <= TAYLOR_MAX = 2e-3 by its Taylor series to z**5 (relative error < 1e-19)."""
    return 1.0 + z * (1.0 + z * (0.5 + z * (1.0 / 6.0 + z * (1.0 / 24.0 + z / 120.0))))


def scaled_exp(v, z):
    """v*exp(z): multiplicative update, by the Taylor series for small z."""
    if abs(z) <= TAYLOR_MAX:
        return v * exp_taylor(z)
    return v * math.exp(z)


def solve_contact_bracketed(ra, a, b, c, y):
    """Root y of  a*10**y + b*exp(-c*y**2) = ra  (ra > 0, c > 0) by safeguarded Newton.

    The bracket [y_lo, y_hi] has H(y_lo) <= 0 <= H(y_hi) by construction:
    y_hi = log10(ra/a); y_lo = min(y_hi - log10 2, -sqrt(ln(2b/ra)/c)); every y below y_lo has
    H(y) <= 0 too, every y above y_hi H(y) > 0.
    """
    y_lo, y_hi = contact_bracket(ra, a, b, c)
    return solve_on_bracket(ra, a, b, c, y, y_lo, y_hi)


def contact_bracket(ra, a, b, c):
    """(y_lo, y_hi) with H(y) <= 0 for every y <= y_lo and H(y) > 0 for every y >= y_hi, H(y) =
    a*10**y + b*exp(-c*y**2) - ra (:func:`solve_contact_bracketed`)."""
    y_hi = math.log10(ra / a)
    y_lo = y_hi - LOG10_2
    lg = math.log(2.0 * b / ra)
    if lg > 0.0:
        y_lo = min(y_lo, -math.sqrt(lg / c))
    return y_lo, y_hi


def solve_on_bracket(ra, a, b, c, y, y_lo, y_hi):
    """Safeguarded Newton for H(y) = a*10**y + b*exp(-c*y**2) - ra on [y_lo, y_hi], H(y_lo) <= 0 <= H(y_hi),
    from y (the midpoint if y is outside)."""
    if not (y_lo < y < y_hi):
        y = 0.5 * (y_lo + y_hi)
    for _ in range(200):
        p = math.exp(LN10 * y)
        q = math.exp(-c * y * y)
        h = a * p + b * q - ra
        dh = LN10 * a * p - 2.0 * c * y * b * q
        if h > 0.0:
            y_hi = y
        else:
            y_lo = y
        if dh > 0.0:
            y_new = y - h / dh
            if not (y_lo < y_new < y_hi):
                y_new = 0.5 * (y_lo + y_hi)
        else:
            y_new = 0.5 * (y_lo + y_hi)
        if abs(y_new - y) < 1e-13 or y_hi - y_lo < 1e-13:
            return y_new
        y = y_new
    return y


def solve_contact_fold(r, m_eff, b, c, vstar, y, p, q, ya, yb):
    """:func:`solve_contact` for integrator = 'fold' (issue 12): when dt is above the unique-root
    limit, H(y) = m_eff v* 10**y + b exp(-c y**2) - |r| has a local maximum at ``ya`` and a local
    minimum at ``yb`` (the folds, fixed per contact and dt: :func:`fold_points`) and up to three
    roots. The root on the branch the contact is on is kept (continuation: the lower, sticking
    branch y < ya, or the upper, sliding branch y > yb); when that branch has no root any more (the
    contact passed its fold), the contact jumps to the other branch: the limit of contacts that
    relax infinitely fast. Without folds (ya >= yb) this is :func:`solve_contact`.
    """
    ra = abs(r)
    if not (ya < yb) or ra < 1e-300 or c == 0.0:
        return solve_contact(r, m_eff, b, c, vstar, y, p, q)
    s = 1.0 if r > 0.0 else -1.0
    a = m_eff * vstar
    if y < 0.5 * (ya + yb):  # on the lower branch: keep it while its root exists (H(ya) >= 0)
        lower = a * math.exp(LN10 * ya) + b * math.exp(-c * ya * ya) - ra >= 0.0
    else:  # on the upper branch: keep it while its root exists (H(yb) <= 0)
        lower = a * math.exp(LN10 * yb) + b * math.exp(-c * yb * yb) - ra > 0.0
    y_lo, y_hi = contact_bracket(ra, a, b, c)
    if lower:
        y = solve_on_bracket(ra, a, b, c, y, min(y_lo, ya), ya)
    else:
        y = solve_on_bracket(ra, a, b, c, y, yb, max(y_hi, yb))
    p = math.exp(LN10 * y)
    return s * vstar * p, y, p, math.exp(-c * y * y)


def taylor_newton_step(a, b, c, ra, y, p, q):
    """One Newton step in y for a*p + b*q = ra with p = 10**y, q = exp(-c y**2) updated by Taylor.

    Returns (y, p, q, slope dH/dy at the start, step d, largest |exponent| used).
    """
    dh = LN10 * a * p - 2.0 * c * y * b * q
    d = (a * p + b * q - ra) / dh
    z = -LN10 * d
    w = c * d * (2.0 * y - d)
    return y - d, p * exp_taylor(z), q * exp_taylor(w), dh, d, max(abs(z), abs(w))


def solve_contact(r, m_eff, b, c, vstar, y, p, q):
    """Velocity u solving  m_eff*u + b*exp(-c*y**2)*sign(u) = r,  y = log10(|u|/vstar).

    The implicit contact step (scheme, step 3): m_eff = m*(1 + dt*eta_c) (the contact damping is
    implicit too), b = dt*epsilon*f0. (y, p, q) = (y, 10**y, exp(-c*y**2)) of this contact's
    previous step are the warm start. Newton's method in y updates 10**y and exp(-c y^2)
    multiplicatively (no transcendental call while the steps are small); if it does not settle
    within a few steps, the bracketed solver takes over. Returns (u, y, p, q) with the new solver
    state.
    """
    ra = abs(r)
    if ra < 1e-300:
        return 0.0, y, p, q
    s = 1.0 if r > 0.0 else -1.0
    if c == 0.0:  # Coulomb limit: stuck (u = 0) unless |r| exceeds b
        if ra <= b:
            return 0.0, y, p, q
        w = (ra - b) / (m_eff * vstar)
        return s * w * vstar, math.log10(w), w, 1.0
    a = m_eff * vstar
    y0 = y
    for _ in range(6):
        h = a * p + b * q - ra
        dh = LN10 * a * p - 2.0 * c * y * b * q
        if not dh > 0.0:
            break
        d = h / dh
        if abs(d) > 1.0:
            break
        p = scaled_exp(p, -LN10 * d)
        q = scaled_exp(q, c * d * (2.0 * y - d))
        y -= d
        if abs(d) < NEWTON_TOL:
            return s * vstar * p, y, p, q
    y = solve_contact_bracketed(ra, a, b, c, y0)
    p = math.exp(LN10 * y)
    return s * vstar * p, y, p, math.exp(-c * y * y)


def block_update(i, ip, im, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm, dtmL):
    """Explicit velocity update of IL block i and UL block i with neighbours ip, im (scheme, steps 1-2).

    Writes the new velocities un[i], Un[i] (contacts not yet applied) and the damping forces
    dampx[i], dampX[i] (for the damping work).
    """
    dx = meta * (ur[ip] + ur[im] + Ur[i] - 3.0 * ur[i])
    dX = meta * (Ur[ip] + Ur[im] + ur[i] - 3.0 * Ur[i])
    fx = K * (xr[ip] + xr[im] - 2.0 * xr[i]) + KT * (Xr[i] - xr[i]) + dx
    fX = KL * (Xr[ip] + Xr[im] - 2.0 * Xr[i]) + KT * (xr[i] - Xr[i]) + Kd * (drive - Xr[i]) + fconst + dX
    un[i] = ur[i] + dtm * fx
    Un[i] = Ur[i] + dtmL * fX
    dampx[i] = dx
    dampX[i] = dX


def block_update_2d(i, ip, im, jp, jm, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, KY, KLY, meta, drive,
                    fconst, dtm, dtmL):
    """:func:`block_update` on the square lattice of 'chain2d' (issue 13): neighbours ip, im along x
    and jp, jm along y; springs K, K_L along x and K_Y = G a, K_LY = N_L G a along y, a pair
    damper m*eta on every spring (the chain's, extended)::

        m dU... as the chain, plus  K_Y (x_jp + x_jm - 2 x_i) - m eta (2 u_i - u_jp - u_jm)  (IL)
                                   K_LY (X_jp + X_jm - 2 X_i) - m eta (2 U_i - U_jp - U_jm) (UL)

    With Ly = 1 (jp = jm = i) the y terms vanish and this is the chain to round-off.
    """
    dx = meta * (ur[ip] + ur[im] + ur[jp] + ur[jm] + Ur[i] - 5.0 * ur[i])
    dX = meta * (Ur[ip] + Ur[im] + Ur[jp] + Ur[jm] + ur[i] - 5.0 * Ur[i])
    fx = (K * (xr[ip] + xr[im] - 2.0 * xr[i]) + KY * (xr[jp] + xr[jm] - 2.0 * xr[i]) + KT * (Xr[i] - xr[i]) + dx)
    fX = (KL * (Xr[ip] + Xr[im] - 2.0 * Xr[i]) + KLY * (Xr[jp] + Xr[jm] - 2.0 * Xr[i]) + KT * (xr[i] - Xr[i])
          + Kd * (drive - Xr[i]) + fconst + dX)
    un[i] = ur[i] + dtm * fx
    Un[i] = Ur[i] + dtmL * fX
    dampx[i] = dx
    dampX[i] = dX


def row_parameters(p):
    """The scheme's constants for one row ``p`` of the (B, P) parameter array: (K, K_L, K_T, K_d,
    m, m*eta, v_d, F_b, dt, dt/m, dt/(N_L m), b = dt*epsilon*f0, c, m_eff = m(1 + dt*eta_c), slow)."""
    dt = p[P_DT]
    m = p[P_M]
    return (p[P_K], p[P_KL], p[P_KT], p[P_KD], m, p[P_META], p[P_VD], p[P_FCONST], dt, dt / m, dt / p[P_ML],
            dt * p[P_AMP], p[P_C], m * (1.0 + dt * p[P_ETAC]), p[P_SLOW])


# The scheme's functions in dependency order; those marked True are small enough to inline.
FUNCTIONS: tuple[tuple[str, bool], ...] = (
    ("exp_taylor", True), ("scaled_exp", True), ("solve_on_bracket", False), ("contact_bracket", True),
    ("solve_contact_bracketed", False),
    ("taylor_newton_step", True), ("solve_contact", False), ("solve_contact_fold", False), ("block_update", True), ("block_update_2d", True), ("row_parameters", True),
)


def fold_points(a, b, c):
    """The folds of the contact equation (:func:`solve_contact_fold`) for arrays a = m_eff v*,
    b = dt epsilon f0 and a scalar c > 0: (ya, yb) with dH/dy < 0 exactly on (ya, yb), or
    (+inf, -inf) where dH/dy > 0 everywhere (dt below the contact's unique-root limit).

    dH/dy = 0  <=>  phi(y) = ln y - c y**2 - ln(10) y + ln(2 c b / (ln(10) a)) = 0 (y > 0); phi is
    concave with its maximum at y* = (sqrt(ln(10)**2 + 8c) - ln(10)) / (4c): no fold if
    phi(y*) <= 0, else one zero on each side, found by bisection to 1e-14 decades.
    """
    import numpy as np

    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    ya = np.full(a.shape, np.inf)
    yb = np.full(a.shape, -np.inf)
    if c <= 0.0 or a.size == 0:
        return ya, yb
    const = np.log(2.0 * c * b / (LN10 * a))
    ystar = (math.sqrt(LN10**2 + 8.0 * c) - LN10) / (4.0 * c)

    def phi(y):
        return np.log(y) - c * y * y - LN10 * y + const

    has = phi(np.full(a.shape, ystar)) > 0.0
    if not has.any():
        return ya, yb
    big = np.full(a.shape, ystar + 1.0)
    while np.any(has & (phi(big) >= 0.0)):
        big = np.where(phi(big) >= 0.0, 2.0 * big, big)
    for lo0, hi0, out, rising in ((np.full(a.shape, 1e-300), np.full(a.shape, ystar), ya, True),
                                  (np.full(a.shape, ystar), big, yb, False)):
        lo, hi = lo0.copy(), hi0.copy()
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            up = phi(mid) > 0.0
            lo, hi = np.where(up == rising, lo, mid), np.where(up == rising, mid, hi)
            if np.all(hi - lo < 1e-14):
                break
        out[has] = (0.5 * (lo + hi))[has]
    return ya, yb


def compile_for(jit: Callable[[str, bool], Callable[[Callable], Callable]]) -> types.SimpleNamespace:
    """The scheme's functions compiled for one target, each calling the others' compiled versions.

    ``jit(name, inline)`` returns the decorator for one function (for example
    ``numba.njit(cache=True, inline="always")`` on the CPU, ``numba.cuda.jit(device=True)`` on the
    GPU). Each function is rebuilt with a globals dict in which the scheme's other functions are
    already their compiled versions, so one source serves every target.
    """
    namespace = dict(globals())
    out = {}
    for name, inline in FUNCTIONS:
        src = globals()[name]
        fn = types.FunctionType(src.__code__, namespace, name, src.__defaults__, src.__closure__)
        fn.__doc__, fn.__qualname__, fn.__module__ = src.__doc__, src.__qualname__, src.__module__
        out[name] = namespace[name] = jit(name, inline)(fn)
    return types.SimpleNamespace(**out)

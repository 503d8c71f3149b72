"""integrator = 'implicit' (issue 27): backward Euler through stick and creep, the adaptive step's
explicit fold scheme through slip events.

At the physical contact stiffness (epsilon = 1) a slip cycle is ~0.1 ms of slip and ~1 s of
creep, in which every contact sits on the rising branch of eq. (1) and the blocks barely move
(docs/model.md, numerical facts). The explicit springs cap every step of the adaptive stepper at
the stable step (~6.9e-7 s): over a million steps per cycle in which nothing happens. This
stepper (:func:`.compose.implicit_stepper`) is the adaptive stepper with more levels: up to the
explicit top (``Config.step_levels``) it *is* the adaptive step (same code, same results); above it
a step of h = dt 2**k is taken by **backward Euler with everything implicit** -- springs, pair
damping, drive and every contact -- whose step is bounded by accuracy alone:

    M (v' - v) = h [ -K (q + h v') - C v' + g(t + h) - f(v') ],      q' = q + h v'

(q = (x, X), v = (u, U); K the springs K, K_L, K_T, K_d; C the pair damping m*eta; g the drive
K_d v_d t or the dead weight F_b; f eq. (1), the paper's contact force with its damping m eta_c u,
on the contact blocks). The velocities v' solve ``A v' + h f(v') = M v + h (g - K q)``,
A = M + h C + h**2 K, by Newton's method: per iteration one solve with the Jacobian A + h
diag(f'), a cyclic block-tridiagonal matrix (2 x 2 blocks, one per (x_i, X_i) pair) solved in O(N)
by :func:`solve_cyclic` (block Thomas elimination with a rank-2 Sherman-Morrison-Woodbury
correction for the periodic corner; compiled into the loop, so no per-step Python: scipy's banded
solvers cannot be called from it; tests/physics/test_implicit.py checks it against
``scipy.linalg.solve``). Each contact's velocity is updated as the fold scheme's scalar solver does,
in y = log10(|u|/v*) (the law is smooth in y, not in u), at most MAX_DY decades per iteration.

**Where it may be taken.** Backward Euler is taken only while every contact stays on the rising
branch of eq. (1) with a margin, y < Y_MAX (there f' > 0, so the Jacobian is symmetric positive
definite and each contact has one root: no folds), and converges within NEWTON_MAX iterations. A
step that leaves the rising branch, or whose error estimate exceeds the tolerance, is rejected,
and the level falls (to the explicit top at most, where the adaptive step with its fold-aware
contacts resolves the slip event on fine steps). The level rises above the explicit top after an
accepted step whose error is below STEP_UP * tol while every contact is on the rising branch.
An implicit step takes any whole number of base steps up to dt 2**level that ends within the
output sample (it has no folds per level, so no time grid); the level, the error memory and the
back-off go on from one sample to the next (``Batch.carry``, checkpointed).

**Error and stability.** The error estimate is the adaptive step's (h/2 max |a^n - a^(n-1)|,
:func:`.adaptive._error`), so ``step_tol`` means the same for both. Backward Euler is L-stable for
the linear part (every mode, springs and damping together, decays for every h: the eigenvalues of
each mode's amplification matrix lie in the unit disk for every h and tend to 0 as h grows:
:func:`slipchain.model.stability.be_amplification`), so its steps are bounded by accuracy alone;
rejection is the accuracy control, not a stability mechanism.

**Works and energy.** An implicit step's works (drive, damping, contacts) and its share of the mean
drive force are taken by the trapezoidal rule between its start and end (:func:`step_balance`; the
right-end rule errs by h/2 times the change of the power per step). Backward Euler's numerical
dissipation per step, 1/2 (dv^T M dv + dq^T K dq), is no work term; it is the step's **energy
residual** (the change of :func:`chain_energy` minus the works), and a step is accepted only if it
is at most ``energy_tol`` (default ENERGY_TOL = 1e-4) of the magnitudes of the step's works (else it is taken again one level
down): where the blocks ring (steady sliding at epsilon = 1e-2) backward Euler would otherwise damp
their oscillations numerically instead of by the pair damping and the contacts (docs/numerics.md,
"The implicit stepper"). A try that falls back to the explicit levels makes the stepper wait 1, 2,
4, ... (at most MAX_BACKOFF of :mod:`.compose`) explicit steps before the next.

Geometry: the chain (1-D, the compiled cyclic solve above), and the slab, half-space and chain2d
(:func:`krylov_be_try`: the same Newton iteration, each linear solve by preconditioned conjugate
gradients on :class:`SlabSystem`, Fourier-diagonal, or :class:`LatticeSystem`), either drive.

**Material 'prony'** (issue 28): the Maxwell arms enter the backward-Euler system exactly
(:class:`Arms`: their exponential update is exact for the step's constant velocity, so their force
at the step's end is linear in the unknowns, h**2 K_b becoming h (h + S) K_b); their work on the
blocks is taken by the trapezoidal rule as the other works, and the arms are updated by the
accepted velocities (:func:`.viscoelastic.prony_be_commit`). The explicit levels are the fold step
at dt alone (``Config.step_levels`` = 0: chosen before the adaptive levels were validated with the
Prony bulk, and kept so that its results stay as committed; docs/guide/viscoelastic.md).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ...model.config import ENERGY_TOL
from ...model.elastic import twoport_energy
from ...model.stability import TRBDF2_GAMMA, trbdf2_weights
from .cpu import scaled_exp
from .viscoelastic import bulk_forces, combined_fields
from ..scheme import (FASTMATH, LN10, P_AMP, P_C, P_ETAC, P_FCONST, P_K, P_KD, P_KL, P_KLY, P_KT, P_KY, P_M, P_META, P_ML, P_VD,
                      Y_LOG, Y_P, Y_Q)

Y_MAX = -0.01  # backward Euler only while every contact has log10(|u|/v*) below this (the rising branch, with margin)
Y_ABORT = -0.001  # an iterate beyond this gives up at once (f' > 0 up to y = 0: the Jacobian stays positive definite)
NEWTON_MAX = 25
NEWTON_DY = 1e-6  # converged: every contact's last update below this (decades; the error left ~ its square) ...
NEWTON_DV = 1e-4  # ... and every other block's below this times the tolerance (m/s)
MAX_DY = 2.0  # largest change of a contact's y in one Newton iteration (decades)
Y_FLOOR = -40.0  # y of a contact whose velocity the update puts at exactly zero
# ENERGY_TOL: a step's energy residual (trapezoidal works) at most this fraction of its works (module docstring),
# the default of Config.energy_tol, which the controller reads from the batch's step control (compose.CTRL_ENERGY)


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def solve_cyclic(a, bb, d, ox, oX, r, z):
    """Solve J z = r for the cyclic block-tridiagonal symmetric J of the implicit chain.

    Block i (2 x 2, unknowns (u_i, U_i)) is [[a[i], bb], [bb, d]]; blocks i and i+1 (and N-1 and 0,
    the periodic corner) are coupled by diag(ox, oX). ``r`` and ``z`` have length 2N, interleaved
    (u_0, U_0, u_1, U_1, ...). Block Thomas elimination without pivoting (J is positive definite
    wherever it is used) on the matrix with the corner removed and the first and last diagonal
    blocks modified, then a rank-2 Sherman-Morrison-Woodbury correction for the corner (the
    block form of Numerical Recipes' ``cyclic``, gamma = -diagonal of block 0)."""
    n = a.size
    g0 = -a[0]
    g1 = -d
    # modified diagonal blocks: B_0 = D_0 - G, B_{n-1} = D_{n-1} - E G^-1 E (E = diag(ox, oX))
    pa = np.empty(n)  # inverse of the eliminated block i: [[pa, pb], [pb, pd]]
    pb = np.empty(n)
    pd = np.empty(n)
    for i in range(n):
        ai = a[i]
        di = d
        if i == 0:
            ai -= g0
            di -= g1
        if i == n - 1:
            ai -= ox * ox / g0
            di -= oX * oX / g1
        if i > 0:  # B_i - O P_{i-1}^-1 O, O = diag(ox, oX)
            ai -= ox * ox * pa[i - 1]
            di -= oX * oX * pd[i - 1]
            bi = bb - ox * oX * pb[i - 1]
        else:
            bi = bb
        inv = 1.0 / (ai * di - bi * bi)
        pa[i] = di * inv
        pb[i] = -bi * inv
        pd[i] = ai * inv
    rhs = np.empty((2 * n, 3))  # r and the two columns of U, swept together (three independent recurrences)
    rhs[:, 0] = r
    rhs[:, 1:] = 0.0
    rhs[0, 1] = g0
    rhs[2 * n - 2, 1] = ox
    rhs[1, 2] = g1
    rhs[2 * n - 1, 2] = oX
    for i in range(1, n):  # forward: y_i = r_i - O P_{i-1}^-1 y_{i-1}
        qa, qb, qd = ox * pa[i - 1], ox * pb[i - 1], oX * pb[i - 1]
        qe = oX * pd[i - 1]
        for c in range(3):
            y0 = rhs[2 * i - 2, c]
            y1 = rhs[2 * i - 1, c]
            rhs[2 * i, c] -= qa * y0 + qb * y1
            rhs[2 * i + 1, c] -= qd * y0 + qe * y1
    i = n - 1
    for c in range(3):
        y0 = rhs[2 * i, c]
        y1 = rhs[2 * i + 1, c]
        rhs[2 * i, c] = pa[i] * y0 + pb[i] * y1
        rhs[2 * i + 1, c] = pb[i] * y0 + pd[i] * y1
    for i in range(n - 2, -1, -1):  # back: z_i = P_i^-1 (y_i - O z_{i+1})
        for c in range(3):
            y0 = rhs[2 * i, c] - ox * rhs[2 * i + 2, c]
            y1 = rhs[2 * i + 1, c] - oX * rhs[2 * i + 3, c]
            rhs[2 * i, c] = pa[i] * y0 + pb[i] * y1
            rhs[2 * i + 1, c] = pb[i] * y0 + pd[i] * y1
    # Woodbury: z = y - Z (I + V^T Z)^-1 V^T y, V^T w = w_0 + G^-1 E w_{n-1}
    e0 = ox / g0
    e1 = oX / g1
    vy0 = rhs[0, 0] + e0 * rhs[2 * n - 2, 0]
    vy1 = rhs[1, 0] + e1 * rhs[2 * n - 1, 0]
    m00 = 1.0 + rhs[0, 1] + e0 * rhs[2 * n - 2, 1]
    m10 = rhs[1, 1] + e1 * rhs[2 * n - 1, 1]
    m01 = rhs[0, 2] + e0 * rhs[2 * n - 2, 2]
    m11 = 1.0 + rhs[1, 2] + e1 * rhs[2 * n - 1, 2]
    det = m00 * m11 - m01 * m10
    c0 = (m11 * vy0 - m01 * vy1) / det
    c1 = (m00 * vy1 - m10 * vy0) / det
    for k in range(2 * n):
        z[k] = rhs[k, 0] - rhs[k, 1] * c0 - rhs[k, 2] * c1


@nb.njit
def chain_coefficients(p, h, J=0, S=0.0):
    """The constant entries of A = M + h C + h**2 K for the chain (module docstring): (a0, bb, d0,
    ox, oX) -- block diagonal (IL, IL-UL, UL) and the couplings of neighbours (IL, UL). With J > 0
    Maxwell arms (material 'prony', :class:`Arms`) the bulk springs K, K_L, K_T enter as h (h + S) K."""
    m = p[P_M]
    meta = p[P_META]
    K, KL, KT, Kd = p[P_K], p[P_KL], p[P_KT], p[P_KD]
    h2 = h * h
    if J > 0:
        hb = h * (h + S)
        return (m + hb * (2.0 * K + KT) + 3.0 * h * meta, -(hb * KT + h * meta),
                p[P_ML] + hb * (2.0 * KL + KT) + h2 * Kd + 3.0 * h * meta, -(hb * K + h * meta), -(hb * KL + h * meta))
    a0 = m + h2 * (2.0 * K + KT) + 3.0 * h * meta
    bb = -(h2 * KT + h * meta)
    d0 = p[P_ML] + h2 * (2.0 * KL + KT + Kd) + 3.0 * h * meta
    return a0, bb, d0, -(h2 * K + h * meta), -(h2 * KL + h * meta)


@nb.njit
def chain_arms(p, mt, br, h, gx, gX, fx, fX):
    """The chain's arms for a backward-Euler step h (:class:`Arms`, compiled): G = sum_j r_j a_j xi_j of
    both layers into gx, gX, the bulk springs' force of G into fx, fX; returns S = sum_j r_j c_j."""
    J = mt.shape[1]
    S = 0.0
    gx[:] = 0.0
    gX[:] = 0.0
    for j in range(J):
        tau = mt[1, j]
        S += mt[0, j] * (-tau * math.expm1(-h / tau))
        ra = mt[0, j] * math.exp(-h / tau)
        for i in range(gx.size):
            gx[i] += ra * br[j, i]
            gX[i] += ra * br[J + j, i]
    bulk_forces(1, gx, gX, fx, fX, p[P_K], p[P_KL], p[P_KT], 0.0, 0.0)
    return S


@nb.njit
def chain_arm_work(p, mt, br, ur, Ur, un, Un, h):
    """The chain's arms' work over an accepted backward-Euler step by the trapezoidal rule: their force
    -K_b g . v at the start (g = sum_j r_j xi_j) and at the end (g' = G + S v', :class:`Arms`)."""
    n = ur.size
    gx, gX, fx, fX = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    combined_fields(mt.shape[1], mt, br, gx, gX)
    bulk_forces(1, gx, gX, fx, fX, p[P_K], p[P_KL], p[P_KT], 0.0, 0.0)
    w = 0.0
    for i in range(n):
        w += fx[i] * ur[i] + fX[i] * Ur[i]
    S = chain_arms(p, mt, br, h, gx, gX, fx, fX)
    for i in range(n):
        gx[i] += S * un[i]
        gX[i] += S * Un[i]
    bulk_forces(1, gx, gX, fx, fX, p[P_K], p[P_KL], p[P_KT], 0.0, 0.0)
    for i in range(n):
        w += fx[i] * un[i] + fX[i] * Un[i]
    return 0.5 * w * h


@nb.njit
def _contact_force(s, y, vstar, amp, c, meta_c):
    """(u, f, df/du) of a contact with sign s and y = log10(|u|/v*): eq. (1) with its damping m eta_c u."""
    pw = math.exp(LN10 * y)
    u = s * vstar * pw
    big = amp * math.exp(-c * y * y)
    return u, s * big + meta_c * u, meta_c + big * (-2.0 * c * y) / (LN10 * vstar * pw)


def _make_be_try(arms: bool):
    """The chain's backward-Euler try (:data:`be_try`; ``arms``: with the Maxwell arms, :data:`be_try_arms`),
    the arms' code compiled only where there are arms (so that the elastic try is compiled as it was
    before them: its fastmath callees make its last bits depend on the surrounding code)."""

    @nb.njit
    def be_try(p, xr, ur, Xr, Ur, st, vs, nc, ys, un, Un, h, t1, tol, yk, sk, ap, have, mt, br):
        """One backward-Euler step of the chain from (x, u, X, U) at time t1 - h: writes the new
        velocities into ``un``, ``Un`` and each contact's (y, sign) into ``yk``, ``sk``, touching
        nothing else. Newton starts from the velocities extrapolated with the last step's accelerations
        ``ap`` (where ``have``; a contact keeps its y where the extrapolation would change its sign).
        Returns the Newton iterations taken, or -1 where the step may not be taken by backward Euler (a
        contact off the rising branch, or no convergence). ``mt``, ``br``: the material 'prony''s terms and
        arms (:class:`Arms`; J = 0: elastic)."""
        n = xr.size
        m = p[P_M]
        K, KL, KT, Kd = p[P_K], p[P_KL], p[P_KT], p[P_KD]
        if arms:
            fgx = np.zeros(n)  # the arms' force K_b G
            fgX = np.zeros(n)
            S = chain_arms(p, mt, br, h, np.empty(n), np.empty(n), fgx, fgX)
            a0, bb, d0, ox, oX = chain_coefficients(p, h, mt.shape[1], S)
        else:
            a0, bb, d0, ox, oX = chain_coefficients(p, h)
        amp = p[P_AMP]
        c = p[P_C]
        meta_c = m * p[P_ETAC]
        drive = p[P_VD] * t1
        fconst = p[P_FCONST]
        mL = p[P_ML]
        rhs = np.empty(2 * n)
        for i in range(n):  # M v + h (g - K q) at the step's start
            ip = i + 1 if i + 1 < n else 0
            im = i - 1 if i > 0 else n - 1
            fx = K * (xr[ip] + xr[im] - 2.0 * xr[i]) + KT * (Xr[i] - xr[i])
            fX = KL * (Xr[ip] + Xr[im] - 2.0 * Xr[i]) + KT * (xr[i] - Xr[i]) + Kd * (drive - Xr[i]) + fconst
            if arms:
                fx += fgx[i]
                fX += fgX[i]
            rhs[2 * i] = m * ur[i] + h * fx
            rhs[2 * i + 1] = mL * Ur[i] + h * fX
            un[i] = ur[i] + h * ap[i] if have else ur[i]
            Un[i] = Ur[i] + h * ap[n + i] if have else Ur[i]
        if not start_contacts(nc, st, ur, un, ys, vs, yk, sk):
            return -1
        diag = np.empty(n)
        res = np.empty(2 * n)
        dv = np.empty(2 * n)
        hf = np.zeros(n)  # h f(u) on the contact blocks
        dk = np.empty(nc)  # h f'(u) of each contact
        free = np.ones(n, dtype=np.bool_)  # blocks without a contact
        pk = np.empty(nc)  # 10**y and exp(-c y**2) of each contact, updated multiplicatively (as newton_pass)
        qk = np.empty(nc)
        for k in range(nc):
            free[st[k]] = False
        factors(nc, c, yk, pk, qk)
        for it in range(NEWTON_MAX):
            for i in range(n):
                diag[i] = a0
            eval_contacts(nc, st, vs, yk, sk, pk, qk, amp, c, meta_c, h, un, hf, dk)
            for k in range(nc):
                diag[st[k]] = a0 + dk[k]
            _residual(n, a0, bb, d0, ox, oX, un, Un, hf, rhs, res)
            solve_cyclic(diag, bb, d0, ox, oX, res, dv)
            big_v = 0.0
            for i in range(n):
                big_v = max(big_v, abs(dv[2 * i + 1]), abs(dv[2 * i]) if free[i] else 0.0)
                un[i] += dv[2 * i]  # contact blocks: overwritten from (y, s) below
                Un[i] += dv[2 * i + 1]
            big_y = update_contacts(nc, st, vs, yk, sk, pk, qk, c, dv, 2)
            if big_y < 0.0:
                return -1
            if big_y < NEWTON_DY and big_v < NEWTON_DV * tol:
                return it + 1 if finish_contacts(nc, st, vs, yk, sk, pk, un) else -1
        return -1

    return be_try


be_try = _make_be_try(False)
be_try_arms = _make_be_try(True)


@nb.njit
def start_contacts(nc, st, ur, un, ys, vs, yk, sk):
    """Newton's start for the contacts of a backward-Euler step: each contact's sign from its velocity
    at the step's start and its y from the solver state, or from the extrapolated velocity in ``un``
    where that keeps the sign (at most Y_MAX). False where a contact is not on the rising branch."""
    for k in range(nc):
        u0 = ur[st[k]]
        sk[k] = 1.0 if u0 >= 0.0 else -1.0
        yk[k] = ys[Y_LOG, k]
        if not yk[k] < Y_MAX:
            return False
        ug = un[st[k]]
        if ug * sk[k] > 0.0:
            yk[k] = min(math.log10(abs(ug) / vs[k]), Y_MAX)
    return True


@nb.njit
def factors(nc, c, yk, pk, qk):
    """10**y and exp(-c y**2) of each contact, exact."""
    for k in range(nc):
        pk[k] = math.exp(LN10 * yk[k])
        qk[k] = math.exp(-c * yk[k] * yk[k])


@nb.njit
def eval_contacts(nc, st, vs, yk, sk, pk, qk, amp, c, meta_c, h, un, hf, dk):
    """Each contact's velocity (into ``un``), h f(u) (into ``hf`` at its block) and h f'(u) (``dk``),
    from its (y, sign): eq. (1) with the damping m eta_c u."""
    for k in range(nc):
        i = st[k]
        u = sk[k] * vs[k] * pk[k]
        big = amp * qk[k]
        un[i] = u
        hf[i] = h * (sk[k] * big + meta_c * u)
        dk[k] = h * (meta_c + big * (-2.0 * c * yk[k]) / (LN10 * vs[k] * pk[k]))


@nb.njit
def update_contacts(nc, st, vs, yk, sk, pk, qk, c, dv, stride):
    """A Newton update of the contacts from the velocity updates ``dv`` (block i's at dv[stride i]):
    in y (the fold scheme's variable, at most MAX_DY decades), or, where it crosses zero, to the new
    sign additively. Returns the largest change of y, or -1 where a contact leaves the rising branch
    (y > Y_ABORT: backward Euler may not be taken)."""
    big_y = 0.0
    for k in range(nc):
        u = sk[k] * vs[k] * pk[k]
        du = dv[stride * st[k]]
        if (u + du) * sk[k] <= 0.0:  # the update crosses zero: the new sign, additively
            sk[k] = -sk[k]
            w = abs(u + du)
            yk[k] = max(math.log10(w / vs[k]), Y_FLOOR) if w > 0.0 else Y_FLOOR
            pk[k] = math.exp(LN10 * yk[k])
            qk[k] = math.exp(-c * yk[k] * yk[k])
            big_y = max(big_y, 1.0)
        else:  # Newton in y (the fold scheme's variable)
            d = min(MAX_DY, max(-MAX_DY, du / (LN10 * u)))
            if yk[k] + d < Y_FLOOR:
                d = Y_FLOOR - yk[k]
            pk[k] = scaled_exp(pk[k], LN10 * d)
            qk[k] = scaled_exp(qk[k], -c * d * (2.0 * yk[k] + d))
            yk[k] += d
            big_y = max(big_y, abs(d))
        if yk[k] > Y_ABORT:
            return -1.0
    return big_y


@nb.njit
def finish_contacts(nc, st, vs, yk, sk, pk, un):
    """Newton converged: each contact's velocity into ``un``; False where one is not below Y_MAX."""
    for k in range(nc):
        if not yk[k] < Y_MAX:
            return False
        un[st[k]] = sk[k] * vs[k] * pk[k]
    return True


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _residual(n, a0, bb, d0, ox, oX, un, Un, hf, rhs, res):
    """-(A v + h f(v) - rhs), interleaved (module docstring)."""
    for i in range(n):
        ip = i + 1 if i + 1 < n else 0
        im = i - 1 if i > 0 else n - 1
        res[2 * i] = rhs[2 * i] - (a0 * un[i] + bb * Un[i] + ox * (un[ip] + un[im]) + hf[i])
        res[2 * i + 1] = rhs[2 * i + 1] - (d0 * Un[i] + bb * un[i] + oX * (Un[ip] + Un[im]))


@nb.njit
def be_contacts(nc, st, vs, ys, yk, sk, un, uk, fk, amp, c, meta_c):
    """An accepted backward-Euler step's contacts: their velocities ``uk`` and applied forces ``fk``
    (eq. 1 at the new velocity), and the fold scheme's solver state (y, 10**y, exp(-c y**2)) exact."""
    for k in range(nc):
        u, f, _ = _contact_force(sk[k], yk[k], vs[k], amp, c, meta_c)
        uk[k] = un[st[k]]
        fk[k] = f
        ys[Y_LOG, k] = yk[k]
        ys[Y_P, k] = math.exp(LN10 * yk[k])
        ys[Y_Q, k] = math.exp(-c * yk[k] * yk[k])


@nb.njit
def chain_damping(p, un, Un, dampx, dampX):
    """The pair damping forces at the new velocities (the implicit step's), for the damping work."""
    n = un.size
    meta = p[P_META]
    for i in range(n):
        ip = i + 1 if i + 1 < n else 0
        im = i - 1 if i > 0 else n - 1
        dampx[i] = meta * (un[ip] + un[im] + Un[i] - 3.0 * un[i])
        dampX[i] = meta * (Un[ip] + Un[im] + un[i] - 3.0 * Un[i])


@nb.njit
def damping_power(dampx, dampX, u, U):
    """sum_i (damp_x u + damp_X U): the pair damping's power (as :func:`.cpu.lattice_commit` sums it)."""
    wd = 0.0
    for i in range(u.size):
        wd += dampx[i] * u[i] + dampX[i] * U[i]
    return wd


@nb.njit
def contact_force(uk, vsk, amp, c, meta_c):
    """Eq. (1) with its damping, f = sign(u) amp exp(-c log10(|u|/v_s)^2) + meta_c u, at a block's
    velocity u != 0 (the one statement for :func:`contact_power_at` and :func:`contact_forces_at`)."""
    y = math.log10(abs(uk) / vsk)
    return math.copysign(amp * math.exp(-c * y * y), uk) + meta_c * uk


@nb.njit
def contact_power_at(nc, st, vs, u, amp, c, meta_c):
    """sum_k f_k u_k with eq. (1) (and its damping) at the blocks' velocities ``u``."""
    pw = 0.0
    for k in range(nc):
        uk = u[st[k]]
        if uk != 0.0:
            pw += contact_force(uk, vs[k], amp, c, meta_c) * uk
    return pw


@nb.njit
def chain_energy(p, xr, ur, Xr, Ur, h, t):
    """The chain's mechanical energy at (x + h u, u, X + h U, U) and drive time t: kinetic, the springs
    K, K_L, K_T, the drive springs K_d (v_d t - X) and the dead weight's potential -F_b X (h = 0:
    the state itself; h > 0: the state a step of velocities (u, U) reaches, without moving it)."""
    n = xr.size
    m, mL = p[P_M], p[P_ML]
    K, KL, KT, Kd = p[P_K], p[P_KL], p[P_KT], p[P_KD]
    drive = p[P_VD] * t
    fconst = p[P_FCONST]
    e = 0.0
    for i in range(n):
        ip = i + 1 if i + 1 < n else 0
        xi, Xi = xr[i] + h * ur[i], Xr[i] + h * Ur[i]
        dx = xr[ip] + h * ur[ip] - xi
        dX = Xr[ip] + h * Ur[ip] - Xi
        e += 0.5 * (m * ur[i] * ur[i] + mL * Ur[i] * Ur[i] + K * dx * dx + KL * dX * dX + KT * (Xi - xi) ** 2
                    + Kd * (drive - Xi) ** 2) - fconst * Xi
    return e


@nb.njit
def step_balance(p, xr, ur, Xr, Ur, un, Un, h, t1, nc, st, vs, dampx, dampX):
    """A backward-Euler step's works by the trapezoidal rule between its start (x, u, X, U) and its
    end (x + h u', u', X + h U', U'), and its energy residual, without moving anything: returns
    (the residual dE - W, the sum of the works' magnitudes, the mean drive force sum, the drive's,
    the damping's and the contacts' work; the contacts' as dissipated, f u h)."""
    amp, c, meta_c = p[P_AMP], p[P_C], p[P_M] * p[P_ETAC]
    f0 = drive_force_sum(p, Xr, t1 - h)
    sx = 0.0
    for i in range(Xr.size):
        sx += Xr[i] + h * Un[i]
    f1 = p[P_KD] * (Xr.size * p[P_VD] * t1 - sx)
    chain_damping(p, ur, Ur, dampx, dampX)
    pd0 = damping_power(dampx, dampX, ur, Ur)
    chain_damping(p, un, Un, dampx, dampX)
    pd1 = damping_power(dampx, dampX, un, Un)
    pc = contact_power_at(nc, st, vs, ur, amp, c, meta_c) + contact_power_at(nc, st, vs, un, amp, c, meta_c)
    fsum = 0.5 * (f0 + f1)
    w_drive = fsum * p[P_VD] * h
    w_damp = 0.5 * (pd0 + pd1) * h
    w_contact = 0.5 * pc * h
    de = chain_energy(p, xr, un, Xr, Un, h, t1) - chain_energy(p, xr, ur, Xr, Ur, 0.0, t1 - h)
    return de - (w_drive + w_damp - w_contact), abs(w_drive) + abs(w_damp) + abs(w_contact), fsum, w_drive, w_damp, w_contact


@nb.njit
def rising(nc, ys):
    """Every contact on the rising branch with the margin that backward Euler needs (y < Y_MAX)."""
    for k in range(nc):
        if not ys[Y_LOG, k] < Y_MAX:
            return False
    return True


@nb.njit
def drive_force_sum(p, Xr, t):
    """sum_i K_d (v_d t - X_i): the drive springs' force at the end of an implicit step."""
    sx = 0.0
    for i in range(Xr.size):
        sx += Xr[i]
    return p[P_KD] * (Xr.size * p[P_VD] * t - sx)




# --- The slab, half-space and chain2d (issue 27): the same backward Euler, solved by Newton-Krylov ---

CG_RTOL = 1e-9  # the Newton iteration's linear solve: relative residual of the preconditioned conjugate gradients
CG_MAXITER = 200


class SpectralOperator:
    """The elastic operator of one row of a slab or half-space, L x = IFFT[a**2 k(q) FFT(x)]
    (``kern`` = a**2 k on the rfft2 grid, :class:`.base.Batch`): one rfft2/irfft2 pair per product."""

    def __init__(self, kern: np.ndarray, shape: tuple[int, int], fft):
        self.kern = kern
        self.shape = shape
        self.fft = fft
        self.n = shape[0] * shape[1]
        self.k0 = float(kern[0, 0])
        self._pair = np.empty((2, self.n))  # apply_both's input
        delta = np.zeros(self.n)
        delta[0] = 1.0
        self.lii = float(self.apply(delta)[0])  # the diagonal of the circulant L

    def apply(self, v: np.ndarray) -> np.ndarray:
        """L v."""
        return self.apply_symbol(self.kern, v)

    def apply_symbol(self, sym: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The circulant operator of Fourier symbol ``sym`` (on the rfft2 grid) applied to v."""
        f = self.fft
        return f.irfft2(sym * f.rfft2(v.reshape(self.shape)), s=self.shape).reshape(self.n)

    def apply_both(self, v: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(L v, L w) by one batched rfft2/irfft2 pair (half the calls' overhead on small grids; v and w
        copied into a pair kept for the purpose, as np.stack would into a new one)."""
        f = self.fft
        pair = self._pair
        pair[0], pair[1] = v, w
        both = f.irfft2(self.kern * f.rfft2(pair.reshape((2, *self.shape)), axes=(1, 2)), s=self.shape, axes=(1, 2))
        return both[0].reshape(self.n), both[1].reshape(self.n)

    def energy(self, x: np.ndarray, lx: np.ndarray, d: float) -> float:
        """(1/2) (x - d) . L (x - d), given L x (a uniform shift d enters mode q = 0 alone)."""
        return 0.5 * float(np.dot(x - d, lx - self.k0 * d))


class Arms:
    """The Maxwell arms of a Prony bulk (material 'prony', issue 28) in a backward-Euler step.

    Each arm's field follows the exponential rule of :mod:`.viscoelastic`, xi_j' = a_j xi_j + c_j w'
    (a_j = exp(-h/tau_j), c_j = tau_j (1 - a_j); w' the step's relative velocity: the blocks' less
    the plate's on the slab, each layer's own on the lattice), exact for a velocity constant over the
    step, which backward Euler's is. Their force at the step's end, -K_b sum_j r_j xi_j' (K_b the
    bulk's stiffness: the slab's L_c, the lattice's springs without the drive springs), is then
    -K_b (G + S w') with G = sum_j r_j a_j xi_j and S = sum_j r_j c_j: linear in the unknowns, so
    the step's matrix keeps its form with h**2 K_b replaced by h (h + S) K_b (S -> h sum_j r_j, the
    glassy stiffness, for h << tau_j; S -> sum_j r_j tau_j, a dashpot, for h >> tau_j) and the
    right-hand side gains -h K_b G. ``mt`` (2, J): r_j, tau_j; ``br`` the body state (rows 0 .. J-1
    the interface layer's fields, J .. 2J-1 the upper layer's)."""

    def __init__(self, mt, br):
        self.r, self.tau = mt[0], mt[1]
        self.J = mt.shape[1]
        self.br = br

    def setup(self, h):
        """S and G (both layers) for a step h; keeps the step's a_j and c_j (``a``, ``c``)."""
        self.a = a = np.exp(-h / self.tau)
        self.c = c = -self.tau * np.expm1(-h / self.tau)
        self.S = float(np.dot(self.r, c))
        J = self.J
        self.G = (np.dot(self.r * a, self.br[:J]), np.dot(self.r * a, self.br[J:2 * J]))
        return self.S

    def mean(self, h):
        """((Gbar of both layers), Sbar): the mean of g over a step h is Gbar + Sbar w', for w' constant
        over the step (xi_j(t) = a_j(t) xi_j + tau_j (1 - a_j(t)) w'): Gbar = sum_j r_j (c_j/h) xi_j,
        Sbar = sum_j r_j tau_j (1 - c_j/h), c_j = tau_j (1 - exp(-h/tau_j))."""
        c = -self.tau * np.expm1(-h / self.tau)
        wa = self.r * c / h
        J = self.J
        return (np.dot(wa, self.br[:J]), np.dot(wa, self.br[J:2 * J])), float(np.dot(self.r, self.tau * (1.0 - c / h)))

    def now(self):
        """g = sum_j r_j xi_j of both layers at the step's start."""
        J = self.J
        return np.dot(self.r, self.br[:J]), np.dot(self.r, self.br[J:2 * J])


class SlabSystem:
    """Backward Euler's linear part on a slab or half-space row (:class:`SpectralOperator` L).

    Under the spring drive the blocks' velocities u' solve (module docstring, with the body's force
    -L (x' - v_d t) and the radiation damping -m gamma (u - v_d) in place of the springs)

        A u' + h f(u') = m u + h (-L x + a**2 k(0) v_d t' + m gamma v_d),   A = (m + h m gamma) I + h**2 L,

    A diagonal in Fourier space (eigenvalues m + h m gamma + h**2 a**2 k(q) > 0). Under the dead
    weight (P_KD = 0) the top is a rigid plate (velocity U', mass N_L m per block, :mod:`.spectral`),
    one more unknown: with b = h (h a**2 k_c(0) + m gamma),

        A u' + h f(u') - b U' = m u - h L_c (x - X),
        n (N_L m + h m gamma + h**2 a**2 k_c(0)) U' - b sum u' = n (N_L m U + h (F_b + a**2 k_c(0) (<x> - X))),

    the plate's row scaled by n so that the matrix stays symmetric (and positive definite: its Schur
    complement on U' is positive).

    ``preconditioner`` (Config.krylov_preconditioner): 'jacobi' or 'additive' (:meth:`precondition`)."""

    def __init__(self, op: SpectralOperator, p, arms: Arms | None = None, preconditioner: str = "jacobi"):
        self.op = op
        self.p = p
        self.n = op.n
        self._preconditioner(preconditioner)
        self.dead = p[P_KD] == 0.0
        self.moves_upper = self.dead  # the plate is a state of the step under the dead weight (TR-BDF2's stages)
        self.size = self.n + 1 if self.dead else self.n
        # material 'prony': the arms act through L_c under the dead weight, through L less its uniform mode
        # (the drive springs' k(0) = kappa_d: the half-space) under the spring drive (model.viscoelastic.arm_kernel)
        self.arms = arms

    def arm_part(self, lv, v):
        """K_b v, given L v: the arms act through L_c itself under the dead weight, through L less its
        uniform mode under the spring drive (the drive springs' k(0) = kappa_d: the half-space;
        :func:`slipchain.model.viscoelastic.arm_kernel`)."""
        return lv if self.dead else lv - self.op.k0 * float(np.mean(v))

    def setup(self, xr, ur, Xr, Ur, h, t1):
        """The right-hand side at the step's start, and the velocities there as one vector."""
        p, op, n = self.p, self.op, self.n
        m, meta, k0 = p[P_M], p[P_META], op.k0
        self.h = h
        self.S = self.arms.setup(h) if self.arms is not None else 0.0
        self.hs = h + self.S  # h**2 L -> h (h + S) L (:class:`Arms`)
        self.cdiag = m + h * meta
        if self.additive:  # the body's own matrix in Fourier space, inverted (:meth:`precondition`)
            self.pinv = 1.0 / (self.cdiag + h * self.hs * op.kern)
        if self.arms is not None:  # the arms' force -K_b G (the right-hand side of either drive)
            G = self.arms.G[0]
            self.lG = self.arm_part(op.apply(G), G)
        if self.dead:
            Xp = float(Xr[0])
            self.lx = op.apply(xr - Xp)  # L_c (x - X): the plate's uniform displacement enters mode q = 0 alone
            self.bp = h * (self.hs * k0 + meta)
            self.ap = p[P_ML] + h * meta + h * self.hs * k0
            rhs_u = m * ur - h * self.lx
            rhs_p = n * (p[P_ML] * Ur[0] + h * (p[P_FCONST] + k0 * (float(np.mean(xr)) - Xp)))
            if self.arms is not None:  # ... and its reaction on the plate, k_c(0) <G>
                rhs_u -= h * self.lG
                rhs_p += n * h * k0 * float(np.mean(G))
            self.diag = np.concatenate([np.full(n, self.cdiag + h * self.hs * op.lii), [n * self.ap]])
            return np.concatenate([rhs_u, [rhs_p]]), np.concatenate([ur, Ur[:1]])
        self.lx = op.apply(xr)
        rhs = m * ur + h * (k0 * p[P_VD] * t1 + meta * p[P_VD]) - h * self.lx
        if self.arms is None:
            self.diag = self.cdiag + h * h * op.lii
            return rhs, ur.copy()
        # the arms through L less its uniform mode: h (h + S) L - h S k(0) P_0
        self.diag = self.cdiag + h * self.hs * op.lii - h * self.S * k0 / n
        return rhs - h * self.lG, ur.copy()

    def matvec(self, v):
        n, h = self.n, self.h
        w = self.cdiag * v[:n] + h * self.hs * self.op.apply(v[:n])
        if not self.dead:
            if self.arms is not None:
                w -= h * self.S * self.op.k0 * float(np.mean(v[:n]))
            return w
        return np.concatenate([w - self.bp * v[n], [n * self.ap * v[n] - self.bp * np.sum(v[:n])]])

    def _preconditioner(self, name: str) -> None:
        if name not in ("jacobi", "additive"):
            raise ValueError(f"preconditioner {name!r}: expected 'jacobi' or 'additive'")
        self.additive = name == "additive"
        # FFT pairs per conjugate-gradient iteration (the matrix's product, and the additive one's inverse):
        # the cost rule's units (:func:`.compose.krylov_implicit_advance`)
        self.cg_units = 2 if self.additive else 1

    def precondition(self, r, jd):
        """'jacobi': r over the diagonal of A + h diag(f'), jd = h f' on the contact blocks (0 elsewhere).

        'additive' (by site, issue 27): the same on the contact blocks (jd > 0) and the plate; on the
        free blocks the exact inverse of the body alone, (m + h m gamma + h (h + S) a**2 k(q))**-1 in
        Fourier space, applied to the residual restricted to them and restricted back: P_f F**-1 P_f
        + P_c D**-1, block-diagonal by site and symmetric positive definite, as conjugate gradients need.
        Where few blocks carry contacts (low load) the free blocks' coupling through the body is what
        Jacobi misses: on a 128 x 128 slab at theta = 0.05, epsilon = 1 it took 9.8 iterations per
        solve against Jacobi's 25 (docs/performance.md); each costs a second FFT pair (``cg_units``)."""
        z = r / (self.diag + jd)
        if self.additive:
            n = self.n
            free = jd[:n] == 0.0
            zf = self.op.apply_symbol(self.pinv, np.where(free, r[:n], 0.0))
            z[:n] = np.where(free, zf, z[:n])
        return z

    def unknowns(self, u, U):
        """The unknowns' vector of velocities (u, U): the blocks', and the plate's under the dead weight."""
        return np.concatenate([u, U[:1]]) if self.dead else u.copy()

    def upper(self, v, Un):
        """The upper layer's velocities from the unknowns: the plate's (dead weight), or zero."""
        Un[:] = v[self.n] if self.dead else 0.0

    def acceleration(self, ap):
        """The last step's accelerations as one vector of the unknowns."""
        return ap[:self.size]

    def balance(self, xr, ur, Xr, Ur, un, Un, h, t1, nc, st, vs):
        """The step's works by the trapezoidal rule and its energy residual (:func:`step_balance`; the
        energy is the kinetic one, the body's (1/2) (x - d) . L (x - d), d = v_d t or the plate's X,
        and under the dead weight the plate's kinetic energy and the weight's potential -F_b n X).
        Under the dead weight the drive force and work are 0 here: the run takes the weight's work
        from the plate's displacement, as for the explicit steps. With the arms (material 'prony')
        their work on the blocks relative to the plate, -L_c g . (u - U), by the same rule (their
        energy is not in the mechanical one: the run's W_visc, as for the explicit steps)."""
        p, op, n = self.p, self.op, self.n
        m, meta, vd, k0 = p[P_M], p[P_META], p[P_VD], op.k0
        t0 = t1 - h
        x1 = xr + h * un
        lun = op.apply(un)
        lx, lx1 = self.lx, self.lx + h * lun
        e0 = 0.5 * m * float(np.dot(ur, ur))
        e1 = 0.5 * m * float(np.dot(un, un))
        if self.dead:
            Xp, Up, Un1 = float(Xr[0]), float(Ur[0]), float(Un[0])
            X1 = Xp + h * Un1
            lx1 -= h * Un1 * k0  # L_c (x' - X') = L_c (x - X) + h (L_c u' - k_c(0) U')
            fb = p[P_FCONST] * n
            e0 += 0.5 * n * p[P_ML] * Up * Up + op.energy(xr - Xp, lx, 0.0) - fb * Xp
            e1 += 0.5 * n * p[P_ML] * Un1 * Un1 + op.energy(x1 - X1, lx1, 0.0) - fb * X1
            w_damp = -0.5 * meta * (float(np.sum((ur - Up) ** 2)) + float(np.sum((un - Un1) ** 2))) * h
            w_visc = self._arm_work(un - Un1, lun - k0 * Un1, h)
            return _balance(p, e1 - e0, 0.0, 0.0, w_damp, h, nc, st, vs, ur, un, w_visc)
        e0 += op.energy(xr, lx, vd * t0)
        e1 += op.energy(x1, lx1, vd * t1)
        fsum = 0.5 * k0 * (n * vd * (t0 + t1) - float(np.sum(xr)) - float(np.sum(x1)))
        w_damp = -0.5 * meta * (float(np.dot(ur - vd, ur)) + float(np.dot(un - vd, un))) * h
        w_visc = self._arm_work(un, lun, h)
        return _balance(p, e1 - e0, fsum, fsum * vd * h, w_damp, h, nc, st, vs, ur, un, w_visc)

    def rate(self, x, u, X, U, t):
        """The accelerations of the linear part at a state (x, u, X, U; time t), as the blocks' and the
        upper layer's arrays: everything but the contacts (TR-BDF2's trapezoidal stage needs the force at
        the step's start, :func:`krylov_trbdf2_try`). Spring drive: m a = -L (x - v_d t) - m gamma (u - v_d)
        (the upper layer none); dead weight: m a = -L_c (x - X) - m gamma (u - U) on the blocks and
        N_L m A = F_b + k_c(0) (<x> - X) + m gamma <u - U> on the plate (every entry of X, U). The elastic
        bulk's (TR-BDF2 is refused with the Prony arms and on :class:`TopSlabSystem`)."""
        p, op = self.p, self.op
        m, meta, k0 = p[P_M], p[P_META], op.k0
        if self.dead:
            Xp, Up = float(X[0]), float(U[0])
            au = (-op.apply(x - Xp) - meta * (u - Up)) / m
            aU = (p[P_FCONST] + k0 * (float(np.mean(x)) - Xp) + meta * (float(np.mean(u)) - Up)) / p[P_ML]
            return au, np.full(self.n, aU)
        return (-op.apply(x) + k0 * p[P_VD] * t - meta * (u - p[P_VD])) / m, np.zeros(self.n)

    def energy(self, x, u, X, U, t):
        """The mechanical energy at a state (as :meth:`balance` has it): kinetic, the body's
        (1/2) (x - d) . L (x - d) (d = v_d t, or the plate's X), and under the dead weight the plate's
        kinetic energy and the weight's potential -F_b n X."""
        p, op, n = self.p, self.op, self.n
        e = 0.5 * p[P_M] * float(np.dot(u, u))
        if self.dead:
            Xp, Up = float(X[0]), float(U[0])
            return e + 0.5 * n * p[P_ML] * Up * Up + op.energy(x - Xp, op.apply(x - Xp), 0.0) - p[P_FCONST] * n * Xp
        return e + op.energy(x, op.apply(x), p[P_VD] * t)

    def powers(self, x, u, X, U, t):
        """(the drive springs' force summed over the blocks, the damping's power) at a state, as
        :meth:`balance` takes them at a step's ends (the dead weight: no drive force here, its work is
        the weight's potential in :meth:`energy`)."""
        p, k0 = self.p, self.op.k0
        meta, vd = p[P_META], p[P_VD]
        if self.dead:
            Up = float(U[0])
            return 0.0, -meta * float(np.sum((u - Up) ** 2))
        return k0 * (self.n * vd * t - float(np.sum(x))), -meta * float(np.dot(u - vd, u))

    def _arm_work(self, w1, lw1, h):
        """The arms' work on the blocks over the step, -h K_b gbar . w' (w' the step's velocity the arms
        act on: relative to the plate under the dead weight; ``lw1`` = L w'; 0 without arms), with gbar the
        mean of g over the step, exact for the velocity constant over the step that the arms' update
        assumes (:meth:`Arms.mean`). Not the trapezoidal rule: its start value -K_b g . w holds the last
        step's velocity, and after explicit steps the fast arms' dashpot part, -c w**2, at that velocity
        is a residual that backward Euler's own damping of the ringing never pays back, so every try
        after explicit steps failed the energy check (issue 29, docs/tester-3d). With gbar the residual
        is backward Euler's numerical dissipation alone, as with elastic springs."""
        if self.arms is None:
            return 0.0
        (gb, _), sb = self.arms.mean(h)
        return -float(np.dot(self.arm_part(self.op.apply(gb), gb) + sb * self.arm_part(lw1, w1), w1)) * h


class TopSlabSystem(SlabSystem):
    """Backward Euler on a row of the viscoelastic slab under the drive springs (material 'prony'),
    whose top is a massless state of its own (:mod:`.viscoelastic`, the two-port of
    :func:`slipchain.model.elastic.slab_twoport`; ``top`` the chunk's :class:`.compose._TopDriver`,
    holding the top's fields Z_c and arms xi_cj in Fourier space, solved at the step's start).

    Per mode and channel c (weights W_c; entries A, K12c, K22c; kappa the drive springs) the top at the
    step's end is the explicit steps' solve (:func:`.viscoelastic.top_solve`) with the blocks' state at
    the step's end, Y' = x' + g_b' = (x + G) + (h + S) u' (the bottom's arms as :class:`Arms`), and
    s = S/h (the top's arms advanced by the same exponential rule over the step)::

        D_c Z_c' = kappa X_d' [c = P, q = 0] - K12c Y' - K22c (G_c - s Z_c),   D_c = K22c (1 + s) + kappa,

    G_c = sum_j r_j a_j xi_cj. Eliminated, the blocks feel the force -(K_eff Y' + B), Fourier-diagonal,

        K_eff = A - sum_c W_c (1 + s) K12c**2 / D_c,
        B = sum_c W_c K12c [(1 + s) kappa X_d' [c = P, q = 0] + kappa (G_c - s Z_c)] / D_c,

    so the step's matrix is the spring-driven slab's with L -> IFFT[K_eff] and h**2 -> h (h + S)
    (without arms, K_eff is the slab in series with the springs and B the drive: the elastic slab's
    own system). The balance takes the energy of slab and springs as the two-port's quadratic form
    (:func:`slipchain.model.elastic.twoport_energy`) and the arms' work on blocks and top over the step
    at its constant velocities (:meth:`Arms.mean`), and keeps the top's end state; :meth:`commit_top`
    writes it into the driver after the step is accepted (so the next solve finds it current and
    adds no work of its own)."""

    def __init__(self, p, arms: Arms, top, row: int, preconditioner: str = "jacobi"):
        self.p = p
        self._preconditioner(preconditioner)
        self.shape = top.batch.shape
        self.fft = top.fft
        self.n = self.shape[0] * self.shape[1]
        self.dead = False
        self.size = self.n
        self.arms = arms
        self.top = top
        self.row = row
        self.tp = tp = top.batch.twoport[row]
        self.A = tp[0]
        self.W = np.stack([tp[1], 1.0 - tp[1]])
        self.K12, self.K22 = tp[2:4], tp[4:6]
        self.kap = p[P_KD]

    def _fourier(self, v):
        return self.fft.rfft2(v.reshape(self.shape))

    def setup(self, xr, ur, Xr, Ur, h, t1):
        p, n, arms = self.p, self.n, self.arms
        m, meta, kap = p[P_M], p[P_META], self.kap
        self.h = h
        self.S = arms.setup(h)
        self.hs = h + self.S
        s = self.S / h
        self.D = self.K22 * (1.0 + s) + kap
        keff = self.A - np.sum(self.W * (1.0 + s) * self.K12 ** 2 / self.D, axis=0)
        self.op = SpectralOperator(keff, self.shape, self.fft)
        self.cdiag = m + h * meta
        if self.additive:
            self.pinv = 1.0 / (self.cdiag + h * self.hs * keff)
        self.cc = arms.c / h
        th = self.top.Th[self.row]  # (2, J, Lx, Lh)
        self.Z0 = self.top.Zh[self.row].copy()
        self.Gc = np.einsum("j,cjxy->cxy", arms.r * arms.a, th)
        self.Gbar_c = np.einsum("j,cjxy->cxy", arms.r * self.cc, th)  # the top's arms' mean over the step (Arms.mean)
        self.xd1 = n * p[P_VD] * t1
        bh = np.sum(self.W * self.K12 * kap * (self.Gc - s * self.Z0) / self.D, axis=0)
        bh[0, 0] += self.W[0, 0, 0] * self.K12[0, 0, 0] * (1.0 + s) * kap * self.xd1 / self.D[0, 0, 0]
        b = self.fft.irfft2(bh, s=self.shape).reshape(n)
        self.diag = self.cdiag + h * self.hs * self.op.lii
        rhs = m * ur + h * meta * p[P_VD] - h * self.op.apply(xr + arms.G[0]) - h * b
        return rhs, ur.copy()

    def matvec(self, v):
        return self.cdiag * v + self.h * self.hs * self.op.apply(v)

    def _top_end(self, yh):
        """The top's fields at the step's end from the transform of Y' (the class docstring)."""
        s = self.S / self.h
        z = (-self.K12 * yh - self.K22 * (self.Gc - s * self.Z0))
        z[0, 0, 0] += self.kap * self.xd1
        return z / self.D

    def _energy(self, xh, Z, xd):
        """The slab's and the drive springs' energy (:func:`slipchain.model.elastic.twoport_energy`)."""
        return twoport_energy(self.tp, self.kap, xh, Z, xd, self.top.weights)

    def balance(self, xr, ur, Xr, Ur, un, Un, h, t1, nc, st, vs):
        p, n, arms = self.p, self.n, self.arms
        m, meta, vd, kap = p[P_M], p[P_META], p[P_VD], self.kap
        t0 = t1 - h
        x1 = xr + h * un
        xh0, xh1 = self._fourier(xr), self._fourier(x1)
        self.Z1 = self._top_end(self._fourier(x1 + arms.G[0] + self.S * un))
        xd0 = n * vd * t0
        e0 = 0.5 * m * float(np.dot(ur, ur)) + self._energy(xh0, self.Z0, xd0)
        e1 = 0.5 * m * float(np.dot(un, un)) + self._energy(xh1, self.Z1, self.xd1)
        self.fd1 = kap * (self.xd1 - float(self.Z1[0, 0, 0].real))
        fsum = 0.5 * (kap * (xd0 - float(self.Z0[0, 0, 0].real)) + self.fd1)
        w_damp = -0.5 * meta * (float(np.dot(ur - vd, ur)) + float(np.dot(un - vd, un))) * h
        # the arms' work on blocks and top at the step's constant velocities u', (Z' - Z)/h (Arms.mean)
        (gb, _), sb = arms.mean(h)
        zdot = (self.Z1 - self.Z0) / h
        uh, gh = self._fourier(un), self._fourier(gb + sb * un)
        gt = self.Gbar_c + sb * zdot
        power = (np.conj(uh) * (self.A * gh + np.sum(self.W * self.K12 * gt, axis=0))
                 + np.sum(self.W * np.conj(zdot) * (self.K12 * gh + self.K22 * gt), axis=0)).real
        w_visc = -h * float(np.sum(self.top.weights * power))
        return _balance(p, e1 - e0, fsum, fsum * vd * h, w_damp, h, nc, st, vs, ur, un, w_visc)

    def commit_top(self, step: int, bs: np.ndarray):
        """After the accepted step: the top's fields and arms at its end into the driver, its solve
        marked current at ``step`` (the body state's last row, scheme.top_rows) with the drive force sum."""
        z0, row = self.Z0, self.row
        th = self.top.Th[row]
        th *= self.arms.a[None, :, None, None]
        th += self.cc[None, :, None, None] * (self.Z1 - z0)[:, None]
        self.top.Zh[row] = self.Z1
        bs[-1, 0] = self.fd1
        bs[-1, 1] = step


def lattice_terms(ly, K, KL, KT, Kd, KY, KLY, meta, a, b, fa, fb, da, db):
    """The springs' forces (fa, fb) and the pair dampers' (da, db) of the fields (a, b) on the two
    layers of the chain2d lattice, as :func:`.scheme.block_update_2d` has them (the drive springs'
    -K_d b included, not their v_d t): the bulk stencil of :func:`.viscoelastic.bulk_forces` twice,
    the dampers being that stencil with every spring constant m eta (row-major (Lx, Ly))."""
    bulk_forces(ly, a, b, fa, fb, K, KL, KT, KY, KLY)
    fb -= Kd * b
    bulk_forces(ly, a, b, da, db, meta, meta, meta, meta, meta)


class LatticeSystem:
    """Backward Euler's linear part on a chain2d row (the (Lx, Ly) lattice of :func:`.scheme.block_update_2d`):
    unknowns (u, U) of every block, A = M + h C + h**2 K (M the masses, C the pair dampers m eta on
    every spring, K the springs K, K_Y, K_L, K_LY, K_T and the drive springs K_d), symmetric positive
    definite; its products by :func:`lattice_terms` (compiled).

    Preconditioner (block-diagonal, by layer): the interface layer by its diagonal with the contacts'
    h f' (Jacobi: in creep the contacts dominate it), the upper layer, which carries no contact, by
    the exact inverse of its own block, diagonal in Fourier space (eigenvalues N_L m + h m eta
    (1 + 4 s_x + 4 s_y) + h**2 (4 K_L s_x + 4 K_LY s_y + K_T + K_d), s = sin**2(pi k/L)): with Jacobi
    alone its lattice Laplacian took 25 conjugate-gradient iterations per solve on 64 x 64."""

    def __init__(self, p, shape, fft, arms: Arms | None = None, preconditioner: str = "jacobi"):
        self.p = p
        self.shape = shape
        self.fft = fft
        self.n = shape[0] * shape[1]
        self.size = 2 * self.n
        self.moves_upper = True  # the upper layer is a state of the step (TR-BDF2's stages)
        self.ly = int(shape[1])
        if preconditioner not in ("jacobi", "additive"):
            raise ValueError(f"preconditioner {preconditioner!r}: expected 'jacobi' or 'additive'")
        self.additive = preconditioner == "additive"
        self.cg_units = 2 if self.additive else 1  # FFT pairs per conjugate-gradient iteration (the cost rule's units)
        self.work = [np.empty(self.n) for _ in range(6)]
        self.arms = arms  # material 'prony': the bulk springs (not K_d) carry the arms (:class:`Arms`)
        kx = np.arange(shape[0])[:, None]
        ky = np.arange(shape[1] // 2 + 1)[None, :]
        self.sx = np.sin(np.pi * kx / shape[0]) ** 2
        self.sy = np.sin(np.pi * ky / shape[1]) ** 2

    def terms(self, a, b):
        p = self.p
        fa, fb, da, db = self.work[:4]
        lattice_terms(self.ly, p[P_K], p[P_KL], p[P_KT], p[P_KD], p[P_KY], p[P_KLY], p[P_META], a, b, fa, fb, da, db)
        return fa, fb, da, db

    def bulk(self, a, b):
        """The bulk springs' force of the fields (a, b) (the arms' stencil: no drive springs)."""
        p = self.p
        fa, fb = self.work[4:]
        bulk_forces(self.ly, a, b, fa, fb, p[P_K], p[P_KL], p[P_KT], p[P_KY], p[P_KLY])
        return fa, fb

    def setup(self, xr, ur, Xr, Ur, h, t1):
        p = self.p
        self.h = h
        self.S = self.arms.setup(h) if self.arms is not None else 0.0
        fx, fX, _, _ = self.terms(xr, Xr)
        g = p[P_KD] * p[P_VD] * t1 + p[P_FCONST]
        h2 = h * h
        hs = h * self.S
        self.upper_symbol = 1.0 / (p[P_ML] + h * p[P_META] * (1.0 + 4.0 * self.sx + 4.0 * self.sy)
                                   + h2 * (4.0 * p[P_KL] * self.sx + 4.0 * p[P_KLY] * self.sy + p[P_KT] + p[P_KD])
                                   + hs * (4.0 * p[P_KL] * self.sx + 4.0 * p[P_KLY] * self.sy + p[P_KT]))
        if self.additive:  # the contact-free operator, per Fourier mode a 2 x 2 block over the two layers, inverted
            lap = 1.0 + 4.0 * self.sx + 4.0 * self.sy  # the dampers' stencil (m eta on every spring, K_T's included)
            a = p[P_M] + h * p[P_META] * lap + (h2 + hs) * (4.0 * p[P_K] * self.sx + 4.0 * p[P_KY] * self.sy + p[P_KT])
            b = 1.0 / self.upper_symbol
            c = h * p[P_META] + (h2 + hs) * p[P_KT]  # the layers' coupling (minus the off-diagonal entry)
            det = a * b - c * c
            self.block_inverse = (b / det, c / det, a / det)
        ny = 2.0 if self.shape[1] > 1 else 0.0  # y neighbours (Ly = 1: the block itself, no bond)
        self.diag_u = p[P_M] + h * p[P_META] * (3.0 + ny) + h2 * (2.0 * p[P_K] + ny * p[P_KY] + p[P_KT])
        rhs = np.concatenate([p[P_M] * ur + h * fx, p[P_ML] * Ur + h * (fX + g)])
        if self.arms is not None:  # h (h + S) K_b on the diagonal, the arms' force K_b G on the right
            self.diag_u += hs * (2.0 * p[P_K] + ny * p[P_KY] + p[P_KT])
            ga, gb = self.bulk(*self.arms.G)
            rhs[:self.n] += h * ga
            rhs[self.n:] += h * gb
        return rhs, np.concatenate([ur, Ur])

    def matvec(self, v):
        p, n, h = self.p, self.n, self.h
        u, U = v[:n], v[n:]
        fx, fX, dx, dX = self.terms(u, U)
        w = np.concatenate([p[P_M] * u - h * dx - h * h * fx, p[P_ML] * U - h * dX - h * h * fX])
        if self.arms is not None:
            ba, bb = self.bulk(u, U)
            w[:n] -= h * self.S * ba
            w[n:] -= h * self.S * bb
        return w

    def precondition(self, r, jd):
        """'jacobi' (by layer): the upper layer by its own block's exact inverse (Fourier space), the interface
        layer by its diagonal with the contacts' h f'. 'additive' (by site, as :meth:`SlabSystem.precondition`):
        the contact blocks by that diagonal, and every other block (the free interface blocks and the whole
        upper layer) by the exact inverse of the contact-free operator (per Fourier mode a 2 x 2 block over the
        two layers, coupled by K_T and its damper) applied to the residual restricted to them and restricted
        back, P_f G^-1 P_f + P_c D^-1: at low load, where few blocks carry contacts, the free blocks' coupling
        through the lattice and to the upper layer is what the diagonal misses. Symmetric positive definite
        either way."""
        n, f = self.n, self.fft
        if not self.additive:
            zU = f.irfft2(self.upper_symbol * f.rfft2(r[n:].reshape(self.shape)), s=self.shape).reshape(n)
            return np.concatenate([r[:n] / (self.diag_u + jd[:n]), zU])
        free = jd[:n] == 0.0
        shp = (2, *self.shape)
        ru, rU = f.rfft2(np.stack([np.where(free, r[:n], 0.0), r[n:]]).reshape(shp), axes=(1, 2))
        ia, ic, ib = self.block_inverse
        z = f.irfft2(np.stack([ia * ru + ic * rU, ic * ru + ib * rU]), s=self.shape, axes=(1, 2)).reshape(2, n)
        return np.concatenate([np.where(free, z[0], r[:n] / (self.diag_u + jd[:n])), z[1]])

    def unknowns(self, u, U):
        return np.concatenate([u, U])

    def upper(self, v, Un):
        Un[:] = v[self.n:]

    def acceleration(self, ap):
        return ap

    def energy(self, x, u, X, U, t):
        """Kinetic, the springs' and the drive springs' energy and the dead weight's potential -F_b X:
        (1/2) q.K q = -(1/2) q.f(q) with the drive springs' -K_d X in f, plus K_d's v_d t terms."""
        p = self.p
        fx, fX, _, _ = self.terms(x, X)
        drive = p[P_VD] * t
        sX = float(np.sum(X))
        return float(0.5 * p[P_M] * np.dot(u, u) + 0.5 * p[P_ML] * np.dot(U, U) - 0.5 * (np.dot(x, fx) + np.dot(X, fX))
                     - p[P_KD] * drive * sX + 0.5 * p[P_KD] * drive * drive * self.n - p[P_FCONST] * sX)

    def rate(self, x, u, X, U, t):
        """The accelerations of the linear part at a state (as :meth:`SlabSystem.rate`): the springs and
        the pair dampers (:func:`lattice_terms`), the drive springs' K_d (v_d t - X) and the dead weight (the
        elastic bulk's: TR-BDF2 is refused with the Prony arms)."""
        p = self.p
        fx, fX, _, _ = self.terms(x, X)
        fx, fX = fx.copy(), fX.copy()
        _, _, dx, dX = self.terms(u, U)
        return (fx + dx) / p[P_M], (fX + dX + p[P_KD] * p[P_VD] * t + p[P_FCONST]) / p[P_ML]

    def powers(self, x, u, X, U, t):
        """(the drive springs' force summed over the blocks, the pair dampers' power) at a state, as
        :meth:`balance` takes them at a step's ends."""
        p = self.p
        _, _, dx, dX = self.terms(u, U)
        return (p[P_KD] * (self.n * p[P_VD] * t - float(np.sum(X))),
                float(np.dot(dx, u) + np.dot(dX, U)))

    def balance(self, xr, ur, Xr, Ur, un, Un, h, t1, nc, st, vs):
        """The step's works by the trapezoidal rule and its energy residual, as :func:`step_balance`
        (with the arms, their work over the step at its velocity, as :meth:`SlabSystem._arm_work`)."""
        p, n = self.p, self.n
        t0 = t1 - h
        x1, X1 = xr + h * un, Xr + h * Un
        de = self.energy(x1, un, X1, Un, t1) - self.energy(xr, ur, Xr, Ur, t0)
        fsum = 0.5 * p[P_KD] * (n * p[P_VD] * (t0 + t1) - float(np.sum(Xr)) - float(np.sum(X1)))
        _, _, d0x, d0X = self.terms(ur, Ur)
        w0 = float(np.dot(d0x, ur) + np.dot(d0X, Ur))
        _, _, d1x, d1X = self.terms(un, Un)
        w_damp = 0.5 * (w0 + float(np.dot(d1x, un) + np.dot(d1X, Un))) * h
        w_visc = 0.0
        if self.arms is not None:  # -h K_b gbar . v', gbar the mean of g over the step (SlabSystem._arm_work)
            (ga, gb), sb = self.arms.mean(h)
            fa, fb = self.bulk(ga + sb * un, gb + sb * Un)
            w_visc = float(np.dot(fa, un) + np.dot(fb, Un)) * h
        return _balance(p, de, fsum, fsum * p[P_VD] * h, w_damp, h, nc, st, vs, ur, un, w_visc)


def _balance(p, de, fsum, w_drive, w_damp, h, nc, st, vs, ur, un, w_visc=0.0):
    """(energy residual, sum of the works' magnitudes, drive force sum, drive, damping, contact and
    the arms' work) of a step with energy change ``de``, the contacts' work by the trapezoidal rule."""
    amp, c, meta_c = p[P_AMP], p[P_C], p[P_M] * p[P_ETAC]
    w_contact = 0.5 * (contact_power_at(nc, st, vs, ur, amp, c, meta_c) + contact_power_at(nc, st, vs, un, amp, c, meta_c)) * h
    return (de - (w_drive + w_damp - w_contact + w_visc), abs(w_drive) + abs(w_damp) + abs(w_contact) + abs(w_visc), fsum,
            w_drive, w_damp, w_contact, w_visc)


def krylov_be_try(system, p, xr, ur, Xr, Ur, st, vs, nc, ys, un, Un, h, t1, tol, yk, sk, ap, have, start=None):
    """One backward-Euler step of a slab, half-space or chain2d row (``system``: :class:`SlabSystem`
    or :class:`LatticeSystem`) from (x, u, X, U) at time t1 - h: writes the new velocities into
    ``un``, ``Un`` and each contact's (y, sign) into ``yk``, ``sk``, touching nothing else. Newton
    as :func:`be_try` (the same contact pieces; the contacts act on the first n unknowns, the blocks'
    velocities); each linear solve, (A + h diag(f')) dv = r, by scipy's conjugate gradients
    preconditioned by the diagonal (Jacobi). Where a contact's h f' dominates (creep at large h:
    h f' ~ 10 against h**2 a**2 k ~ 1e-3 at h = 1 ms, epsilon = 1) that is nearly the inverse;
    where none does, the preconditioned spectrum lies within the spread of A's diagonal over its
    eigenvalues, so the iterations stay few either way. Returns (Newton iterations or -1 where the
    step may not be taken by backward Euler, conjugate-gradient iterations). (The preconditioner is the
    system's own, ``system.precondition``: Jacobi on the slab, by layer on chain2d.) ``start`` (TR-BDF2's
    stages, whose base state is no velocity the blocks had): Newton's start from the velocities (u, U)
    extrapolated over ``dh`` with the last step's accelerations, the contacts' signs from u, instead of from
    the base (x, u, X, U) extrapolated over h."""
    from scipy.sparse.linalg import LinearOperator, cg

    n = xr.size
    amp, c, meta_c = p[P_AMP], p[P_C], p[P_M] * p[P_ETAC]
    rhs, v = system.setup(xr, ur, Xr, Ur, h, t1)
    size = system.size
    u_sign = ur
    if start is not None:
        u_sign, U_start, dh = start
        v = system.unknowns(u_sign, U_start)
        if have:
            v += dh * system.acceleration(ap)
    elif have:
        v += h * system.acceleration(ap)
    un[:] = v[:n]
    if not start_contacts(nc, st, u_sign, un, ys, vs, yk, sk):
        return -1, 0
    hf = np.zeros(size)
    dk = np.empty(nc)
    pk = np.empty(nc)
    qk = np.empty(nc)
    free = np.ones(size, dtype=bool)
    free[st[:nc]] = False
    factors(nc, c, yk, pk, qk)
    jd = np.zeros(size)  # h f' on the contact blocks
    sites = st[:nc]
    cg_its = [0]

    def count(_):
        cg_its[0] += 1

    jac = LinearOperator((size, size), matvec=lambda w: system.matvec(w) + jd * w, dtype=float)
    for it in range(NEWTON_MAX):
        v[:n] = un
        eval_contacts(nc, st, vs, yk, sk, pk, qk, amp, c, meta_c, h, un, hf, dk)
        v[sites] = un[sites]
        jd[sites] = dk
        res = rhs - (system.matvec(v) + hf)
        dv, info = cg(jac, res, rtol=CG_RTOL, atol=0.0, maxiter=CG_MAXITER,
                      M=LinearOperator((size, size), matvec=lambda r: system.precondition(r, jd), dtype=float),
                      callback=count)
        if info != 0:
            return -1, cg_its[0]
        big_v = float(np.max(np.abs(dv[free]))) if free.any() else 0.0
        v += dv
        un[:] = v[:n]  # contact blocks: overwritten from (y, s) below
        big_y = update_contacts(nc, st, vs, yk, sk, pk, qk, c, dv, 1)
        if big_y < 0.0:
            return -1, cg_its[0]
        if big_y < NEWTON_DY and big_v < NEWTON_DV * tol:
            system.upper(v, Un)
            return (it + 1 if finish_contacts(nc, st, vs, yk, sk, pk, un) else -1), cg_its[0]
    return -1, cg_its[0]


GAMMA = TRBDF2_GAMMA  # TR-BDF2's stage fraction (the stability analysis's): the trapezoidal rule to t + gamma h


@nb.njit
def contact_forces_at(nc, st, vs, u, amp, c, meta_c, out):
    """Eq. (1) with its damping at the blocks' velocities ``u``, into ``out`` at each contact's block
    (as :func:`contact_power_at` evaluates it: zero at zero velocity)."""
    for k in range(nc):
        uk = u[st[k]]
        if uk != 0.0:
            out[st[k]] = contact_force(uk, vs[k], amp, c, meta_c)


class TrBdf2Step:
    """One TR-BDF2 step's states for its balance and commit: the start (x, u, X, U) at t0, the
    trapezoidal stage's end at t0 + gamma h, and the BDF2 stage's base positions (xB, XB), from which
    the positions at the step's end are xB + h2 u', XB + h2 U' (h2 = (1 - gamma)/(2 - gamma) h); the
    times t0, t_g = t0 + gamma h, t1."""

    def __init__(self, start, stage, xB, XB, h2, t0, tg, t1):
        self.start, self.stage, self.xB, self.XB, self.h2 = start, stage, xB, XB, h2
        self.t0, self.tg, self.t1 = t0, tg, t1


def krylov_trbdf2_try(system, p, xr, ur, Xr, Ur, st, vs, nc, ys, un, Un, h, t1, tol, yk, sk, ap, have):
    """One TR-BDF2 step (``Config.implicit_scheme = 'trbdf2'``, issue 27) of a slab, half-space or chain2d
    row from (x, u, X, U) at t0 = t1 - h, as :func:`krylov_be_try`'s two solves:

    1. the trapezoidal rule to t_g = t0 + gamma h, gamma = 2 - sqrt(2):
       q_g = q + (gamma h/2)(v + v_g), M (v_g - v) = (gamma h/2)(F(q, v, t0) + F(q_g, v_g, t_g)),
       which is backward Euler with step h1 = gamma h/2 from the base state (q + h1 v, v + h1 M^-1 F(q, v, t0)):
       its force at the start (the linear part, :meth:`SlabSystem.rate`, and the contacts' eq. (1)) is the
       one more operator product;
    2. BDF2 over (t0, t_g, t1): q' = c1 q_g - c2 q + h2 v', M v' = M (c1 v_g - c2 v) + h2 F(q', v', t1), with
       c1 = 1/(gamma (2 - gamma)), c2 = (1 - gamma)**2/(gamma (2 - gamma)), h2 = (1 - gamma)/(2 - gamma) h:
       backward Euler with step h2 from the base (c1 q_g - c2 q, c1 v_g - c2 v).

    Second order and L-stable (:func:`slipchain.model.stability.trbdf2_amplification`); every contact
    must stay on the rising branch in both stages (each solve's own condition). Writes the new velocities
    into ``un``, ``Un`` and the contacts' (y, sign) into ``yk``, ``sk``, touching nothing else. Returns
    (Newton iterations of both solves, or -1 where the step may not be taken, conjugate-gradient
    iterations, :class:`TrBdf2Step` or None)."""
    n = xr.size
    g = GAMMA
    h1, h2, c1, c2 = trbdf2_weights(h, g)
    t0 = t1 - h
    tg = t0 + g * h
    upper = system.moves_upper  # the upper layer (chain2d) or the plate (dead weight) is a state of the step
    au, aU = system.rate(xr, ur, Xr, Ur, t0)
    fc = np.zeros(n)
    contact_forces_at(nc, st, vs, ur, p[P_AMP], p[P_C], p[P_M] * p[P_ETAC], fc)
    au -= fc / p[P_M]
    xb, ub = xr + h1 * ur, ur + h1 * au
    Xb, Ub = (Xr + h1 * Ur, Ur + h1 * aU) if upper else (Xr, Ur)
    its1, cg1 = krylov_be_try(system, p, xb, ub, Xb, Ub, st, vs, nc, ys, un, Un, h1, tg, tol, yk, sk, ap, have,
                              (ur, Ur, g * h))
    if its1 < 0:
        return -1, cg1, None
    ug, Ug = un.copy(), Un.copy()
    xg = xb + h1 * ug
    Xg = Xb + h1 * Ug if upper else Xr
    xB, uB = c1 * xg - c2 * xr, c1 * ug - c2 * ur
    XB, UB = (c1 * Xg - c2 * Xr, c1 * Ug - c2 * Ur) if upper else (Xr, Ur)
    its2, cg2 = krylov_be_try(system, p, xB, uB, XB, UB, st, vs, nc, ys, un, Un, h2, t1, tol, yk, sk, ap, have,
                              (ug, Ug, (1.0 - g) * h))
    if its2 < 0:
        return -1, cg1 + cg2, None
    return its1 + its2, cg1 + cg2, TrBdf2Step((xr.copy(), ur.copy(), Xr.copy(), Ur.copy()), (xg, ug, Xg, Ug), xB, XB, h2,
                                              t0, tg, t1)


def trbdf2_balance(system, p, step, un, Un, nc, st, vs):
    """A TR-BDF2 step's works, each stage's by the trapezoidal rule between its ends, and its energy
    residual (the change of :meth:`SlabSystem.energy` less the works), in :func:`_balance`'s order (the
    drive force sum its mean over the step)."""
    amp, c, meta_c = p[P_AMP], p[P_C], p[P_M] * p[P_ETAC]
    x1 = step.xB + step.h2 * un
    X1 = step.XB + step.h2 * Un if system.moves_upper else step.XB
    states = [(*step.start, step.t0), (*step.stage, step.tg), (x1, un, X1, Un, step.t1)]
    pw = [system.powers(*s) for s in states]
    cp = [contact_power_at(nc, st, vs, s[1], amp, c, meta_c) for s in states]
    f_int = w_damp = w_contact = 0.0
    for i in range(2):
        d = states[i + 1][4] - states[i][4]
        f_int += 0.5 * (pw[i][0] + pw[i + 1][0]) * d
        w_damp += 0.5 * (pw[i][1] + pw[i + 1][1]) * d
        w_contact += 0.5 * (cp[i] + cp[i + 1]) * d
    h = step.t1 - step.t0
    w_drive = f_int * p[P_VD]
    de = system.energy(*states[2]) - system.energy(*states[0])
    return (de - (w_drive + w_damp - w_contact), abs(w_drive) + abs(w_damp) + abs(w_contact), f_int / h, w_drive,
            w_damp, w_contact, 0.0)


__all__ = ["ENERGY_TOL", "GAMMA", "NEWTON_MAX", "TrBdf2Step", "contact_force", "contact_forces_at", "krylov_trbdf2_try", "trbdf2_balance", "Arms", "LatticeSystem", "SlabSystem", "SpectralOperator", "TopSlabSystem", "Y_MAX", "be_contacts", "be_try", "be_try_arms", "krylov_be_try", "chain_arm_work", "chain_arms", "chain_coefficients", "chain_damping", "contact_power_at",
           "damping_power", "chain_energy", "drive_force_sum", "rising", "solve_cyclic",
           "step_balance"]

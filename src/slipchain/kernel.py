"""Compiled CPU kernel (numba) for the two-chain model: advances a batch of realisations.

Equations of motion (MODEL.md; Fig. 4 of the paper), periodic in i:

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
        m u + dt f(u, v*) = r,    r = m u^n + dt F_i,
    solved by Newton's method in y = log10(|u|/v*), warm-started from the previous step: two
    branch-free, vectorised steps for all contacts (:func:`newton_pass`), accepted when the second
    is below NEWTON_TOL = 1e-5
    decades (error left < 3e-10 decades); the others continue in :func:`solve_contact`, whose
    last resort is bisection-safeguarded Newton on a bracket that always contains the root.
 4. Positions: x^{n+1} = x^n + dt u^{n+1}, X^{n+1} = X^n + dt U^{n+1}.

Without contacts and damping this is symplectic Euler: first order in the velocities
(second order for positions, being leapfrog with velocities at half steps), with a bounded
energy error for dt < 2/omega_max ~ 1e-6 s. The contact term is L-stable (backward Euler), so
the ~1e-15 s relaxation times of f near sticking (MODEL.md, numerical facts) impose no limit;
the only limit is that the scalar equation keep one root, dt*max|df/du|_weakening < m, which
:class:`slipchain.config.Config` enforces. Explicit damping needs dt*eta*6 < 2 (dt < 1e-6 s).
Overall order: 1 (checked by tests/test_convergence.py).

Batch layout: arrays of shape (B, N) for the state, (B, C) for contacts (padded; ``n_contacts``
gives each row's count), (B, P) for the parameters. Rows are independent.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

LN10 = math.log(10.0)
LOG10_2 = math.log10(2.0)

# Parameter columns in the (B, P) parameter array.
P_K, P_KL, P_KT, P_KD, P_M, P_ML, P_META, P_VD, P_DT, P_AMP, P_C, P_ETAC, P_SLOW, P_FCONST = range(14)
N_PARAMS = 14  # P_FCONST: constant force on every UL block (dead-weight drive; 0 with the spring drive)

# Output columns per sample and accumulator columns.
O_FD, O_XMEAN, O_XUMEAN = range(3)  # mean f_d over the sample; mean x and mean X at its end
N_OUT = 3
A_WDRIVE, A_WDAMP, A_WCONTACT = range(3)  # work by drive point, by damping, by contacts
N_ACC = 3
C_F, C_U, C_U2, C_SLOW = range(4)  # per-contact sums over steps: force, u, u^2, steps with |u| < slow
N_CACC = 4
Y_LOG, Y_P, Y_Q = range(3)  # per-contact solver state: y = log10(|u|/v*), p = 10**y, q = exp(-c y^2)
N_YS = 3

# LLVM may contract to FMA, reassociate sums and use reciprocals; never assume finite values
# (the non-finite checks must keep working).
FASTMATH = {"contract", "reassoc", "nsz", "arcp"}

NEWTON_TOL = 1e-5  # accept after a Newton step in y (decades) below this: the error left,
# ~|H''/2H'|*d**2 < 3e-10 decades, is a relative velocity error below 1e-9
TAYLOR_MAX = 2e-3  # largest |z| for which the vectorised pass updates exp by its Taylor series



@nb.njit(cache=True, inline="always")
def _exp_taylor(z):
    """exp(z) for |z| <= TAYLOR_MAX = 2e-3 by its Taylor series to z**5 (relative error < 1e-19)."""
    return 1.0 + z * (1.0 + z * (0.5 + z * (1.0 / 6.0 + z * (1.0 / 24.0 + z / 120.0))))


@nb.njit(cache=True, inline="always")
def _scaled_exp(v, z):
    """v*exp(z): multiplicative update, by the Taylor series for small z."""
    if abs(z) <= TAYLOR_MAX:
        return v * _exp_taylor(z)
    return v * math.exp(z)


@nb.njit(cache=True)
def solve_contact_bracketed(ra, a, b, c, y):
    """Root y of  a*10**y + b*exp(-c*y**2) = ra  (ra > 0, c > 0) by safeguarded Newton.

    The bracket [y_lo, y_hi] has H(y_lo) <= 0 <= H(y_hi) by construction:
    y_hi = log10(ra/a); y_lo = min(y_hi - log10 2, -sqrt(ln(2b/ra)/c)).
    """
    y_hi = math.log10(ra / a)
    y_lo = y_hi - LOG10_2
    lg = math.log(2.0 * b / ra)
    if lg > 0.0:
        y_lo = min(y_lo, -math.sqrt(lg / c))
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


@nb.njit(cache=True, inline="always")
def _taylor_newton_step(a, b, c, ra, y, p, q):
    """One Newton step in y for a*p + b*q = ra with p = 10**y, q = exp(-c y**2) updated by Taylor.

    Returns (y, p, q, slope dH/dy at the start, step d, largest |exponent| used).
    """
    dh = LN10 * a * p - 2.0 * c * y * b * q
    d = (a * p + b * q - ra) / dh
    z = -LN10 * d
    w = c * d * (2.0 * y - d)
    return y - d, p * _exp_taylor(z), q * _exp_taylor(w), dh, d, max(abs(z), abs(w))


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def newton_pass(nc, ra, vstar, ys, unew, ok, m_eff, b, c):
    """Two Newton steps from the warm start for every contact, branch-free so that it vectorises.

    Same equation as :func:`solve_contact`, for ra = |r| > 0 and c > 0; 10**y and exp(-c y^2)
    are updated by Taylor series, valid while the steps are small. A contact is accepted
    (ok = True) if the second step is below NEWTON_TOL (the error left is then < 3e-10 decades)
    and every update stayed in the Taylor range; otherwise it keeps its warm start and
    :func:`solve_contact` finishes it.
    """
    for k in range(nc):
        a = m_eff * vstar[k]
        y0 = ys[Y_LOG, k]
        p0 = ys[Y_P, k]
        q0 = ys[Y_Q, k]
        y1, p1, q1, dh1, _, e1 = _taylor_newton_step(a, b, c, ra[k], y0, p0, q0)
        y2, p2, q2, dh2, d2, e2 = _taylor_newton_step(a, b, c, ra[k], y1, p1, q1)
        good = ((dh1 > 0.0) & (dh2 > 0.0) & (abs(d2) < NEWTON_TOL) & (e1 <= TAYLOR_MAX)
                & (e2 <= TAYLOR_MAX) & (ra[k] > 1e-300))
        ok[k] = good
        ys[Y_LOG, k] = y2 if good else y0
        ys[Y_P, k] = p2 if good else p0
        ys[Y_Q, k] = q2 if good else q0
        unew[k] = vstar[k] * p2


@nb.njit(cache=True)
def solve_contact(r, m_eff, b, c, vstar, y, p, q):
    """Velocity u solving  m_eff*u + b*exp(-c*y**2)*sign(u) = r,  y = log10(|u|/vstar).

    m_eff = m*(1 + dt*eta_c) (the contact damping is implicit too), b = dt*epsilon*f0.
    (y, p, q) = (y, 10**y, exp(-c*y**2)) of this contact's previous step are the warm start.
    Newton's method in y updates 10**y and exp(-c y^2) multiplicatively (no transcendental
    call while the steps are small); if it does not settle within a few steps, the bracketed
    solver takes over. Returns (u, y, p, q) with the new solver state.
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
        p = _scaled_exp(p, -LN10 * d)
        q = _scaled_exp(q, c * d * (2.0 * y - d))
        y -= d
        if abs(d) < NEWTON_TOL:
            return s * vstar * p, y, p, q
    y = solve_contact_bracketed(ra, a, b, c, y0)
    p = math.exp(LN10 * y)
    return s * vstar * p, y, p, math.exp(-c * y * y)



@nb.njit(cache=True, inline="always")
def _block_update(i, ip, im, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm, dtmL):
    """Explicit velocity update of IL block i and UL block i with neighbours ip, im."""
    dx = meta * (ur[ip] + ur[im] + Ur[i] - 3.0 * ur[i])
    dX = meta * (Ur[ip] + Ur[im] + ur[i] - 3.0 * Ur[i])
    fx = K * (xr[ip] + xr[im] - 2.0 * xr[i]) + KT * (Xr[i] - xr[i]) + dx
    fX = KL * (Xr[ip] + Xr[im] - 2.0 * Xr[i]) + KT * (xr[i] - Xr[i]) + Kd * (drive - Xr[i]) + fconst + dX
    un[i] = ur[i] + dtm * fx
    Un[i] = Ur[i] + dtmL * fX
    dampx[i] = dx
    dampX[i] = dX


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _explicit_forces(xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm, dtmL):
    """Explicit velocity update of all blocks (springs, drive, damping); returns sum of drive forces.

    Interior blocks in one branch-free loop (vectorisable); the two periodic ends separately.
    """
    n = xr.size
    for i in range(1, n - 1):
        _block_update(i, i + 1, i - 1, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm,
                      dtmL)
    _block_update(0, 1, n - 1, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm, dtmL)
    _block_update(n - 1, 0, n - 2, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm,
                  dtmL)
    sx = 0.0
    for i in range(n):
        sx += Xr[i]
    return Kd * (n * drive - sx)


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _move(xr, ur, Xr, Ur, un, Un, dampx, dampX, dt):
    """Positions from the new velocities; returns the work of the damping forces over the step."""
    wd = 0.0
    for i in range(xr.size):
        xr[i] += dt * un[i]
        Xr[i] += dt * Un[i]
        wd += dampx[i] * un[i] + dampX[i] * Un[i]
        ur[i] = un[i]
        Ur[i] = Un[i]
    return wd * dt


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _contact_sums(nc, fk, uk, ca, slow):
    """Accumulate per-contact force, velocity, velocity**2, slow steps; returns sum f*u."""
    p = 0.0
    for k in range(nc):
        ca[C_F, k] += fk[k]
        ca[C_U, k] += uk[k]
        ca[C_U2, k] += uk[k] * uk[k]
        ca[C_SLOW, k] += 1.0 if abs(uk[k]) < slow else 0.0
        p += fk[k] * uk[k]
    return p


@nb.njit(cache=True)
def advance(x, u, X, U, step, params, sites, vstar, n_contacts, ysolve, n_samples, sample_steps,
            out, acc, cacc, status):
    """Advance every row b of the batch by n_samples*sample_steps steps (scheme: module docstring).

    In/out: x, u, X, U (B, N); step (B,) int64 steps taken; ysolve (B, N_YS, C) contact solver
    warm starts. Inputs: params (B, P); sites, vstar (B, C); n_contacts (B,).
    Outputs (accumulated, zero them to restart): out (B, n_samples, N_OUT) per-sample values;
    acc (B, N_ACC) work sums [J]; cacc (B, N_CACC, C) per-contact sums over steps.
    status (B,): -1 while finite; set to the step at which a non-finite value appeared (the row
    then stops advancing).
    """
    nb_rows, n = x.shape
    cmax = sites.shape[1]
    un = np.empty(n)
    Un = np.empty(n)
    dampx = np.empty(n)
    dampX = np.empty(n)
    rk = np.empty(cmax)
    ra = np.empty(cmax)
    uk = np.empty(cmax)
    fk = np.empty(cmax)
    ok = np.empty(cmax, dtype=np.bool_)
    for row in range(nb_rows):
        if status[row] >= 0:
            continue
        K = params[row, P_K]
        KL = params[row, P_KL]
        KT = params[row, P_KT]
        Kd = params[row, P_KD]
        m = params[row, P_M]
        meta = params[row, P_META]
        vd = params[row, P_VD]
        fconst = params[row, P_FCONST]
        dt = params[row, P_DT]
        dtm = dt / m
        dtmL = dt / params[row, P_ML]
        inv_dt = 1.0 / dt
        bc = dt * params[row, P_AMP]
        c = params[row, P_C]
        m_eff = m * (1.0 + dt * params[row, P_ETAC])
        slow = params[row, P_SLOW]
        nc = n_contacts[row]
        xr = x[row]
        ur = u[row]
        Xr = X[row]
        Ur = U[row]
        ys = ysolve[row]
        ca = cacc[row]
        vs = vstar[row]
        st = sites[row]
        w_drive = 0.0
        w_damp = 0.0
        w_contact = 0.0
        for s in range(n_samples):
            for k in range(nc):  # exact 10**y and exp(-c y^2): no round-off drift of the updates
                ys[Y_P, k] = math.exp(LN10 * ys[Y_LOG, k])
                ys[Y_Q, k] = math.exp(-c * ys[Y_LOG, k] * ys[Y_LOG, k])
            fd_sum = 0.0
            for _ in range(sample_steps):
                drive = vd * (step[row] * dt)
                fsum = _explicit_forces(xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm,
                                        dtmL)
                for k in range(nc):
                    rk[k] = m * un[st[k]]
                    ra[k] = abs(rk[k])
                if c > 0.0:
                    newton_pass(nc, ra, vs, ys, uk, ok, m_eff, bc, c)
                else:
                    ok[:nc] = False
                for k in range(nc):
                    if ok[k]:
                        uk[k] = math.copysign(uk[k], rk[k])
                    else:
                        uk[k], ys[Y_LOG, k], ys[Y_P, k], ys[Y_Q, k] = solve_contact(
                            rk[k], m_eff, bc, c, vs[k], ys[Y_LOG, k], ys[Y_P, k], ys[Y_Q, k])
                    fk[k] = (rk[k] - m * uk[k]) * inv_dt  # the contact force f(u) actually applied
                    un[st[k]] = uk[k]
                w_contact -= _contact_sums(nc, fk, uk, ca, slow) * dt
                w_damp += _move(xr, ur, Xr, Ur, un, Un, dampx, dampX, dt)
                w_drive += fsum * vd * dt
                fd_sum += fsum / n
                step[row] += 1
            xs = 0.0
            Xs = 0.0
            for i in range(n):
                xs += xr[i]
                Xs += Xr[i]
            out[row, s, O_FD] += fd_sum / sample_steps
            out[row, s, O_XMEAN] += xs / n
            out[row, s, O_XUMEAN] += Xs / n
            if not (math.isfinite(fd_sum) and math.isfinite(xs) and math.isfinite(w_contact)):
                status[row] = step[row]
                break
        acc[row, A_WDRIVE] += w_drive
        acc[row, A_WDAMP] += w_damp
        acc[row, A_WCONTACT] += w_contact

"""The CPU pieces of the engine: the scheme of :mod:`slipchain.engine.scheme` compiled with numba.

The chains' body (:func:`lattice_explicit`: the explicit update of every block by
:func:`~slipchain.engine.scheme.block_update`, vectorised over the interior blocks;
:func:`lattice_commit`: the positions), the contacts (:func:`_contacts`: two branch-free Newton
steps for all contacts in :func:`newton_pass`, which vectorises, the rest in
:func:`~slipchain.engine.scheme.solve_contact` or its fold-aware version), the per-contact sums and
a sample's end. :mod:`.compose` composes them with a stepper into the loops (column layout in
:mod:`slipchain.engine.scheme`).
"""

from __future__ import annotations

import math

import numba as nb

from ..scheme import (C_F, C_SLOW, C_U, C_U2, FASTMATH, LN10, NEWTON_TOL, O_FD, O_XMEAN, O_XUMEAN, P_FCONST, P_K, P_KD,
                      P_KL, P_KLY, P_KT, P_KY, P_LAT, P_LY, P_M, P_META, P_ML, P_VD, TAYLOR_MAX, Y_FA, Y_FB, Y_LOG, Y_P,
                      Y_Q, compile_for)

_scheme = compile_for(lambda name, inline: nb.njit(inline="always" if inline else "never"))
exp_taylor = _scheme.exp_taylor
scaled_exp = _scheme.scaled_exp
solve_contact_bracketed = _scheme.solve_contact_bracketed
taylor_newton_step = _scheme.taylor_newton_step
solve_contact = _scheme.solve_contact
solve_contact_fold = _scheme.solve_contact_fold
solve_on_bracket = _scheme.solve_on_bracket
block_update = _scheme.block_update
block_update_2d = _scheme.block_update_2d
row_parameters = _scheme.row_parameters


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def newton_pass(nc, ra, vstar, ys, unew, ok, m_eff, b, c):
    """Two Newton steps from the warm start for every contact, branch-free so that it vectorises.

    Same equation as :func:`~slipchain.engine.scheme.solve_contact`, for ra = |r| > 0 and c > 0; 10**y and exp(-c y^2)
    are updated by Taylor series, valid while the steps are small. A contact is accepted
    (ok = True) if the second step is below NEWTON_TOL (the error left is then < 3e-10 decades)
    and every update stayed in the Taylor range; otherwise it keeps its warm start and
    :func:`~slipchain.engine.scheme.solve_contact` finishes it.
    """
    for k in range(nc):
        a = m_eff * vstar[k]
        y0 = ys[Y_LOG, k]
        p0 = ys[Y_P, k]
        q0 = ys[Y_Q, k]
        y1, p1, q1, dh1, _, e1 = taylor_newton_step(a, b, c, ra[k], y0, p0, q0)
        y2, p2, q2, dh2, d2, e2 = taylor_newton_step(a, b, c, ra[k], y1, p1, q1)
        good = ((dh1 > 0.0) & (dh2 > 0.0) & (abs(d2) < NEWTON_TOL) & (e1 <= TAYLOR_MAX)
                & (e2 <= TAYLOR_MAX) & (ra[k] > 1e-300))
        ok[k] = good
        ys[Y_LOG, k] = y2 if good else y0
        ys[Y_P, k] = p2 if good else p0
        ys[Y_Q, k] = q2 if good else q0
        unew[k] = vstar[k] * p2



@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _explicit_forces(xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm, dtmL):
    """Explicit velocity update of all blocks (springs, drive, damping); returns sum of drive forces.

    Interior blocks in one branch-free loop (vectorisable); the two periodic ends separately.
    """
    n = xr.size
    for i in range(1, n - 1):
        block_update(i, i + 1, i - 1, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm,
                      dtmL)
    block_update(0, 1, n - 1, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm, dtmL)
    block_update(n - 1, 0, n - 2, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, meta, drive, fconst, dtm,
                  dtmL)
    sx = 0.0
    for i in range(n):
        sx += Xr[i]
    return Kd * (n * drive - sx)


@nb.njit(inline="always")
def lattice_neighbours(ix, iy, lx, ly):
    """Block (ix, iy) of the periodic (Lx, Ly) lattice of 'chain2d' (row-major, block ix*Ly + iy) and its
    neighbours: (i, ip, im, jp, jm), ip/im along x, jp/jm along y, as unsigned indices.

    Unsigned, so that numba adds no negative-index wrap (i + n where i < 0): with it the vectorised loop's runtime
    alias check also spanned a wrapped range past each array's end, a false conflict whenever a written array lay
    there, which sent the row to the scalar loop (its sums associated otherwise): the 2-D chains' last bits followed
    the heap (docs/performance.md, "The 2-D chains' bits followed the heap"). Used by every 2-D stencil
    (:func:`_explicit_forces_2d`, :func:`.viscoelastic.bulk_forces`).
    """
    base = ix * ly
    return (nb.uint64(base + iy), nb.uint64(((ix + 1) % lx) * ly + iy), nb.uint64(((ix + lx - 1) % lx) * ly + iy),
            nb.uint64(base + (iy + 1 if iy + 1 < ly else 0)), nb.uint64(base + (iy - 1 if iy > 0 else ly - 1)))


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _explicit_forces_2d(ly, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, KY, KLY, meta, drive, fconst, dtm,
                        dtmL):
    """:func:`_explicit_forces` on the (Lx, Ly) lattice of 'chain2d' (row-major, block ix*Ly + iy)."""
    n = xr.size
    lx = n // ly
    for ix in range(lx):
        for iy in range(ly):
            i, ip, im, jp, jm = lattice_neighbours(ix, iy, lx, ly)
            block_update_2d(i, ip, im, jp, jm, xr, ur, Xr, Ur, un, Un, dampx, dampX, K, KL, KT, Kd, KY, KLY, meta,
                            drive, fconst, dtm, dtmL)
    sx = 0.0
    for i in range(n):
        sx += Xr[i]
    return Kd * (n * drive - sx)


@nb.njit
def _contacts(nc, un, st, rk, ra, uk, fk, ok, vs, ys, m, m_eff, bc, c, inv_dt, fold):
    """The implicit contact solve of one step (scheme, step 3) for one row: every contact block's
    new velocity written into ``un``, the force applied into ``fk``. ``fold``: integrator 'fold'
    (the contacts the vectorised pass leaves go to :func:`~slipchain.engine.scheme.solve_contact_fold`)."""
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
        elif fold:
            uk[k], ys[Y_LOG, k], ys[Y_P, k], ys[Y_Q, k] = solve_contact_fold(
                rk[k], m_eff, bc, c, vs[k], ys[Y_LOG, k], ys[Y_P, k], ys[Y_Q, k], ys[Y_FA, k], ys[Y_FB, k])
        else:
            uk[k], ys[Y_LOG, k], ys[Y_P, k], ys[Y_Q, k] = solve_contact(
                rk[k], m_eff, bc, c, vs[k], ys[Y_LOG, k], ys[Y_P, k], ys[Y_Q, k])
        fk[k] = (rk[k] - m * uk[k]) * inv_dt  # the contact force f(u) actually applied
        un[st[k]] = uk[k]


@nb.njit
def _refresh_solver(nc, ys, c):
    """Exact 10**y and exp(-c y^2) at the start of a sample: no round-off drift of the updates."""
    for k in range(nc):
        ys[Y_P, k] = math.exp(LN10 * ys[Y_LOG, k])
        ys[Y_Q, k] = math.exp(-c * ys[Y_LOG, k] * ys[Y_LOG, k])


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def contact_power(nc, fk, uk):
    """sum_k f_k u_k over the contacts, in a loop that writes nothing (spectral.body_explicit says
    why); one function for every stepper, so that the fixed and the adaptive step sum alike."""
    p = 0.0
    for k in range(nc):
        p += fk[k] * uk[k]
    return p


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _contact_sums(nc, fk, uk, ca, slow):
    """Accumulate per-contact force, velocity, velocity**2, slow steps; returns sum f*u."""
    p = contact_power(nc, fk, uk)
    for k in range(nc):
        ca[C_F, k] += fk[k]
        ca[C_U, k] += uk[k]
        ca[C_U2, k] += uk[k] * uk[k]
        ca[C_SLOW, k] += 1.0 if abs(uk[k]) < slow else 0.0
    return p


@nb.njit(cache=True, inline="always")
def lattice_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t):
    """The chains' body, explicit part (:mod:`.compose`; scheme, steps 1-2) for one row with
    parameters ``p``, a step h at drive time t: :func:`_explicit_forces_2d` on the lattice of
    'chain2d', else :func:`_explicit_forces`; returns the sum of drive forces. (``Fr``, ``k0``:
    nothing from outside the kernel; ``mt``, ``br``: no internal variables, material 'elastic'.)"""
    m = p[P_M]
    drive = p[P_VD] * t
    if p[P_LAT] > 0.0:
        return _explicit_forces_2d(int(p[P_LY]), xr, ur, Xr, Ur, un, Un, dampx, dampX, p[P_K], p[P_KL], p[P_KT],
                                   p[P_KD], p[P_KY], p[P_KLY], p[P_META], drive, p[P_FCONST], h / m, h / p[P_ML])
    return _explicit_forces(xr, ur, Xr, Ur, un, Un, dampx, dampX, p[P_K], p[P_KL], p[P_KT], p[P_KD], p[P_META], drive,
                            p[P_FCONST], h / m, h / p[P_ML])


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def lattice_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h):
    """The chains' body, commit (:mod:`.compose`; scheme, step 4): the positions from the new
    velocities; returns (the damping work over the step, 0: no bulk viscosity). The update itself,
    not a wrapper inlined around a call (measured, benchmarks/bench_default.py: such a wrapper in
    the step loop cost the chain's fixed-step kernel about 5 %)."""
    wd = 0.0
    for i in range(xr.size):  # the work in a loop that writes nothing (spectral.body_explicit says why)
        wd += dampx[i] * un[i] + dampX[i] * Un[i]
    for i in range(xr.size):
        xr[i] += h * un[i]
        Xr[i] += h * Un[i]
        ur[i] = un[i]
        Ur[i] = Un[i]
    return wd * h, 0.0


@nb.njit
def _end_sample(xr, Xr, fd_sum, sample_steps, w_contact, out_s):
    """Write one sample's outputs (mean f_d, and mean x and X at its end) into ``out_s`` (N_OUT,);
    returns False if a non-finite value appeared (the row then stops)."""
    n = xr.size
    xs = 0.0
    Xs = 0.0
    for i in range(n):
        xs += xr[i]
        Xs += Xr[i]
    out_s[O_FD] += fd_sum / sample_steps
    out_s[O_XMEAN] += xs / n
    out_s[O_XUMEAN] += Xs / n
    return math.isfinite(fd_sum) and math.isfinite(xs) and math.isfinite(w_contact)


__all__ = ["block_update", "lattice_commit", "lattice_explicit", "newton_pass", "solve_contact", "solve_contact_bracketed"]

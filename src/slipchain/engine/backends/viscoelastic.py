"""The chains' viscoelastic body (issue 28, ``material = "prony"``): the lattice body of
:mod:`.cpu` plus the Maxwell arms of a Prony series (:mod:`slipchain.model.viscoelastic`).

Per row, the material table ``mt`` (2, J) holds r_j = E_j / E_inf and tau_j (at the run's
temperature), and the body state ``br`` (2 J + 4, n) the internal fields: rows 0 .. J-1 the
interface layer's xi_j, rows J .. 2J-1 the upper layer's, then four work rows (the arms' combined
field g = sum_j r_j xi_j of both layers and their force on every block, kept for the work).

Explicit part (scheme, steps 1-2): the arms pull on every block with the bulk springs' stencil
(K, K_L, K_T; on the 2-D lattice also K_Y, K_LY; never the drive springs K_d) applied to g, at the
step's start as the springs do; the blocks' new velocities are the elastic body's plus
h/m times that force. Commit (step 4): the arms' work over the step, then ``xi_j <- a_j xi_j + tau_j (1 - a_j) u'`` (exact for the
displacement h u' linear over the step, :func:`slipchain.model.viscoelastic.exponential_weights`),
then the elastic body's commit (positions). A rejected adaptive step changes nothing here (the
commit alone writes the state). Sums are taken in loops that write nothing, as elsewhere
(:func:`.spectral.body_explicit` says why).

The arms' work is their force times the step's mean velocity (u + u')/2, the velocity with which
the explicit step changes the kinetic energy exactly (m (u'^2 - u^2)/2 = h F (u + u')/2). Taken
with u' alone, as the damping's is, it left a first-order residual in the energy balance that is
large here (the default compound's arms dissipate a third of the drive's work; measured 2.7e-3,
1.4e-3, 6.7e-4 of W_drive at 4e-8, 2e-8, 1e-8 s, beyond the tolerance on the adaptive step's
larger levels). The arms' own dissipation, -W_bulk = -(their work + the change of their energy),
is checked against the Prony formula for a sinusoidal motion (tests/physics/test_viscoelastic.py).
"""

from __future__ import annotations

import math

import numba as nb

import numpy as np

from ..scheme import BODY_ROWS, FASTMATH, P_DT, P_K, P_KD, P_KL, P_KLY, P_KT, P_KY, P_LAT, P_LY, P_M, P_META, P_ML, P_VD
from .cpu import lattice_commit, lattice_explicit, lattice_neighbours
from .spectral import body_commit, body_explicit


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def combined_fields(J, mt, br, gx, gX):
    """g = sum_j r_j xi_j of both layers into gx, gX."""
    n = gx.size
    for i in range(n):
        gx[i] = 0.0
        gX[i] = 0.0
    for j in range(J):
        r = mt[0, j]
        xj = br[j]
        Xj = br[J + j]
        for i in range(n):
            gx[i] += r * xj[i]
            gX[i] += r * Xj[i]


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def bulk_forces(ly, gx, gX, fx, fX, K, KL, KT, KY, KLY):
    """The bulk springs' force on every block for displacement fields gx (interface layer), gX
    (upper layer): the chains' stencil without drive, damping or dead weight (``ly`` = 1: the chain;
    else the (Lx, Ly) lattice of 'chain2d', row-major)."""
    n = gx.size
    lx = n // ly
    for ix in range(lx):
        for iy in range(ly):
            i, ip, im, jp, jm = lattice_neighbours(ix, iy, lx, ly)  # unsigned: no false alias conflict (its docstring)
            t = KT * (gX[i] - gx[i])
            fx[i] = K * (gx[ip] + gx[im] - 2.0 * gx[i]) + KY * (gx[jp] + gx[jm] - 2.0 * gx[i]) + t
            fX[i] = KL * (gX[ip] + gX[im] - 2.0 * gX[i]) + KLY * (gX[jp] + gX[jm] - 2.0 * gX[i]) - t


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _kick(un, Un, fx, fX, dtm, dtmL):
    for i in range(un.size):
        un[i] += dtm * fx[i]
        Un[i] += dtmL * fX[i]


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _arm_work(fx, fX, ur, Ur, un, Un):
    """sum of the arms' force times the step's mean velocity (a loop that writes nothing)."""
    w = 0.0
    for i in range(un.size):
        w += fx[i] * (ur[i] + un[i]) + fX[i] * (Ur[i] + Un[i])
    return 0.5 * w


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _relax(J, mt, br, un, Un, h):
    """xi_j <- a_j xi_j + tau_j (1 - a_j) u' for every term and layer."""
    for j in range(J):
        tau = mt[1, j]
        a = math.exp(-h / tau)
        c = -tau * math.expm1(-h / tau)
        xj = br[j]
        Xj = br[J + j]
        for i in range(un.size):
            xj[i] = a * xj[i] + c * un[i]
            Xj[i] = a * Xj[i] + c * Un[i]


@nb.njit(cache=True, inline="always")
def prony_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t):
    """The viscoelastic chains' explicit part (module docstring); returns the drive force sum."""
    J = mt.shape[1]
    gx, gX, fx, fX = br[2 * J], br[2 * J + 1], br[2 * J + 2], br[2 * J + 3]
    combined_fields(J, mt, br, gx, gX)
    ly = int(p[P_LY]) if p[P_LAT] > 0.0 else 1
    bulk_forces(ly, gx, gX, fx, fX, p[P_K], p[P_KL], p[P_KT], p[P_KY], p[P_KLY])
    fsum = lattice_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t)
    _kick(un, Un, fx, fX, h / p[P_M], h / p[P_ML])
    return fsum


@nb.njit(cache=True, inline="always")
def prony_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h):
    """The viscoelastic chains' commit (module docstring); returns (damping work, the arms' work)."""
    J = mt.shape[1]
    w_visc = _arm_work(br[2 * J + 2], br[2 * J + 3], ur, Ur, un, Un) * h
    _relax(J, mt, br, un, Un, h)
    return lattice_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h)[0], w_visc


# The slab under the dead weight (issue 28): the whole kernel k_c(q) is the rubber's, linear in the
# modulus for every q (the clamped top is the plate), so the arms' force is
# -IFFT[a**2 k_c FFT(sum_j r_j xi_j)] with xi_j the arms' fields of the blocks' displacement relative
# to the plate (rows 0 .. J-1 of the body state; rows J .. 2J-1 unused). The FFT driver
# (:func:`.compose.fft_advance`) adds it to the elastic force it hands the body and keeps it in the
# work row 2J + 2; the plate feels its reaction through the force's mean, as the elastic one's.
# The half-space under the spring drive: k(q) = G q (...) is the rubber's, linear in the modulus, for
# every q != 0, and k(0) = kappa_d is the drive springs' alone, so the arms act on every mode but the
# uniform one (:func:`slipchain.model.viscoelastic.arm_kernel`); there is no plate (U = 0).
# The radiation damping stays at the relaxed modulus (c_s from E_inf), as the drive springs do in
# the chains.


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def slab_prony_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t):
    """The viscoelastic slab's explicit part: the elastic slab's with the arms' force already in ``Fr``."""
    return body_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t)


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _slab_arm_work(fa, ur, Ur, un, Un):
    """sum of the arms' force times the step's mean velocity relative to the plate (which takes the
    reaction): a loop that writes nothing."""
    w = 0.0
    for i in range(un.size):
        w += fa[i] * ((ur[i] + un[i]) - (Ur[i] + Un[i]))
    return 0.5 * w


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def _slab_relax(J, mt, br, un, Un, h):
    """xi_j <- a_j xi_j + tau_j (1 - a_j) (u' - U') for every term."""
    for j in range(J):
        tau = mt[1, j]
        a = math.exp(-h / tau)
        c = -tau * math.expm1(-h / tau)
        xj = br[j]
        for i in range(un.size):
            xj[i] = a * xj[i] + c * (un[i] - Un[i])


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def slab_prony_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h):
    """The viscoelastic slab's commit: the arms' work, their update, then the elastic slab's commit;
    returns (damping work, the arms' work)."""
    J = mt.shape[1]
    w_visc = _slab_arm_work(br[2 * J + 2], ur, Ur, un, Un) * h
    _slab_relax(J, mt, br, un, Un, h)
    return body_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h)[0], w_visc


# The slab under the drive springs (issue 28): the springs hold the slab's top, so k(q) is the slab in
# series with them, not linear in the modulus. The slab is then a two-port per mode
# (:func:`slipchain.model.elastic.slab_twoport`, channels P and S), linear in the modulus in each
# entry, and the top's displacement is a state of its own: the fields Z_P, Z_S (real in space), kept in
# Fourier space through a chunk by the FFT driver (:func:`.compose.fft_advance`) and in the body state
# between chunks (rows from 2J + BODY_ROWS, scheme.top_rows). The top is massless: after every step it is
# put in equilibrium with the blocks (:func:`top_solve`), its Maxwell arms advanced by the same exponential
# rule over the step. The blocks then feel -(A (x + g_b) + sum_c w_c**2 K12c (Z_c + g_tc)) (g: the arms'
# combined fields), of which the arms' part is kept in work row 2J + 2 as on the plate's slab; the drive
# is the springs' pull on the top's uniform mode, kappa a**2 (v_d t - <Z_P>) per block.


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def slab_top_prony_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t):
    """The viscoelastic slab's explicit part under the drive springs: ``Fr`` is the body's whole force
    (the drive reaches the blocks through the top); returns the drive springs' force sum, which the
    top's solve left in the body state."""
    n = xr.size
    dtm = h / p[P_M]
    meta = p[P_META]
    vd = p[P_VD]
    for i in range(n):
        d = -meta * (ur[i] - vd)
        un[i] = ur[i] + dtm * (Fr[i] + d)
        dampx[i] = d
    for i in range(n):
        Un[i] = Ur[i]
    return br[br.shape[0] - 1, 0]  # the body state's last row (scheme.top_rows)


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def top_solve(xh, gbh, Zh, Th, ft, tp, mt, bs, steps, params, wgt, fel, farm, wtop):
    """Put every row's top in equilibrium with its blocks (the module's comment above), in Fourier space.

    Every complex array is given as its float64 view (real and imaginary parts interleaved along the
    last axis), and the coefficient arrays tp, wgt with every entry repeated twice to match: every
    coefficient is real, so the parts never mix and the loops run over unit-stride floats.
    xh, gbh: (B, Lx, 2 Lh) transforms of the blocks' displacements and of their arms' combined field;
    Zh (B, 2, Lx, Lh) the top's fields, Th (B, 2, J, Lx, Lh) its arms, ft (B, 2, Lx, Lh) the arms' force
    on the top at the last call (updated in place); tp (B, 6, Lx, Lh) :func:`~slipchain.model.elastic.twoport_kernel`;
    bs the body state (its last row: the drive force sum and the step of the last solve, written
    here). Per row, with h the time since the last solve (none: the state is kept; never solved: the
    relaxed equilibrium, the arms as they are, no work)::

        (K22 (1 + S) + kappa) Z' = kappa X_d - K12 (x + g_b) - K22 (sum_j r_j a_j xi_j - S Z),  S = sum_j r_j c_j / h
        xi_j <- a_j xi_j + c_j (Z' - Z) / h,   c_j = tau_j (1 - a_j)

    (channel by channel; X_d = n v_d t in the uniform mode of channel P). The arms' work on the top over
    the step, by the trapezoidal rule in Z, is added to wtop. Returns in fel, farm the transforms of the
    body's force on the blocks, elastic and the arms'."""
    b = xh.shape[0]
    nm = xh[0].size  # real and imaginary parts interleaved: every coefficient is real
    J = mt.shape[2]
    meta = bs.shape[1] - 1  # the body state's last row (scheme.top_rows)
    a = np.empty(J)
    cc = np.empty(J)
    gp = np.empty(nm)
    gt = np.empty(nm)
    dz = np.empty(nm)
    w2 = wgt.reshape(nm)
    for row in range(b):
        p = params[row]
        kap = p[P_KD]
        last = bs[row, meta, 1]
        st = steps[row]
        relaxed = last < 0.0
        ds = 0.0 if relaxed else st - last
        solve = relaxed or ds > 0.0
        S = 0.0
        if solve and not relaxed:
            h = ds * p[P_DT]
            for j in range(J):
                tau = mt[row, 1, j]
                a[j] = math.exp(-h / tau)
                cc[j] = -tau * math.expm1(-h / tau) / h
                S += mt[row, 0, j] * cc[j]
        xd = p[P_VD] * st * p[P_DT] * bs.shape[2]  # n v_d t
        x = xh[row].reshape(nm)
        gb = gbh[row].reshape(nm)
        A = tp[row, 0].reshape(nm)
        wp = tp[row, 1].reshape(nm)
        fe = fel[row].reshape(nm)
        fa = farm[row].reshape(nm)
        for m in range(nm):
            fe[m] = -A[m] * x[m]
            fa[m] = -A[m] * gb[m]
        w = 0.0
        for c in range(2):
            k12 = tp[row, 2 + c].reshape(nm)
            d = tp[row, 4 + c].reshape(nm)
            z = Zh[row, c].reshape(nm)
            f = ft[row, c].reshape(nm)
            if solve:
                for m in range(nm):
                    gp[m] = 0.0
                for j in range(J):  # relaxed: the arms as they are; else their decayed part
                    rj = mt[row, 0, j] * (1.0 if relaxed else a[j])
                    th = Th[row, c, j].reshape(nm)
                    for m in range(nm):
                        gp[m] += rj * th[m]
                rhs = kap * xd if c == 0 else 0.0  # the uniform mode's real part, entry 0
                if relaxed:
                    for m in range(nm):
                        z[m] = (-k12[m] * (x[m] + gb[m]) - d[m] * gp[m]) / (d[m] + kap)
                    z[0] += rhs / (d[0] + kap)
                else:
                    for m in range(nm):
                        zn = (-k12[m] * (x[m] + gb[m]) - d[m] * (gp[m] - S * z[m])) / (d[m] * (1.0 + S) + kap)
                        dz[m] = zn - z[m]
                        z[m] = zn
                    z[0] += rhs / (d[0] * (1.0 + S) + kap)
                    dz[0] += rhs / (d[0] * (1.0 + S) + kap)
            if solve and not relaxed:  # the arms' update; their combined field is then gp + S dz
                for j in range(J):
                    aj = a[j]
                    cj = cc[j]
                    th = Th[row, c, j].reshape(nm)
                    for m in range(nm):
                        th[m] = aj * th[m] + cj * dz[m]
                for m in range(nm):
                    gt[m] = gp[m] + S * dz[m]
            elif relaxed:
                for m in range(nm):
                    gt[m] = gp[m]
            else:
                for m in range(nm):
                    gt[m] = 0.0
                for j in range(J):
                    rj = mt[row, 0, j]
                    th = Th[row, c, j].reshape(nm)
                    for m in range(nm):
                        gt[m] += rj * th[m]
            for m in range(nm):
                wc = wp[m] if c == 0 else 1.0 - wp[m]
                fn = -(k12[m] * gb[m] + d[m] * gt[m])
                if solve and not relaxed:
                    w += w2[m] * wc * (0.5 * (f[m] + fn)) * dz[m]
                f[m] = fn
                fe[m] -= wc * k12[m] * z[m]
                fa[m] -= wc * k12[m] * gt[m]
        wtop[row] += w
        if solve:
            bs[row, meta, 1] = st
        bs[row, meta, 0] = kap * (xd - Zh[row, 0, 0, 0])


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def prony_be_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h):
    """A backward-Euler step's commit on the chains (integrator 'implicit', :class:`.implicit.Arms`):
    the arms' update with the step's velocities, then the elastic body's commit (the arms' work is
    the step's balance's, by the trapezoidal rule)."""
    _relax(mt.shape[1], mt, br, un, Un, h)
    return lattice_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h)


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def slab_prony_be_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h):
    """A backward-Euler step's commit on the slab under the dead weight (as :func:`prony_be_commit`)."""
    _slab_relax(mt.shape[1], mt, br, un, Un, h)
    return body_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h)


__all__ = ["BODY_ROWS", "slab_top_prony_explicit", "top_solve", "bulk_forces", "combined_fields", "prony_be_commit", "slab_prony_be_commit", "prony_commit", "prony_explicit", "slab_prony_commit", "slab_prony_explicit"]


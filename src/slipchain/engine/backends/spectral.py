"""The slab and half-space geometries on the CPU (issue 13): elastic force by FFT, contacts by numba.

The interface is an (Lx, Ly) periodic grid of blocks (mass m) on the bottom face of a quasi-static
elastic body; the body's force on the blocks is ``-IFFT[a**2 k(q) FFT(x - v_d t)]``
(:func:`slipchain.model.elastic.elastic_force`, k from :mod:`slipchain.model.elastic`), with the
radiation damping ``-m gamma (u - v_d)``, ``gamma = c_s/a`` (G/c_s per area, relative to the
slider's body moving with the drive). Equation of motion of block i::

    m du_i/dt = F_el,i - m gamma (u_i - v_d) - f(u_i, v*_i) [if i carries a contact]

Step n -> n+1 (the chain's scheme, :mod:`slipchain.engine.scheme`, with the elastic force in
place of the springs):

1. F_el from x^n: one batched ``rfft2``/``irfft2`` pair for all rows (scipy.fft), the drive's
   uniform displacement added to the q = 0 mode alone (a**2 k(0) v_d t on every block);
2. u^{n+1} = u^n + dt/m (F_el - m gamma (u^n - v_d)) for every block (numba, :func:`_step`);
3. contact blocks: the chain's implicit contact solve (:func:`.cpu._contacts`);
4. x^{n+1} = x^n + dt u^{n+1}; the works: drive a**2 k(0) (N v_d t - sum x^n) v_d dt (the uniform
   mode of the elastic force is what the drive transmits), damping, contacts.

The drive force per block, f_d = a**2 k(0) (v_d t - <x>), is what mu_star averages. Explicit, so
``Config`` requires dt below the stable step of the modes, h**2 omega**2 + 2 h gamma < 4
(:mod:`slipchain.model.stability`).

**Dead weight** (issue 26): the top is a rigid plate, carried by the applied force F_b per block
instead of the drive springs, with the slab's mass N_L m per block (the chain's upper layer under
the dead weight; ``X``, ``U`` of every block hold the plate's displacement and velocity, so that
the slider's position <X> is read as in the chain). The body's force on the blocks is then
``-IFFT[a**2 k_c(q) FFT(x - X)]`` with k_c the kernel of the clamped top (the plate moves
uniformly: every q != 0 mode sees the top held), the radiation damping is relative to the plate,
``-m gamma (u_i - U)``, and the plate moves by the reactions::

    N_L m dU/dt = F_b - <F_el> + m gamma (<u> - U)

**Adaptive step** (integrator = 'adaptive', :func:`_adaptive_step`): the chain's controller of
:mod:`.adaptive` per row (levels h = dt 2**k on the fixed step's time grid, the error estimate
from consecutive accelerations, rejection and restore); rows advance in lock-step one accepted
step per FFT, a rejected step is retried at once (the positions, hence the elastic force, have
not moved).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..scheme import (FASTMATH, A_WCONTACT, A_WDAMP, A_WDRIVE, N_ACC, N_CACC, N_OUT, N_YS_STATE, O_FD, O_XMEAN, O_XUMEAN,
                      P_AMP, P_C, P_ETAC, P_FOLD, P_KD, P_ML)
from .adaptive import (STEP_UP, _copy_solver_state, _error, _grid_level, _keep_acceleration, _load_folds,
                       _rejected_level, _weighted_contact_sums)
from .base import Batch, ChunkOutput
from .cpu import _contact_sums, _contacts, _refresh_solver, row_parameters


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _step(F, x, u, step, params, k0, sites, vstar, n_contacts, ysolve, cacc, acc, fd, status, un, damp, rk, ra, uk,
          fk, ok):
    """Steps 2-4 of the module docstring for every live row, given -IFFT[a**2 k FFT(x)] in F (B, N)
    (the drive, uniform, enters through k(0) = ``k0`` alone)."""
    nb_rows, n = x.shape
    for row in range(nb_rows):
        if status[row] >= 0 or params[row, P_KD] == 0.0:  # the dead-weight rows: _plate_step
            continue
        K, KL, KT, Kd, m, meta, vd, fconst, dt, dtm, dtmL, bc, c, m_eff, slow = row_parameters(params[row])
        xr = x[row]
        ur = u[row]
        Fr = F[row]
        sx = 0.0
        f_drive = k0[row] * vd * (step[row] * dt)  # the uniform mode's share of the drive, a**2 k(0) v_d t
        for i in range(n):
            d = -meta * (ur[i] - vd)
            un[i] = ur[i] + dtm * (Fr[i] + f_drive + d)
            damp[i] = d
            sx += xr[i]
        nc = n_contacts[row]
        _contacts(nc, un, sites[row], rk, ra, uk, fk, ok, vstar[row], ysolve[row], m, m_eff, bc, c, 1.0 / dt,
                  params[row, P_FOLD] > 0.0)
        w_contact = _contact_sums(nc, fk, uk, cacc[row], slow) * dt
        wd = 0.0
        for i in range(n):
            xr[i] += dt * un[i]
            wd += damp[i] * un[i]
            ur[i] = un[i]
        fsum = k0[row] * (n * vd * (step[row] * dt) - sx)
        acc[row, A_WDRIVE] += fsum * vd * dt
        acc[row, A_WDAMP] += wd * dt
        acc[row, A_WCONTACT] -= w_contact
        fd[row] += fsum / n
        step[row] += 1


@nb.njit(cache=True)
def _explicit(Fr, xr, ur, Ur, vd, t, k0, meta, m, mL, fconst, dead, h, un, damp):
    """The explicit part of one step of length h for one row (module docstring): the blocks' new
    velocities (contacts not yet applied) in ``un`` and damping forces in ``damp``; returns the
    plate's new velocity (dead weight; 0 with the spring drive) and the drive force sum (spring)."""
    n = xr.size
    if dead:
        up = Ur[0]
        sf = 0.0
        su = 0.0
        for i in range(n):
            d = -meta * (ur[i] - up)
            un[i] = ur[i] + h / m * (Fr[i] + d)
            damp[i] = d
            sf += Fr[i]
            su += ur[i]
        return up + h / mL * (fconst - sf / n + meta * (su / n - up)), 0.0
    f_drive = k0 * vd * t
    sx = 0.0
    for i in range(n):
        d = -meta * (ur[i] - vd)
        un[i] = ur[i] + h / m * (Fr[i] + f_drive + d)
        damp[i] = d
        sx += xr[i]
    return 0.0, k0 * (n * vd * t - sx)


@nb.njit(cache=True)
def _commit(xr, ur, Xr, Ur, un, damp, Unew, dead, h):
    """Positions from the accepted velocities (blocks, and the plate with the dead weight); returns
    the damping work over the step (the dampers act between block and plate, or block and drive)."""
    wd = 0.0
    for i in range(xr.size):
        xr[i] += h * un[i]
        ur[i] = un[i]
        if dead:
            wd += damp[i] * (un[i] - Unew)
            Xr[i] += h * Unew
            Ur[i] = Unew
        else:
            wd += damp[i] * un[i]
    return wd * h


@nb.njit(cache=True)
def _plate_step(F, x, u, X, U, step, params, sites, vstar, n_contacts, ysolve, cacc, acc, status, un, damp, rk, ra,
                uk, fk, ok):
    """One fixed step (integrator 'fixed' or 'fold') of every live dead-weight row (module docstring)."""
    nb_rows, n = x.shape
    for row in range(nb_rows):
        if status[row] >= 0 or params[row, P_KD] != 0.0:
            continue
        K, KL, KT, Kd, m, meta, vd, fconst, dt, dtm, dtmL, bc, c, m_eff, slow = row_parameters(params[row])
        Unew, _ = _explicit(F[row], x[row], u[row], U[row], vd, 0.0, 0.0, meta, m, params[row, P_ML], fconst, True,
                            dt, un, damp)
        nc = n_contacts[row]
        _contacts(nc, un, sites[row], rk, ra, uk, fk, ok, vstar[row], ysolve[row], m, m_eff, bc, c, 1.0 / dt,
                  params[row, P_FOLD] > 0.0)
        acc[row, A_WCONTACT] -= _weighted_contact_sums(nc, fk, uk, cacc[row], slow, 1.0) * dt
        acc[row, A_WDAMP] += _commit(x[row], u[row], X[row], U[row], un, damp, Unew, True, dt)
        step[row] += 1


@nb.njit(cache=True)
def _adaptive_step(F, x, u, X, U, step, params, k0, sites, vstar, n_contacts, ysolve, folds, control, cacc, acc, fd,
                   status, j, level, loaded, have, aprev, sample_steps, un, Un, damp, rk, ra, uk, fk, ok, ysave):
    """One accepted adaptive step of every live row whose sample is not complete (``j`` base steps
    done of ``sample_steps``): the controller of :func:`.adaptive.advance` per row (module docstring)."""
    nb_rows, n = x.shape
    for row in range(nb_rows):
        if status[row] >= 0 or j[row] >= sample_steps:
            continue
        K, KL, KT, Kd, m, meta, vd, fconst, dt0, _, _, _, c, _, slow = row_parameters(params[row])
        dead = params[row, P_KD] == 0.0
        mL = params[row, P_ML]
        amp = params[row, P_AMP]
        etac = params[row, P_ETAC]
        tol = control[row, 0]
        top = int(control[row, 1])
        nc = n_contacts[row]
        xr, ur, Xr, Ur, ys = x[row], u[row], X[row], U[row], ysolve[row]
        while True:
            lv = _grid_level(level[row], j[row], sample_steps)
            if lv != loaded[row]:
                _load_folds(nc, ys, folds[row, lv])
                loaded[row] = lv
            w = 1 << lv
            h = dt0 * w
            Unew, fsum = _explicit(F[row], xr, ur, Ur, vd, step[row] * dt0, k0[row], meta, m, mL, fconst, dead, h, un,
                                   damp)
            for i in range(n):
                Un[i] = Unew if dead else Ur[i]
            if lv > 0:  # keep the contacts' solver state: the step may be rejected
                _copy_solver_state(nc, ys, ysave)
            _contacts(nc, un, sites[row], rk, ra, uk, fk, ok, vstar[row], ys, m, m * (1.0 + h * etac), h * amp, c,
                      1.0 / h, True)
            err = _error(n, ur, Ur, un, Un, aprev[row], h) if have[row] else 0.0
            if lv > 0 and err > tol:  # rejected: again from the same state (the same elastic force), finer
                _copy_solver_state(nc, ysave, ys)
                level[row] = _rejected_level(lv, err, tol)
                control[row, 3] += 1.0
                continue
            _keep_acceleration(n, ur, Ur, un, Un, aprev[row], h)
            acc[row, A_WCONTACT] -= _weighted_contact_sums(nc, fk, uk, cacc[row], slow, w) * h
            acc[row, A_WDAMP] += _commit(xr, ur, Xr, Ur, un, damp, Unew, dead, h)
            acc[row, A_WDRIVE] += fsum * vd * h
            fd[row] += fsum / n * w
            step[row] += w
            j[row] += w
            control[row, 2] += 1.0
            if have[row] and err < STEP_UP * tol and lv < top:
                lv += 1
            level[row] = lv
            have[row] = True
            break


@nb.njit(cache=True)
def _end_sample(x, X, status, step, fd, out, s, sample_steps, acc):
    """Record sample s (mean f_d, <x> and <X>: the plate with the dead weight, else 0, there being no
    upper layer) and flag rows that went non-finite."""
    nb_rows, n = x.shape
    for row in range(nb_rows):
        if status[row] >= 0:
            continue
        xs = 0.0
        Xs = 0.0
        for i in range(n):
            xs += x[row, i]
            Xs += X[row, i]
        out[row, s, O_FD] += fd[row] / sample_steps
        out[row, s, O_XMEAN] += xs / n
        out[row, s, O_XUMEAN] += Xs / n
        if not (math.isfinite(fd[row]) and math.isfinite(xs) and math.isfinite(acc[row, A_WCONTACT])):
            status[row] = step[row]
        fd[row] = 0.0


def advance(batch: Batch, n_samples: int, sample_steps: int, fft=None) -> ChunkOutput:
    """Advance every live row of a slab/half-space batch by n_samples*sample_steps steps
    (module docstring); ``fft`` the FFT module (scipy.fft by default)."""
    if fft is None:
        import scipy.fft as fft
    b, n = batch.x.shape
    lx, ly = batch.shape
    kern = batch.kernel
    k0 = np.ascontiguousarray(kern[:, 0, 0])
    neg = -kern
    out = np.zeros((b, n_samples, N_OUT))
    acc = np.zeros((b, N_ACC))
    cmax = batch.sites.shape[1]
    cacc = np.zeros((b, N_CACC, cmax))
    fd = np.zeros(b)
    un, damp = np.empty(n), np.empty(n)
    rk, ra, uk, fk = (np.empty(cmax) for _ in range(4))
    ok = np.empty(cmax, dtype=np.bool_)
    dead = bool(np.any(batch.params[:, P_KD] == 0.0))  # dead-weight rows: the body acts on x - X
    grid = batch.x.reshape(b, lx, ly)  # a view: the FFT reads the state in place

    def force():
        spec = fft.rfft2(grid if not dead else (batch.x - batch.X).reshape(b, lx, ly), axes=(1, 2))
        spec *= neg
        return fft.irfft2(spec, s=(lx, ly), axes=(1, 2), overwrite_x=True).reshape(b, n)

    adaptive = batch.folds is not None
    if adaptive:
        aprev = np.zeros((b, 2 * n))
        Un = np.empty(n)
        ysave = np.empty((N_YS_STATE, cmax))
    for s in range(n_samples):
        for row in np.flatnonzero(batch.status < 0):  # exact 10**y, exp(-c y^2) at every sample, as the chain's
            _refresh_solver(batch.n_contacts[row], batch.ysolve[row], batch.params[row, P_C])
        if adaptive:  # every sample starts at level 0 with no estimate (checkpoints resume bit for bit)
            j = np.zeros(b, dtype=np.int64)
            level = np.zeros(b, dtype=np.int64)
            loaded = np.full(b, -1, dtype=np.int64)
            have = np.zeros(b, dtype=np.bool_)
            while np.any((batch.status < 0) & (j < sample_steps)):
                _adaptive_step(force(), batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, k0, batch.sites,
                               batch.vstar, batch.n_contacts, batch.ysolve, batch.folds, batch.step_control, cacc, acc,
                               fd, batch.status, j, level, loaded, have, aprev, sample_steps, un, Un, damp, rk, ra, uk,
                               fk, ok, ysave)
        else:
            for _ in range(sample_steps):
                F = force()
                _step(F, batch.x, batch.u, batch.step, batch.params, k0, batch.sites, batch.vstar,
                      batch.n_contacts, batch.ysolve, cacc, acc, fd, batch.status, un, damp, rk, ra, uk, fk, ok)
                if dead:
                    _plate_step(F, batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites,
                                batch.vstar, batch.n_contacts, batch.ysolve, cacc, acc, batch.status, un, damp, rk, ra,
                                uk, fk, ok)
        _end_sample(batch.x, batch.X, batch.status, batch.step, fd, out, s, sample_steps, acc)
    return ChunkOutput(out, acc, cacc)


__all__ = ["advance"]

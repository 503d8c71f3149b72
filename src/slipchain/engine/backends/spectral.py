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
``Config`` requires dt*omega_max < 1.8 with omega_max**2 = a**2 max k / m.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..scheme import FASTMATH, A_WCONTACT, A_WDAMP, A_WDRIVE, N_ACC, N_CACC, N_OUT, O_FD, O_XMEAN, P_C, P_FOLD
from .base import Batch, ChunkOutput
from .cpu import _contact_sums, _contacts, _refresh_solver, row_parameters


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _step(F, x, u, step, params, k0, sites, vstar, n_contacts, ysolve, cacc, acc, fd, status, un, damp, rk, ra, uk,
          fk, ok):
    """Steps 2-4 of the module docstring for every live row, given -IFFT[a**2 k FFT(x)] in F (B, N)
    (the drive, uniform, enters through k(0) = ``k0`` alone)."""
    nb_rows, n = x.shape
    for row in range(nb_rows):
        if status[row] >= 0:
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
def _end_sample(x, status, step, fd, out, s, sample_steps, acc):
    """Record sample s (mean f_d and <x>; the upper layer's <X> stays 0: there is none) and flag
    rows that went non-finite."""
    nb_rows, n = x.shape
    for row in range(nb_rows):
        if status[row] >= 0:
            continue
        xs = 0.0
        for i in range(n):
            xs += x[row, i]
        out[row, s, O_FD] += fd[row] / sample_steps
        out[row, s, O_XMEAN] += xs / n
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
    grid = batch.x.reshape(b, lx, ly)  # a view: the FFT reads the state in place
    for s in range(n_samples):
        for row in np.flatnonzero(batch.status < 0):  # exact 10**y, exp(-c y^2) at every sample, as the chain's
            _refresh_solver(batch.n_contacts[row], batch.ysolve[row], batch.params[row, P_C])
        for _ in range(sample_steps):
            spec = fft.rfft2(grid, axes=(1, 2))
            spec *= neg
            F = fft.irfft2(spec, s=(lx, ly), axes=(1, 2), overwrite_x=True)
            _step(F.reshape(b, n), batch.x, batch.u, batch.step, batch.params, k0, batch.sites, batch.vstar,
                  batch.n_contacts, batch.ysolve, cacc, acc, fd, batch.status, un, damp, rk, ra, uk, fk, ok)
        _end_sample(batch.x, batch.status, batch.step, fd, out, s, sample_steps, acc)
    return ChunkOutput(out, acc, cacc)


__all__ = ["advance"]

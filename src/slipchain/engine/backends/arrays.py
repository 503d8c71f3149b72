"""The slab and half-space written once in array operations, for NumPy on the CPU and CuPy on a GPU
(issue 13).

The same step as :mod:`.spectral` (its docstring has the equations), with every loop replaced by
whole-array operations of an array namespace ``xp`` and its FFT module: NumPy with scipy.fft (a
second, independent implementation of the CPU path, which tests compare with the numba loop), or
CuPy with cupyx.scipy.fft (cuFFT, with CuPy's plan cache) where a GPU is lent. All realisations
of a batch advance together: one batched FFT pair per step for every row.

The contact solve is the scheme's equation ``m_eff u + b exp(-c y**2) sign(u) = r``,
``y = log10(|u|/v*)``, by safeguarded Newton on the bracket of
:func:`slipchain.engine.scheme.solve_contact_bracketed`, vectorised over all contacts, from the
previous step's y, iterated until every contact's step or bracket is below ``Y_TOL`` decades. The
numba path accepts a Newton step below 1e-5 decades (an error below 3e-10 decades), so the two
paths agree to about 1e-9 per step, not bit for bit; the root is unique (dt below the
unique-root limit, checked by ``Config``).
"""

from __future__ import annotations

import math

import numpy as np

from ..scheme import (A_WCONTACT, C_F, C_SLOW, C_U, C_U2, N_ACC, N_CACC, N_OUT, O_FD, O_XMEAN,
                      P_AMP, P_C, P_DT, P_ETAC, P_M, P_META, P_SLOW, P_VD, Y_LOG)
from .base import Batch, ChunkOutput, gpu_refusal

Y_TOL = 1e-13  # decades: the bracketed solver's own stopping rule
MAX_ITER = 200
LN10 = math.log(10.0)
LOG10_2 = math.log10(2.0)


def solve_contacts(xp, r, m_eff, b, c, vstar, y):
    """u solving m_eff u + b exp(-c y**2) sign(u) = r for arrays (rows broadcast against contacts),
    from the warm start y; returns (u, y). c = 0 (Coulomb) sticks below |r| = b."""
    ra = xp.abs(r)
    s = xp.where(r > 0, 1.0, -1.0)
    tiny = ra < 1e-300
    ra_safe = xp.where(tiny, 1.0, ra)
    a = m_eff * vstar
    coulomb = c == 0.0
    c_safe = xp.where(coulomb, 1.0, c)
    y_hi = xp.log10(ra_safe / a)
    lg = xp.log(2.0 * b / ra_safe)
    y_lo = xp.minimum(y_hi - LOG10_2, xp.where(lg > 0, -xp.sqrt(xp.maximum(lg, 0.0) / c_safe), y_hi - LOG10_2))
    y = xp.where((y > y_lo) & (y < y_hi), y, 0.5 * (y_lo + y_hi))
    for _ in range(MAX_ITER):
        p = xp.exp(LN10 * y)
        q = xp.exp(-c_safe * y * y)
        h = a * p + b * q - ra_safe
        dh = LN10 * a * p - 2.0 * c_safe * y * b * q
        y_hi = xp.where(h > 0, y, y_hi)
        y_lo = xp.where(h > 0, y_lo, y)
        newton = y - h / xp.where(dh > 0, dh, 1.0)
        y_new = xp.where((dh > 0) & (newton > y_lo) & (newton < y_hi), newton, 0.5 * (y_lo + y_hi))
        done = (xp.abs(y_new - y) < Y_TOL) | (y_hi - y_lo < Y_TOL)
        y = y_new
        if bool(xp.all(done)):
            break
    u = s * vstar * xp.exp(LN10 * y)
    if bool(xp.any(coulomb)):
        w = xp.maximum(ra - b, 0.0) / (m_eff * vstar)
        u = xp.where(coulomb, s * w * vstar, u)
        y = xp.where(coulomb & (w > 0), xp.log10(xp.where(w > 0, w, 1.0)), y)
    return xp.where(tiny, 0.0, u), y


class ArrayBackend:
    """``advance(batch, n_samples, sample_steps)`` for the slab and half-space in array operations
    of ``xp`` (NumPy or CuPy) with the FFT module ``fft`` (scipy.fft or cupyx.scipy.fft)."""

    def __init__(self, xp=np, fft=None, name: str = "arrays"):
        if fft is None:
            import scipy.fft as fft
        self.xp, self.fft, self.name = xp, fft, name

    def advance(self, batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
        if batch.kernel is None:
            raise ValueError(f"geometry = '{batch.geometry}' has no elastic kernel: the array backend runs 'slab' "
                             "and 'halfspace' only")
        why = gpu_refusal(batch)  # the capability table's GPU column is this code's
        if why is not None:
            raise ValueError(f"{why} (backend='cpu')")
        xp, fft = self.xp, self.fft
        b, n = batch.x.shape
        lx, ly = batch.shape
        dev = xp.asarray
        x, u = dev(batch.x), dev(batch.u)
        step = dev(batch.step)
        pr = dev(batch.params)
        col = lambda k: pr[:, k][:, None]  # noqa: E731  (B, 1) parameter columns
        m, dt, vd, meta = col(P_M), col(P_DT), col(P_VD), col(P_META)
        bc, c, slow = dt * col(P_AMP), col(P_C), col(P_SLOW)
        m_eff = m * (1.0 + dt * col(P_ETAC))
        neg = -dev(batch.kernel)
        k0 = dev(batch.kernel[:, 0, 0])[:, None]
        cmax = batch.sites.shape[1]
        valid = dev(np.arange(cmax)[None, :] < batch.n_contacts[:, None])
        flat = dev(batch.sites + np.arange(b)[:, None] * n)  # contact -> index into x.ravel()
        vstar = dev(batch.vstar)
        y = dev(batch.ysolve[:, Y_LOG, :])
        live = dev(batch.status < 0)[:, None]
        status = dev(batch.status)
        out = xp.zeros((b, n_samples, N_OUT))
        acc = xp.zeros((b, N_ACC))
        cacc = xp.zeros((b, N_CACC, cmax))
        for s in range(n_samples):
            fd = xp.zeros((b, 1))
            for _ in range(sample_steps):
                spec = fft.rfft2(x.reshape(b, lx, ly), axes=(1, 2))
                spec *= neg
                F = fft.irfft2(spec, s=(lx, ly), axes=(1, 2)).reshape(b, n)
                t = step[:, None] * dt
                damp = -meta * (u - vd)
                un = u + (dt / m) * (F + k0 * vd * t + damp)
                sx = xp.sum(x, axis=1, keepdims=True)
                r = m * un.reshape(-1)[flat]
                uk, y_new = solve_contacts(xp, r, m_eff, bc, c, vstar, y)
                y = xp.where(valid, y_new, y)
                uk = xp.where(valid, uk, 0.0)
                fk = xp.where(valid, (r - m * uk) / dt, 0.0)
                unf = un.reshape(-1)
                unf[flat[valid]] = uk[valid]
                un = unf.reshape(b, n)
                gate = live & (status[:, None] < 0)
                cacc[:, C_F] += xp.where(gate, fk, 0.0)
                cacc[:, C_U] += xp.where(gate, uk, 0.0)
                cacc[:, C_U2] += xp.where(gate, uk * uk, 0.0)
                cacc[:, C_SLOW] += xp.where(gate & valid & (xp.abs(uk) < slow), 1.0, 0.0)
                fsum = k0 * (n * vd * t - sx)
                work = xp.concatenate([fsum * vd * dt, xp.sum(damp * un, axis=1, keepdims=True) * dt,
                                       -xp.sum(fk * uk, axis=1, keepdims=True) * dt,
                                       xp.zeros((b, N_ACC - 3))], axis=1)  # (elastic only: no bulk work)
                acc += xp.where(gate, work, 0.0)
                fd += xp.where(gate, fsum / n, 0.0)
                x = xp.where(gate, x + dt * un, x)
                u = xp.where(gate, un, u)
                step = step + gate[:, 0].astype(step.dtype)
            gate = (live & (status[:, None] < 0))[:, 0]
            xs = xp.sum(x, axis=1)
            out[:, s, O_FD] += xp.where(gate, fd[:, 0] / sample_steps, 0.0)
            out[:, s, O_XMEAN] += xp.where(gate, xs / n, 0.0)
            bad = gate & ~(xp.isfinite(fd[:, 0]) & xp.isfinite(xs) & xp.isfinite(acc[:, A_WCONTACT]))
            status = xp.where(bad, step, status)
        host = (lambda a: a.get()) if hasattr(x, "get") else np.asarray
        batch.x[...], batch.u[...], batch.step[...], batch.status[...] = host(x), host(u), host(step), host(status)
        batch.ysolve[:, Y_LOG, :] = host(y)
        return ChunkOutput(host(out), host(acc), host(cacc))


def cupy_backend() -> ArrayBackend:
    """The array backend on a GPU: CuPy and cuFFT (``pip install slipchain[gpu-fft]``); ImportError
    with what to install where CuPy is missing."""
    try:
        import cupy
        import cupyx.scipy.fft as cufft
    except ImportError as err:
        raise ImportError(f"the slab and half-space on a GPU need CuPy ({err}); install the extra: "
                          "pip install 'slipchain[gpu-fft]'") from None
    return ArrayBackend(cupy, cufft, name="gpu-cupy")


__all__ = ["ArrayBackend", "cupy_backend", "solve_contacts"]

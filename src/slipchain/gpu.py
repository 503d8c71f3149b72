"""GPU backend (numba.cuda): a batch of realisations in one launch, the time loop inside the kernel.

One CUDA thread block per realisation (row of the batch); its threads share the chain's blocks
(thread t owns blocks t, t + T, t + 2T, ...) and its contacts (likewise). One time step is the
CPU scheme of :mod:`slipchain.kernel`, separated by block-wide barriers:

1. explicit velocity update of every owned block (springs, drive or dead weight, damping);
2. barrier; each owned contact solves its implicit equation ``m_eff*u + dt*f(u) = r`` (the
   same safeguarded Newton solver as the CPU fallback, :func:`slipchain.kernel.solve_contact_bracketed`,
   compiled as a device function, converged to 1e-13 decades);
3. barrier; positions; barrier.

Per-sample outputs (mean f_d, mean x, mean X) are reduced across the block in shared memory
once per sample; work and per-contact sums stay in registers/global memory. No per-step launch
or host round trip: the host copies the batch in and out once per call of :meth:`GPUBackend.advance`
(a chunk of 0.5 ms of simulated time in :func:`slipchain.simulation.simulate`).

Why numba.cuda and not CuPy raw kernels: the solver and the scheme are already numba-compiled
Python; numba.cuda compiles the same function for the device (no second implementation of the
contact solver in CUDA C), and its simulator (``NUMBA_ENABLE_CUDASIM=1``) runs the kernel on
the CPU, so CI tests it without a GPU. Importing this module never needs CUDA: the kernel is
compiled on first launch.
"""

from __future__ import annotations

import math

import numpy as np
from numba import cuda, float64  # imports without a GPU; kernels compile on first launch

from . import kernel as K

THREADS_MAX = 128  # threads per block (shared-memory reduction size); fewer for small chains


def cuda_available() -> bool:
    """True when numba.cuda finds a GPU (or its simulator is enabled)."""
    try:
        return bool(cuda.is_available())
    except Exception:  # pragma: no cover - numba without its CUDA target
        return False


_bracketed = cuda.jit(device=True)(K.solve_contact_bracketed.py_func)
LN10 = K.LN10


@cuda.jit(device=True)
def _solve(r, m_eff, b, c, vstar, y):
    ra = abs(r)
    if ra < 1e-300:
        return 0.0, y
    s = 1.0 if r > 0.0 else -1.0
    if c == 0.0:
        if ra <= b:
            return 0.0, y
        w = (ra - b) / (m_eff * vstar)
        return s * w * vstar, math.log10(w)
    y = _bracketed(ra, m_eff * vstar, b, c, y)
    return s * vstar * math.exp(LN10 * y), y


@cuda.jit(device=True)
def _block_sum(buf, value, tid, nthreads):
    buf[tid] = value
    cuda.syncthreads()
    stride = 1
    while stride < nthreads:
        if tid % (2 * stride) == 0 and tid + stride < nthreads:
            buf[tid] += buf[tid + stride]
        cuda.syncthreads()
        stride *= 2
    total = buf[0]
    cuda.syncthreads()
    return total


@cuda.jit
def advance_kernel(x, u, X, U, step, params, sites, vstar, n_contacts, ylog, n_samples, sample_steps,
            out, acc, cacc, status, un, Un, dampx, dampX):
    row = cuda.blockIdx.x
    tid = cuda.threadIdx.x
    nthreads = cuda.blockDim.x
    buf = cuda.shared.array(THREADS_MAX, float64)
    n = x.shape[1]
    if status[row] >= 0:
        return
    Kk = params[row, K.P_K]
    KL = params[row, K.P_KL]
    KT = params[row, K.P_KT]
    Kd = params[row, K.P_KD]
    m = params[row, K.P_M]
    meta = params[row, K.P_META]
    vd = params[row, K.P_VD]
    fconst = params[row, K.P_FCONST]
    dt = params[row, K.P_DT]
    dtm = dt / m
    dtmL = dt / params[row, K.P_ML]
    bc = dt * params[row, K.P_AMP]
    c = params[row, K.P_C]
    m_eff = m * (1.0 + dt * params[row, K.P_ETAC])
    slow = params[row, K.P_SLOW]
    nc = n_contacts[row]
    step0 = step[row]
    w_drive = 0.0
    w_damp = 0.0
    w_contact = 0.0
    bad = 0
    for s in range(n_samples):
        fd_local = 0.0
        for j in range(sample_steps):
            drive = vd * ((step0 + s * sample_steps + j) * dt)
            fsum_local = 0.0
            i = tid
            while i < n:
                ip = i + 1 if i + 1 < n else 0
                im = i - 1 if i > 0 else n - 1
                dx = meta * (u[row, ip] + u[row, im] + U[row, i] - 3.0 * u[row, i])
                dX = meta * (U[row, ip] + U[row, im] + u[row, i] - 3.0 * U[row, i])
                fx = Kk * (x[row, ip] + x[row, im] - 2.0 * x[row, i]) + KT * (X[row, i] - x[row, i]) + dx
                fX = (KL * (X[row, ip] + X[row, im] - 2.0 * X[row, i]) + KT * (x[row, i] - X[row, i])
                      + Kd * (drive - X[row, i]) + fconst + dX)
                un[row, i] = u[row, i] + dtm * fx
                Un[row, i] = U[row, i] + dtmL * fX
                dampx[row, i] = dx
                dampX[row, i] = dX
                fsum_local += Kd * (drive - X[row, i])
                i += nthreads
            cuda.syncthreads()
            k = tid
            while k < nc:
                site = sites[row, k]
                r = m * un[row, site]
                uk, yk = _solve(r, m_eff, bc, c, vstar[row, k], ylog[row, k])
                ylog[row, k] = yk
                fk = (r - m * uk) / dt
                un[row, site] = uk
                cacc[row, K.C_F, k] += fk
                cacc[row, K.C_U, k] += uk
                cacc[row, K.C_U2, k] += uk * uk
                if abs(uk) < slow:
                    cacc[row, K.C_SLOW, k] += 1.0
                w_contact -= fk * uk * dt
                k += nthreads
            cuda.syncthreads()
            i = tid
            while i < n:
                x[row, i] += dt * un[row, i]
                X[row, i] += dt * Un[row, i]
                w_damp += (dampx[row, i] * un[row, i] + dampX[row, i] * Un[row, i]) * dt
                u[row, i] = un[row, i]
                U[row, i] = Un[row, i]
                i += nthreads
            w_drive += fsum_local * vd * dt
            fd_local += fsum_local / n
            cuda.syncthreads()
        xs_local = 0.0
        Xs_local = 0.0
        i = tid
        while i < n:
            xs_local += x[row, i]
            Xs_local += X[row, i]
            i += nthreads
        fd = _block_sum(buf, fd_local, tid, nthreads)
        xs = _block_sum(buf, xs_local, tid, nthreads)
        Xs = _block_sum(buf, Xs_local, tid, nthreads)
        wc = _block_sum(buf, w_contact, tid, nthreads)
        if tid == 0:
            out[row, s, K.O_FD] += fd / sample_steps
            out[row, s, K.O_XMEAN] += xs / n
            out[row, s, K.O_XUMEAN] += Xs / n
        if not (math.isfinite(fd) and math.isfinite(xs) and math.isfinite(wc)):
            bad = 1
            if tid == 0:
                status[row] = step0 + (s + 1) * sample_steps
            break
    wd = _block_sum(buf, w_drive, tid, nthreads)
    wdamp = _block_sum(buf, w_damp, tid, nthreads)
    wc = _block_sum(buf, w_contact, tid, nthreads)
    if tid == 0:
        acc[row, K.A_WDRIVE] += wd
        acc[row, K.A_WDAMP] += wdamp
        acc[row, K.A_WCONTACT] += wc
        step[row] = status[row] if bad else step0 + n_samples * sample_steps


class GPUBackend:
    """Same interface as :class:`slipchain.backend.CPUBackend`: ``advance(batch, n_samples, sample_steps)``."""

    name = "gpu"

    def __init__(self, threads: int | None = None):
        if not cuda_available():
            raise RuntimeError("backend 'gpu' needs a CUDA GPU (numba.cuda found none); use backend = 'cpu' or 'auto'")
        self.threads = threads

    def advance(self, batch, n_samples: int, sample_steps: int):
        from .backend import ChunkOutput

        kernel = advance_kernel
        b, n = batch.x.shape
        cmax = batch.sites.shape[1]
        threads = self.threads or min(THREADS_MAX, max(1, n))
        out = np.zeros((b, n_samples, K.N_OUT))
        acc = np.zeros((b, K.N_ACC))
        cacc = np.zeros((b, K.N_CACC, cmax))
        ylog = np.ascontiguousarray(batch.ysolve[:, K.Y_LOG, :])
        d = {k: cuda.to_device(np.ascontiguousarray(v)) for k, v in dict(
            x=batch.x, u=batch.u, X=batch.X, U=batch.U, step=batch.step, params=batch.params, sites=batch.sites,
            vstar=batch.vstar, n_contacts=batch.n_contacts, ylog=ylog, out=out, acc=acc, cacc=cacc,
            status=batch.status).items()}
        scratch = [cuda.device_array((b, n)) for _ in range(4)]
        kernel[b, threads](d["x"], d["u"], d["X"], d["U"], d["step"], d["params"], d["sites"], d["vstar"],
                           d["n_contacts"], d["ylog"], n_samples, sample_steps, d["out"], d["acc"], d["cacc"],
                           d["status"], *scratch)
        for name in ("x", "u", "X", "U", "step", "status"):
            getattr(batch, name)[...] = d[name].copy_to_host()
        batch.ysolve[:, K.Y_LOG, :] = d["ylog"].copy_to_host()
        return ChunkOutput(d["out"].copy_to_host(), d["acc"].copy_to_host(), d["cacc"].copy_to_host())


__all__ = ["GPUBackend", "THREADS_MAX", "cuda_available"]

"""The CUDA backend (numba.cuda): a batch of realisations in one launch, the time loop inside the kernel.

One CUDA thread block per realisation (row of the batch); its threads share the chain's blocks
(thread t owns blocks t, t + T, t + 2T, ...) and its contacts (likewise). One time step is the
scheme of :mod:`slipchain.engine.scheme`, the same source the CPU backend compiles, here compiled
as device functions, separated by block-wide barriers:

1. explicit velocity update of every owned block (:func:`~slipchain.engine.scheme.block_update`);
2. barrier; each owned contact solves its implicit equation ``m_eff*u + dt*f(u) = r``
   (:func:`~slipchain.engine.scheme.solve_contact`: warm-started Newton in y = log10(|u|/v*),
   bracketed fallback), with 10**y and exp(-c y^2) recomputed exactly at every sample as on the CPU;
3. barrier; positions; barrier.

While they fit in a block's 48 KB of shared memory (N <= 736 at 256 threads), a row's state and
scratch arrays live in shared memory for the whole chunk (copied in and out once per launch): a
step's barriers then wait on shared-memory traffic instead of global-memory round trips. Larger
chains keep them in global memory (same device function, other array arguments).
Per-sample outputs (mean f_d, mean x, mean X) are reduced across the block in shared memory
once per sample; work and per-contact sums stay in registers/global memory. No per-step launch
or host round trip: the host copies the batch in and out once per call of :meth:`CUDABackend.advance`
(a chunk of 0.5 ms of simulated time in :func:`slipchain.engine.simulate.simulate`). With
``keep_buffers=True`` the device arrays and the CUDA stream are allocated on a batch's first chunk
and kept with the batch (no device allocation or free between chunks, which could synchronise
concurrent batches); off by default until measured on a GPU (`bench_gpu.py --concurrent`).

Why numba.cuda and not CuPy raw kernels: the scheme is numba-compiled Python already; numba.cuda
compiles the same functions for the device (no second implementation in CUDA C), and its
simulator (``NUMBA_ENABLE_CUDASIM=1``) runs the kernel on the CPU, so CI tests it without a GPU.
Importing this module never needs CUDA: the kernel is compiled on first launch.
"""

from __future__ import annotations

import functools
import math
import threading

import numpy as np
from numba import cuda, float64  # imports without a GPU; kernels compile on first launch

from .. import scheme as S
from .base import Batch, ChunkOutput, gpu_refusal

SHARED_ARRAYS = 8  # x, u, X, U and the scratch un, Un, dampx, dampX of a row, in shared memory when they fit
SHARED_BYTES = 48 * 1024  # shared memory a block may use without opting in to more
THREADS_MAX = 256  # threads per block (shared-memory reduction size); fewer for small chains. Measured on an
# H100 (benchmarks/bench_gpu.py --threads): a step's latency falls with more threads per chain
# (fewer blocks of the chain per thread), 32 -> 128 threads: 15.0 -> 5.1 us per step at N = 301


# numba-cuda initialises the driver lazily and not thread-safely: two threads of one process
# (the sweep's GPU worker) initialising it at once fail with CUDA_ERROR_NOT_INITIALIZED
# (seen on an H100 with numba-cuda 0.30.4). Initialisation and each thread's first context
# activation happen under this lock.
_INIT_LOCK = threading.Lock()


def cuda_available() -> bool:
    """True when numba.cuda finds a GPU (or its simulator is enabled)."""
    try:
        with _INIT_LOCK:
            return bool(cuda.is_available())
    except Exception:  # pragma: no cover - numba without its CUDA target
        return False


@functools.cache
def _sm_count() -> int:
    """Multiprocessors of the current GPU (the simulator has no such notion: unlimited); asked once."""
    try:
        with _INIT_LOCK:
            return int(cuda.get_current_device().MULTIPROCESSOR_COUNT)
    except AttributeError:  # numba's CUDA simulator
        return 1 << 30


_scheme = S.compile_for(lambda name, inline: cuda.jit(device=True))
solve_contact = _scheme.solve_contact
block_update = _scheme.block_update
row_parameters = _scheme.row_parameters
LN10 = S.LN10
O_FD, O_XMEAN, O_XUMEAN = S.O_FD, S.O_XMEAN, S.O_XUMEAN
A_WDRIVE, A_WDAMP, A_WCONTACT = S.A_WDRIVE, S.A_WDAMP, S.A_WCONTACT
C_F, C_U, C_U2, C_SLOW = S.C_F, S.C_U, S.C_U2, S.C_SLOW
Y_LOG, Y_P, Y_Q = S.Y_LOG, S.Y_P, S.Y_Q


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


@cuda.jit(device=True)
def _advance_row(xr, ur, Xr, Ur, unr, Unr, dxr, dXr, buf, p, st, vs, nc, ys, ca, outr, n_samples, sample_steps,
                 step0, tid, nthreads):
    """One row's time loop (the scheme, steps 1-4, with barriers) on 1-d state arrays that live in
    shared or in global memory. Returns (first non-finite step or -1, W_drive, W_damping,
    W_contacts), block-reduced."""
    n = xr.shape[0]
    K, KL, KT, Kd, m, meta, vd, fconst, dt, dtm, dtmL, bc, c, m_eff, slow = row_parameters(p)
    w_drive = 0.0
    w_damp = 0.0
    w_contact = 0.0
    bad = -1
    for s in range(n_samples):
        k = tid
        while k < nc:  # exact 10**y and exp(-c y^2) at every sample, as on the CPU
            ys[Y_P, k] = math.exp(LN10 * ys[Y_LOG, k])
            ys[Y_Q, k] = math.exp(-c * ys[Y_LOG, k] * ys[Y_LOG, k])
            k += nthreads
        fd_local = 0.0
        for j in range(sample_steps):
            drive = vd * ((step0 + s * sample_steps + j) * dt)
            fsum_local = 0.0
            i = tid
            while i < n:
                ip = i + 1 if i + 1 < n else 0
                im = i - 1 if i > 0 else n - 1
                block_update(i, ip, im, xr, ur, Xr, Ur, unr, Unr, dxr, dXr, K, KL, KT, Kd, meta, drive, fconst, dtm, dtmL)
                fsum_local += Kd * (drive - Xr[i])
                i += nthreads
            cuda.syncthreads()
            k = tid
            while k < nc:
                site = st[k]
                r = m * unr[site]
                uk, ys[Y_LOG, k], ys[Y_P, k], ys[Y_Q, k] = solve_contact(r, m_eff, bc, c, vs[k], ys[Y_LOG, k],
                                                                         ys[Y_P, k], ys[Y_Q, k])
                fk = (r - m * uk) / dt
                unr[site] = uk
                ca[C_F, k] += fk
                ca[C_U, k] += uk
                ca[C_U2, k] += uk * uk
                if abs(uk) < slow:
                    ca[C_SLOW, k] += 1.0
                w_contact -= fk * uk * dt
                k += nthreads
            cuda.syncthreads()
            i = tid
            while i < n:
                xr[i] += dt * unr[i]
                Xr[i] += dt * Unr[i]
                w_damp += (dxr[i] * unr[i] + dXr[i] * Unr[i]) * dt
                ur[i] = unr[i]
                Ur[i] = Unr[i]
                i += nthreads
            w_drive += fsum_local * vd * dt
            fd_local += fsum_local / n
            cuda.syncthreads()
        xs_local = 0.0
        Xs_local = 0.0
        i = tid
        while i < n:
            xs_local += xr[i]
            Xs_local += Xr[i]
            i += nthreads
        fd = _block_sum(buf, fd_local, tid, nthreads)
        xs = _block_sum(buf, xs_local, tid, nthreads)
        Xs = _block_sum(buf, Xs_local, tid, nthreads)
        wc = _block_sum(buf, w_contact, tid, nthreads)
        if tid == 0:
            outr[s, O_FD] += fd / sample_steps
            outr[s, O_XMEAN] += xs / n
            outr[s, O_XUMEAN] += Xs / n
        if not (math.isfinite(fd) and math.isfinite(xs) and math.isfinite(wc)):
            bad = step0 + (s + 1) * sample_steps
            break
    return (bad, _block_sum(buf, w_drive, tid, nthreads), _block_sum(buf, w_damp, tid, nthreads),
            _block_sum(buf, w_contact, tid, nthreads))


@cuda.jit
def advance_kernel(x, u, X, U, step, params, sites, vstar, n_contacts, ysolve, n_samples, sample_steps,
                   out, acc, cacc, status, un, Un, dampx, dampX, in_shared):
    """Advance row blockIdx.x of the batch. With ``in_shared`` = 1 the row's eight state and scratch
    arrays are copied into dynamic shared memory for the chunk (launch with SHARED_ARRAYS*N +
    threads doubles of it); else they stay in global memory and only the reduction buffer is shared."""
    row = cuda.blockIdx.x
    tid = cuda.threadIdx.x
    nthreads = cuda.blockDim.x
    if status[row] >= 0:
        return
    sh = cuda.shared.array(0, float64)
    n = x.shape[1]
    step0 = step[row]
    if in_shared:
        i = tid
        while i < n:
            sh[i] = x[row, i]
            sh[n + i] = u[row, i]
            sh[2 * n + i] = X[row, i]
            sh[3 * n + i] = U[row, i]
            i += nthreads
        cuda.syncthreads()
        bad, wd, wdamp, wc = _advance_row(sh[0:n], sh[n:2 * n], sh[2 * n:3 * n], sh[3 * n:4 * n], sh[4 * n:5 * n],
                                          sh[5 * n:6 * n], sh[6 * n:7 * n], sh[7 * n:8 * n],
                                          sh[SHARED_ARRAYS * n:SHARED_ARRAYS * n + nthreads], params[row], sites[row],
                                          vstar[row], n_contacts[row], ysolve[row], cacc[row], out[row], n_samples,
                                          sample_steps, step0, tid, nthreads)
        i = tid
        while i < n:
            x[row, i] = sh[i]
            u[row, i] = sh[n + i]
            X[row, i] = sh[2 * n + i]
            U[row, i] = sh[3 * n + i]
            i += nthreads
    else:
        bad, wd, wdamp, wc = _advance_row(x[row], u[row], X[row], U[row], un[row], Un[row], dampx[row], dampX[row],
                                          sh[0:nthreads], params[row], sites[row], vstar[row], n_contacts[row],
                                          ysolve[row], cacc[row], out[row], n_samples, sample_steps, step0, tid,
                                          nthreads)
    if tid == 0:
        acc[row, A_WDRIVE] += wd
        acc[row, A_WDAMP] += wdamp
        acc[row, A_WCONTACT] += wc
        if bad >= 0:
            status[row] = bad
            step[row] = bad
        else:
            step[row] = step0 + n_samples * sample_steps


class CUDABackend:
    """Same interface as :class:`~slipchain.engine.backends.host.CPUBackend`: ``advance(batch, n_samples, sample_steps)``."""

    name = "gpu"

    def __init__(self, threads: int | None = None, shared: bool = True, keep_buffers: bool = False):
        if not cuda_available():
            raise RuntimeError("backend 'gpu' needs a CUDA GPU (numba.cuda found none); use backend 'cpu' or 'auto'")
        self.threads = threads
        self.shared = shared  # a row's state in shared memory where it fits (N <= 736 at 256 threads)
        # True: a batch's device arrays and stream are kept from chunk to chunk (written to let
        # concurrent batches overlap; not yet measured on a GPU, so off: `bench_gpu.py --concurrent`)
        self.keep_buffers = keep_buffers
        self._arrays = None  # the slab's array backend on CuPy, made on first use

    @staticmethod
    def default_threads(rows: int) -> int:
        """Threads per CUDA block: 256 while every row has a multiprocessor to itself (shortest
        step), else 128 (more blocks resident per multiprocessor). H100, N = 301: 3.9 vs 5.3 us per
        step at 132 rows; 7.8 vs 6.8 us at 256 rows (benchmarks/bench_gpu.py --threads)."""
        return THREADS_MAX if rows <= _sm_count() else 128

    def advance(self, batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
        why = gpu_refusal(batch)
        if why is not None:
            raise ValueError(f"{why} (backend='cpu' or 'auto')")
        if batch.geometry != "chain":
            if self._arrays is None:  # slab, half-space: the array code on CuPy (cuFFT)
                from .arrays import cupy_backend

                self._arrays = cupy_backend()
            return self._arrays.advance(batch, n_samples, sample_steps)
        b, n = batch.x.shape
        threads = self.threads or min(self.default_threads(b), max(1, n))
        in_shared = (SHARED_ARRAYS * n + threads) * 8 <= SHARED_BYTES and self.shared
        shared_bytes = ((SHARED_ARRAYS * n if in_shared else 0) + threads) * 8
        dev = _device_buffers(batch, in_shared) if self.keep_buffers else _DeviceBuffers(batch, in_shared)
        stream, d = dev.stream, dev.arrays
        # The host batch is the truth between calls (the driver changes params and status, observers
        # read the state), so everything is copied in and out; with keep_buffers into device arrays
        # allocated once per batch (see _DeviceBuffers), else into fresh ones.
        for name in _STATE:
            d[name].copy_to_device(np.ascontiguousarray(getattr(batch, name)), stream=stream)
        if dev.zeros["out"].shape[1] != n_samples:  # (the chunk length changes rarely: a row's last chunk, a ramp)
            dev.zeros["out"] = np.zeros((b, n_samples, S.N_OUT))
            d["out"] = cuda.device_array_like(dev.zeros["out"], stream=stream)
        for name in ("out", "acc", "cacc"):  # the kernel adds to these
            d[name].copy_to_device(dev.zeros[name], stream=stream)
        advance_kernel[b, threads, stream, shared_bytes](
            d["x"], d["u"], d["X"], d["U"], d["step"], d["params"], d["sites"], d["vstar"], d["n_contacts"],
            d["ysolve"], n_samples, sample_steps, d["out"], d["acc"], d["cacc"], d["status"], *dev.scratch,
            int(in_shared))
        for name in ("x", "u", "X", "U", "step", "status", "ysolve"):
            d[name].copy_to_host(getattr(batch, name), stream=stream)
        res = [d[k].copy_to_host(stream=stream) for k in ("out", "acc", "cacc")]
        stream.synchronize()
        return ChunkOutput(*res)


_STATE = ("x", "u", "X", "U", "step", "params", "sites", "vstar", "n_contacts", "ysolve", "status")


class _DeviceBuffers:
    """A batch's device arrays and CUDA stream; with ``keep_buffers`` allocated on its first chunk
    and reused for every later one. Why: allocating and freeing device memory per chunk (cuda.to_device, numba's
    deferred cuMemFree) may synchronise the whole device, so batches advanced from several threads
    (the sweep's GPU worker) would wait for each other's kernels instead of overlapping."""

    def __init__(self, batch: Batch, in_shared: bool):
        b, n = batch.x.shape
        with _INIT_LOCK:
            self.stream = cuda.stream()  # (activates this thread's context under the lock)
        self.key = (batch.x.shape, batch.sites.shape, batch.ysolve.shape, in_shared)
        self.arrays = {name: cuda.device_array_like(np.ascontiguousarray(getattr(batch, name)), stream=self.stream)
                       for name in _STATE}
        self.zeros = {"out": np.zeros((b, 0, S.N_OUT)), "acc": np.zeros((b, S.N_ACC)),
                      "cacc": np.zeros((b, S.N_CACC, batch.sites.shape[1]))}
        for name, z in self.zeros.items():
            self.arrays[name] = cuda.device_array_like(z, stream=self.stream)
        self.scratch = [cuda.device_array((1, 1) if in_shared else (b, n), stream=self.stream) for _ in range(4)]


def _device_buffers(batch: Batch, in_shared: bool) -> _DeviceBuffers:
    """The batch's :class:`_DeviceBuffers` (kept on the batch object, so they live and die with it)."""
    dev = batch.__dict__.get("_cuda_buffers")
    if dev is None or dev.key != (batch.x.shape, batch.sites.shape, batch.ysolve.shape, in_shared):
        dev = _DeviceBuffers(batch, in_shared)
        batch.__dict__["_cuda_buffers"] = dev
    return dev


GPUBackend = CUDABackend  # the name used before 0.2

__all__ = ["CUDABackend", "GPUBackend", "SHARED_ARRAYS", "THREADS_MAX", "cuda_available"]

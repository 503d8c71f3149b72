"""A probe, not engine code: what the slab's explicit steps would gain if a whole chunk were one compiled
call, its FFTs inside numba (rocket-fft, which teaches numba numpy.fft; not a dependency of slipchain).

    pip install rocket-fft==0.4.1          # into a scratch environment or the venv, then
    python benchmarks/fft_chunk_probe.py   # about 2 minutes on one core here

Today the slab's and half-space's driver (compose.fft_advance) takes one rfft2/irfft2 pair per explicit
step from Python, then calls the compiled step of every row (24 arguments unboxed per call): on the
tester's 16 x 16 grid most of a step's time is that Python layer (docs/performance.md, "Where the
tester's explicit steps go"). Here the elastic slab's fold step (epsilon = 1e-2, spring drive, steady
start, 2 ms) is advanced twice from the same state: by compose.fft_advance, and by one compiled function
that loops over the samples and steps, calls numpy.fft.rfft2/irfft2 in numba and then the row stepper's
code (the same Python function as the engine's compiled step, jitted again here with the same flags and
no cache, as the engine's loops compile their callees). It prints whether the state and the chunk's
outputs are bit-identical and the cost per step of each, side by side in one process. rocket-fft runs
the same pocketfft/DUCC transforms as scipy.fft (checked here first on the shapes used: bit-identical).
"""

from __future__ import annotations

import copy
import os
import sys
import tempfile
import time

os.environ.setdefault("NUMBA_CACHE_DIR", tempfile.mkdtemp(prefix="slipchain-probe-"))

import numba as nb  # noqa: E402
import numpy as np  # noqa: E402
import scipy.fft  # noqa: E402

try:
    import rocket_fft  # noqa: F401,E402  (registers numpy.fft for numba)
except ImportError:
    print("benchmarks/fft_chunk_probe.py needs rocket-fft (pip install rocket-fft==0.4.1); nothing run", file=sys.stderr)
    sys.exit(2)

from slipchain.engine.backends import Batch, compose, spectral  # noqa: E402
from slipchain.engine.backends.compose import N_CT, _chunk_outputs, _stepper_inputs, scratch_arrays, start_sample  # noqa: E402
from slipchain.model.config import make_config  # noqa: E402
from slipchain.model.system import build_system, initial_state  # noqa: E402

N_SAMPLES = 20


def _chunk(step_rows):
    @nb.njit
    def chunk(x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control, bstate, material, ctl,
              aprev, cacc, acc, fd, sample_steps, status, scratch, neg, k0, out, n_samples, lx, ly):
        b, n = x.shape
        for s in range(n_samples):
            for row in range(b):
                if status[row] < 0:
                    start_sample(row, n_contacts, ysolve, params, ctl)
            for _ in range(sample_steps):
                spec = np.fft.rfft2(x.reshape((b, lx, ly)), axes=(1, 2))
                spec *= neg
                force = np.fft.irfft2(spec, s=(lx, ly), axes=(1, 2)).reshape((b, n))
                step_rows(force, k0, x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control,
                          bstate, material, ctl, aprev, cacc, acc, fd, sample_steps, status, scratch)
            spectral.end_sample(x, X, status, steps, fd, out, s, sample_steps, acc)

    return chunk


def compiled_advance(chunk, batch, sample_steps):
    b, n = batch.x.shape
    lx, ly = batch.shape
    k0, neg = np.ascontiguousarray(batch.kernel[:, 0, 0]), -batch.kernel
    out, acc, cacc = _chunk_outputs(batch, N_SAMPLES)
    _, folds, control = _stepper_inputs(batch)
    chunk(batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites, batch.vstar, batch.n_contacts,
          batch.ysolve, folds, control, batch.bstate, batch.material, np.zeros((b, N_CT), dtype=np.int64),
          np.zeros((b, 2 * n)), cacc, acc, np.zeros(b), sample_steps, batch.status, scratch_arrays(n, batch.sites.shape[1]),
          neg, k0, out, N_SAMPLES, lx, ly)
    return out, acc, cacc


@nb.njit
def _fft_pair(x, s):
    return np.fft.rfft2(x), np.fft.irfft2(np.fft.rfft2(x), s)


def main() -> None:
    rng = np.random.default_rng(0)
    for shape in ((8, 8), (16, 16), (64, 64)):
        x = rng.standard_normal(shape)
        f, i = _fft_pair(x, shape)
        assert np.array_equal(f, scipy.fft.rfft2(x)) and np.array_equal(i, scipy.fft.irfft2(scipy.fft.rfft2(x), s=shape)), shape
    print("rocket-fft's rfft2/irfft2 in numba: bit-identical to scipy.fft on 8x8, 16x16, 64x64")
    for L in (8, 16, 64):
        cfg = make_config(geometry="slab", N=L, Ly=L, theta=0.5, epsilon=1e-2, integrator="fold", dt=5e-8,
                          start="steady", t_total=2e-3, output_interval=1e-4, seed=1)
        system = build_system(cfg)
        batch0 = Batch.pack([system], [initial_state(system)])
        engine_step = compose.loop(batch0.geometry, False, batch0.material_name, False)
        chunk = _chunk(nb.njit(**{k: v for k, v in engine_step.targetoptions.items() if k != "nopython"})(engine_step.py_func))
        b1, b2 = copy.deepcopy(batch0), copy.deepcopy(batch0)
        r1 = compose.fft_advance(b1, N_SAMPLES, cfg.sample_steps)
        r2 = compiled_advance(chunk, b2, cfg.sample_steps)
        same = all(np.array_equal(getattr(b1, k), getattr(b2, k)) for k in ("x", "u", "X", "U", "ysolve")) and all(
            np.array_equal(p, q) for p, q in zip((r1.out, r1.acc, r1.cacc), r2))
        cost = {}
        for name, advance in (("fft_advance", lambda b: compose.fft_advance(b, N_SAMPLES, cfg.sample_steps)),
                              ("compiled chunk", lambda b: compiled_advance(chunk, b, cfg.sample_steps))):
            times = []
            for _ in range(3):
                b = copy.deepcopy(batch0)
                t = time.perf_counter()
                advance(b)
                times.append(time.perf_counter() - t)
            cost[name] = min(times) / (N_SAMPLES * cfg.sample_steps) * 1e6
        print(f"{L:3d} x {L:<3d} fold step: bit-identical {same}; fft_advance {cost['fft_advance']:.1f} us/step, "
              f"compiled chunk {cost['compiled chunk']:.1f} us/step ({cost['fft_advance'] / cost['compiled chunk']:.2f}x)")


if __name__ == "__main__":
    main()

"""The slab's fixed step with the whole chunk compiled (compose.fft_chunk_driver: its FFTs in numba by
rocket-fft) against the Python driver it replaces (compose.fft_advance given its FFT module, which keeps
the per-step Python loop: one rfft2/irfft2 pair per step from Python, then the compiled step of every row).

    python benchmarks/bench_fft_chunk.py     # about 2 minutes on one core here

Elastic slab, fold step (epsilon = 1e-2, spring drive, steady start, dt = 5e-8 s, 20 samples of 1e-4 s)
on 8 x 8, 16 x 16 and 64 x 64, both drivers from the same state in one process, best of three each; it
checks that the state and the chunk's outputs are bit-identical and prints the cost per step of each
and their ratio (the ratio is what compares across machines).
"""

from __future__ import annotations

import copy
import time

import numpy as np

from slipchain.engine.backends import Batch, compose
from slipchain.engine.backends.pocketfft import fft_module, numba_fft
from slipchain.model.config import make_config
from slipchain.model.system import build_system, initial_state

N_SAMPLES = 20


def main() -> None:
    assert numba_fft(), "numpy.fft does not compile in numba here (rocket-fft): the compiled chunk is not used"
    for L in (8, 16, 64):
        cfg = make_config(geometry="slab", N=L, Ly=L, theta=0.5, epsilon=1e-2, integrator="fold", dt=5e-8,
                          start="steady", t_total=2e-3, output_interval=1e-4, seed=1)
        system = build_system(cfg)
        batch0 = Batch.pack([system], [initial_state(system)])
        drivers = {"python": lambda b: compose.fft_advance(b, N_SAMPLES, cfg.sample_steps, fft=fft_module()),
                   "compiled": lambda b: compose.fft_advance(b, N_SAMPLES, cfg.sample_steps)}
        ends, cost = {}, {}
        for name, advance in drivers.items():
            advance(copy.deepcopy(batch0))  # compile or load
            times = []
            for _ in range(3):
                b = copy.deepcopy(batch0)
                t = time.perf_counter()
                r = advance(b)
                times.append(time.perf_counter() - t)
            ends[name] = (b, r)
            cost[name] = min(times) / (N_SAMPLES * cfg.sample_steps) * 1e6
        (b1, r1), (b2, r2) = ends["python"], ends["compiled"]
        same = all(np.array_equal(getattr(b1, k), getattr(b2, k)) for k in ("x", "u", "X", "U", "ysolve")) and all(
            np.array_equal(getattr(r1, k), getattr(r2, k)) for k in ("out", "acc", "cacc"))
        print(f"{L:3d} x {L:<3d} fold step: bit-identical {same}; Python driver {cost['python']:.1f} us/step, "
              f"compiled chunk {cost['compiled']:.1f} us/step ({cost['python'] / cost['compiled']:.2f}x)")


if __name__ == "__main__":
    main()

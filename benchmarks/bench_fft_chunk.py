"""The slab's steps compiled against the per-step Python drivers they replace, from the same state in one
process: the elastic slab's fixed step with the whole chunk compiled (compose.fft_chunk_driver, its FFTs in
numba by rocket-fft) against compose.fft_advance given its FFT module (which keeps the per-step Python
loop), and the implicit stepper's explicit steps compiled (compose.krylov_explicit_driver) against
compose.krylov_implicit_advance given its FFT module, on the tester's block; and the rubber's fold step
there (the tester's first protocol).

    python benchmarks/bench_fft_chunk.py     # about 3 minutes on one core here

Fold step: elastic slab, epsilon = 1e-2, spring drive, steady start, dt = 5e-8 s, 20 samples of 1e-4 s, on
8 x 8, 16 x 16 and 64 x 64, best of three; the adaptive step (the default integrator) the same on 16 x 16
(per base step of dt). The tester: 16 x 16 rubber slab H = 50 a under the tester's top,
theta = 1, mu_a = 0.95 applied within 1 ms, from rest, the implicit stepper, its first 20 ms (the top
rings: mostly explicit steps), with the implicit stepper and with the fold step, best of two. Each line says whether the two give the same bits (state and
outputs) and their costs; the ratio is what compares across machines.
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
STATE = ("x", "u", "X", "U", "ysolve", "bstate", "carry")


def best_time(cfg, driver, repeat: int, **kw):
    """``driver`` (with ``kw``) over N_SAMPLES samples from the config's start, after one run to compile or
    load it: (the last run's batch, its chunk output, the best of ``repeat`` runs in seconds)."""
    system = build_system(cfg)
    batch0 = Batch.pack([system], [initial_state(system)])
    driver(copy.deepcopy(batch0), N_SAMPLES, cfg.sample_steps, **kw)  # compile or load
    times = []
    for _ in range(repeat):
        b = copy.deepcopy(batch0)
        t = time.perf_counter()
        r = driver(b, N_SAMPLES, cfg.sample_steps, **kw)
        times.append(time.perf_counter() - t)
    return b, r, min(times)


def compare(cfg, driver, repeat: int):
    """The Python driver (``driver`` given its FFT module) and the compiled one from the same state: (whether
    the state and the chunk's outputs are bit-identical, best seconds of each, base steps of the run)."""
    b1, r1, python = best_time(cfg, driver, repeat, fft=fft_module())
    b2, r2, compiled = best_time(cfg, driver, repeat)
    same = all(getattr(b1, k) is None or np.array_equal(getattr(b1, k), getattr(b2, k)) for k in STATE) and all(
        np.array_equal(getattr(r1, k), getattr(r2, k)) for k in ("out", "acc", "cacc"))
    return same, python, compiled, int(b2.step[0])


def main() -> None:
    assert numba_fft(), "numpy.fft does not compile in numba here (rocket-fft): the compiled chunk is not used"
    for L, integrator in ((8, "fold"), (16, "fold"), (64, "fold"), (16, "adaptive")):
        cfg = make_config(geometry="slab", N=L, Ly=L, theta=0.5, epsilon=1e-2, integrator=integrator, dt=5e-8,
                          start="steady", t_total=2e-3, output_interval=1e-4, seed=1)
        same, py, co, _ = compare(cfg, compose.fft_advance, 3)
        per = 1e6 / (N_SAMPLES * cfg.sample_steps)
        print(f"{L:3d} x {L:<3d} {integrator} step: bit-identical {same}; Python driver {py * per:.1f} us/step, "
              f"compiled chunk {co * per:.1f} us/step ({py / co:.2f}x)")
    for integrator, driver in (("implicit", compose.krylov_implicit_advance), ("fold", compose.fft_advance)):
        cfg = make_config(geometry="slab", N=16, Ly=16, N_L=50, epsilon=1.0, material="prony", integrator=integrator,
                          dt=1e-7, eta_c=1e5, theta=1.0, dead_weight=0.95, top_mass="tester", start="rest", t_ramp=1e-3,
                          output_interval=1e-3, t_total=0.02, seed=0)
        same, py, co, steps = compare(cfg, driver, 2)
        print(f"tester 16 x 16, {integrator}, 20 ms ({steps} base steps): bit-identical {same}; Python driver "
              f"{py:.2f} s, compiled {co:.2f} s ({py / co:.2f}x)")


if __name__ == "__main__":
    main()

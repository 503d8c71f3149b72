"""Issue 13: the cost of one step of the 2-D geometries against L, beside the FFT floor.

The floor is one rfft2 + irfft2 pair of an L x L float64 field (scipy.fft, one thread); the force
(:func:`slipchain.model.elastic.elastic_force`) adds the subtraction of the drive and the
multiplication by k(q); the slab step is a whole engine step (``CPUBackend.advance`` on one
L x L slab, theta = 0.3, steady start: FFT pair, velocity update, contact solve, positions and
sums), after a warm-up of WARM_UP = 10,000 steps (0.2 ms simulated; 2,500 at L = 1024) that leaves
the steady start's transient, in which contacts fall back to the bracketed solver and a step costs
up to 2.5 times more (L = 256: 1.9 ms after 300 steps, 0.7 ms after 10,000);
the chain2d step the same for the 2-D chains (no FFT). Prints one row per L: microseconds
per call or step (best of 3-5 repeats) and the ratios to the floor, measured side by side in one
process.

    .venv/bin/python benchmarks/fft_floor.py [--max-L 1024]
"""

from __future__ import annotations

import argparse
import platform
import timeit

import numpy as np
import scipy.fft as sfft

from slipchain.engine.backends import Batch, CPUBackend
from slipchain.model.config import make_config
from slipchain.model.elastic import elastic_force, slab_kernel, wavenumbers
from slipchain.model.system import build_system, initial_state


WARM_UP = 10_000


def step_cost(geometry: str, L: int, steps: int) -> float:
    """Seconds per engine step of one L x L realisation (best of 3 chunks of ``steps``)."""
    cfg = make_config(geometry=geometry, N=L, Ly=L, theta=0.3, start="steady")
    system = build_system(cfg)
    batch = Batch.pack([system], [initial_state(system)])
    backend = CPUBackend()
    backend.advance(batch, 1, WARM_UP if L <= 512 else WARM_UP // 4)  # compile, and leave the start's transient
    return min(timeit.repeat(lambda: backend.advance(batch, 1, steps), number=1, repeat=3)) / steps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-L", type=int, default=1024)
    args = ap.parse_args()
    a, G, H, kappa = 1e-4, 1e7 / 3, 5e-4, 333.0 / 1e-8
    print(f"# {platform.processor() or platform.machine()}, numpy {np.__version__}")
    print("| L | rfft2+irfft2 (us) | elastic_force (us) | ratio | slab step (us) | ratio | chain2d step (us) | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    L = 32
    while L <= args.max_L:
        rng = np.random.default_rng(0)
        u = rng.normal(size=(L, L)) * 1e-9
        k = slab_kernel(*wavenumbers(L, L, a), H, G, 0.5, kappa)
        n = max(3, int(2e6 / (L * L)))
        floor = min(timeit.repeat(lambda: sfft.irfft2(sfft.rfft2(u), s=u.shape), number=n, repeat=5)) / n
        force = min(timeit.repeat(lambda: elastic_force(u, 1e-9, k, a), number=n, repeat=5)) / n
        steps = max(3, int(2e5 / (L * L)))
        slab = step_cost("slab", L, steps)
        chain2d = step_cost("chain2d", L, steps)
        print(f"| {L} | {floor * 1e6:.1f} | {force * 1e6:.1f} | {force / floor:.2f} | {slab * 1e6:.1f} | "
              f"{slab / floor:.2f} | {chain2d * 1e6:.1f} | {chain2d / floor:.2f} |", flush=True)
        L *= 2


if __name__ == "__main__":
    main()

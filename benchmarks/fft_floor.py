"""Issue 13 groundwork: the cost of the slab's elastic force per step against L, beside its floor.

The floor is one rfft2 + irfft2 pair of an L x L float64 field (scipy.fft, one thread); the force
(:func:`slipchain.model.elastic.elastic_force`) adds the subtraction of the drive and the
multiplication by k(q). Prints one row per L: microseconds per call (best of 5 repeats) and the
ratio, measured side by side in one process.

    .venv/bin/python benchmarks/fft_floor.py [--max-L 1024]
"""

from __future__ import annotations

import argparse
import platform
import timeit

import numpy as np
import scipy.fft as sfft

from slipchain.model.elastic import elastic_force, slab_kernel, wavenumbers


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-L", type=int, default=1024)
    args = ap.parse_args()
    a, G, H, kappa = 1e-4, 1e7 / 3, 5e-4, 333.0 / 1e-8
    print(f"# {platform.processor() or platform.machine()}, numpy {np.__version__}")
    print("| L | rfft2+irfft2 (us) | elastic_force (us) | ratio |")
    print("|---|---|---|---|")
    L = 32
    while L <= args.max_L:
        rng = np.random.default_rng(0)
        u = rng.normal(size=(L, L)) * 1e-9
        k = slab_kernel(*wavenumbers(L, L, a), H, G, 0.5, kappa)
        n = max(3, int(2e6 / (L * L)))
        floor = min(timeit.repeat(lambda: sfft.irfft2(sfft.rfft2(u), s=u.shape), number=n, repeat=5)) / n
        force = min(timeit.repeat(lambda: elastic_force(u, 1e-9, k, a), number=n, repeat=5)) / n
        print(f"| {L} | {floor * 1e6:.1f} | {force * 1e6:.1f} | {force / floor:.2f} |")
        L *= 2


if __name__ == "__main__":
    main()

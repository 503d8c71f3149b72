"""Do a run's bits depend on where its arrays lie? (2026-12-06, thirty-ninth session; a diagnostic, not a timing)

Runs one piece of a run (``bench_worker_allocator.CASES``: TRIALS times in one process, 1 ms after 1 ms) with a
different set of live arrays of random sizes allocated before each trial, so that the piece's own arrays land
elsewhere in the heap, and prints how many trials gave each hash of the state and the chunk's outputs. One hash:
the piece's arithmetic does not follow the addresses. Found on 2026-12-06: the 2-D chains on 64 x 64 (implicit and
adaptive) gave a second hash in one trial of 12 (seed 3), in their positions and velocities. Traced and fixed the
same day (the stencil's neighbour indices unsigned: docs/performance.md, "The 2-D chains' bits followed the heap"):
one hash in 12 of 12 at seeds 3, 4, 5 for both cases since; the 1-D chain, the 2-D chains at 16-48 squared, the slab
and the tester's block gave one before too.

    python benchmarks/heap_bits.py --case fig6-chain2d --L 64 --seed 3 --trials 12
    python benchmarks/heap_bits.py --case chain2d-adaptive --L 64 --seed 3 --trials 12
    python benchmarks/heap_bits.py --case tester --L 64 --seed 3 --trials 12
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from bench_worker_allocator import CASES, piece  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", choices=sorted(CASES), default="fig6-chain2d")
    ap.add_argument("--L", type=int, default=64)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--trials", type=int, default=12)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    keep, seen = [], {}
    for trial in range(args.trials):
        keep.append([np.ones(int(s)) for s in rng.integers(1, 40000, size=int(rng.integers(0, 30)))])
        seen.setdefault(piece(args.case, args.L, 1, 1)[2], []).append(trial)
    print(f"{args.case} {args.L} x {args.L}, seed {args.seed}: " +
          "; ".join(f"{h}: trials {v}" for h, v in seen.items()))


if __name__ == "__main__":
    main()

"""Issue 26, composition: the loops composed from pieces against the three hand-written loops they
replace, side by side in one run (alternating processes, each with its own fresh NUMBA_CACHE_DIR).

1. The chain's fixed-step kernel: ns per block-step (2N blocks), N = 301, theta = 0.5, steady
   sliding at dt = 2e-8 s (as benchmarks/bench_default.py).
2. The slab's loop: us per step of a 64 x 64 slab (fig6-3d setting, steady start), fixed step
   (its default dt, 2e-8 s) and the default adaptive step (per base step, dt = 1e-7 s).
3. Agreement: mu_star of the slab runs before and after (the chains are bit for bit; the slab's
   fastmath loop now sees the drive's time as a value, which moves round-off).

    git worktree add /tmp/old 9111503
    .venv/bin/python benchmarks/bench_compose.py --old /tmp/old [--repeat 3 --rounds 2]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import tempfile
from pathlib import Path

from bench_default import child  # the same side-by-side child process; its "kernel" is the chain's timing

SLAB = r"""
import json, sys, time
import slipchain as sc
from slipchain import build_system, initial_state, make_config
from slipchain.engine.backends import Batch
from slipchain.engine.backends.host import CPUBackend
what, repeat = sys.argv[1], int(sys.argv[2])
integ = dict(integrator="fixed") if what == "slab-fixed" else {}
cfg = make_config(geometry="slab", N=64, Ly=64, theta=0.5, start="steady", seed=1, **integ)
s = build_system(cfg)
b = Batch.pack([s], [initial_state(s)])
cpu = CPUBackend()
samples, steps = 10, cfg.sample_steps
cpu.advance(b, samples, steps)  # compile and warm up
times = []
for _ in range(repeat):
    t = time.perf_counter()
    cpu.advance(b, samples, steps)
    times.append((time.perf_counter() - t) / (samples * steps) * 1e6)
ds = sc.run(dict(geometry="slab", N=64, Ly=64, theta=0.5, start="steady", seed=1, t_total=0.004, **integ))
print(json.dumps({"us": times, "mu_star": float(ds.attrs["mu_star"])}))
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--old", type=Path, required=True, help="a checkout of the commit before the composition")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--only", choices=("kernel", "slab-fixed", "slab-adaptive"), help="one loop only")
    args = ap.parse_args()
    here = Path(__file__).resolve().parents[1]
    caches = {name: tempfile.mkdtemp(prefix=f"numba-{name}-") for name in ("old", "new")}
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores; {args.rounds} rounds x "
          f"{args.repeat} timings, alternated")
    print("| loop | unit | three loops | composed | composed/three |\n|---|---|---|---|---|")
    mu = {}
    for what, unit in (("kernel", "ns per block-step"), ("slab-fixed", "us per step"),
                       ("slab-adaptive", "us per base step")):
        if args.only and what != args.only:
            continue
        t: dict[str, list[float]] = {"old": [], "new": []}
        for _ in range(args.rounds):
            for name, src in (("old", args.old), ("new", here)):
                r = child(src, what, args.repeat, caches[name]) if what == "kernel" else child(
                    src, what, args.repeat, caches[name], SLAB)
                t[name] += r["ns" if what == "kernel" else "us"]
                mu[(what, name)] = r.get("mu_star")
        old, new = statistics.median(t["old"]), statistics.median(t["new"])
        print(f"| {what} | {unit} (median) | {old:.3f} | {new:.3f} | {new / old:.3f} |")
    for what in ("slab-fixed", "slab-adaptive"):
        if (what, "old") not in mu:
            continue
        a, b = mu[(what, "old")], mu[(what, "new")]
        print(f"\n{what}, 4 ms: mu_star {a!r} (three loops) vs {b!r} (composed), relative difference {abs(a - b) / a:.1e}")


if __name__ == "__main__":
    main()

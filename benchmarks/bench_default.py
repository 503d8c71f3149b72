"""Issue 26: the engine before and after, side by side in one run (alternating processes, one core each).

1. The chain's fixed-step kernel: ns per block-step (2N blocks), N = 301, theta = 0.5, steady
   sliding at dt = 2e-8 s, median of ``--repeat`` timings of 2 ms after 2 ms of warm-up; this
   checkout against ``--old`` (a checkout of the commit before, e.g. ``git worktree add /tmp/old
   4a0c63f``), each in its own process with its own fresh NUMBA_CACHE_DIR, alternated.
2. The adaptive step at the reference point (N = 301, theta = 1, eta_c = 0.1 omega0, v_d = v0,
   steady start, 20 ms from dt = 1e-7 s): steps taken per base step and the share of steps
   rejected, old (largest step 8e-7 s, above the stable step 6.87e-7 s) and new (4e-7 s).

    .venv/bin/python benchmarks/bench_default.py --old /tmp/old [--repeat 5] [--extra NAME=PATH ...]

``--extra NAME=PATH``: more checkouts timed in the same alternation (the kernel only), each reported
against ``--old``; e.g. the old kernel with a later fix applied, to tell the fix's cost from the
refactor's.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import json, sys, time
from slipchain import build_system, initial_state, make_config
from slipchain.engine.backends import Batch
from slipchain.engine.backends.host import CPUBackend
what, repeat = sys.argv[1], int(sys.argv[2])
out = {}
if what == "kernel":
    cfg = make_config(N=301, theta=0.5, eta_c=1e5, start="steady", integrator="fixed", dt=2e-8)
    s = build_system(cfg)
    b = Batch.pack([s], [initial_state(s)])
    cpu = CPUBackend()
    steps = cfg.sample_steps
    cpu.advance(b, 200, steps)  # compile and warm up: 2 ms
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        cpu.advance(b, 200, steps)
        times.append((time.perf_counter() - t) / (200 * steps * 2 * cfg.N) * 1e9)
    out["ns"] = times
else:
    cfg = make_config(N=301, theta=1.0, eta_c=1e5, start="steady", integrator="adaptive", dt=1e-7)
    s = build_system(cfg)
    b = Batch.pack([s], [initial_state(s)])
    CPUBackend().advance(b, 2000, cfg.sample_steps)  # 20 ms
    out.update(levels=cfg.step_levels, taken=float(b.step_control[0, 2]), rejected=float(b.step_control[0, 3]),
               base_steps=int(b.step[0]))
print(json.dumps(out))
"""


def child(src: Path, what: str, repeat: int, cache: str, code: str = CHILD) -> dict:
    """Run ``code`` (default: this module's CHILD) for ``what`` in a fresh process on the checkout ``src``
    with the numba cache ``cache``; its last line of output, as JSON."""
    env = {**os.environ, "PYTHONPATH": str(src / "src"), "NUMBA_CACHE_DIR": cache}
    proc = subprocess.run([sys.executable, "-c", code, what, str(repeat)], env=env, capture_output=True, text=True,
                          check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--old", type=Path, required=True, help="a checkout of the commit before issue 26")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--extra", action="append", default=[], metavar="NAME=PATH",
                    help="another checkout to time beside the two (the kernel only)")
    args = ap.parse_args()
    here = Path(__file__).resolve().parents[1]
    trees = {"old": args.old, "new": here, **{e.split("=", 1)[0]: Path(e.split("=", 1)[1]) for e in args.extra}}
    caches = {name: tempfile.mkdtemp(prefix=f"numba-{name}-") for name in trees}
    ns: dict[str, list[float]] = {name: [] for name in trees}
    for _ in range(args.rounds):
        for name, src in trees.items():
            ns[name] += child(src, "kernel", args.repeat, caches[name])["ns"]
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores; {args.rounds} rounds x "
          f"{args.repeat} timings, alternated")
    old, new = statistics.median(ns["old"]), statistics.median(ns["new"])
    print("| chain, fixed step, N = 301, theta = 0.5 | before | after | after/before |\n|---|---|---|---|")
    print(f"| ns per block-step (median) | {old:.3f} | {new:.3f} | {new / old:.3f} |")
    for name in trees:
        if name not in ("old", "new"):
            ex = statistics.median(ns[name])
            print(f"| {name}: ns per block-step (median) | {old:.3f} | {ex:.3f} | {ex / old:.3f} |")
    print("\n| adaptive step, reference point, 20 ms from dt = 1e-7 | largest step | steps per base step | "
          "rejected / taken |\n|---|---|---|---|")
    for name, src in (("before", args.old), ("after", here)):
        r = child(src, "adaptive", 1, caches["old" if name == "before" else "new"])
        print(f"| {name} | {1e-7 * 2 ** r['levels']:.1e} s | {r['taken'] / r['base_steps']:.3f} | "
              f"{r['rejected'] / r['taken']:.4f} |")


if __name__ == "__main__":
    main()

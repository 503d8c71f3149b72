"""Memory estimate against measurement (issue 11): peak RSS of runs beside :func:`slipchain.engine.memory.estimate_bytes`.

Each case runs in a fresh process: a small run first (numba compiled, interpreter warm), then the
case; the growth of the peak resident set (``ru_maxrss``) is what the case needed. The estimate
should lie at or above it and not far above (the check would refuse runs that fit).

    .venv/bin/python benchmarks/memory_estimate.py
"""

from __future__ import annotations

import json
import subprocess
import sys

CASES = [  # N, theta, t_total, output_interval
    (1_000_000, 1.0, 2e-6, 1e-6),
    (2_000_000, 0.05, 2e-6, 1e-6),
    (4_000_000, 0.05, 2e-6, 1e-6),
    (2_000_000, 1.0, 2e-6, 1e-6),
    (100_000, 1.0, 1e-2, 1e-5),
    (1001, 1.0, 2e-2, 1e-7),
]

CHILD = """
import json, resource, sys
from slipchain import make_config, run
from slipchain.engine.memory import estimate_bytes
N, theta, T, oi = json.loads(sys.argv[1])
run(make_config(N=101, theta=0.5, t_total=2e-6, output_interval=1e-6, start="steady"))
r0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
cfg = make_config(N=N, theta=theta, t_total=T, output_interval=oi, start="steady")
run(cfg)
r1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"measured": r1 - r0, "estimate": estimate_bytes(cfg)}))
"""


def main() -> None:
    print(f"{'N':>9} {'theta':>6} {'t_total':>8} {'interval':>8} {'measured MB':>12} {'estimate MB':>12} {'ratio':>6}")
    for case in CASES:
        out = subprocess.run([sys.executable, "-c", CHILD, json.dumps(case)], capture_output=True, text=True, check=True)
        r = json.loads(out.stdout.strip().splitlines()[-1])
        print(f"{case[0]:>9} {case[1]:>6} {case[2]:>8.0e} {case[3]:>8.0e} {r['measured'] / 2**20:>12.1f} "
              f"{r['estimate'] / 2**20:>12.1f} {r['estimate'] / max(r['measured'], 1):>6.2f}")


if __name__ == "__main__":
    main()

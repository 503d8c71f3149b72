"""Sweep throughput on a local Dask cluster: 1 worker vs all cores, side by side in one run.

    .venv/bin/python benchmarks/bench_sweep.py [--members 16]

Runs the same small sweep (N = 301, theta = 0.5, v_d = v0, eta_c = 0.1 omega0, fixed 10 ms, one
member per seed) into fresh stores with 1 and with n worker processes, and prints wall times,
the sum of the members' own run times, the speed-up and the parallel efficiency. The paper
preset's wall time is measured by running it (`slipchain reproduce --preset paper`); the store's
invocations.jsonl and docs/fig6-paper/report.md record it.
"""

from __future__ import annotations

import argparse
import tempfile
import time

from slipchain.sweeps.executor import default_workers, run_sweep
from slipchain.sweeps.store import Store
from slipchain.sweeps.definition import make_sweep


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--members", type=int, default=16)
    args = ap.parse_args()
    sw = make_sweep({"name": "bench", "base": {"theta": 0.5, "t_total": 1e-2},
                     "grid": {"seed": list(range(args.members))}})
    rows = []
    for n in (1, default_workers()):
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            rep = run_sweep(sw, f"{d}/s", n_workers=n, progress=False)
            wall = time.perf_counter() - t0
            cpu = float(Store.open(f"{d}/s").dataset()["wall_time_s"].sum())
            assert len(rep.ran) == args.members
            rows.append((n, wall, cpu))
    base = rows[0][1]
    print(f"{'workers':>8} {'wall s':>8} {'sum of member s':>16} {'speed-up':>9} {'efficiency':>10}")
    for n, wall, cpu in rows:
        print(f"{n:>8} {wall:>8.1f} {cpu:>16.1f} {base / wall:>9.2f} {base / wall / n:>10.2f}")


if __name__ == "__main__":
    main()

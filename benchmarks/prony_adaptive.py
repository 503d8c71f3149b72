"""Issue 28: the adaptive step with the viscoelastic bulk against the fold step, over many slip events.

The Fig. 6 point theta = 1, eta_c = 0.1 omega0, v_d = v0, N = 301, epsilon = 1e-2, the default
compound at 20 °C, steady start, ``--t`` seconds simulated, seeds 0 .. ``--seeds``-1; each run one
process (``--workers`` at a time; wall times are then only comparable within a run of this script
on an otherwise idle machine). Per integrator: mu_star's mean over seeds, its mean difference from
``fold`` at 2e-8 s (the adaptive step's base step), paired by seed, with the standard error of the
paired differences, the mean wall time and the largest energy residual.

    .venv/bin/python benchmarks/prony_adaptive.py [--t 0.2] [--seeds 4] [--workers 2]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from concurrent.futures import ProcessPoolExecutor

KINDS = {"fold 1e-7 (fold's default)": dict(integrator="fold", dt=1e-7),
         "fold 2e-8": dict(integrator="fold", dt=2e-8),
         "adaptive (defaults: 2e-8 .. 8e-8, tol 1e-3)": dict(integrator="adaptive")}
REFERENCE = "fold 2e-8"


def one(kind: str, seed: int, t: float) -> tuple[str, int, float, float, float, float]:
    from slipchain import make_config, run

    cfg = make_config(N=301, theta=1.0, eta_c=1e5, v_d=1e-3, epsilon=1e-2, start="steady", material="prony",
                      t_total=t, seed=seed, **KINDS[kind])
    t0 = time.perf_counter()
    ds = run(cfg, progress=False)
    return (kind, seed, time.perf_counter() - t0, float(ds.attrs["mu_star"]), float(ds.attrs["mu_star_sem"]),
            float(ds.attrs["check_energy_balance"]))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--t", type=float, default=0.2)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    one(REFERENCE, 0, 1e-3)  # compile into the cache before the timed runs
    jobs = [(k, s, args.t) for s in range(args.seeds) for k in KINDS]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(one, *zip(*jobs)))
    res = {(k, s): (w, mu, se, eb) for k, s, w, mu, se, eb in rows}
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, {args.workers} workers; "
          f"{args.seeds} seeds x {args.t} s")
    print("| integrator | mu_star, mean of seeds | minus fold 2e-8, paired | wall per run (s) | largest energy residual |")
    print("|---|---|---|---|---|")
    for k in KINDS:
        mus = [res[k, s][1] for s in range(args.seeds)]
        d = [res[k, s][1] - res[REFERENCE, s][1] for s in range(args.seeds)]
        sd = statistics.stdev(d) / args.seeds**0.5 if args.seeds > 1 else float("nan")
        print(f"| {k} | {statistics.mean(mus):.5f} | {statistics.mean(d):+.5f} +- {sd:.5f} | "
              f"{statistics.mean(res[k, s][0] for s in range(args.seeds)):.1f} | "
              f"{max(res[k, s][3] for s in range(args.seeds)):.1e} |")
    print("\nper seed (mu_star +- its SE over time):")
    for s in range(args.seeds):
        print(s, "  ".join(f"{k.split(' (')[0]}: {res[k, s][1]:.5f} +- {res[k, s][2]:.5f}" for k in KINDS))


if __name__ == "__main__":
    main()

"""Issue 12: the fold-aware integrator against the fixed step at the reference point, side by side.

Reference point: N = 301, theta = 1, eta_c = 0.1 omega0, v_d = v0, epsilon = 1e-2, automatic run
length (SE(mu_star) <= 0.01). For each seed, the fixed step at dt = 2e-8 (the default; the
unique-root limit is 3.6e-8) and integrator = 'fold' at larger dt; prints per dt the wall time
(sum over the seeds, compilation excluded), its ratio to the fixed step's, and the seed mean of
mu_star with its error and the difference to the fixed step's in units of the combined error.

    .venv/bin/python benchmarks/bench_fold.py [--seeds 4] [--dts 5e-8 1e-7 2e-7]
"""

from __future__ import annotations

import argparse
import platform

import numpy as np

from slipchain import make_config, run

REF = dict(N=301, theta=1.0, eta_c=1e5, v_d=1e-3)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--dts", type=float, nargs="+", default=[5e-8, 1e-7, 2e-7])
    args = ap.parse_args()
    run(make_config(N=11, theta=0.5, t_total=1e-5))  # compile
    run(make_config(N=11, theta=0.5, t_total=1e-5, integrator="fold", dt=1e-7))
    print(f"# {platform.processor() or platform.machine()}; reference point, {args.seeds} seeds")
    print("| integrator | dt (s) | wall (s) | speed-up | mu_star | SE | (mu - mu_fixed)/SE_combined | energy balance (max) |")
    print("|---|---|---|---|---|---|---|---|")
    base = None
    for integ, dt in [("fixed", 2e-8)] + [("fold", d) for d in args.dts]:
        mus, ses, wall, energy = [], [], 0.0, 0.0
        for seed in range(args.seeds):
            ds = run(make_config(**REF, seed=seed, integrator=integ, dt=dt))
            mus.append(ds.attrs["mu_star"])
            ses.append(ds.attrs["mu_star_sem"])
            wall += ds.attrs["wall_time_s"]
            energy = max(energy, ds.attrs["check_energy_balance"])
        mu = float(np.mean(mus))
        se = float(max(np.std(mus, ddof=1) / np.sqrt(len(mus)), np.sqrt(np.mean(np.square(ses)) / len(mus))))
        if base is None:
            base = (mu, se, wall)
        z = (mu - base[0]) / np.hypot(se, base[1]) if integ != "fixed" else 0.0
        print(f"| {integ} | {dt:g} | {wall:.1f} | {base[2] / wall:.1f} | {mu:.4f} | {se:.4f} | {z:+.2f} | {energy:.1e} |",
              flush=True)


if __name__ == "__main__":
    main()

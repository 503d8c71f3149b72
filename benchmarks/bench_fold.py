"""Issue 12: the fold-aware and adaptive integrators against the fixed step at the reference point, side by side.

Reference point: N = 301, theta = 1, eta_c = 0.1 omega0, v_d = v0, epsilon = 1e-2, automatic run
length (SE(mu_star) <= 0.01). For each seed, the fixed step at dt = 2e-8 (the default; the
unique-root limit is 3.6e-8), integrator = 'fold' at larger dt and integrator = 'adaptive' from
dt = 1e-7 at the tolerances ``--tols``; prints per case the wall time
(sum over the seeds, compilation excluded), its ratio to the fixed step's, and the seed mean of
mu_star with its error and the difference to the fixed step's in units of the combined error.

    .venv/bin/python benchmarks/bench_fold.py [--seeds 4] [--dts 5e-8 1e-7 2e-7] [--tols 1e-2 1e-3]
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
    ap.add_argument("--tols", type=float, nargs="*", default=[1e-2, 1e-3])
    args = ap.parse_args()
    run(make_config(N=11, theta=0.5, t_total=1e-5, integrator="fixed"))  # compile
    run(make_config(N=11, theta=0.5, t_total=1e-5, integrator="fold", dt=1e-7))
    run(make_config(N=11, theta=0.5, t_total=1e-5, integrator="adaptive", dt=1e-7))
    print(f"# {platform.processor() or platform.machine()}; reference point, {args.seeds} seeds")
    print("| integrator | dt (s) [step_tol] | wall (s) | speed-up | mu_star | SE | (mu - mu_fixed)/SE_combined | energy balance (max) |")
    print("|---|---|---|---|---|---|---|---|")
    base = None
    cases = [("fixed", 2e-8, {})] + [("fold", d, {}) for d in args.dts]
    cases += [("adaptive", 1e-7, {"step_tol": t}) for t in args.tols]
    for integ, dt, extra in cases:
        mus, ses, wall, energy = [], [], 0.0, 0.0
        for seed in range(args.seeds):
            ds = run(make_config(**REF, seed=seed, integrator=integ, dt=dt, **extra))
            mus.append(ds.attrs["mu_star"])
            ses.append(ds.attrs["mu_star_sem"])
            wall += ds.attrs["wall_time_s"]
            energy = max(energy, ds.attrs["check_energy_balance"])
        mu = float(np.mean(mus))
        se = float(max(np.std(mus, ddof=1) / np.sqrt(len(mus)), np.sqrt(np.mean(np.square(ses)) / len(mus))))
        if base is None:
            base = (mu, se, wall)
        z = (mu - base[0]) / np.hypot(se, base[1]) if integ != "fixed" else 0.0
        label = f"{dt:g}" + (f" [{extra['step_tol']:g}]" if extra else "")
        print(f"| {integ} | {label} | {wall:.1f} | {base[2] / wall:.1f} | {mu:.4f} | {se:.4f} | {z:+.2f} | {energy:.1e} |",
              flush=True)


if __name__ == "__main__":
    main()

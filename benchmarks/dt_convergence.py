"""Is the default time step converged? mu_star at dt and dt/2 in every regime (issue 2, item 5).

Regimes: v_d = v0 and 0.3 v0, theta = 0.1 and 1, eta_c = 0.1 omega0 (the strongest stick-slip),
seed 0, automatic run length (sem_target 0.01). The same seed gives the same disorder; the
trajectories still decorrelate (the dynamics are chaotic), so the two estimates are close to
independent and |difference| is compared with its own standard error sqrt(se1^2 + se2^2) as well
as with the SE of one run.

    .venv/bin/python benchmarks/dt_convergence.py [--dt 2e-8]
"""

from __future__ import annotations

import argparse
import math

from slipchain import make_config, run

REGIMES = [(1e-3, 1.0), (1e-3, 0.1), (3e-4, 1.0), (3e-4, 0.1)]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--dt", type=float, default=make_config(integrator="fixed").dt)
    ap.add_argument("--eta-c", type=float, default=1e5)
    args = ap.parse_args()
    print("| v_d (m/s) | theta | mu_star(dt) | mu_star(dt/2) | diff | diff / SE(dt) | diff / combined SE | wall (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for v_d, theta in REGIMES:
        res = []
        for dt in (args.dt, args.dt / 2):
            ds = run(make_config(v_d=v_d, theta=theta, dt=dt, eta_c=args.eta_c, integrator="fixed"))
            res.append(ds.attrs)
        (a, b) = res
        diff = b["mu_star"] - a["mu_star"]
        comb = math.hypot(a["mu_star_sem"], b["mu_star_sem"])
        print(f"| {v_d:g} | {theta:g} | {a['mu_star']:.4f} ± {a['mu_star_sem']:.4f} | {b['mu_star']:.4f} ± "
              f"{b['mu_star_sem']:.4f} | {diff:+.4f} | {abs(diff) / a['mu_star_sem']:.2f} | {abs(diff) / comb:.2f} | "
              f"{a['wall_time_s']:.0f} + {b['wall_time_s']:.0f} |", flush=True)


if __name__ == "__main__":
    main()

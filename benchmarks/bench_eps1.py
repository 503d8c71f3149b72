"""Issue 12: the cost of one epsilon = 1 run relative to the same run at epsilon = 1e-2, side by side.

The reference point (N = 301, theta = 1, eta_c = 0.1 omega0, v_d = v0), automatic length (SE of
mu_star <= 0.01), seeds 0 and 1:

* epsilon = 1e-2 with today's default (fixed step, dt = 2e-8, rest start), and with the settings
  of the epsilon = 1 preset (adaptive from dt = 1e-7, steady start, 1 ms samples, min_cycles 20);
* epsilon = 1 with the preset's settings (presets/fig6-eps1.toml).

Prints, per case, the simulated time, the wall time (compilation excluded), the wall time per
simulated second and mu_star.

    .venv/bin/python benchmarks/bench_eps1.py [--seeds 2]
"""

from __future__ import annotations

import argparse
import platform

from slipchain import make_config, run

REF = dict(N=301, theta=1.0, eta_c=1e5, v_d=1e-3)
PRESET = dict(integrator="adaptive", dt=1e-7, start="steady", output_interval=1e-3, min_cycles=20, t_max=30.0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=2)
    args = ap.parse_args()
    run(make_config(N=11, theta=0.5, t_total=1e-5, integrator="fixed"))  # compile
    run(make_config(N=11, theta=0.5, t_total=1e-5, integrator="adaptive", dt=1e-7))
    print(f"# {platform.processor() or platform.machine()}; reference point, seeds 0..{args.seeds - 1}")
    print("| epsilon | settings | seed | simulated (s) | wall (s) | wall per simulated s | mu_star | SE |")
    print("|---|---|---|---|---|---|---|---|")
    cases = [(1e-2, "fixed 2e-8, rest", dict(integrator="fixed", dt=2e-8)), (1e-2, "eps1 preset", PRESET),
             (1.0, "eps1 preset", PRESET)]
    walls = {}
    for eps, label, extra in cases:
        for seed in range(args.seeds):
            ds = run(make_config(**REF, epsilon=eps, seed=seed, **extra))
            a = ds.attrs
            walls.setdefault((eps, label), []).append(a["wall_time_s"])
            print(f"| {eps:g} | {label} | {seed} | {a['t_total']:.3g} | {a['wall_time_s']:.1f} | "
                  f"{a['wall_time_s'] / a['t_total']:.1f} | {a['mu_star']:.4f} | {a['mu_star_sem']:.4f} |", flush=True)
    base = sum(walls[(1e-2, "fixed 2e-8, rest")])
    for key, w in walls.items():
        print(f"# {key}: wall {sum(w):.1f} s, {sum(w) / base:.1f} x the epsilon = 1e-2 default")


if __name__ == "__main__":
    main()

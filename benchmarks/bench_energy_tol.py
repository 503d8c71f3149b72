"""Issue 29 (and 27): the implicit stepper's energy tolerance on the tester's block, side by side.

Under a slowly rising weight the tester's heavy top creeps, and there the backward-Euler step is bounded
by its energy residual (its numerical dissipation at most ``energy_tol`` of the step's works), not by the
error estimate (measured on 128 x 128, theta = 0.05: err/tol ~ 7e-6 at the accepted steps of 12.8 us,
the residual at 0.63 of its bound; docs/numerics.md). This runs the tester's block (slab H = 50 a of the
default compound at 20 °C, the tester's top mass, ``--L`` squared, the weight raised from rest at
``--rate`` per second, the tester-onset presets' 1.015 over 5.8 s by default, through 0.98 of the run)
for ``--t`` simulated seconds at each ``--energy-tol`` in turn, ``--repeat`` times alternating (so a background load drifts over all
alike), after one short run each to compile; prints per tolerance the wall time, the backward-Euler
tries, the plate's advance, the energy balance, the largest difference of the plate's path (the
drive force's record with ``--fig6``) from the first tolerance's (relative to its largest value) and the wall-time ratios to the first.

    .venv/bin/python benchmarks/bench_energy_tol.py [--L 32] [--theta 0.05] [--t 0.5] [--repeat 1]
    .venv/bin/python benchmarks/bench_energy_tol.py --fig6 --L 32 --theta 0.05 --t 0.3

``--fig6``: Fig. 6's point in 3-D instead (issue 27, the fig6-3d-eps1 preset's slab: N_L = 5, epsilon = 1,
eta_c = 0.1 omega0, v_d = v0, steady start), where low load's steps are bounded by the energy residual too
(docs/performance.md); prints mu_star in place of the plate's advance.
"""

from __future__ import annotations

import argparse

import numpy as np

from bench_preconditioner import _counting, _cpu, _result, alternating
from slipchain.engine.backends import compose


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--L", type=int, default=32)
    ap.add_argument("--theta", type=float, default=0.05)
    ap.add_argument("--rate", type=float, default=1.015 / 5.8, help="the hanging weight's rise, mu_a per second")
    ap.add_argument("--t", type=float, default=0.5, help="simulated seconds")
    ap.add_argument("--energy-tol", type=float, nargs="+", default=[1e-4, 1e-3, 1e-2])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--fig6", action="store_true", help="Fig. 6's driven slab instead of the tester's block")
    args = ap.parse_args()
    compose.implicit.krylov_be_try = _counting
    cfg = dict(geometry="slab", N=args.L, Ly=args.L, N_L=50, theta=args.theta, epsilon=1.0, seed=0, material="prony",
               temperature=20.0, integrator="implicit", dead_weight=args.rate * 0.98 * args.t, top_mass="tester",
               start="rest", t_ramp=0.98 * args.t, t_total=args.t, dt=2.5e-8 if args.theta < 0.1 else 1e-7,
               output_interval=1e-3)  # the onset presets' first t seconds (their ramp must end within the run)
    if args.fig6:
        cfg = dict(geometry="slab", N=args.L, Ly=args.L, N_L=5, theta=args.theta, eta_c=1e5, v_d=1e-3, start="steady",
                   dt=1e-7, epsilon=1.0, seed=0, output_interval=1e-3, t_total=args.t, integrator="implicit")
    tols = args.energy_tol
    walls, last = alternating(cfg, "energy_tol", tols, args.repeat,
                              dict(t_total=4e-3) if args.fig6 else dict(t_total=4e-3, t_ramp=2e-3))
    what = ("Fig. 6's slab (v_d = v0, steady start)" if args.fig6 else
            f"the tester's block, the weight rising {args.rate:.4g}/s from rest")
    print(f"{_cpu()}; {what}, {args.L} x {args.L}, theta = {args.theta}, {args.t} s simulated, "
          f"{args.repeat} alternating repeat(s)")
    path = "f_d" if args.fig6 else "X_mean"  # the drive force's record (the driven slab), or the plate's position
    x0 = last[tols[0]][0][path].values
    for e in tols:
        ds, its = last[e]
        x = ds[path].values
        print(f"energy_tol {e:7.0e}: wall {np.mean(walls[e]):8.2f} s (runs {', '.join(f'{w:.2f}' for w in walls[e])}); "
              f"tries {its.shape[0]}; {_result(ds)}; {path} off by "
              f"{np.abs(x - x0).max() / np.abs(x0).max():.1e}; energy {float(ds.attrs['check_energy_balance']):.2e}; "
              f"wall ratio to {tols[0]:.0e}: {np.mean(walls[tols[0]]) / np.mean(walls[e]):.2f}x")


if __name__ == "__main__":
    main()

"""Issue 27: the implicit stepper against the explicit adaptive step, side by side in one run.

The epsilon = 1 reference point (N = 301, theta = 1, eta_c = 0.1 omega0, v_d = v0, steady start,
dt = 1e-7, step_tol = 0.01), a fixed window of simulated time (default 5 s, about 4.5 slip
cycles of 1.1 s; ``--t 22`` for the issue's 20 cycles), output samples of 10 ms and 1 ms; and the
same run at epsilon = 1e-2; with ``--geometry slab`` (or ``halfspace``, ``chain2d``) the same point on an
``--L`` x ``--L`` interface (N_L = 5) instead of the chain. Prints per case the wall time (compilation excluded), the steps
accepted, mu_star +- SE, the energy balance and the slip events' sample times, and the ratios.
Accuracy: the implicit and adaptive runs are compared event by event (the same output samples,
the drop of f_d summed over them) and by mu_star in units of its SE.

    .venv/bin/python benchmarks/bench_implicit.py [--t 5] [--intervals 1e-2 1e-3] [--no-eps2]
    .venv/bin/python benchmarks/bench_implicit.py --geometry slab --L 64 --t 1 --intervals 1e-3 --no-eps2
    .venv/bin/python benchmarks/bench_implicit.py --geometry slab --L 128 --cycles 20   (implicit alone: 20 cycles)
    .venv/bin/python benchmarks/bench_implicit.py --material prony --t 1.5 --intervals 1e-3 --no-eps2

With ``--material prony`` (the default compound at 20 °C) the explicit comparison is the fold step at
dt (the adaptive step is refused with this material); ``--dead-weight F`` runs the point under the
dead weight F (per block, in units of the normal force) from rest instead of the spring drive (the
Prony slab runs under the dead weight only).
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from slipchain import make_config, run
from slipchain.engine.backends import Batch
from slipchain.engine.backends.host import CPUBackend
from slipchain.model.system import build_system, initial_state

REF = dict(N=301, theta=1.0, eta_c=1e5, v_d=1e-3, start="steady", dt=1e-7, seed=0)


def events(ds):
    """(sample times, drops) of the slip events: the first sample of each run of samples where f_d
    falls by over 5 % of its maximum, and the fall over that sample and the next."""
    f, t = ds.f_d.values, ds.time.values
    at = np.where(np.diff(f) < -0.05 * f.max())[0]
    at = at[np.r_[True, np.diff(at) > 1]] if at.size else at
    return t[at], np.array([f[k] - f[min(k + 2, f.size - 1)] for k in at])


def accepted_steps(cfg) -> float:
    system = build_system(cfg)
    batch = Batch.pack([system], [initial_state(system)])
    n = int(round(cfg.t_total / cfg.output_interval))
    CPUBackend().advance(batch, n, cfg.sample_steps)
    return float(batch.step_control[0, 2])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--t", type=float, default=5.0, help="simulated seconds")
    ap.add_argument("--intervals", type=float, nargs="+", default=[1e-2, 1e-3])
    ap.add_argument("--no-eps2", action="store_true", help="skip the epsilon = 1e-2 runs")
    ap.add_argument("--geometry", default="chain", choices=["chain", "chain2d", "slab", "halfspace"])
    ap.add_argument("--L", type=int, default=64, help="interface side (2-D geometries)")
    ap.add_argument("--cycles", type=int, default=0,
                    help="only: the implicit run with the automatic length (SE 0.01, this many cycles, 1-ms samples)")
    ap.add_argument("--material", default="elastic", choices=["elastic", "prony"])
    ap.add_argument("--dead-weight", type=float, default=None)
    args = ap.parse_args()
    ref = REF if args.geometry == "chain" else dict(REF, geometry=args.geometry, N=args.L, Ly=args.L, N_L=5)
    ref = dict(ref, material=args.material)
    if args.dead_weight is not None:
        ref = dict(ref, dead_weight=args.dead_weight, start="rest")
    other = "fold" if args.material == "prony" else "adaptive"  # the explicit stepper to compare with
    if args.cycles:
        run(make_config(**dict(ref, t_total=2e-3, integrator="implicit", epsilon=1.0)))  # compile
        cfg = make_config(**ref, epsilon=1.0, integrator="implicit", output_interval=1e-3, sem_target=0.01,
                          min_cycles=args.cycles, t_max=30.0)
        t0 = time.perf_counter()
        ds = run(cfg)
        wall = time.perf_counter() - t0
        te, _ = events(ds)
        print(f"# {platform.processor() or platform.machine()}; {args.geometry} {args.L} x {args.L}, epsilon = 1, implicit: "
              f"wall {wall:.1f} s, {float(ds.time.values[-1]):.2f} s simulated, {te.size} slip events, mu_star "
              f"{ds.attrs['mu_star']:.4f} +- {ds.attrs['mu_star_sem']:.4f}, energy balance "
              f"{ds.attrs['check_energy_balance']:.1e}, status {ds.attrs['status']}")
        return
    for integ in ("implicit", other):  # compile
        run(make_config(**dict(ref, t_total=1e-4, integrator=integ, epsilon=1.0)))
    where = "chain, N = 301" if args.geometry == "chain" else f"{args.geometry}, {args.L} x {args.L}"
    print(f"# {platform.processor() or platform.machine()}; epsilon = 1 reference point ({where}, material "
          f"{args.material}{'' if args.dead_weight is None else f', dead weight {args.dead_weight:g} from rest'}), "
          f"{args.t:g} s simulated")
    print("| epsilon | output interval (s) | integrator | wall (s) | steps accepted | mu_star | SE | energy balance |"
          " slip events (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for interval in args.intervals:
        res = {}
        cases = ((1.0, "implicit"), (1.0, other)) + (() if args.no_eps2 else ((1e-2, "implicit"), (1e-2, other)))
        for eps, integ in cases:
            cfg = make_config(**ref, epsilon=eps, integrator=integ, t_total=args.t, output_interval=interval)
            t0 = time.perf_counter()
            ds = run(cfg)
            wall = time.perf_counter() - t0
            a = ds.attrs
            te, drops = events(ds)
            steps = accepted_steps(cfg) if (integ, eps) == ("implicit", 1.0) else float("nan")  # a second run: where cheap
            res[(eps, integ)] = (wall, a["mu_star"], a["mu_star_sem"], te, drops)
            print(f"| {eps:g} | {interval:g} | {integ} | {wall:.2f} | {steps:.0f} | {a['mu_star']:.4f} | "
                  f"{a['mu_star_sem']:.4f} | {a['check_energy_balance']:.1e} | {np.round(te, 3).tolist()} |", flush=True)
        wi, mi, si, ti, di = res[(1.0, "implicit")]
        wa, ma, sa, ta, da = res[(1.0, other)]
        same = ti.size == ta.size and np.array_equal(ti, ta)
        dd = np.abs(di - da).max() / da.max() if same and da.size else float("nan")
        print(f"# interval {interval:g}: implicit {wa / wi:.1f}x faster than {other} at epsilon = 1; "
              f"events in the same samples: {same}, largest drop difference {dd:.1%}; "
              f"mu_star difference {(mi - ma) / np.hypot(si, sa):+.3f} combined SE", flush=True)
        if not args.no_eps2:
            print(f"# epsilon = 1 implicit costs {wi / res[(1e-2, 'implicit')][0]:.2f}x the epsilon = 1e-2 implicit run "
                  f"and {wi / res[(1e-2, other)][0]:.2f}x the epsilon = 1e-2 {other} run", flush=True)


if __name__ == "__main__":
    main()

"""Issue 27: the implicit stepper's two conjugate-gradient preconditioners on the slab, side by side.

``krylov_preconditioner = 'jacobi'`` (the default) against ``'additive'`` (by site: Jacobi on the
contact blocks, the body's exact Fourier inverse on the free ones; implicit.SlabSystem.precondition)
at the low load where the slab's backward-Euler solves are dearest (the fig6-3d-eps1 point: epsilon = 1,
eta_c = 0.1 omega0, v_d = v0, steady start, N_L = 5, 1-ms samples). Each case runs once to compile,
then ``--repeat`` times alternating the two (so a background load drifts over both alike); prints
per preconditioner the wall time, the backward-Euler tries, Newton and conjugate-gradient iterations
per solve, mu_star and the energy balance, and the wall-time ratio.

    .venv/bin/python benchmarks/bench_preconditioner.py [--L 64] [--theta 0.05] [--t 0.1] [--repeat 2]
    .venv/bin/python benchmarks/bench_preconditioner.py --tester 0.95 --t-ramp 0.05 --L 16 --t 0.06 --repeat 1

``--tester MU_A``: the tester's block instead (issue 29: slab H = 50 a of the default compound at 20 °C,
the tester's top mass, the hanging weight MU_A raised from rest over ``--t-ramp`` s; dt = 5e-8 s).
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from slipchain import run
from slipchain.engine.backends import compose, implicit

COUNTS: list[tuple[int, int]] = []
_REAL = implicit.krylov_be_try


def _counting(*args, **kwargs):
    its, n_cg = _REAL(*args, **kwargs)
    COUNTS.append((its, n_cg))
    return its, n_cg


def _cpu() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def _result(ds) -> str:
    if "velocity" in ds.attrs:  # the dead weight: the plate's mean velocity over the run
        x = ds.X_mean.values
        return f"plate advance {x[-1] - x[0]:.6e} m"
    return f"mu_star {float(ds.attrs['mu_star']):.6f}"


def alternating(cfg: dict, key: str, values, repeat: int, short: dict) -> tuple[dict, dict]:
    """Run ``cfg`` with ``key`` at each of ``values``: once each with ``short`` (to compile), then
    ``repeat`` times alternating; returns the wall times per value and its last (dataset, backward-Euler
    tries' (Newton, conjugate-gradient) iterations)."""
    for value in values:
        run(dict(cfg, **{key: value}, **short))
    walls: dict = {v: [] for v in values}
    last: dict = {}
    for _ in range(repeat):
        for value in values:
            COUNTS.clear()
            t0 = time.perf_counter()
            ds = run(dict(cfg, **{key: value}))
            walls[value].append(time.perf_counter() - t0)
            last[value] = (ds, np.array(COUNTS).reshape(-1, 2))
    return walls, last


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--L", type=int, default=64)
    ap.add_argument("--theta", type=float, default=0.05)
    ap.add_argument("--t", type=float, default=0.1, help="simulated seconds")
    ap.add_argument("--v-d", type=float, default=1e-3)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--tester", type=float, default=None, metavar="MU_A", help="the tester's block under weight MU_A")
    ap.add_argument("--t-ramp", type=float, default=0.3)
    args = ap.parse_args()
    compose.implicit.krylov_be_try = _counting
    cfg = dict(geometry="slab", N=args.L, Ly=args.L, N_L=5, theta=args.theta, eta_c=1e5, v_d=args.v_d, start="steady",
               dt=1e-7, epsilon=1.0, seed=0, output_interval=1e-3, t_total=args.t, integrator="implicit")
    if args.tester is not None:
        cfg.update(N_L=50, material="prony", temperature=20.0, dead_weight=args.tester, top_mass="tester", start="rest",
                   t_ramp=args.t_ramp, dt=5e-8)
    names = ("jacobi", "additive")
    short = dict(t_total=2e-3, t_ramp=1e-3) if args.tester is not None else dict(t_total=2e-3)
    walls, last = alternating(cfg, "krylov_preconditioner", names, args.repeat, short)
    what = (f"the tester's block, mu_a = {args.tester}, ramp {args.t_ramp} s" if args.tester is not None
            else f"v_d = {args.v_d:g}")
    print(f"{_cpu()}; slab {args.L} x {args.L}, theta = {args.theta}, {what}, "
          f"{args.t} s simulated, {args.repeat} alternating repeats")
    for name in names:
        ds, its = last[name]
        newton = int(np.abs(its[:, 0]).sum())
        print(f"{name:9s} wall {np.mean(walls[name]):8.2f} s (runs {', '.join(f'{w:.2f}' for w in walls[name])}); "
              f"tries {its.shape[0]}, Newton {newton}, CG/solve {its[:, 1].sum() / max(newton, 1):.2f}; "
              f"{_result(ds)}; energy {float(ds.attrs['check_energy_balance']):.2e}")
    print(f"jacobi / additive wall: {np.mean(walls['jacobi']) / np.mean(walls['additive']):.2f}x")


if __name__ == "__main__":
    main()

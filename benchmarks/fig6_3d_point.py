"""Fig. 6's point in 3-D at the physical contact stiffness, as the fig6-3d-eps1 presets run it (epsilon = 1, N_L = 5,
eta_c = 0.1 omega0, steady start, seed 0): the command-line arguments and the config, shared by the benchmarks that
time one such point (bench_trbdf2.py, bench_output_interval.py)."""

from __future__ import annotations

import argparse


def add_point_arguments(ap: argparse.ArgumentParser, *, L: int, theta: float, t: float) -> None:
    """--geometry, --L, --theta, --v-d, --t (simulated seconds) and --dt, with these defaults for L, theta and t."""
    ap.add_argument("--geometry", default="slab", choices=["slab", "halfspace", "chain2d"])
    ap.add_argument("--L", type=int, default=L)
    ap.add_argument("--theta", type=float, default=theta)
    ap.add_argument("--v-d", type=float, default=1e-3)
    ap.add_argument("--t", type=float, default=t, help="simulated seconds")
    ap.add_argument("--dt", type=float, default=1e-7, help="base step (s); the fig6-3d-eps1 presets take 5e-8 at v_d1, theta <= 0.2")


def point_config(args: argparse.Namespace) -> dict:
    """The point's config (without stepper, output interval or length) on an --L x --L interface."""
    return dict(geometry=args.geometry, N=args.L, Ly=args.L, N_L=5, theta=args.theta, eta_c=1e5, v_d=args.v_d,
                start="steady", dt=args.dt, epsilon=1.0, seed=0)

"""Issue 29, a pilot: the tester's top on a thick viscoelastic slab, pulled by a dead weight.

A slab of thickness H = 50 a (the tester's ~0.5 cm block) on an L x L interface, epsilon = 1 (or
``--epsilon``), the
default compound at 20 °C, the implicit stepper, its rigid top carrying the tester's load and hanging
weight (``top_mass = "tester"``: (1 + mu_a) p0 a**2 / g per block, p0 = theta p_theta1; p_theta1 absent
is epsilon tau_f, the model's own normal stress), from rest, the weight applied over ``--ramp`` seconds
(one output sample: at once, as the tester does). Prints the top's mass, the wall time, the velocity
classification and the plate's velocity every 10 ms.

    .venv/bin/python benchmarks/tester_pilot.py --L 16 --mu-a 0.6 --theta 0.5 --t 0.3
    .venv/bin/python benchmarks/tester_pilot.py --L 16 --mu-a 0.6 --theta 0.5 --t 0.6 --ramp 0.2
    .venv/bin/python benchmarks/tester_pilot.py --L 16 --mu-a 0.6 --theta 0.5 --t 0.1 --p-theta1 1e5
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from slipchain import make_config, run


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--L", type=int, default=16)
    ap.add_argument("--mu-a", type=float, default=0.6)
    ap.add_argument("--theta", type=float, default=0.5)
    ap.add_argument("--t", type=float, default=0.3, help="simulated seconds")
    ap.add_argument("--ramp", type=float, default=1e-3, help="the weight's ramp (s); one sample: at once")
    ap.add_argument("--p-theta1", type=float, default=None, help="Pa at theta = 1 (absent: epsilon tau_f)")
    ap.add_argument("--epsilon", type=float, default=1.0)
    args = ap.parse_args()
    extra = {} if args.p_theta1 is None else {"p_theta1": args.p_theta1}
    cfg = make_config(geometry="slab", N=args.L, Ly=args.L, N_L=50, epsilon=args.epsilon, material="prony",
                      integrator="implicit", dt=1e-7, seed=0, theta=args.theta, dead_weight=args.mu_a,
                      top_mass="tester", start="rest", output_interval=1e-3, t_total=args.t, t_ramp=args.ramp, **extra)
    print(f"# {platform.processor() or platform.machine()}; {args.L} x {args.L}, H = 50 a, epsilon = {args.epsilon:g}, "
          f"mu_a = {args.mu_a:g}, "
          f"theta = {args.theta:g}, ramp {args.ramp:g} s: top {cfg.upper_mass:.3g} kg per block "
          f"({cfg.upper_mass / cfg.m:.3g} m), p0 = {cfg.p_nominal:.3g} Pa", flush=True)
    t0 = time.perf_counter()
    ds = run(cfg, progress=False)
    wall = time.perf_counter() - t0
    a = ds.attrs
    v = np.gradient(ds.X_mean.values, ds.time.values)
    print(f"wall {wall:.1f} s; {a['velocity_status']}: velocity {a['velocity']:.3g} m/s ({a.get('velocity_reason', '')}); "
          f"energy balance {a['check_energy_balance']:.2e}")
    print("plate velocity every 10 ms (m/s):", np.array2string(v[::10], precision=3))


if __name__ == "__main__":
    main()

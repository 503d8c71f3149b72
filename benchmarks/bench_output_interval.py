"""Issue 27: the output sample's length against the implicit stepper's cost, side by side in one process.

An implicit step ends within its output sample (``implicit_plan`` in :mod:`slipchain.engine.backends.compose`), so
with 1-ms samples no step through the creep of a stick-slip cycle is longer than 1 ms, wherever accuracy would allow
more. This runs Fig. 6's point in 3-D at the physical contact stiffness (the fig6-3d-eps1 presets: epsilon = 1,
N_L = 5, eta_c = 0.1 omega0, steady start) on an ``--L`` x ``--L`` slab or chain2d at load ``--theta`` and drive
velocity ``--v-d`` for ``--t`` simulated seconds, once per ``--intervals`` value (s), after a short run of each to
compile; prints per interval the wall time, the mean of f_d over the run, the energy balance and the wall-time ratio
to the first interval. (mu_star is not printed: a window of a second or two is no steady window.)

    .venv/bin/python benchmarks/bench_output_interval.py --geometry slab --theta 1 --t 1.0 --scheme trbdf2 \
        --preconditioner additive --intervals 1e-3 5e-3 2e-3
    .venv/bin/python benchmarks/bench_output_interval.py --geometry chain2d --theta 0.7 --v-d 3e-4 --t 1.5 \
        --intervals 1e-3 5e-3
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

from slipchain import run

sys.path.insert(0, str(Path(__file__).parent))
from fig6_3d_point import add_point_arguments, point_config  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    add_point_arguments(ap, L=128, theta=1.0, t=1.0)
    ap.add_argument("--scheme", default="backward-euler", choices=["backward-euler", "trbdf2", "adaptive"],
                    help="implicit_scheme of integrator 'implicit', or the explicit adaptive step")
    ap.add_argument("--preconditioner", default="jacobi", choices=["jacobi", "additive"])
    ap.add_argument("--intervals", type=float, nargs="+", default=[1e-3, 5e-3], help="output_interval values (s)")
    args = ap.parse_args()
    stepper = (dict(integrator="adaptive") if args.scheme == "adaptive" else
               dict(integrator="implicit", implicit_scheme=args.scheme, krylov_preconditioner=args.preconditioner))
    cfg = dict(point_config(args), **stepper)
    for oi in args.intervals:
        run(dict(cfg, output_interval=oi, t_total=2e-2))
    print(f"# {platform.processor() or platform.machine()}; {args.geometry} {args.L} x {args.L}, epsilon = 1, theta = "
          f"{args.theta:g}, v_d = {args.v_d:g}, dt = {args.dt:g} s, {args.scheme} ({args.preconditioner}), "
          f"{args.t:g} s simulated from the steady start")
    first = None
    for oi in args.intervals:
        t0 = time.perf_counter()
        ds = run(dict(cfg, output_interval=oi, t_total=args.t))
        wall = time.perf_counter() - t0
        first = first or wall
        print(f"output_interval {oi:8.3g} s  wall {wall:8.2f} s  mean f_d {float(ds.f_d.values.mean()):.6g} N  energy "
              f"{float(ds.attrs['check_energy_balance']):.2e}  {first / wall:.2f}x the first", flush=True)


if __name__ == "__main__":
    main()

"""Issue 27: TR-BDF2 (``implicit_scheme = 'trbdf2'``) against backward Euler (the implicit stepper's
default) and the explicit adaptive step, side by side in one process.

Fig. 6's point in 3-D at the physical contact stiffness (the fig6-3d-eps1 presets: epsilon = 1,
N_L = 5, eta_c = 0.1 omega0, steady start, dt = 1e-7 s, 1-ms samples) on an ``--L`` x ``--L`` slab or
chain2d at load ``--theta`` and drive velocity ``--v-d``, ``--t`` simulated seconds. Each variant runs once
short (to compile), then ``--repeat`` times alternating; prints per variant the mean wall time, mu_star,
the energy balance, the drive force's largest and rms difference from the adaptive step's record
(relative to its largest value) and the wall-time ratios.

    .venv/bin/python benchmarks/bench_trbdf2.py --geometry slab --L 64 --theta 0.05 --t 0.1
    .venv/bin/python benchmarks/bench_trbdf2.py --geometry chain2d --L 64 --theta 0.05 --t 0.1 --preconditioner additive
    .venv/bin/python benchmarks/bench_trbdf2.py --geometry chain2d --L 128 --theta 0.2 --v-d 1e-3 --dt 5e-8 --t 0.05 \
        --variants adaptive backward-euler   # fig6-3d-eps1-128-fast2's choice at theta = 0.2
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

from slipchain import run

sys.path.insert(0, str(Path(__file__).parent))
from fig6_3d_point import add_point_arguments, point_config  # noqa: E402

VARIANTS = {"adaptive": dict(integrator="adaptive"), "backward-euler": dict(integrator="implicit"),
            "trbdf2": dict(integrator="implicit", implicit_scheme="trbdf2")}


def main() -> None:
    ap = argparse.ArgumentParser()
    add_point_arguments(ap, L=32, theta=0.05, t=0.1)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--preconditioner", default="jacobi", choices=["jacobi", "additive"],
                    help="krylov_preconditioner of the two implicit variants")
    args = ap.parse_args()
    cfg = dict(point_config(args), output_interval=1e-3, t_total=args.t)
    if args.preconditioner != "jacobi":
        for name in VARIANTS:
            if VARIANTS[name]["integrator"] == "implicit":
                VARIANTS[name] = dict(VARIANTS[name], krylov_preconditioner=args.preconditioner)
    for name in args.variants:
        run(dict(cfg, **VARIANTS[name], t_total=4e-3))
    walls: dict = {name: [] for name in args.variants}
    last: dict = {}
    for _ in range(args.repeat):
        for name in args.variants:
            t0 = time.perf_counter()
            last[name] = run(dict(cfg, **VARIANTS[name]))
            walls[name].append(time.perf_counter() - t0)
    print(f"# {platform.processor() or platform.machine()}; {args.geometry} {args.L} x {args.L}, epsilon = 1, theta = "
          f"{args.theta:g}, v_d = {args.v_d:g}, dt = {args.dt:g} s, {args.t:g} s simulated, {args.repeat} alternating repeat(s), "
          f"krylov_preconditioner {args.preconditioner}")
    ref = last[args.variants[0]].f_d.values
    scale = np.abs(ref).max()
    for name in args.variants:
        ds, w = last[name], float(np.mean(walls[name]))
        f = ds.f_d.values
        print(f"{name:15s} wall {w:8.2f} s  mu_star {float(ds.attrs['mu_star']):.6f}  energy "
              f"{float(ds.attrs['check_energy_balance']):.2e}  f_d vs {args.variants[0]}: max "
              f"{np.abs(f - ref).max() / scale:.1e} rms {np.sqrt(np.mean((f - ref) ** 2)) / scale:.1e}  "
              + "  ".join(f"{o}/{name} {np.mean(walls[o]) / w:.2f}x" for o in args.variants if o != name))


if __name__ == "__main__":
    main()

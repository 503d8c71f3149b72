"""Issue 28: the cost of a viscoelastic run (material = 'prony', the default compound) against the
elastic one, with each stepper it runs, side by side in one process.

The Fig. 6 point theta = 1, eta_c = 0.1 omega0 at v_d1 = 1 mm/s (N = 301, epsilon = 1e-2), from the
steady start, a fixed length of simulated time:

* elastic: fixed (its default dt, 2e-8 s), fold (its default dt, 1e-7 s), adaptive (dt 1e-7 s, the
  engine's default);
* prony at 20 °C and 11 °C: fixed (2e-8 s), fold (its default dt, 1e-7 s); the adaptive step is
  refused with this material (the capability table says why);
* prony fold at the elastic fold's dt is the per-step cost of the Maxwell arms alone;
* the slab (32 x 32, H = 5 a, theta = 0.5) under the dead weight (mu_a = 0.8) and on the drive
  springs: elastic and prony at 20 °C, fold at the same dt (the arms cost one more FFT per step and
  their update; on the springs also the top's solve, mode by mode).

* ``--implicit``: the slab (32 x 32, H = 5 a, theta = 0.5) at the physical contact stiffness
  (epsilon = 1), where the implicit stepper is meant to win: fold (1e-7 s) against implicit, elastic
  and prony at 20 °C, on the drive springs (the rubber's top a state of its own) and under the dead
  weight (mu_a = 0.5), steady start.

Prints wall time (compilation excluded), wall per simulated second, the ratio to the elastic run
with the same stepper, mu_star with its SE, and the default and stable steps.

    .venv/bin/python benchmarks/bench_viscoelastic.py [--t-total 0.05] [--slab-only | --implicit]
"""

from __future__ import annotations

import argparse
import platform

from slipchain import make_config, run

REF = dict(N=301, theta=1.0, eta_c=1e5, v_d=1e-3, start="steady", seed=0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--t-total", type=float, default=0.05)
    ap.add_argument("--slab-only", action="store_true", help="only the slab's rows")
    ap.add_argument("--implicit", action="store_true", help="only the slab at epsilon = 1: fold against implicit")
    args = ap.parse_args()
    if args.implicit:
        return implicit_rows(args)
    if args.slab_only:
        return slab_rows(args)
    for extra in (dict(integrator="fixed"), dict(integrator="fold"), dict(integrator="adaptive", dt=1e-7),
                  dict(material="prony", integrator="fixed"), dict(material="prony")):  # compile
        run(make_config(N=11, theta=0.5, t_total=1e-5, **extra))
    cases = [("elastic", "fixed", dict(integrator="fixed")), ("elastic", "fold", dict(integrator="fold")),
             ("elastic", "adaptive", dict(integrator="adaptive", dt=1e-7))]
    for T in (20.0, 11.0):
        cases += [(f"prony {T:g} °C", "fixed", dict(material="prony", temperature=T, integrator="fixed")),
                  (f"prony {T:g} °C", "fold", dict(material="prony", temperature=T))]
    print(f"# {platform.processor() or platform.machine()}; N = 301, theta = 1, eta_c = 0.1 omega0, v_d = 1 mm/s, "
          f"steady start, {args.t_total:g} s simulated")
    print("| material | stepper | dt (s) | stable dt (s) | wall (s) | wall per simulated s | x elastic, same stepper "
          "| mu_star | SE |")
    print("|---|---|---|---|---|---|---|---|---|")
    elastic = {}
    for material, stepper, extra in cases:
        cfg = make_config(**REF, t_total=args.t_total, **extra)
        a = run(cfg).attrs
        w = a["wall_time_s"]
        if material == "elastic":
            elastic[stepper] = w
        ratio = w / elastic[stepper] if stepper in elastic else float("nan")
        print(f"| {material} | {stepper} | {cfg.dt:g} | {cfg.dt_stable:.3g} | {w:.2f} | {w / a['t_total']:.1f} | "
              f"{ratio:.2f} | {a['mu_star']:.4f} | {a['mu_star_sem']:.4f} |", flush=True)
    slab_rows(args)


def slab_rows(args) -> None:
    slab = dict(geometry="slab", N=32, Ly=32, theta=0.5, start="steady", integrator="fold", dt=1e-7,
                t_total=args.t_total / 10, seed=0)
    drives = {"dead weight": dict(dead_weight=0.8), "drive springs": {}}
    for kw in drives.values():  # compile
        run(make_config(**{**slab, "N": 4, "Ly": 4, "t_total": 1e-5}, **kw))
        run(make_config(**{**slab, "N": 4, "Ly": 4, "t_total": 1e-5}, **kw, material="prony"))
    print("| slab 32 x 32 | material | dt (s) | stable dt (s) | wall (s) | wall per simulated s | x elastic |")
    for drive, kw in drives.items():
        base = None
        for material in ("elastic", "prony"):
            cfg = make_config(**slab, **kw, **({"material": "prony"} if material == "prony" else {}))
            ds = run(cfg)
            w = ds.attrs["wall_time_s"]
            base = base or w
            print(f"| {drive} | {material} | {cfg.dt:g} | {cfg.dt_stable:.3g} | {w:.2f} | {w / ds.attrs['t_total']:.1f} | "
                  f"{w / base:.2f} |", flush=True)


def implicit_rows(args) -> None:
    slab = dict(geometry="slab", N=32, Ly=32, theta=0.5, start="steady", dt=1e-7, epsilon=1.0, t_total=args.t_total,
                seed=0)
    drives = {"drive springs": {}, "dead weight": dict(dead_weight=0.5)}
    for kw in drives.values():  # compile
        for integrator in ("fold", "implicit"):
            for mat in ({}, {"material": "prony"}):
                run(make_config(**{**slab, "N": 4, "Ly": 4, "t_total": 1e-4}, **kw, **mat, integrator=integrator))
    print(f"# {platform.processor() or platform.machine()}; slab 32 x 32, H = 5 a, theta = 0.5, epsilon = 1, "
          f"steady start, {args.t_total:g} s simulated")
    print("| drive | material | stepper | wall (s) | wall per simulated s | implicit / fold | energy residual |")
    print("|---|---|---|---|---|---|---|")
    for drive, kw in drives.items():
        for material in ("elastic", "prony"):
            walls = {}
            for integrator in ("fold", "implicit"):
                cfg = make_config(**slab, **kw, integrator=integrator,
                                  **({"material": "prony"} if material == "prony" else {}))
                a = run(cfg).attrs
                walls[integrator] = w = a["wall_time_s"]
                ratio = f"{w / walls['fold']:.3f}" if integrator == "implicit" else ""
                print(f"| {drive} | {material} | {integrator} | {w:.2f} | {w / a['t_total']:.1f} | {ratio} | "
                      f"{a['check_energy_balance']:.1e} |", flush=True)


if __name__ == "__main__":
    main()

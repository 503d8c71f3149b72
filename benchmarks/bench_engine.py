"""Engine benchmark (issue 2): reference-point wall time, ns per block-step, ratio to solve_ivp.

1. Reference point: N = 301, theta = 1, eta_c = 0.1 omega0, v_d = v0, default (automatic) run
   length; wall time of ``slipchain.run``, median of ``--repeat`` runs (compilation excluded).
2. ns per block-step (2N blocks per step) at theta = 0.1, 0.5, 1, timed over 2 ms of steady
   sliding after 4 ms of warm-up.
3. The same problem over a short window (``--window`` seconds from the steady start) with
   scipy.integrate.solve_ivp, BDF and LSODA with the Jacobian's sparsity pattern (what a typical
   Python user would write). Accuracy is matched: both are compared with a tight Radau solution
   (analytic Jacobian, rtol 1e-10) and solve_ivp's rtol is the loosest of 1e-3..1e-9 whose
   error in f_d is no larger than the kernel's at the default dt. Ratios are taken in this run.

    .venv/bin/python benchmarks/bench_engine.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from slipchain import build_system, initial_state, make_config, run, simulate
from slipchain.engine.backends import Batch, get_backend
from slipchain.engine.reference import reference_fd

REF = dict(N=301, theta=1.0, eta_c=1e5, v_d=1e-3, integrator="fixed", dt=2e-8)  # the fixed-step kernel (issue 26: no longer the default)


def reference_point(repeat: int) -> None:
    run(make_config(N=11, theta=0.5, t_total=1e-5, integrator="fixed"))  # compile
    walls, mus = [], []
    for _ in range(repeat):
        ds = run(make_config(**REF))
        walls.append(ds.attrs["wall_time_s"])
        mus.append((ds.attrs["mu_star"], ds.attrs["mu_star_sem"], ds.attrs["t_total"], ds.attrs["steps"]))
    mu, se, t, steps = mus[0]
    print(f"reference point: wall {statistics.median(walls):.2f} s median of {repeat} ({', '.join(f'{w:.2f}' for w in walls)}); "
          f"mu_star = {mu:.4f} ± {se:.4f}, simulated {t * 1e3:.1f} ms = {steps} steps, "
          f"{statistics.median(walls) / steps / (2 * REF['N']) * 1e9:.2f} ns per block-step overall")


def ns_per_block_step() -> dict[float, float]:
    out = {}
    backend = get_backend("cpu")
    for theta in (0.1, 0.5, 1.0):
        cfg = make_config(**{**REF, "theta": theta}, start="steady")
        s = build_system(cfg)
        batch = Batch.pack([s], [initial_state(s)])
        backend.advance(batch, 400, cfg.sample_steps)  # 4 ms warm-up
        n = 200
        t0 = time.perf_counter()
        backend.advance(batch, n, cfg.sample_steps)
        wall = time.perf_counter() - t0
        out[theta] = wall / (n * cfg.sample_steps * 2 * cfg.N) * 1e9
        print(f"theta = {theta:.1f}: {out[theta]:.2f} ns per block-step")
    return out


def versus_solve_ivp(window: float) -> None:
    interval = window / 10
    cfg = make_config(**REF, start="steady", t_total=window, output_interval=interval)
    system = build_system(cfg)
    state = initial_state(system)
    t0 = time.perf_counter()
    fd_ref, _ = reference_fd(system, state, interval, 10, method="Radau", rtol=1e-10)
    t_radau = time.perf_counter() - t0
    t0 = time.perf_counter()
    fd_k = simulate(system).f_d.values
    t_kernel = time.perf_counter() - t0
    err_k = np.max(np.abs(fd_k - fd_ref))
    scale = np.max(np.abs(fd_ref))
    print(f"window {window * 1e6:.0f} us, N = 301, theta = 1: tight Radau reference took {t_radau:.1f} s")
    print(f"kernel (dt = {cfg.dt:g}): {t_kernel * 1e3:.1f} ms, max |f_d error| = {err_k:.2e} N ({err_k / scale:.1e} of max f_d)")
    for method in ("BDF", "LSODA"):
        chosen = None
        for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9):
            t0 = time.perf_counter()
            try:
                fd_i, res = reference_fd(system, state, interval, 10, method=method, rtol=rtol, analytic_jacobian=False)
            except RuntimeError as e:
                print(f"  {method} rtol={rtol:g}: failed ({e})")
                continue
            wall = time.perf_counter() - t0
            err = np.max(np.abs(fd_i - fd_ref))
            print(f"  {method} rtol={rtol:g}: {wall:.2f} s, error {err:.2e} N, nfev {res.nfev}")
            if err <= err_k:
                chosen = (rtol, wall, err)
                break
        if chosen:
            print(f"{method} at rtol {chosen[0]:g} (error no larger than the kernel's at dt = {cfg.dt:g}): "
                  f"{chosen[1]:.2f} s -> kernel is {chosen[1] / t_kernel:.0f}x faster")
            # solve_ivp's loosest tolerance may already be more accurate than the kernel: refine the
            # kernel's dt until it is at least as accurate, and compare at that dt too.
            dt = cfg.dt
            while dt > cfg.dt / 256:
                dt /= 2
                t0 = time.perf_counter()
                fd_f = simulate(build_system(cfg.with_updates(dt=dt))).f_d.values
                t_f = time.perf_counter() - t0
                err_f = np.max(np.abs(fd_f - fd_ref))
                if err_f <= chosen[2]:
                    print(f"  kernel at dt = {dt:g}: {t_f:.2f} s, error {err_f:.2e} N <= {method}'s {chosen[2]:.2e} N "
                          f"-> kernel is {chosen[1] / t_f:.0f}x faster at equal accuracy")
                    break
        else:
            print(f"{method}: no rtol down to 1e-9 matched the kernel's accuracy")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--window", type=float, default=2e-5)
    ap.add_argument("--skip-reference", action="store_true")
    args = ap.parse_args()
    ns_per_block_step()
    versus_solve_ivp(args.window)
    if not args.skip_reference:
        reference_point(args.repeat)


if __name__ == "__main__":
    main()

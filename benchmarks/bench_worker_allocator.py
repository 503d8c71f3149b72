"""Dask's worker allocator setting against glibc's defaults, on the tester's block and Fig. 6's 128 x 128 (2026-12-06).

Dask's nanny starts every worker with MALLOC_TRIM_THRESHOLD_=65536 (``distributed.nanny.pre-spawn-environ``),
which also fixes glibc's mmap threshold at 128 KiB: the slab's compiled steps, which allocate their FFTs'
results every step (about 1.3 MB at 128 x 128 with the rubber), then map and fault in fresh pages every
step. ``slipchain.sweeps.executor.dask_client`` starts its workers without it (LOCAL_WORKER_ENVIRON). This
runs the same piece of a run (a case of CASES on L x L: by default the tester's block, theta = 0.05, mu_a = 0.8
released at once, dt = 2.5e-8 s, the implicit stepper as the tester presets run it; --samples ms after --warm ms)
on a worker of slipchain's local cluster and on one of Dask's default LocalCluster, one after the other, each
alone on its core, and prints the wall per base step of each and whether the states are bit-identical.

    python benchmarks/bench_worker_allocator.py            # the tester's block, 128 x 128
    python benchmarks/bench_worker_allocator.py --L 128 --case tester fig6-slab fig6-chain2d --samples 2
    python benchmarks/bench_worker_allocator.py --L 64
"""

from __future__ import annotations

import argparse
import logging


CASES = {
    # the tester's block released at once (tester-128-long-3's theta = 0.05 member, seed 0)
    "tester": dict(geometry="slab", N_L=50, epsilon=1.0, material="prony", integrator="implicit", dt=2.5e-8,
                   eta_c=1e5, theta=0.05, dead_weight=0.8, top_mass="tester", start="rest", t_ramp=1e-3,
                   output_interval=1e-3, t_total=0.01, seed=0),
    # Fig. 6 in 3-D at epsilon = 1 (fig6-3d-eps1-128): the slab's and the 2-D chains' dearest members
    "fig6-slab": dict(geometry="slab", N_L=5, epsilon=1.0, integrator="implicit", start="steady", eta_c=1e5,
                      output_interval=1e-3, theta=0.05, v_d=1e-3, dt=5e-8, t_total=0.01, seed=0),
    "fig6-chain2d": dict(geometry="chain2d", N_L=5, epsilon=1.0, integrator="implicit", start="steady", eta_c=1e5,
                         output_interval=1e-3, theta=0.5, v_d=1e-3, dt=1e-7, t_total=0.01, seed=0),
    # the same 2-D chains with the adaptive step (explicit steps only; benchmarks/heap_bits.py)
    "chain2d-adaptive": dict(geometry="chain2d", N_L=5, epsilon=1.0, integrator="adaptive", start="steady", eta_c=1e5,
                             output_interval=1e-3, theta=0.5, v_d=1e-3, dt=1e-7, t_total=0.01, seed=0),
}


def piece(case: str, L: int, warm: int, samples: int):
    """On a worker: the case's L x L run advanced ``warm`` samples (compiles), then ``samples`` more, timed;
    returns (wall seconds, base steps, a hash of the state and the chunk's outputs, MALLOC_TRIM_THRESHOLD_)."""
    import hashlib
    import os
    import time

    import numpy as np

    from slipchain.engine.backends import Batch, compose
    from slipchain.model.config import make_config
    from slipchain.model.system import build_system, initial_state

    cfg = make_config(N=L, Ly=L, **CASES[case])
    system = build_system(cfg)
    batch = Batch.pack([system], [initial_state(system)])
    compose.advance(batch, warm, cfg.sample_steps)
    t = time.perf_counter()
    out = compose.advance(batch, samples, cfg.sample_steps)
    wall = time.perf_counter() - t
    h = hashlib.sha256()
    for name in ("x", "u", "X", "U", "ysolve", "bstate", "carry"):
        h.update(np.ascontiguousarray(getattr(batch, name)).tobytes())
    for name in ("out", "acc", "cacc"):
        h.update(np.ascontiguousarray(getattr(out, name)).tobytes())
    return wall, samples * cfg.sample_steps, h.hexdigest()[:16], os.environ.get("MALLOC_TRIM_THRESHOLD_")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", choices=sorted(CASES), nargs="+", default=["tester"])
    ap.add_argument("--L", type=int, default=128)
    ap.add_argument("--warm", type=int, default=1, help="samples (ms) before the timed ones")
    ap.add_argument("--samples", type=int, default=1, help="timed samples (ms)")
    args = ap.parse_args()
    from distributed import Client, LocalCluster

    from slipchain.sweeps.executor import dask_client

    rows = []
    with dask_client(n_workers=1) as client:
        ours = [client.submit(piece, c, args.L, args.warm, args.samples, pure=False).result() for c in args.case]
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0",
                      silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
        dasks = [client.submit(piece, c, args.L, args.warm, args.samples, pure=False).result() for c in args.case]
    print(f"# {args.L} x {args.L}: {args.samples} ms after {args.warm} ms, one worker at a time")
    print("| case | worker | MALLOC_TRIM_THRESHOLD_ | base steps | wall (s) | us per base step | state |")
    print("|---|---|---|---|---|---|---|")
    for case, a, b in zip(args.case, ours, dasks):
        for name, (wall, steps, digest, trim) in (("slipchain's local cluster", a), ("Dask's default", b)):
            print(f"| {case} | {name} | {trim} | {steps} | {wall:.1f} | {wall / steps * 1e6:.0f} | {digest} |")
        rows.append(f"{case}: Dask's default / ours {b[0] / a[0]:.2f}x, bit-identical {a[2] == b[2]}")
    print("\n".join(rows))


if __name__ == "__main__":
    main()

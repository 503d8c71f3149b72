"""GPU throughput and the paper preset on the GPU (run on a machine with an NVIDIA GPU).

    pip install -e ".[gpu]"
    python benchmarks/bench_gpu.py                 # block-steps per second vs batch size, GPU and CPU
    python benchmarks/bench_gpu.py --paper         # also: slipchain reproduce --preset paper --backend gpu
    python benchmarks/bench_gpu.py --agreement     # also: a full run at the reference point on GPU and CPU

Block-steps per second = batch size * N * steps / wall time, for N = 301, theta = 1,
eta_c = 0.1 omega0, v_d = v0, steady start, 20 000 steps per launch (the first launch, which
compiles, is not timed). The CPU figure (one core, numba) is measured in the same run.
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
import time

from slipchain import build_system, initial_state, make_config
from slipchain.engine.backends import Batch, CPUBackend, get_backend

STEPS = 20_000


def throughput(backend, batch_size: int, n: int = 301) -> float:
    systems = [build_system(make_config(N=n, theta=1.0, start="steady", seed=s)) for s in range(batch_size)]
    batch = Batch.pack(systems, [initial_state(s) for s in systems])
    backend.advance(batch, 1, 100)  # compile / warm up
    t0 = time.perf_counter()
    backend.advance(batch, STEPS // 500, 500)
    return batch_size * n * STEPS / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--paper", action="store_true")
    ap.add_argument("--agreement", action="store_true")
    args = ap.parse_args()
    gpu = get_backend("gpu")
    print(f"{'batch':>6} {'GPU block-steps/s':>18} {'CPU block-steps/s (1 core)':>27}")
    cpu1 = throughput(CPUBackend(), 1)
    for b in (1, 8, 32, 128, 256, 512, 1024):
        print(f"{b:>6} {throughput(gpu, b):>18.3e} {cpu1:>27.3e}")
    if args.agreement:  # issue 6: mu_star from GPU and CPU within their standard errors over a full run
        from slipchain import run

        res = {b: run(None, backend=b) for b in ("cpu", "gpu")}
        for b, ds in res.items():
            print(f"{b}: mu_star = {ds.attrs['mu_star']:.4f} ± {ds.attrs['mu_star_sem']:.4f}, "
                  f"{ds.attrs['t_total'] * 1e3:.1f} ms simulated, {ds.attrs['wall_time_s']:.1f} s wall")
        diff = res["gpu"].attrs["mu_star"] - res["cpu"].attrs["mu_star"]
        se = (res["gpu"].attrs["mu_star_sem"] ** 2 + res["cpu"].attrs["mu_star_sem"] ** 2) ** 0.5
        print(f"difference {diff:+.4f} = {diff / se:+.2f} combined SE")
    if args.paper:
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            subprocess.run(["slipchain", "reproduce", "--preset", "paper", "--backend", "gpu", "--store", f"{d}/store",
                            "--out", f"{d}/out", "--no-progress"], check=True)
            print(f"paper preset on the GPU: {time.perf_counter() - t0:.1f} s wall")


if __name__ == "__main__":
    main()

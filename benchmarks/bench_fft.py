"""The slab drivers' FFT without scipy.fft's Python layer (engine/backends/pocketfft.py): whole runs
with scipy.fft and with :func:`slipchain.engine.backends.pocketfft.fft_module`, side by side in one
process (alternating, best of ``--repeats``), and whether they give the same bits.

Cases: the elastic slab's fixed step on 4 x 4, 8 x 8, 16 x 16 and 32 x 32 (steady start, 2 ms at
dt = 2e-8 s) and the tester's rubber block (the tester-16 presets' physics: slab, N_L = 50,
epsilon = 1, 'prony', implicit, the tester's top mass, from rest, the weight in 1 ms) on 8 x 8 and
16 x 16 over 10 ms, where the contacts keep slipping and most steps are explicit.

    .venv/bin/python benchmarks/bench_fft.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import hashlib
import platform
import time

import scipy.fft

import slipchain as sc
from slipchain.engine.backends import compose
from slipchain.engine.backends.pocketfft import fft_module

TESTER = dict(geometry="slab", N_L=50, epsilon=1.0, material="prony", integrator="implicit", dt=1e-7, seed=0,
              theta=0.5, dead_weight=0.6, top_mass="tester", start="rest", output_interval=1e-3, t_total=0.01,
              t_ramp=1e-3)


def cases():
    for L in (4, 8, 16, 32):
        yield f"slab fixed {L}x{L}, 2 ms", dict(geometry="slab", N=L, Ly=L, theta=0.5, seed=1, integrator="fixed",
                                                 dt=2e-8, start="steady", t_total=2e-3, output_interval=1e-4)
    for L in (8, 16):
        yield f"tester implicit {L}x{L}, 10 ms", dict(TESTER, N=L, Ly=L)


def timed(cfg, fft) -> tuple[float, str]:
    compose.fft_module = lambda: fft
    t = time.perf_counter()
    ds = sc.run(cfg, progress=False)
    wall = time.perf_counter() - t
    return wall, hashlib.sha256(ds.f_d.values.tobytes() + ds.x.values.tobytes()).hexdigest()[:12]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    direct = fft_module()
    print(f"# {platform.processor() or platform.machine()}, scipy {scipy.__version__}, direct: {type(direct).__name__}")
    print(f"{'case':32s} {'scipy.fft [s]':>14s} {'direct [s]':>11s} {'ratio':>6s}  same bits")
    for name, cfg in cases():
        timed(dict(cfg, t_total=2 * cfg["output_interval"]), direct)  # compile or load the loop
        best = {"scipy": float("inf"), "direct": float("inf")}
        bits = {}
        for _ in range(args.repeats):
            for key, fft in (("scipy", scipy.fft), ("direct", direct)):
                wall, bits[key] = timed(cfg, fft)
                best[key] = min(best[key], wall)
        print(f"{name:32s} {best['scipy']:14.3f} {best['direct']:11.3f} {best['scipy'] / best['direct']:6.2f}  "
              f"{bits['scipy'] == bits['direct']}", flush=True)


if __name__ == "__main__":
    main()

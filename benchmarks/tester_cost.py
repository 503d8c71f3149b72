"""Issue 29: what a simulated second of the tester's block costs at each interface size, with the explicit
steps compiled (compose.fft_chunk_driver, compose.krylov_explicit_driver) and with the per-step Python drivers
they replaced, from the same state in one process (``bench_fft_chunk.compare``: the two must give the same bits).

The block as the tester presets build it: a slab H = 50 a of the default compound at 20 °C on an L x L
interface, epsilon = 1, eta_c = 0.1 omega0, the tester's top mass, theta = 1, mu_a = 0.95 applied within
1 ms, from rest, dt = 1e-7 s; its first 5 ms (20 samples of 0.25 ms: the weight's pull and the top's
ringing, where even the implicit stepper takes explicit steps, so an upper bound on what a creeping run
costs), the fold step and the implicit stepper. Prints seconds of wall per simulated second and the ratio.

    python benchmarks/tester_cost.py                 # 16, 32, 64, 128: about 10 minutes on one core here
    python benchmarks/tester_cost.py --sizes 16 32   # a quicker look
"""

from __future__ import annotations

import argparse
import platform
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from bench_fft_chunk import N_SAMPLES, compare  # noqa: E402

from slipchain.engine.backends import compose  # noqa: E402
from slipchain.model.config import make_config  # noqa: E402

INTERVAL = 2.5e-4


def tester_config(L: int, **overrides):
    """The tester's block on an L x L interface (module docstring), its first N_SAMPLES samples of INTERVAL."""
    cfg = dict(geometry="slab", N=L, Ly=L, N_L=50, epsilon=1.0, material="prony", integrator="fold", dt=1e-7,
               eta_c=1e5, theta=1.0, dead_weight=0.95, top_mass="tester", start="rest", t_ramp=1e-3,
               output_interval=INTERVAL, t_total=N_SAMPLES * INTERVAL, seed=0)
    return make_config(**{**cfg, **overrides})


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[16, 32, 64, 128])
    args = ap.parse_args()
    t_sim = N_SAMPLES * INTERVAL
    print(f"# {platform.processor() or platform.machine()}: the tester's block, theta = 1, mu_a = 0.95 at once, "
          f"first {t_sim * 1e3:g} ms; wall seconds per simulated second (best of 1 after a warm-up run)", flush=True)
    for L in args.sizes:
        for integrator, driver in (("fold", compose.fft_advance), ("implicit", compose.krylov_implicit_advance)):
            same, py, co, steps = compare(tester_config(L, integrator=integrator), driver, 1)
            print(f"{L:4d} x {L:<4d} {integrator:8s} ({steps} base steps): bit-identical {same}; Python driver "
                  f"{py / t_sim:8.0f} s/s, compiled {co / t_sim:8.0f} s/s ({py / co:.2f}x)", flush=True)


if __name__ == "__main__":
    main()

"""Issue 29: where a compiled step of the tester's block goes, by part: the block with the rubber ('prony') and
elastic, at theta = 1 (every site carries a contact) and 0.05 (few do), the fold step compiled whole
(compose.fft_advance), the first 5 ms from rest with the weight at once, best of two. The elastic block at
theta = 0.05 is about the FFT pair's floor; theta = 1 adds the contacts' solve; the rubber adds its arms
(their sum, and a second row in the batched FFT pair for their force L_c g).

    python benchmarks/tester_step_parts.py 16
    python benchmarks/tester_step_parts.py 64
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from bench_fft_chunk import N_SAMPLES, best_time  # noqa: E402
from tester_cost import tester_config  # noqa: E402

from slipchain.engine.backends import compose  # noqa: E402


def main() -> None:
    L = int(sys.argv[1])
    for material in ("prony", "elastic"):
        for theta in (1.0, 0.05):
            cfg = tester_config(L, material=material, theta=theta)
            us = best_time(cfg, compose.fft_advance, 2)[2] / (N_SAMPLES * cfg.sample_steps) * 1e6
            print(f"{L}x{L} {material:8s} theta {theta}: {us:.1f} us/step, {us * 1e3 / (L * L):.0f} ns/site", flush=True)


if __name__ == "__main__":
    main()

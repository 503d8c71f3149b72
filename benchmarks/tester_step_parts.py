"""Issue 29: where a compiled step of the tester's block goes, by part: the block with the rubber ('prony') and
elastic, at theta = 1 (every site carries a contact) and 0.05 (few do), the fold step compiled whole
(compose.fft_advance), the first 5 ms from rest with the weight at once, best of two. The elastic block at
theta = 0.05 is about the FFT pair's floor; theta = 1 adds the contacts' solve; the rubber adds its arms
(their sum, and a second row in the batched FFT pair for their force L_c g).

    python benchmarks/tester_step_parts.py 16
    python benchmarks/tester_step_parts.py 64
"""
import copy, time, sys
import numpy as np
from slipchain.engine.backends import Batch, compose
from slipchain.model.config import make_config
from slipchain.model.system import build_system, initial_state
def t(cfg, reps=2):
    system = build_system(cfg); b0 = Batch.pack([system], [initial_state(system)])
    compose.fft_advance(copy.deepcopy(b0), 20, cfg.sample_steps)
    best = 1e9
    for _ in range(reps):
        b = copy.deepcopy(b0); s = time.perf_counter(); compose.fft_advance(b, 20, cfg.sample_steps); best = min(best, time.perf_counter() - s)
    return best / (20 * cfg.sample_steps) * 1e6
L = int(sys.argv[1])
base = dict(geometry="slab", N=L, Ly=L, N_L=50, epsilon=1.0, integrator="fold", dt=1e-7, eta_c=1e5, dead_weight=0.95,
            top_mass="tester", start="rest", t_ramp=1e-3, output_interval=2.5e-4, t_total=5e-3, seed=0)
for mat in ("prony", "elastic"):
    for theta in (1.0, 0.05):
        us = t(make_config(**base, material=mat, theta=theta))
        print(f"{L}x{L} {mat:8s} theta {theta}: {us:.1f} us/step, {us*1e3/(L*L):.0f} ns/site", flush=True)

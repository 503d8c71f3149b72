"""Every composed loop, compiled in a process and loaded from numba's cache by the next: the same bits?

    python benchmarks/jitcache_bits.py            # two processes on a fresh NUMBA_CACHE_DIR, then the table

Each case is a short run of one combination (body x stepper x drive: every loop that
``compose._loop`` and ``compose._row_loop`` build). The first process compiles every loop (and writes
the cache), the second loads them (slipchain.engine.jitcache). A run's f_d and x are hashed in each; the
table says whether the two agree and what each process took (its whole wall time: compilation, or
loading, plus the runs). The loops marked ``COMPILE_EACH_PROCESS`` are compiled in both.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time

SLAB = dict(geometry="slab", N=8, Ly=8, N_L=5)
CASES = {
    "chain fixed": dict(N=31, integrator="fixed", dt=2e-8),
    "chain adaptive": dict(N=31, integrator="adaptive", dt=2e-8),
    "chain implicit": dict(N=31, integrator="implicit", epsilon=1.0, dt=1e-7, t_total=0.05, output_interval=1e-3),
    "chain dead weight": dict(N=31, integrator="fixed", dt=2e-8, dead_weight=0.7, start="rest"),
    "chain prony fold": dict(N=31, material="prony", integrator="fold", dt=2e-8),
    "chain prony adaptive": dict(N=31, material="prony", integrator="adaptive", dt=2e-8),
    "chain prony implicit": dict(N=31, material="prony", integrator="implicit", epsilon=1.0, dt=1e-7, t_total=0.05,
                                 output_interval=1e-3),
    "chain2d implicit": dict(geometry="chain2d", N=8, Ly=8, integrator="implicit", epsilon=1.0, dt=1e-7, t_total=0.02,
                             output_interval=1e-3),
    "chain2d prony implicit": dict(geometry="chain2d", N=8, Ly=8, material="prony", integrator="implicit", epsilon=1.0,
                                   dt=1e-7, t_total=0.02, output_interval=1e-3),
    "slab fixed": dict(SLAB, integrator="fixed", dt=2e-8),
    "slab adaptive": dict(SLAB, integrator="adaptive", dt=2e-8),
    "slab implicit": dict(SLAB, integrator="implicit", epsilon=1.0, dt=1e-7, t_total=0.02, output_interval=1e-3),
    "halfspace fixed": dict(geometry="halfspace", N=8, Ly=8, integrator="fixed", dt=2e-8),
    "slab prony dead weight fold": dict(SLAB, material="prony", integrator="fold", dt=5e-8, dead_weight=0.7, start="rest"),
    "slab prony dead weight adaptive": dict(SLAB, material="prony", integrator="adaptive", dt=2e-8, dead_weight=0.7,
                                            start="rest"),
    "slab prony springs fold": dict(SLAB, material="prony", integrator="fold", dt=5e-8),
    "slab prony springs adaptive": dict(SLAB, material="prony", integrator="adaptive", dt=2e-8),
    "slab prony springs implicit": dict(SLAB, material="prony", integrator="implicit", epsilon=1.0, dt=1e-7,
                                        t_total=0.02, output_interval=1e-3),
}
COMMON = dict(theta=0.5, start="steady", t_total=2e-3, output_interval=1e-4, seed=1)


def probe() -> None:
    from slipchain import make_config, run

    out = {}
    for name, kw in CASES.items():
        ds = run(make_config(**{**COMMON, **kw}), progress=False)
        out[name] = hashlib.sha256(ds.f_d.values.tobytes() + ds.x.values.tobytes()).hexdigest()[:16]
    print(json.dumps(out))


def main() -> None:
    if sys.argv[1:] == ["--probe"]:
        probe()
        return
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        runs, walls = [], []
        for _ in range(2):
            t0 = time.perf_counter()
            r = subprocess.run([sys.executable, __file__, "--probe"], capture_output=True, text=True, env=env, check=True)
            walls.append(time.perf_counter() - t0)
            runs.append(json.loads(r.stdout.strip().splitlines()[-1]))
    print(f"first process (compiles, fills the cache): {walls[0]:.1f} s; second (loads): {walls[1]:.1f} s\n")
    print("| case | first process | second process | same bits |\n|---|---|---|---|")
    for name in CASES:
        a, b = runs[0][name], runs[1][name]
        print(f"| {name} | {a} | {b} | {'yes' if a == b else '**no**'} |")
    sys.exit(0 if runs[0] == runs[1] else 1)


if __name__ == "__main__":
    main()

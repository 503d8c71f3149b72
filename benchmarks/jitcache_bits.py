"""Every composed loop, compiled in a process and loaded from numba's cache by the next: the same bits?

    python benchmarks/jitcache_bits.py            # three processes on fresh NUMBA_CACHE_DIRs, then the table

Each case is a short run of one combination (body x stepper x drive: every loop that
``compose._loop`` and ``compose._row_loop`` build). The first process compiles every loop (and writes
the cache), the second loads them (slipchain.engine.jitcache); a third, on another fresh cache, runs the
cases in reverse order (each loop compiled after other loops have filled the cache: a loop's bits must
not depend on what the cache held when it was compiled). A run's f_d and x are hashed in each; the
table says whether the two agree and what each process took (its whole wall time: compilation, or
loading, plus the runs). Every loop is compiled by a fresh process and loaded, in every process (since
2026-11-27 the chain's implicit stepper with the elastic body too, which was compiled in each).
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


def probe(reverse: bool = False) -> None:
    from slipchain import make_config, run

    out = {}
    for name, kw in (reversed(CASES.items()) if reverse else CASES.items()):
        ds = run(make_config(**{**COMMON, **kw}), progress=False)
        out[name] = hashlib.sha256(ds.f_d.values.tobytes() + ds.x.values.tobytes()).hexdigest()[:16]
    print(json.dumps(out))


def main() -> None:
    if sys.argv[1:2] == ["--probe"]:
        probe(sys.argv[2:] == ["--reverse"])
        return
    runs, walls = [], []
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as other:
        for directory, flags in ((cache, []), (cache, []), (other, ["--reverse"])):
            t0 = time.perf_counter()
            r = subprocess.run([sys.executable, __file__, "--probe", *flags], capture_output=True, text=True,
                               env={**os.environ, "NUMBA_CACHE_DIR": directory}, check=True)
            walls.append(time.perf_counter() - t0)
            runs.append(json.loads(r.stdout.strip().splitlines()[-1]))
    print(f"first process (compiles, fills the cache): {walls[0]:.1f} s; second (loads): {walls[1]:.1f} s; "
          f"third (another cache, the cases in reverse order: compiles): {walls[2]:.1f} s\n")
    print("| case | first process | second process | third process | same bits |\n|---|---|---|---|---|")
    for name in CASES:
        a, b, c = runs[0][name], runs[1][name], runs[2][name]
        print(f"| {name} | {a} | {b} | {c} | {'yes' if a == b == c else '**no**'} |")
    sys.exit(0 if runs[0] == runs[1] == runs[2] else 1)


if __name__ == "__main__":
    main()

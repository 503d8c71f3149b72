"""What a clean clone pays to compile the composed loops: one tiny run per geometry x stepper x material x
drive, in order, on an empty numba cache; a cell's time is the compile of the loops it is the first to
need (each in a fresh process, slipchain.engine.jitcache) plus a 0.2-ms run.

    python benchmarks/compile_loops.py     # about 5 minutes on one core here; prints one line per cell

epsilon = 1 throughout, so 'fixed' is run as 'fold' (the fixed stepper with the fold-aware contacts; the
plain fixed step is refused at this stiffness) and the adaptive step takes no level above dt (its loop
is the fixed one). Measured 2026-11-27 (docs/performance.md, "The suite's time: commands in the
test's process"). The cache is a fresh temporary directory, removed at the end.
"""

from __future__ import annotations

import itertools
import os
import shutil
import tempfile
import time

CACHE = tempfile.mkdtemp(prefix="slipchain-compile-")
os.environ["NUMBA_CACHE_DIR"] = CACHE  # before numba is imported

from slipchain import make_config, run  # noqa: E402


def main() -> None:
    base = dict(theta=1.0, epsilon=1.0, eta_c=1e5, v_d=1e-3, seed=0, t_total=2e-4, output_interval=1e-5, N=8, dt=1e-7)
    total = 0.0
    for geo, integ, mat, drive in itertools.product(["chain", "chain2d", "slab", "halfspace"],
                                                    ["fold", "adaptive", "implicit"], ["elastic", "prony"],
                                                    ["springs", "dead"]):
        if geo == "halfspace" and drive == "dead":
            continue  # the half-space has no plate to carry a weight (model.capabilities)
        kw = dict(base, geometry=geo, integrator="fold" if (mat == "prony" and integ == "adaptive") else integ,
                  material=mat, **({} if geo == "chain" else {"Ly": 8}), **({"N_L": 5} if geo == "slab" else {}))
        kw.update(dict(dead_weight=0.3, start="rest") if drive == "dead" else dict(start="steady"))
        t = time.perf_counter()
        run(make_config(**kw), progress=False)
        dt = time.perf_counter() - t
        total += dt
        print(f"{dt:6.1f} s  {geo:9s} {kw['integrator']:8s} {mat:7s} {drive}", flush=True)
    print(f"{total:6.1f} s  in all")
    shutil.rmtree(CACHE, ignore_errors=True)


if __name__ == "__main__":
    main()

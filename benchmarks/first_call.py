"""What a process pays on its first run when numba's cache already holds every composed loop: the helpers that
the Python drivers call (compiled in each process; none is cached on its own, slipchain.engine.jitcache).

    python benchmarks/first_call.py            # about two minutes here: fills a fresh cache, then a process per case

One process fills a fresh NUMBA_CACHE_DIR with every case's loops; then each case runs in a fresh process on
that cache: ``import slipchain``, a first 2-ms run, the same run again (its difference from the first is what
the process compiled), and the helpers that numba's compile events name, slowest first. Measured 2026-12-02
(docs/performance.md, "The suite on the AVX2 machine again"). The cache is removed at the end.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile

SHORT = dict(theta=0.5, t_total=2e-3, output_interval=1e-3)
CASES = {
    "chain fixed": dict(SHORT, N=16),
    "chain implicit": dict(SHORT, N=16, integrator="implicit", epsilon=1.0, dt=1e-7),
    "slab fixed": dict(SHORT, geometry="slab", N=8, Ly=8),
    "rubber slab implicit": dict(SHORT, geometry="slab", N=8, Ly=8, N_L=5, integrator="implicit", epsilon=1.0,
                                 dt=1e-7, material="prony"),
}

PROBE = r"""
import json, sys, time
t0 = time.perf_counter()
import slipchain as sc
from numba.core import event
t1 = time.perf_counter()
cfg = json.loads(sys.argv[1])
with event.install_recorder("numba:compile") as rec:
    sc.run(cfg, progress=False)
t2 = time.perf_counter()
sc.run(cfg, progress=False)
t3 = time.perf_counter()
start, took = {}, {}
for ts, e in rec.buffer:
    name = e.data["dispatcher"].py_func.__qualname__
    if e.is_start:
        start[name] = ts
    else:
        took[name] = ts - start.get(name, ts)
print(json.dumps(dict(imp=t1 - t0, first=t2 - t1, second=t3 - t2, helpers=sorted(took.items(), key=lambda kv: -kv[1]))))
"""


def _probe(cfg: dict, env: dict) -> dict:
    out = subprocess.run([sys.executable, "-c", PROBE, json.dumps(cfg)], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    cache = tempfile.mkdtemp(prefix="slipchain-first-call-")
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    try:
        fill = "import json, sys, slipchain as sc\nfor c in json.loads(sys.argv[1]): sc.run(c, progress=False)"
        subprocess.run([sys.executable, "-c", fill, json.dumps(list(CASES.values()))], env=env, check=True)
        print(f"{'case':24s} {'import':>7s} {'first':>7s} {'second':>7s}  helpers compiled (s)")
        for name, cfg in CASES.items():
            r = _probe(cfg, env)
            top = ", ".join(f"{h} {s:.2f}" for h, s in r["helpers"][:4])
            print(f"{name:24s} {r['imp']:7.2f} {r['first']:7.2f} {r['second']:7.2f}  {len(r['helpers'])}: {top}")
    finally:
        shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    main()

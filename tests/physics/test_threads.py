"""A run's bits do not depend on the BLAS library's thread count (slipchain.engine.threads): the same
slab run in processes started with OPENBLAS_NUM_THREADS = 1 and = 2 gives the same record. Without the
engine's limit they differ from an interface of 10 001 sites up, where OpenBLAS splits a dot product of
scipy's conjugate gradients over its threads (measured: 128 x 80 sites, 2 ms, two hashes apart; 128 x 40,
the same), so this is also a run in this process against the same run in a sweep's worker, which Dask
starts with one BLAS thread."""

import os
import subprocess
import sys

from threadpoolctl import threadpool_info

from slipchain.engine.threads import one_blas_thread

SCRIPT = """
import hashlib
import numpy as np
from slipchain import make_config, run
cfg = make_config(geometry="slab", N=128, Ly=80, N_L=5, eta_c=1e5, dt=1e-7, epsilon=1.0, theta=1.0, integrator="implicit",
                  start="steady", t_total=2e-3, output_interval=1e-3, seed=0)
ds = run(cfg, progress=False)
h = hashlib.sha256()
for k in ("X_mean", "f_d", "x_mean", "x", "X"):
    h.update(np.ascontiguousarray(ds[k].values).tobytes())
print(h.hexdigest())
"""


def test_a_run_gives_the_same_bits_on_one_blas_thread_and_on_two():
    hashes = []
    for threads in ("1", "2"):
        env = {**os.environ, "OPENBLAS_NUM_THREADS": threads}
        r = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        hashes.append(r.stdout.strip().splitlines()[-1])
    assert hashes[0] == hashes[1]


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_the_limit_holds_inside_nested_runs_and_is_lifted_after_the_last():
    """Nested runs share the limit (the outer run's holds after the inner one ends) and the process's own
    limits come back after the last. (Runs in several threads: see slipchain.engine.threads.)"""
    import numpy as np  # noqa: F401  (BLAS loaded)

    before = _blas_threads()
    with one_blas_thread():
        outer = _blas_threads()
        with one_blas_thread():
            inner = _blas_threads()
        after_inner = _blas_threads()
    assert set(outer) == set(inner) == set(after_inner) == {1}
    assert _blas_threads() == before

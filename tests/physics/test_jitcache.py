"""The composed loops are loaded from numba's on-disk cache by a second process (slipchain.engine.jitcache).

Before, their cache key held a per-process uuid of the dispatchers they close over: every process
compiled them again (and appended another entry to the cache). Here two processes share a fresh cache
directory: the first compiles, the second must load the composed loops it runs (here the chain's and the slab's fixed
step) and give the same results to the bit; the one loop marked to be compiled in each process (the chain's implicit stepper
with the elastic body, whose cached code gives other last bits) must be compiled in both.
benchmarks/jitcache_bits.py checks every composed loop the same way (too slow for the suite)."""

import json
import os
import subprocess
import sys

import numba as nb

from slipchain.engine.jitcache import StableFunctionCache, describe, stable_cache

PROBE = r"""
import hashlib, json
from slipchain import make_config, run
from slipchain.engine.backends import compose
out = {}
for name, kw, loop in [
        ("chain", dict(N=8, theta=0.5, integrator="fixed", dt=2e-8), ("chain", False)),
        ("slab", dict(geometry="slab", N=4, Ly=4, theta=0.5, integrator="fixed", dt=2e-8), ("slab", False)),
        ("chain_implicit", dict(N=8, theta=0.5, integrator="implicit", epsilon=1.0, dt=1e-7), ("chain", "implicit"))]:
    ds = run(make_config(**kw, start="steady", t_total=2e-4, output_interval=1e-5, seed=1), progress=False)
    disp = compose.loop(*loop)
    sig = disp.signatures[0]
    out[name] = dict(hits=sum(disp.stats.cache_hits.values()), misses=sum(disp.stats.cache_misses.values()),
                     key=repr(disp._cache._index_key(sig, disp.targetctx.codegen())[2]),
                     bits=hashlib.sha256(ds.f_d.values.tobytes() + ds.x.values.tobytes()).hexdigest())
print(json.dumps(out))
"""


def _probe(cache_dir):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir)}
    r = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_a_second_process_loads_the_composed_loops_and_gets_the_same_bits(tmp_path):
    first = _probe(tmp_path)
    second = _probe(tmp_path)
    assert set(first) == {"chain", "slab", "chain_implicit"}
    for name in first:
        if name == "chain_implicit":  # marked COMPILE_EACH_PROCESS (jitcache.stable_cache): compiled in both
            assert first[name]["misses"] >= 1 and second[name]["misses"] >= 1 and second[name]["hits"] == 0
            assert second[name]["bits"] == first[name]["bits"]
            continue
        assert first[name]["misses"] >= 1 and first[name]["hits"] == 0, (name, first[name])  # compiled
        assert second[name]["hits"] >= 1 and second[name]["misses"] == 0, (name, second[name])  # loaded
        assert second[name]["key"] == first[name]["key"]
        assert second[name]["bits"] == first[name]["bits"]


def _factory(callee, flag):
    @stable_cache
    @nb.njit(cache=True)
    def loop(x):
        return callee(x) if flag else -callee(x)

    return loop


@nb.njit
def _one(x):
    return x + 1.0


@nb.njit
def _two(x):
    return x + 2.0


def test_the_key_tells_closures_apart_by_callee_and_value():
    a, b, c = _factory(_one, True), _factory(_two, True), _factory(_one, False)
    assert isinstance(a._cache, StableFunctionCache)
    texts = {describe(tuple(cell.cell_contents for cell in f.py_func.__closure__)) for f in (a, b, c)}
    assert len(texts) == 3
    assert describe((_one, True)) == describe((_one, True))
    assert (a(1.0), b(1.0), c(1.0)) == (2.0, 3.0, -2.0)

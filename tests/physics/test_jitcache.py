"""A composed loop's code, and so a run's bits, do not depend on what the process compiled before nor on
what numba's on-disk cache held (slipchain.engine.jitcache).

Before, the loops' cache key held a per-process uuid of the dispatchers they close over: every process
compiled them again. With a stable key they were loaded by later processes; but a loop's compiled code
depended on what its process had compiled before (the slab's fixed-step loop compiled after the chain's
gave other f_d and x than compiled alone, and the chain's after the slab's), and the cache carried that
into every later process: the suite's test that the fold step equals the adaptive step at an
unreachable tolerance failed in a working tree whose cache a sweep had filled (the last bit of
W_contacts). Now a loop missing from the cache is compiled by a fresh process, alone, with every
callee (none is cached on its own), and loaded from the cache. Here: the slab alone on one cache, then
the chain and the slab on the same cache, then both (the chain first) on an empty one: the same key
and bits in each; with them the chain's adaptive loop, which has the fixed loop's name and argument
types (each fresh process names its functions from its own offset: the first version of this change,
without it, crashed in numba's linking when one process loaded loops of one name from two fresh
processes); and the chain's implicit stepper with the elastic body, whose loaded code differs from the
code compiled in a process (it was compiled in each process until 2026-11-27), loaded in each with the
same bits. benchmarks/jitcache_bits.py checks every composed loop (too slow for the suite)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numba as nb
from numba.core.caching import NullCache
from numba.core.dispatcher import Dispatcher

from slipchain.engine.jitcache import StableFunctionCache, describe, stable_cache

PROBE = r"""
import hashlib, json, subprocess, sys
from slipchain import make_config, run
from slipchain.engine.backends import compose
children = []  # the fresh processes this process starts to compile a loop (jitcache's subprocess.run)
real = subprocess.run
subprocess.run = lambda *a, **k: children.append(1) or real(*a, **k)
CASES = {"chain": (dict(N=8, theta=0.5, integrator="fixed", dt=2e-8), ("chain", False)),
         "slab": (dict(geometry="slab", N=4, Ly=4, theta=0.5, integrator="fixed", dt=2e-8), ("slab", False)),
         "chain_adaptive": (dict(N=8, theta=0.5, integrator="adaptive", dt=2e-8), ("chain", True)),
         "chain_implicit": (dict(N=8, theta=0.5, integrator="implicit", epsilon=1.0, dt=1e-7), ("chain", "implicit"))}
out = {}
for name in sys.argv[1:]:
    kw, loop = CASES[name]
    before = len(children)
    ds = run(make_config(**kw, start="steady", t_total=2e-4, output_interval=1e-5, seed=1), progress=False)
    # the slab's fixed step runs its whole chunk compiled (compose.fft_chunk_driver), the others the composed loop
    disp = compose._fft_chunk("spectral", False) if loop == ("slab", False) else compose.loop(*loop)
    sig = disp.signatures[0]
    out[name] = dict(hits=sum(disp.stats.cache_hits.values()), misses=sum(disp.stats.cache_misses.values()),
                     children=len(children) - before,
                     key=repr(disp._cache._index_key(sig, disp.targetctx.codegen())[2]),
                     bits=hashlib.sha256(ds.f_d.values.tobytes() + ds.x.values.tobytes()).hexdigest())
print(json.dumps(out))
"""


def _start(cache_dir, *cases):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir)}
    return subprocess.Popen([sys.executable, "-c", PROBE, *cases], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env)


def _result(proc):
    out, err = proc.communicate()
    assert proc.returncode == 0, err
    return json.loads(out.strip().splitlines()[-1])


def _probe(cache_dir, *cases):
    return _result(_start(cache_dir, *cases))


def _loaded(r):
    return r["hits"] >= 1 and r["misses"] == 0


def test_a_loop_has_the_same_bits_whatever_the_process_compiled_before_and_the_cache_held(tmp_path):
    # the suite's own cache (conftest's NUMBA_CACHE_DIR, shared by both xdist workers): these loops are compiled
    # there once for the whole suite, by whichever process needs them first; and an empty one
    shared, empty = Path(os.environ["NUMBA_CACHE_DIR"]), tmp_path / "empty"
    first = _probe(shared, "slab", "chain_implicit")  # loads these two loops, compiling those the cache lacks
    second = _probe(shared, "chain", "slab", "chain_implicit")
    # on an empty cache, the chain's loop first, then the slab's; and two loops of one name and argument
    # types (compose.kernel_driver's closure), each compiled by its own fresh process, loaded by one; beside
    # it, at the same time, a process that asks for the slab's and the chain's loops: each loop is compiled
    # once (the index's file lock), the process that waited loads it
    third, beside = _start(empty, "chain", "chain_adaptive", "slab"), _start(empty, "slab", "chain")
    third, beside = _result(third), _result(beside)
    assert _loaded(third["chain_adaptive"]) and third["chain_adaptive"]["key"] != third["chain"]["key"]
    for name in ("chain", "slab"):
        assert third[name]["children"] + beside[name]["children"] == 1, (name, third[name], beside[name])
    for name in ("chain", "slab", "chain_implicit"):
        runs = [r[name] for r in (first, second, third, beside) if name in r]
        assert all(_loaded(r) for r in runs), (name, runs)  # a miss is compiled by a fresh process, then loaded
        assert len({r["key"] for r in runs}) == 1, name  # the same key in every process
        assert len({r["bits"] for r in runs}) == 1, (name, [r["bits"][:12] for r in runs])


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


# Called from Python only, never from a compiled loop: these may keep numba's cache (their cached code is
# linked into nothing).
PYTHON_ONLY = {"scratch_arrays", "end_sample", "top_solve", "slab_prony_be_commit", "_dot", "_arm_sums"}


def _closure_dispatchers(f, seen):
    for cell in f.__closure__ or ():
        v = cell.cell_contents
        items = v if isinstance(v, tuple) else (v,)
        for d in items:
            if isinstance(d, Dispatcher) and id(d) not in seen:
                seen.add(id(d))
                yield d
                yield from _closure_dispatchers(d.py_func, seen)


def test_what_a_cached_loop_calls_is_not_cached_on_its_own():
    """The rule that keeps a loop's bits independent of the cache's content (module docstring): a compiled
    function that a loop calls (not inlined by numba) is compiled with the loop, never loaded from the cache."""
    from slipchain.engine.backends import adaptive, compose, cpu, implicit, spectral, viscoelastic

    for module in (adaptive, compose, cpu, implicit, spectral, viscoelastic):
        for name, obj in vars(module).items():
            if isinstance(obj, Dispatcher) and obj.targetoptions.get("inline") != "always":
                assert isinstance(obj._cache, NullCache) or name in PYTHON_ONLY, f"{module.__name__}.{name} is cached"
    for body in ("lattice", "lattice-prony", "spectral", "spectral-prony", "spectral-prony-top"):
        for stepper in (False, True, "implicit"):
            loop = compose._loop(body, stepper)
            assert isinstance(loop._cache, StableFunctionCache)
            for d in _closure_dispatchers(loop.py_func, set()):
                assert isinstance(d._cache, NullCache) or d.targetoptions.get("inline") == "always", (
                    body, stepper, d.py_func.__qualname__)
    # the elastic slab's fixed step, a whole chunk compiled (its FFTs in numba); the implicit stepper's explicit steps
    chunks = [compose._fft_chunk(b, a) for b in ("spectral", "spectral-prony") for a in (False, True)] + [compose._krylov_explicit(b) for b in ("spectral", "spectral-prony",
                                                                                     "lattice", "lattice-prony")]
    for chunk in chunks:
        assert isinstance(chunk._cache, StableFunctionCache)
        called = list(_closure_dispatchers(chunk.py_func, set()))
        assert any(d.py_func.__name__ == "step_rows" for d in called)
        for d in called:
            assert isinstance(d._cache, NullCache) or d.targetoptions.get("inline") == "always", d.py_func.__qualname__

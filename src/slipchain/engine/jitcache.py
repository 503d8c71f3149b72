"""numba's on-disk cache for the composed loops, with a key that is the same in every process.

numba keys a cached closure by a pickle of its cell contents (``numba.core.caching.Cache._index_key``).
The composed loops of :mod:`.backends.compose` are closures over other dispatchers (the body's explicit
part and commit, the stepper), and a dispatcher's pickle carries a uuid drawn anew in each process: so
every process missed the cache, compiled the loops again and appended one more entry to the cache
directory (47 entries of one loop were found in a working tree). Every ``slipchain run``, every Dask
worker of a sweep and every test that starts a process paid that compilation (seconds per loop).

:func:`stable_cache` gives such a dispatcher a cache whose key describes the closure by what it is:
each captured dispatcher by its module, qualified name, bytecode, compile options and (recursively) its
own closure; plain values (numbers, strings, flags) by ``repr``; and the content hash of the sources of
:mod:`slipchain.engine` and :mod:`slipchain.model`, the modules whose functions a composed loop inlines.
So an edit in any of those modules invalidates the composed loops' cache entries, which numba's own
check (the defining file's time stamp) would not see. A closure holding anything else keeps numba's key
(it is then compiled in each process, as before).

**A loop is compiled by a fresh process, alone.** LLVM optimises a loop together with the compiled
functions it calls, and with fastmath the result depended on what the process had compiled before: the
slab's fixed-step loop compiled after the chain's gave other f_d and x than compiled alone, the chain's
after the slab's likewise, and a loop compiled with a callee loaded from the cache (compiled by another
process in another context) differed again. The cache then carried those bits into every later process,
so a run's last bits depended on the history of the working tree's cache (found when the suite's test
that the fold step equals the adaptive step at an unreachable tolerance failed in a tree whose cache a
sweep had filled, in the last bit of W_contacts; a fresh clone passed). So: a loop missing from the cache
is compiled in a fresh Python process that builds only that loop (:meth:`StableFunctionCache.load_overload`,
from the recipe its factory set, ``compose._loop``) and writes it to the cache, and every process loads it
from there (each such process names its compiled functions from its own offset, or two loops of one
qualified name and argument types compiled by two processes would be linked one for the other: the
reverse-order case of ``benchmarks/jitcache_bits.py`` crashed so); and the loops' callees (samples,
bodies, the steppers' helpers, the contact solve of :mod:`slipchain.engine.scheme`) are compiled with
``cache=False``, so that the fresh process compiles them too. Only the loops, the functions numba
inlines anyway (``inline="always"``) and four functions called from Python only keep numba's cache (tests/physics/test_jitcache.py checks the rule, and that a loop has
the same bits whatever was compiled or cached before). The cost: a Python start and the import for each
loop compiled (once per cache and source version), and the callees compiled in each process that calls
them from Python (the Krylov stepper's helpers).

This leans on two numba internals, ``Dispatcher._cache`` and ``FunctionCache._index_key`` (numba 0.68, the
version requirements.lock pins); a numba that changes them makes the test above fail, not the results."""

from __future__ import annotations

import hashlib
import importlib
import itertools
import os
import pickle
import subprocess
import sys
import warnings
from functools import lru_cache
from pathlib import Path
from typing import Any

from filelock import FileLock
from numba.core.bytecode import FunctionIdentity
from numba.core.caching import FunctionCache
from numba.core.dispatcher import Dispatcher

_PLAIN = (bool, int, float, complex, str, bytes, type(None))


@lru_cache(maxsize=1)
def sources_digest() -> str:
    """sha256 of the sources of slipchain.engine and slipchain.model (paths and contents)."""
    root = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for f in sorted([*(root / "engine").rglob("*.py"), *(root / "model").rglob("*.py")]):
        h.update(f.relative_to(root).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()


class Unstable(TypeError):
    """A closure holds a value that has no process-independent description."""


def describe(obj: Any) -> str:
    """A text that is the same in every process for the same closure content (:class:`Unstable` if none)."""
    if isinstance(obj, _PLAIN):
        return repr(obj)
    if isinstance(obj, (tuple, list)):
        return f"{type(obj).__name__}({', '.join(describe(v) for v in obj)})"
    if isinstance(obj, (set, frozenset)):
        return f"set({', '.join(sorted(describe(v) for v in obj))})"
    if isinstance(obj, dict):
        return f"dict({', '.join(sorted(f'{describe(k)}: {describe(v)}' for k, v in obj.items()))})"
    if isinstance(obj, Dispatcher):
        return f"dispatcher[{describe(obj.targetoptions)}]({_function(obj.py_func)})"
    if callable(obj) and hasattr(obj, "__code__"):
        return _function(obj)
    raise Unstable(type(obj).__name__)


def _function(f) -> str:
    closure = tuple(c.cell_contents for c in f.__closure__ or ())
    return f"{f.__module__}.{f.__qualname__}:{f.__code__.co_code.hex()}:{describe(closure)}"


# Set in the process that :meth:`StableFunctionCache.load_overload` starts to compile one loop.
CHILD_ENV = "SLIPCHAIN_JIT_CHILD"


class StableFunctionCache(FunctionCache):
    """numba's FunctionCache with the process-independent closure key of the module docstring.

    ``recipe`` (module, factory, arguments), set by the factory that built the loop, lets a cache miss be
    compiled in a fresh process (:meth:`load_overload`)."""

    recipe: tuple[str, str, tuple] | None = None

    def load_overload(self, sig, target_context):
        """The cached loop; on a miss, the loop compiled for this signature in a fresh Python process
        (:func:`_compile_child`, which writes it to the cache) and loaded from there, so that its code
        does not depend on what this process compiled before (module docstring). Where that cannot be
        done (no recipe, the key is numba's own, the child failed), None: numba compiles it here.

        One process at a time compiles into an index file (a file lock beside it, held across the
        fresh process): numba's index is read, changed and written back, and a new entry's data file
        takes the first free number, so two processes adding loops of one name at once could lose an
        entry or write one loop's code under the other's number. A process that waited finds the loop
        another compiled and loads it (the Dask workers of a sweep, the suite's two workers, ask for the
        same loops at the same moment: each was compiled twice)."""
        found = super().load_overload(sig, target_context)
        if found is not None or self.recipe is None or os.environ.get(CHILD_ENV):
            return found
        if self._closure_text() is None:
            return None
        os.makedirs(self._cache_path, exist_ok=True)
        with FileLock(self._cache_file._index_path + ".lock"):
            found = super().load_overload(sig, target_context)  # compiled by another process meanwhile?
            if found is not None:
                return found
            child = subprocess.run([sys.executable, "-c",
                                    "from slipchain.engine.jitcache import _compile_child; _compile_child()"],
                                   input=pickle.dumps((self.recipe, tuple(sig))), capture_output=True,
                                   env={**os.environ, CHILD_ENV: "1"})
        if child.returncode != 0:
            warnings.warn(f"compiling {self.recipe} in a fresh process failed (exit {child.returncode}); compiled in this "
                          f"process instead, so its last bits may depend on what this process compiled before:\n"
                          f"{child.stderr.decode(errors='replace')[-2000:]}", RuntimeWarning, stacklevel=2)
            return None
        return super().load_overload(sig, target_context)

    def _closure_text(self) -> str | None:
        """:func:`describe` of the closure, None where it has no process-independent description."""
        try:
            return describe(tuple(c.cell_contents for c in self._py_func.__closure__ or ()))
        except Unstable:
            return None

    def _index_key(self, sig, codegen):
        key = super()._index_key(sig, codegen)
        text = self._closure_text()
        if text is None:
            return key  # numba's own key: compiled in each process
        closure = hashlib.sha256((text + sources_digest()).encode()).hexdigest()
        return key[0], key[1], (key[2][0], closure)


def stable_cache(dispatcher: Dispatcher) -> Dispatcher:
    """Give a ``cache=True`` closure dispatcher the process-independent key (before its first compile).
    Only the loops compiled on their own need it (compose's drivers); the ``inline="always"``
    steppers are inlined into them and never compiled, nor cached, alone.

    Every process runs the loop's cached code, compiled alone by a fresh process (module docstring), so
    a run's bits do not depend on whether its loop was compiled or loaded in this process. (The code
    loaded can differ from the same loop compiled in a process: the chain's implicit stepper with the
    elastic body by 6e-15 relative in f_d, the rubber slab under the springs likewise; that is why no
    process runs a loop it compiled itself. The chain's implicit stepper was until 2026-11-27 marked
    to be compiled in each process instead, 38 s of compiling in every process that ran it.)"""
    cache = getattr(dispatcher, "_cache", None)
    if isinstance(cache, FunctionCache) and not isinstance(cache, StableFunctionCache):
        dispatcher._cache = StableFunctionCache(dispatcher.py_func)
    return dispatcher


def _compile_child() -> None:
    """In the fresh process of :meth:`StableFunctionCache.load_overload`: build the loop from its recipe
    (read pickled from stdin with the signature) and compile it, which writes it to the cache."""
    data = sys.stdin.buffer.read()
    (module, factory, args), sig = pickle.loads(data)
    # numba names a compiled function by its qualified name, argument types and a per-process counter
    # (FunctionIdentity._unique_ids): two fresh processes would give two loops with the same qualified name
    # and types (compose's closures) the same name, and a process that loads both would link one in place of
    # the other. Each loop's process counts from its own offset, drawn from its recipe and signature.
    FunctionIdentity._unique_ids = itertools.count(10**12 * (1 + int(hashlib.sha256(data).hexdigest()[:12], 16)))
    getattr(importlib.import_module(module), factory)(*args).compile(sig)


__all__ = ["CHILD_ENV", "StableFunctionCache", "describe", "sources_digest", "stable_cache"]

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
(it is then compiled in each process, as before). Every loop so cached gives the same bits loaded as
compiled (``benchmarks/jitcache_bits.py``: all 18 loops; tests/physics/test_jitcache.py); the one loop that
did not is compiled in each process (:data:`COMPILE_EACH_PROCESS`, :func:`stable_cache`).

This leans on two numba internals, ``Dispatcher._cache`` and ``FunctionCache._index_key`` (numba 0.68, the
version requirements.lock pins); a numba that changes them makes the test above fail, not the results."""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path
from typing import Any

from numba.core.caching import FunctionCache
from numba.core.dispatcher import Dispatcher

# A dispatcher with this attribute set makes every closure over it keep numba's own key (compiled in each
# process): the one loop whose code loaded from the cache differs from the code compiled in the process
# (compose.implicit_stepper's elastic chain step; see :func:`stable_cache`).
COMPILE_EACH_PROCESS = "compile_in_each_process"
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
        if getattr(obj, COMPILE_EACH_PROCESS, False):
            raise Unstable(f"{obj.py_func.__qualname__} is compiled in each process")
        return f"dispatcher[{describe(obj.targetoptions)}]({_function(obj.py_func)})"
    if callable(obj) and hasattr(obj, "__code__"):
        return _function(obj)
    raise Unstable(type(obj).__name__)


def _function(f) -> str:
    closure = tuple(c.cell_contents for c in f.__closure__ or ())
    return f"{f.__module__}.{f.__qualname__}:{f.__code__.co_code.hex()}:{describe(closure)}"


class StableFunctionCache(FunctionCache):
    """numba's FunctionCache with the process-independent closure key of the module docstring."""

    def _index_key(self, sig, codegen):
        key = super()._index_key(sig, codegen)
        try:
            text = describe(tuple(c.cell_contents for c in self._py_func.__closure__ or ()))
        except Unstable:
            return key  # numba's own key: compiled in each process
        closure = hashlib.sha256((text + sources_digest()).encode()).hexdigest()
        return key[0], key[1], (key[2][0], closure)


def stable_cache(dispatcher: Dispatcher) -> Dispatcher:
    """Give a ``cache=True`` closure dispatcher the process-independent key (before its first compile).
    Only the loops compiled on their own need it (compose's samples and drivers); the ``inline="always"``
    steppers are inlined into them and never compiled, nor cached, alone.

    The cached code must be the code a process would compile, or a run's last bits would depend on
    whether its loop came from the cache (a run resumed in a new process would differ from the
    uninterrupted run). It is, for every composed loop checked (``benchmarks/jitcache_bits.py``) but
    one: the chain's implicit stepper with the elastic body gives other last bits from the cache than
    compiled in the process (6e-15 relative in f_d from the first sample; its backward-Euler try's
    fastmath callees are optimised with the code around them, and the driver and sample function are
    separate numba units that LLVM optimises together only when both are compiled in the process).
    That stepper is marked :data:`COMPILE_EACH_PROCESS`, so the loops over it keep numba's own key and
    are compiled in each process, as all composed loops were before."""
    cache = getattr(dispatcher, "_cache", None)
    if isinstance(cache, FunctionCache) and not isinstance(cache, StableFunctionCache):
        dispatcher._cache = StableFunctionCache(dispatcher.py_func)
    return dispatcher


__all__ = ["COMPILE_EACH_PROCESS", "StableFunctionCache", "describe", "sources_digest", "stable_cache"]

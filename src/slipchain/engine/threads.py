"""One BLAS thread while the engine runs.

The implicit stepper's Krylov solves (``scipy.sparse.linalg.cg`` on the slab, the half-space and the
2-D chains) take norms and dot products of vectors with one entry per interface block (or two, on the
2-D chains). OpenBLAS splits a dot product of more than 10 000 entries over its threads (one per core
by default) and adds the threads' partial sums in another order than one thread does, so from a
128 x 80 interface up a run's last bits depended on the machine's number of cores, and a run in this
process differed from the same run in a sweep's worker, where Dask's nanny starts every worker with
``OPENBLAS_NUM_THREADS=1``. Where the cores are busy (a sweep on every core) the threads also wait
for each other: measured on this project's 2-core machine beside two sweeps, a norm of 32 768 entries
took 70 us on two threads against 3 us on one, and 10 ms of a 128 x 80 slab under the implicit stepper
15.0 s against 6.4 s (docs/performance.md). No vector here is long enough to gain from threads.

:func:`one_blas_thread` limits BLAS to one thread (threadpoolctl) for the duration of a run and
restores the process's own limits when the last run of the process ends (nested runs share the limit:
the count of runs in progress decides when it is lifted). Runs in several threads of one process: the
limit is set by the thread that enters first, and with scipy-openblas 0.3.31 a setting made in one
thread did not show in the others once several threads had called BLAS (seen in the suite after
tests/physics/test_concurrency.py); such a process should start with ``OPENBLAS_NUM_THREADS=1``, as
Dask's workers do.
"""

from __future__ import annotations

import threading
from contextlib import contextmanager
from typing import Iterator

from threadpoolctl import threadpool_limits

_lock = threading.Lock()
_depth = 0
_limiter: threadpool_limits | None = None


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """BLAS on one thread inside the block (module docstring); nested and concurrent blocks share it."""
    global _depth, _limiter
    with _lock:
        if _depth == 0:
            _limiter = threadpool_limits(limits=1, user_api="blas")
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0 and _limiter is not None:
                _limiter.restore_original_limits()
                _limiter = None


__all__ = ["one_blas_thread"]

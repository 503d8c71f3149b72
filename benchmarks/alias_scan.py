"""Which compiled loops guard a vectorised loop with an alias check over a wrapped range? (2026-12-06, fortieth session;
a diagnostic, not a timing)

numba wraps a negative index (``i + n`` where ``i < 0``) unless the index is unsigned or LLVM proves it non-negative.
Where it cannot, the runtime alias check in front of a vectorised loop also covers the range past a 1-D array's end
(its bounds built from the array's length, ``shl i64 %arg.<name>.5.0, 3``), and a written array that lies there sends
the loop to its scalar version, which with fastmath can give other last bits: the bits then follow the heap. That was
the 2-D chains' stencil (docs/performance.md, "The 2-D chains' bits followed the heap"). This script runs short cases of
every body and stepper (``slab_bits.CASES``, the 1-D chain, chain2d adaptive and prony-implicit at 48 x 48) with every
loop compiled in this process (``SLIPCHAIN_JIT_CHILD=1``, a fresh ``NUMBA_CACHE_DIR``, so that ``inspect_llvm`` sees
the IR), and lists each slipchain function whose vectorised loops' checks use such bounds. Row offsets of 2-D arrays
(their ``.5.1``) are not counted.

    SLIPCHAIN_JIT_CHILD=1 NUMBA_CACHE_DIR=$(mktemp -d) .venv/bin/python benchmarks/alias_scan.py

2026-12-06 (Xeon, AVX-512; about 15 min, mostly compiling): nothing in 83 compiled overloads after the fix; before it,
the same rule on the chain2d adaptive loop's IR flagged ``cpu._explicit_forces_2d`` alone (bounds from xr, ur, Xr, Ur).
"""

import gc
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import slipchain as sc  # noqa: E402
from numba.core.dispatcher import Dispatcher  # noqa: E402
from slab_bits import CASES  # noqa: E402

EXTRA = (
    dict(theta=1, eta_c=1e5, seed=0, t_total=0.003),
    dict(geometry="chain2d", N=48, Ly=48, integrator="adaptive", epsilon=1.0, eta_c=1e5, start="steady", t_total=2e-3,
         output_interval=1e-3),
    dict(geometry="chain2d", N=48, Ly=48, N_L=5, material="prony", integrator="implicit", dt=1e-7, epsilon=1.0,
         eta_c=1e5, start="steady", t_total=2e-3, output_interval=1e-3),
)


def wrapped_bounds(ir: str) -> dict[str, list[str]]:
    """{function: 1-D array arguments whose length scales an offset} for each slipchain function in ``ir`` that has a
    vectorised loop's alias check (``vector.memcheck``)."""
    found = {}
    for f in re.split(r"^define ", ir, flags=re.M)[1:]:
        name = re.search(r'@"?([^"(]+)', f).group(1)
        if "slipchain" not in name or "vector.memcheck" not in f:
            continue
        header = f.split("{", 1)[0]
        one_d = {a for a in re.findall(r"%arg\.([\w.]+?)\.5\.0", header) if f"%arg.{a}.5.1" not in header}
        uses = sorted({a for a in re.findall(r"shl i64 %arg\.([\w.]+?)\.5\.0(?:\.fr)?, 3", f) if a in one_d})
        if uses:
            found[re.sub(r"B\d.*", "", name)] = uses
    return found


def main() -> None:
    for cfg in (*CASES.values(), *EXTRA):
        sc.run(cfg, progress=False)
    seen, flagged = 0, {}
    for d in gc.get_objects():
        if not isinstance(d, Dispatcher) or "slipchain" not in (d.py_func.__module__ or ""):
            continue
        for sig in d.signatures:
            try:
                ir = d.inspect_llvm(sig)
            except Exception:  # noqa: BLE001 (a cached overload: no IR to read)
                continue
            seen += 1
            flagged.update(wrapped_bounds(ir))
    for name, args in sorted(flagged.items()):
        print(f"{name}: bounds from the length of {', '.join(args)}")
    print(f"{seen} compiled overloads read; {len(flagged)} functions with wrapped alias-check bounds")


if __name__ == "__main__":
    main()

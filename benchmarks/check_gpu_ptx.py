"""Compile the GPU kernel to PTX without a GPU: evidence that it is valid CUDA, not only simulator Python.

    pip install -e ".[gpu]"        # numba-cuda and the CUDA 12 toolkit wheels (NVVM); no driver needed
    python benchmarks/check_gpu_ptx.py [--cc 9.0]

numba-cuda compiles device functions for the *current* device's compute capability, which needs a
driver; this script substitutes a device of the requested capability (default 9.0, H100) for that
lookup only, then compiles the kernel with ``cuda.compile_ptx`` and prints the size of the PTX and
the number of barriers.
"""

from __future__ import annotations

import argparse


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cc", default="9.0")
    args = ap.parse_args()
    cc = tuple(int(x) for x in args.cc.split("."))

    import numba.cuda.dispatcher as dispatcher
    from numba import cuda, float64, int64

    class _Device:
        compute_capability = cc

    dispatcher.get_current_device = lambda: _Device()

    from slipchain.engine.backends import cuda as gpu

    a2, a3 = float64[:, :], float64[:, :, :]
    sig = (a2, a2, a2, a2, int64[:], a2, int64[:, :], a2, int64[:], a3, int64, int64, a3, a2, a3, int64[:],
           a2, a2, a2, a2)
    ptx, _ = cuda.compile_ptx(gpu.advance_kernel.py_func, sig, cc=cc)
    print(f"advance_kernel -> PTX for sm_{cc[0]}{cc[1]}: {len(ptx.splitlines())} lines, "
          f"{ptx.count('bar.sync')} barriers, {ptx.count('.shared')} shared-memory declarations/uses")


if __name__ == "__main__":
    main()

#!/bin/bash
# A sweep on the lent device machine's CPUs (issue 29: 16 cores beside this project's 2). Run there by
# the device tool from the repository root, with the wheels the image lacks carried in .whl
# (docs/guide/gpu.md). Usage: benchmarks/device_sweep.sh SWEEP SECONDS [WORKERS [SWEEP OPTIONS...]]
# e.g. benchmarks/device_sweep.sh fig6-rubber-slab 540 13 --only temperature=11 --only v_d=3e-4
# The sweep stops (SIGINT, as Ctrl-C: finished members are kept, and a running member's last checkpoint,
# STORE/checkpoints, which a later `slipchain sweep` on the same store resumes) after SECONDS; the store
# comes back as a tarball in $OUT (SWEEP.store.tgz.N: two sweeps can run side by side, each on its own store
# /tmp/store-SWEEP), split into parts of 15 MiB (the device returns at most 8 files of
# 16 MiB each, 64 MiB in all: a 15-member rubber store of 21.8 MB did not come back whole). Here:
# cat SWEEP.store.tgz.* | tar xz (it unpacks as store-SWEEP/). Machine, versions and the sweep's start and
# end times go to SWEEP.machine.txt, its log to SWEEP.sweep.log.
# FROM=stores/NAME (a store in the working tree, which travels) continues that store instead of a fresh
# one: its finished members are kept and its runs in flight resume from their checkpoints. To carry on
# here, copy the returned store's checkpoints/*.nc and new members/*.nc into the local store (the
# checkpoint format is the same on every machine; a run resumed across machines is not bit-identical
# to one computed on one machine, as results across CPUs never are: compare them statistically).
# e.g. FROM=stores/tester-16-slower benchmarks/device_sweep.sh tester-16-slower 520 12 --only t_ramp=6.0
set -u
sweep=$1; limit=$2; workers=${3:-$(nproc)}; shift $(( $# < 3 ? $# : 3 ))
store=/tmp/store-$sweep
if [ -n "${FROM:-}" ]; then rm -rf "$store" && cp -r "$FROM" "$store" || exit 3; fi
[ -d /tmp/site/numpy ] || python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 3
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 NUMBA_CACHE_DIR=/tmp/numba-cache
out=${OUT:-/tmp/out}; mkdir -p "$out"
{ nproc; lscpu | grep -E "Model name|Thread|Socket|^CPU\(s\)"; python3 -c "import numpy, numba, scipy, xarray, dask, pydantic; print('numpy', numpy.__version__, 'numba', numba.__version__, 'scipy', scipy.__version__)"; python3 -c "from slipchain.engine.backends import pocketfft, compose; print('compiled chunks (fft, dot, einsum):', pocketfft.numba_fft(), compose.numba_dot(), compose.numba_einsum())"; } | tee "$out/$sweep.machine.txt"
echo "sweep start $(date +%s)" >> "$out/$sweep.machine.txt"
timeout -s INT -k 30 "$limit" python3 -m slipchain sweep "$sweep" --store "$store" --workers "$workers" --no-progress "$@" 2>&1 | tee "$out/$sweep.sweep.log"
echo "sweep end $(date +%s)" >> "$out/$sweep.machine.txt"
tar czf - -C /tmp "store-$sweep" | split -b 15M -d -a 1 - "$out/$sweep.store.tgz."
ls -la "$out"

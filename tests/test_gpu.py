"""The GPU backend: importable without CUDA, and on numba's CUDA simulator equal to the CPU kernel.

CI has no GPU: the kernel runs on the simulator (NUMBA_ENABLE_CUDASIM=1, which must be set before
numba.cuda is imported, hence the subprocesses) on tiny systems. Speed is measured on hardware
(benchmarks/bench_gpu.py), not here.
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from slipchain import build_system, make_config, simulate
from slipchain.backend import CPUBackend, get_backend
from slipchain.gpu import cuda_available
from slipchain.simulation import simulate_batch

SIM_ENV = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1"}

COMPARE = r"""
import json, numpy as np
from slipchain import build_system, make_config, initial_state
from slipchain.backend import Batch, CPUBackend, get_backend
from slipchain.simulation import simulate_batch
base = dict(N=11, dt=2e-8, output_interval=2e-7)
cfgs = [make_config(**base, theta=0.5, start="steady", seed=1),
        make_config(**base, theta=1.0, eta_c=1e6, v_d=3e-4, seed=2),
        make_config(**base, theta=0.3, start="steady", dead_weight=0.9, t_total=4e-6),
        make_config(**base, theta=0.5, E=1e15, seed=3)]            # diverges
systems = [build_system(c) for c in cfgs]
states = [initial_state(s) for s in systems]
bc, bg = Batch.pack(systems, states), Batch.pack(systems, states)
gpu = get_backend("gpu")
oc, og = CPUBackend().advance(bc, 8, 10), gpu.advance(bg, 8, 10)
ok = [0, 1, 2]
rel = lambda a, b: float(np.max(np.abs(a - b)) / np.max(np.abs(a)))
res = {"fd": rel(oc.out[ok], og.out[ok]), "x": rel(bc.x[ok], bg.x[ok]), "U": rel(bc.U[ok], bg.U[ok]),
       "acc": rel(oc.acc[ok], og.acc[ok]), "cacc": rel(oc.cacc[ok], og.cacc[ok]),
       "status_cpu": bc.status.tolist(), "status_gpu": bg.status.tolist(),
       "steps": [bc.step.tolist(), bg.step.tolist()]}
short = [c.with_updates(t_total=1.6e-6, backend="gpu") for c in cfgs[:2]]
g = simulate_batch([build_system(c) for c in short])
c = simulate_batch([build_system(c.with_updates(backend="cpu")) for c in short])
res["run_fd"] = max(rel(a["f_d"].values, b["f_d"].values) for a, b in zip(c, g))
res["run_status"] = [d.attrs["status"] for d in g]
print(json.dumps(res))
"""


def test_gpu_kernel_on_the_simulator_agrees_with_the_cpu_kernel():
    proc = subprocess.run([sys.executable, "-c", COMPARE], capture_output=True, text=True, env=SIM_ENV, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    r = json.loads(proc.stdout.strip().splitlines()[-1])
    # same scheme, same solver equation: differences are the CPU Newton tolerance (< 3e-10 decades)
    assert r["fd"] < 1e-9 and r["x"] < 1e-9 and r["U"] < 1e-9 and r["acc"] < 1e-8 and r["cacc"] < 1e-8, r
    assert r["status_cpu"][:3] == [-1, -1, -1] and r["status_gpu"][:3] == [-1, -1, -1]
    assert r["status_cpu"][3] >= 0 and r["status_gpu"][3] >= 0  # the diverging row is caught on both
    assert r["steps"][0][:3] == r["steps"][1][:3] == [80, 80, 80]
    assert r["run_fd"] < 1e-9 and len(r["run_status"]) == 2


def test_gpu_code_imports_without_cuda_and_auto_falls_back_to_the_cpu():
    if cuda_available():  # pragma: no cover - a machine with a GPU
        pytest.skip("a GPU is present")
    assert isinstance(get_backend("auto"), CPUBackend)
    with pytest.raises(RuntimeError, match="backend 'gpu' needs a CUDA GPU"):
        get_backend("gpu")
    proc = subprocess.run([sys.executable, "-m", "slipchain", "run", "--set", "N=11", "--set", "t_total=1e-5",
                           "--backend", "gpu"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "needs a CUDA GPU" in proc.stderr


def test_a_batch_gives_exactly_the_single_runs():
    cfgs = [make_config(N=31, theta=t, start="steady", v0=0.01, delta=0.2, t_total=2e-3, seed=s)
            for t, s in ((0.5, 0), (1.0, 1), (0.2, 2))]
    cfgs.append(cfgs[0].with_updates(t_total=1e-3))  # a shorter row stops on its own
    together = simulate_batch([build_system(c) for c in cfgs])
    for c, ds in zip(cfgs, together):
        alone = simulate(build_system(c))
        np.testing.assert_array_equal(ds["f_d"].values, alone["f_d"].values)
        np.testing.assert_array_equal(ds["x"].values, alone["x"].values)
        assert ds.attrs["mu_star"] == alone.attrs["mu_star"] and ds.attrs["t_total"] == alone.attrs["t_total"]
    with pytest.raises(ValueError, match="a batch needs equal N, dt and output_interval"):
        simulate_batch([build_system(cfgs[0]), build_system(cfgs[0].with_updates(N=41))])

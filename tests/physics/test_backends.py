"""Every backend computes the same scheme: CPU and CUDA agree step by step, batches equal single runs.

The CUDA backend runs on numba's CUDA simulator here (tests/conftest.py), on tiny systems; on a
GPU with ``SLIPCHAIN_TEST_CUDA=hardware``. Both backends compile the same source
(:mod:`slipchain.engine.scheme`), so they differ only by floating-point reassociation (CPU
fastmath) and the order of the per-sample block sums.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

from slipchain import build_system, initial_state, make_config, simulate
from slipchain.model.config import Config
from slipchain.engine import scheme as S
from slipchain.engine.backends import Batch, CPUBackend, get_backend
from slipchain.engine.simulate import simulate_batch

BASE = dict(N=11, dt=2e-8, output_interval=2e-7, integrator="fixed")
CONFIGS = [make_config(**BASE, theta=0.5, start="steady", seed=1),
           make_config(**BASE, theta=1.0, eta_c=1e6, v_d=3e-4, seed=2),
           make_config(**BASE, theta=0.3, start="steady", dead_weight=0.9, t_total=4e-6),
           # diverges: springs 1e8 times stiffer, past Config's stable-step check (model_construct)
           Config.model_construct(**{**make_config(**BASE, theta=0.5, seed=3).model_dump(), "E": 1e15})]


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


@pytest.mark.cuda
def test_cuda_kernel_agrees_with_the_cpu_kernel_step_by_step():
    systems = [build_system(c) for c in CONFIGS]
    states = [initial_state(s) for s in systems]
    bc, bg = Batch.pack(systems, states), Batch.pack(systems, states)
    oc, og = CPUBackend().advance(bc, 8, 10), get_backend("gpu").advance(bg, 8, 10)
    ok = [0, 1, 2]
    # Same scheme and the same solver (warm-started Newton to 1e-5 decades): only round-off differs.
    for a, b in ((oc.out[ok], og.out[ok]), (bc.x[ok], bg.x[ok]), (bc.U[ok], bg.U[ok]), (oc.acc[ok], og.acc[ok]),
                 (oc.cacc[ok], og.cacc[ok]), (bc.ysolve[ok, :S.N_YS_STATE], bg.ysolve[ok, :S.N_YS_STATE])):
        assert _rel(a, b) < 1e-12
    assert np.array_equal(bc.ysolve[:, S.N_YS_STATE:], bg.ysolve[:, S.N_YS_STATE:])  # the folds: inputs, untouched
    assert bc.status[:3].tolist() == bg.status[:3].tolist() == [-1, -1, -1]
    assert bc.status[3] >= 0 and bg.status[3] >= 0  # the diverging row is caught on both
    assert bc.step[:3].tolist() == bg.step[:3].tolist() == [80, 80, 80]


@pytest.mark.cuda
@pytest.mark.parametrize("keep", [False, True])
def test_cuda_chunks_see_host_changes_with_fresh_or_kept_device_buffers(keep):
    # Device arrays fresh every chunk (the default, measured on an H100) or kept from chunk to chunk
    # (keep_buffers=True, not yet measured on a GPU): either way the host batch stays the truth: two
    # chunks equal one of twice the length, and a row the driver marks finished is skipped.
    from slipchain.engine.backends.cuda import CUDABackend

    systems = [build_system(c) for c in CONFIGS[:3]]
    states = [initial_state(s) for s in systems]
    gpu = CUDABackend(keep_buffers=keep)
    one, two = Batch.pack(systems, states), Batch.pack(systems, states)
    o1 = gpu.advance(one, 4, 10)
    a = gpu.advance(two, 2, 10)
    buffers = two.__dict__.get("_cuda_buffers")
    b = gpu.advance(two, 2, 10)
    assert (buffers is not None and two.__dict__.get("_cuda_buffers") is buffers) if keep else buffers is None
    for name in ("x", "u", "X", "U", "ysolve", "step"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    np.testing.assert_array_equal(o1.out, np.concatenate([a.out, b.out], axis=1))
    np.testing.assert_allclose(o1.cacc, a.cacc + b.cacc, rtol=1e-13, atol=0)  # (sums grouped differently)
    x0 = two.x[0].copy()
    two.status[0] = two.step[0]  # finished: the kernel must skip row 0 from now on
    gpu.advance(two, 2, 10)
    np.testing.assert_array_equal(two.x[0], x0)
    assert two.step[1] == two.step[2] == 60 and two.step[0] == 40


def test_runs_on_a_backend_match_the_cpu(backend):
    # Over 80 steps (simulator) the backends agree to round-off; over 1000 steps (CPU, a real GPU)
    # round-off differences (CPU fastmath reassociation, GPU fused multiply-adds) grow through the
    # dynamics: measured 8e-12 on an H100, hence the wider bound there.
    # On the CPU the reference is a second implementation of the same scheme (issue 26: it compared
    # the CPU with itself): the chain run as chain2d with one row (the lattice stencil, its own loop).
    tol = 1e-12 if backend.small or backend.name == "cpu" else 1e-9
    short = [c.with_updates(t_total=backend.steps(2e-5, 1.6e-6)) for c in CONFIGS[:3]]
    got = simulate_batch([build_system(c) for c in short], backend=backend.name)
    other = [c.with_updates(geometry="chain2d") for c in short] if backend.name == "cpu" else short
    ref = simulate_batch([build_system(c) for c in other], backend="cpu")
    for g, r in zip(got, ref):
        # (too short for the after-run displacement check to pass from rest: same verdict on both)
        assert g.attrs["status"] == r.attrs["status"] and g.attrs["backend"] == backend.name
        assert _rel(r["f_d"].values, g["f_d"].values) < tol  # (zero for the dead-weight row: no drive springs)
        assert _rel(r["x_mean"].values, g["x_mean"].values) < tol
        assert g.attrs["check_energy_balance"] == pytest.approx(r.attrs["check_energy_balance"], rel=1e-6, abs=1e-12)


def test_a_batch_gives_exactly_the_single_runs(backend):
    cfgs = [make_config(N=backend.steps(31, 11), theta=t, start="steady", v0=0.01, delta=0.2, integrator="fixed",
                        t_total=backend.steps(2e-3, 1e-6), output_interval=backend.steps(1e-5, 2e-7), seed=s)
            for t, s in ((0.5, 0), (1.0, 1), (0.2, 2))]
    cfgs.append(cfgs[0].with_updates(t_total=cfgs[0].t_total / 2))  # a shorter row stops on its own
    together = simulate_batch([build_system(c) for c in cfgs], backend=backend.name)
    for c, ds in zip(cfgs, together):
        alone = simulate(build_system(c), backend=backend.name)
        np.testing.assert_array_equal(ds["f_d"].values, alone["f_d"].values)
        np.testing.assert_array_equal(ds["x"].values, alone["x"].values)
        assert ds.attrs["mu_star"] == alone.attrs["mu_star"] and ds.attrs["t_total"] == alone.attrs["t_total"]
    with pytest.raises(ValueError, match="a batch needs equal N, dt, output_interval"):
        simulate_batch([build_system(cfgs[0]), build_system(cfgs[0].with_updates(N=41))])


def test_cuda_code_imports_without_cuda_and_auto_falls_back_to_the_cpu():
    # A process without the simulator and (in CI) without a GPU.
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "0"}
    script = ("from slipchain.engine.backends import get_backend, CPUBackend\n"
              "from slipchain.engine.backends.cuda import cuda_available\n"
              "print(cuda_available(), type(get_backend('auto')).__name__)\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    has_gpu, auto = proc.stdout.split()
    if has_gpu == "True":  # pragma: no cover - a machine with a GPU
        pytest.skip("a GPU is present")
    assert auto == "CPUBackend"
    proc = subprocess.run([sys.executable, "-m", "slipchain", "run", "--set", "N=11", "--set", "t_total=1e-5",
                           "--set", "integrator=fixed", "--backend", "gpu"], capture_output=True, text=True,
                          timeout=120, env=env)
    assert proc.returncode == 2 and "needs a CUDA GPU" in proc.stderr
    # the capability table (issue 26): the default adaptive step is refused on the GPU with its reason
    proc = subprocess.run([sys.executable, "-m", "slipchain", "run", "--set", "N=11", "--set", "t_total=1e-5",
                           "--backend", "gpu"], capture_output=True, text=True, timeout=120, env=env)
    assert proc.returncode == 2 and "integrator = 'adaptive' runs on the CPU only" in " ".join(proc.stderr.split())
    proc = subprocess.run([sys.executable, "-m", "slipchain", "run", "--backend", "tpu"], capture_output=True,
                          text=True, timeout=120, env=env)
    assert proc.returncode == 2 and "tpu" in proc.stderr

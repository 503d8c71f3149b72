"""Issue 26: the engine's loops are composed from pieces. A body written here, outside the engine
(blocks on springs to the ground, no contacts), composes with the engine's own steppers and driver
and is checked against independent statements: the exact solution of symplectic Euler's recurrence
(fixed step) and of the differential equation (adaptive step)."""

from __future__ import annotations

import numba as nb
import numpy as np

from slipchain.engine import scheme as S
from slipchain.engine.backends import compose

OMEGA = np.array([1.0e3, 2.0e3, 3.0e3, 5.0e3])  # rad/s, one per block


@nb.njit(cache=True)
def _ground_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t):
    """Block i on a spring to the ground, m du/dt = -m omega_i**2 x (omega_i**2 in Xr[i], which never moves)."""
    for i in range(xr.size):
        un[i] = ur[i] - h * Xr[i] * xr[i]
        Un[i] = Ur[i]
        dampx[i] = 0.0
        dampX[i] = 0.0
    return 0.0


@nb.njit(cache=True)
def _ground_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h):
    """(``mt``, ``br``: a material's constants and state, none here.) Returns (damping work, bulk work)."""
    for i in range(xr.size):
        xr[i] += h * un[i]
        ur[i] = un[i]
    return 0.0, 0.0


def _run(adaptive: bool, dt: float, n_samples: int, sample_steps: int, tol: float = 0.0, levels: int = 0,
         stepwise: bool = False):
    """``stepwise``: the fixed stepper's samples by :func:`compose.step_sample` (one step per call, as
    the adaptive stepper's are) instead of :func:`compose.fixed_sample` (the step written out)."""
    n = OMEGA.size
    if adaptive:
        sample = compose.step_sample(compose.adaptive_stepper(_ground_explicit, _ground_commit))
    elif stepwise:
        sample = compose.step_sample(compose.fixed_stepper(_ground_explicit, _ground_commit, False))
    else:
        sample = compose.fixed_sample(_ground_explicit, _ground_commit, False)
    advance = compose.kernel_driver(sample)
    x = np.ones((1, n))
    u = np.zeros((1, n))
    X = (OMEGA**2)[None, :].copy()
    U = np.zeros((1, n))
    p = np.zeros((1, S.N_PARAMS))
    p[0, S.P_M] = p[0, S.P_ML] = 1.0
    p[0, S.P_DT] = dt
    control = np.array([[tol, float(levels), 0.0, 0.0, float(levels), 0.0]])  # (compose.N_CONTROL columns)
    out = np.zeros((1, n_samples, S.N_OUT))
    steps = np.zeros(1, dtype=np.int64)
    advance(x, u, X, U, steps, p, np.zeros((1, 1), dtype=np.int64), np.ones((1, 1)), np.zeros(1, dtype=np.int64),
            np.zeros((1, S.N_YS, 1)), np.zeros((1, levels + 1, 2, 1)), control, np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 0)), n_samples,
            sample_steps, out,
            np.zeros((1, S.N_ACC)), np.zeros((1, S.N_CACC, 1)), np.full(1, -1, dtype=np.int64))
    return out[0, :, S.O_XMEAN], control[0], steps[0]


def test_a_body_from_outside_composes_with_the_fixed_stepper_exactly():
    """Symplectic Euler on x'' = -omega**2 x from x = 1, u = 0: x_n = cos(n th) - (h**2 omega**2 / 2) sin(n th) /
    sin(th), cos(th) = 1 - h**2 omega**2 / 2 (the recurrence's exact solution), for every block."""
    dt, steps = 1e-5, 50
    got, _, taken = _run(False, dt, 20, steps)
    k = steps * np.arange(1, 21)[:, None]
    th = np.arccos(1.0 - (dt * OMEGA) ** 2 / 2.0)
    exact = np.cos(k * th) - (dt * OMEGA) ** 2 / 2.0 * np.sin(k * th) / np.sin(th)
    np.testing.assert_allclose(got, exact.mean(axis=1), rtol=0, atol=1e-11)
    assert taken == 20 * steps
    # the fixed stepper's sample written out (the chains' kernel) is its step repeated, bit for bit
    stepwise, _, taken_stepwise = _run(False, dt, 20, steps, stepwise=True)
    assert taken_stepwise == taken
    np.testing.assert_array_equal(stepwise, got)


def test_the_same_body_composes_with_the_adaptive_stepper():
    """The adaptive stepper on the same body: far fewer steps than base steps, the time grid of the
    fixed step (every sample ends on it), and the solution of the ODE, cos(omega t) over 1 to 5
    periods, to an error that falls with the tolerance (measured: 5.6e-3 at tol 0.1 with 10 % of
    the base steps, 1.1e-3 at 0.01 with 24 %)."""
    dt, steps, ns = 1e-7, 1000, 60
    t = dt * steps * np.arange(1, ns + 1)
    exact = np.cos(np.outer(t, OMEGA)).mean(axis=1)
    errors = []
    for tol in (1e-1, 1e-2):
        got, control, base = _run(True, dt, ns, steps, tol=tol, levels=6)
        assert base == ns * steps
        assert control[2] < 0.3 * base  # steps taken
        errors.append(np.abs(got - exact).max())
    assert errors[1] < errors[0] / 3.0 and errors[0] < 0.02


def test_every_geometry_has_one_body_and_one_loop_per_stepper():
    """The combinations the CPU runs map onto the composed loops: one per (body, stepper), shared by
    the geometries of a body, and the fold integrator is the fixed stepper (its solver is per row)."""
    assert set(compose.BODIES) == {"chain", "chain2d", "slab", "halfspace"}
    assert compose.loop("chain", False) is compose.loop("chain2d", False)
    assert compose.loop("slab", True) is compose.loop("halfspace", True)
    assert compose.loop("chain", True) is not compose.loop("chain", False)


def test_the_slab_explicit_steps_compiled_whole_give_the_python_drivers_bits():
    """The elastic slab's and half-space's fixed step ('fixed', 'fold') and adaptive step run a whole chunk in one compiled call,
    its FFTs in numba (compose.fft_chunk_driver; rocket-fft, a dependency, so the compiled path is taken here).
    It does fft_advance's arithmetic in fft_advance's order: the state and the chunk's outputs equal those
    of the Python driver (the same function given its FFT module, which keeps the per-step Python loop) bit
    for bit, under the spring drive, the dead weight (the body on x - X) and for the half-space; the adaptive
    step (the rows in lock-step) on a batch of two rows; the rubber's fold step (its arms' field in the same
    batched FFT) under the dead weight and on the half-space."""
    import copy

    from slipchain.engine.backends import Batch
    from slipchain.engine.backends.pocketfft import fft_module, numba_fft
    from slipchain.model.config import make_config
    from slipchain.model.system import build_system, initial_state

    assert numba_fft() and compose.numba_einsum()
    base = dict(N=8, Ly=6, theta=0.5, seed=2, output_interval=1e-4, t_total=1e-3)
    for cfg in (dict(base, geometry="slab", integrator="fold", dt=5e-8, start="steady"),
                dict(base, geometry="slab", integrator="fixed", dt=2e-8, dead_weight=0.5, start="rest"),
                dict(base, geometry="halfspace", integrator="fixed", dt=2e-8, start="steady"),
                dict(base, geometry="slab", integrator="adaptive", dt=2e-8, start="steady", theta=(0.5, 1.0)),
                dict(base, geometry="slab", N_L=5, material="prony", integrator="fold", dt=1e-7, epsilon=1.0, eta_c=1e5,
                     dead_weight=0.3, start="rest"),
                dict(base, geometry="halfspace", material="prony", integrator="fold", dt=1e-7, epsilon=1.0, eta_c=1e5,
                     start="steady")):
        configs = [make_config(**dict(cfg, theta=t)) for t in np.atleast_1d(cfg["theta"])]
        config, systems = configs[0], [build_system(c) for c in configs]
        batch = Batch.pack(systems, [initial_state(s) for s in systems])
        body = compose.BODIES[batch.geometry] + ("-prony" if batch.material_name == "prony" else "")
        chunk = compose._fft_chunk(body, cfg["integrator"] == "adaptive")
        before = len(chunk.signatures)
        one, two = copy.deepcopy(batch), copy.deepcopy(batch)
        compiled = compose.fft_advance(one, 5, config.sample_steps)
        assert len(chunk.signatures) >= max(before, 1)  # the compiled path ran
        python = compose.fft_advance(two, 5, config.sample_steps, fft=fft_module())
        for name in ("x", "u", "X", "U", "ysolve", "step", "status", "bstate"):
            assert np.array_equal(getattr(one, name), getattr(two, name)), (cfg, name)
        for name in ("out", "acc", "cacc"):
            assert np.array_equal(getattr(compiled, name), getattr(python, name)), (cfg, name)
        assert np.abs(one.x - batch.x).max() > 0  # it moved


def test_the_implicit_steppers_explicit_steps_compiled_give_the_python_drivers_bits():
    """The implicit stepper's explicit steps on the slab, half-space and chain2d run compiled between its
    backward-Euler tries (compose.krylov_explicit_driver: the body's force by numpy.fft and np.dot in numba,
    then the rows' adaptive step). Against the same driver given its FFT module (which keeps them in Python):
    the same state, outputs and carried controller, bit for bit, for the elastic slab under either drive,
    the rubber slab under the dead weight (the tester's body), the half-space and chain2d."""
    import copy

    from slipchain.engine.backends import Batch
    from slipchain.engine.backends.pocketfft import fft_module
    from slipchain.model.config import make_config
    from slipchain.model.system import build_system, initial_state

    assert compose.numba_dot()
    base = dict(N=8, Ly=8, theta=1.0, seed=0, epsilon=1.0, eta_c=1e5, v_d=1e-3, integrator="implicit", dt=1e-7,
                output_interval=1e-3, t_total=4e-3)
    cases = (dict(base, geometry="slab", start="steady"),
             dict(base, geometry="slab", dead_weight=0.4, start="rest"),
             dict(base, geometry="slab", N_L=5, material="prony", dead_weight=0.3, start="rest"),
             dict(base, geometry="halfspace", start="steady"),
             dict(base, geometry="chain2d", start="steady"))
    for cfg in cases:
        config = make_config(**cfg)
        system = build_system(config)
        batch = Batch.pack([system], [initial_state(system)])
        one, two = copy.deepcopy(batch), copy.deepcopy(batch)
        body = compose.BODIES[batch.geometry] + ("-prony" if batch.material_name == "prony" else "")
        compiled = compose.krylov_implicit_advance(one, 4, config.sample_steps)
        assert compose._krylov_explicit(body).signatures, cfg  # the compiled path ran
        python = compose.krylov_implicit_advance(two, 4, config.sample_steps, fft=fft_module())
        for name in ("x", "u", "X", "U", "ysolve", "step", "status", "bstate", "carry", "step_control"):
            assert np.array_equal(getattr(one, name), getattr(two, name)), (cfg, name)
        for name in ("out", "acc", "cacc"):
            assert np.array_equal(getattr(compiled, name), getattr(python, name)), (cfg, name)
        assert one.step_control[0, 2] > 0 and np.abs(one.x - batch.x).max() > 0  # explicit steps taken; it moved


def test_without_rocket_fft_the_slab_keeps_its_python_driver(monkeypatch):
    """Where rocket-fft cannot be imported (a user's environment without it), numba_fft says so, and
    fft_advance and krylov_implicit_advance then take their per-step Python drivers (which the two tests
    above show give the compiled chunks' bits)."""
    import sys

    from slipchain.engine.backends import pocketfft

    assert pocketfft.numba_fft() is True  # here rocket-fft is installed (a dependency)
    pocketfft.numba_fft.cache_clear()
    monkeypatch.setitem(sys.modules, "rocket_fft", None)  # import rocket_fft raises ImportError
    try:
        assert pocketfft.numba_fft() is False
    finally:
        pocketfft.numba_fft.cache_clear()  # the next call checks again, rocket_fft back in sys.modules

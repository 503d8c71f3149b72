"""integrator = 'adaptive' (issue 12): the fold-aware scheme with a doubling step.

Limits and independent checks: with a tolerance no step can meet it is the fold integrator bit
for bit; with the default tolerance it takes several times fewer steps and agrees with the
fold integrator (and with the fixed step far below the unique-root limit) through slip events,
to within the first-order error of the fold step itself; energy balance at the physical contact
stiffness; the cycle counter of the automatic length on series with known cycles.
"""

import numpy as np
import pytest

import slipchain as sc
from slipchain.engine.backends import Batch
from slipchain.engine.backends.host import CPUBackend
from slipchain.model.config import STABLE_FRACTION, ConfigError, make_config
from slipchain.model.stability import chain_modes, spectral_radius
from slipchain.model.system import build_system, initial_state
from slipchain.results.observables import count_cycles, steady_estimate
from slipchain.sweeps.definition import member_id

BASE = dict(N=31, theta=0.5, seed=3, t_total=1e-3, output_interval=1e-5, start="steady")


def _steps(cfg: dict, n_samples: int, rejected: bool = False) -> float | tuple[float, float]:
    """Advance a one-row batch by n_samples output samples; the steps taken per base step dt (and
    the steps rejected)."""
    system = build_system(make_config(**cfg))
    batch = Batch.pack([system], [initial_state(system)])
    CPUBackend().advance(batch, n_samples, system.config.sample_steps)
    assert batch.step[0] == n_samples * system.config.sample_steps
    taken = float(batch.step_control[0, 2]) / batch.step[0]
    return (taken, float(batch.step_control[0, 3])) if rejected else taken


def _radius(cfg, h):
    """Spectral radius of the chain's contact-free step of length h (every Fourier mode's amplification)."""
    modes = chain_modes(cfg.N, cfg.Ly, cfg.m, cfg.N_L, cfg.K, cfg.K_L, cfg.K_T, cfg.K_d, cfg.K_Y, cfg.K_LY, cfg.eta)
    return spectral_radius(*modes, h)


def test_the_largest_adaptive_step_is_linearly_stable():
    """Issue 26: the top level is a step whose amplification matrices all have spectral radius < 1,
    with the margin STABLE_FRACTION, and the next doubling would leave it. Before, dt = 1e-7 doubled
    up to 8e-7 s, which the linear analysis shows unstable (radius 1.9: its rejections hid it)."""
    for dt in (2e-8, 1e-7, 2e-7):
        cfg = make_config(integrator="adaptive", dt=dt)
        top = cfg.dt * 2.0**cfg.step_levels
        assert _radius(cfg, top) < 1.0
        assert _radius(cfg, top / STABLE_FRACTION) <= 1.0 + 1e-7  # the margin is inside the stable range
        assert cfg.step_levels == 6 or 2.0 * top > STABLE_FRACTION * cfg.dt_stable
    assert _radius(make_config(), 8e-7) > 1.5
    assert make_config(integrator="adaptive", dt=1e-7).step_levels == 2  # up to 4e-7 s at the paper's values


def test_unreachable_tolerance_is_the_fold_integrator_bit_for_bit():
    """err < tol/8 never holds for tol = 1e-300 v_d: every step at dt, the fold scheme's operations."""
    cfg = dict(BASE, dt=1e-7)
    a = sc.run(dict(cfg, integrator="fold"))
    b = sc.run(dict(cfg, integrator="adaptive", step_tol=1e-300))
    assert np.array_equal(a.f_d.values, b.f_d.values) and np.array_equal(a.x.values, b.x.values)
    assert a.attrs["W_contacts"] == b.attrs["W_contacts"]
    assert _steps(dict(cfg, integrator="adaptive", step_tol=1e-300), 10, rejected=True) == (1.0, 0.0)


def test_adaptive_step_grows_and_agrees_with_the_fold_step_through_slip_events():
    """Steady start, N = 31 (slip events of up to 65 % in f_d within the first millisecond): the
    adaptive step from dt = 1e-7 takes fewer steps than the fold step and its f_d(t) differs
    from the fixed step at 2.5e-9 by no more than the fold step at 1e-7 does (first order), and
    far less than the events' size; tightening the tolerance does not make it worse."""
    ref = sc.run(dict(BASE, dt=2.5e-9, integrator="fixed")).f_d.values
    assert np.diff(ref).min() < -0.3 * ref.max()
    fold = np.abs(sc.run(dict(BASE, dt=1e-7, integrator="fold")).f_d.values - ref).max() / ref.max()
    errs = {tol: np.abs(sc.run(dict(BASE, dt=1e-7, integrator="adaptive", step_tol=tol)).f_d.values - ref).max()
            / ref.max() for tol in (1e-2, 1e-4)}
    assert errs[1e-2] < 2.0 * fold and errs[1e-2] < 0.05, (errs, fold)
    assert errs[1e-4] <= errs[1e-2] * 1.5 + 1e-3, errs
    taken, rejected = _steps(dict(BASE, dt=1e-7, integrator="adaptive"), 100, rejected=True)
    assert taken < 0.6 and rejected > 0  # coarse steps between events, events started again on fine steps


def test_physical_contact_stiffness_conserves_energy_and_follows_the_fold_step():
    """epsilon = 1, theta = 1, steady start, 0.1 s: the whole chain's slip and reload; energy balance
    holds, f_d(t) agrees with the fold integrator at the same dt within 2 % of its range, and the
    step is on average at least three times dt."""
    cfg = dict(N=31, theta=1.0, epsilon=1.0, start="steady", dt=1e-7, t_total=0.1, output_interval=1e-3, seed=0)
    fold = sc.run(dict(cfg, integrator="fold"))
    ada = sc.run(dict(cfg, integrator="adaptive"))
    assert ada.attrs["check_energy_balance_passed"] == 1
    f, g = fold.f_d.values, ada.f_d.values
    assert np.abs(f - g).max() < 0.02 * (f.max() - f.min() + 1e-300)
    assert _steps(dict(cfg, integrator="adaptive"), 20) < 1 / 3


def test_count_cycles_on_series_with_known_cycles():
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 7.0, 7000, endpoint=False)
    saw = t % 1.0  # seven teeth: a loading ramp, a sudden drop at every integer (6 inside)
    assert count_cycles(saw) == 6
    assert count_cycles(saw + 0.02 * rng.standard_normal(t.size)) == 6  # noise is not counted
    noise = rng.standard_normal(2000)
    assert count_cycles(noise) > 200  # decorrelates every few samples
    assert count_cycles(np.ones(50)) == 0


def test_min_cycles_ends_the_automatic_run_once_the_window_holds_them():
    """The run stops before t_max, at a check where the steady window holds min_cycles cycles (counted
    here again from the stored trace), and not before: at the check before, the window held fewer,
    or the standard error was not yet reached. (Issue 26: the test before passed through t_max.)"""
    from slipchain.engine.control import chunk_samples, geometric_check_index, MIN_STEADY_SAMPLES

    cfg = dict(N=31, theta=0.5, seed=5, sem_target=0.05, t_max=2.0, output_interval=1e-4, min_cycles=300)
    long = sc.run(cfg)
    assert long.attrs["status"] == "completed" and long.attrs["t_total"] < 2.0 - 1e-9  # min_cycles ended it
    fd = long.f_d.values / long.attrs["mu_star_norm"]
    est = steady_estimate(fd)
    assert count_cycles(fd[est.start:]) >= 300
    # the last check that did not stop it: the window held fewer cycles, or the other conditions failed
    chunk = chunk_samples(make_config(**cfg), 1e-4)
    ends = np.arange(chunk, fd.size, chunk)
    checks = [n for n in ends if geometric_check_index(n, MIN_STEADY_SAMPLES) != geometric_check_index(n - chunk, MIN_STEADY_SAMPLES)]
    before = fd[:checks[-1]] if checks else fd[:0]
    if before.size:
        e = steady_estimate(before)
        assert count_cycles(before[e.start:]) < 300 or e.sem > 0.05 or not e.drift_ok
    short = sc.run(dict(cfg, min_cycles=0))
    assert short.attrs["t_total"] < long.attrs["t_total"]


def test_adaptive_keys_errors_and_ids():
    assert member_id(make_config(**BASE)) == member_id(make_config(**BASE, step_tol=0.01, min_cycles=0))
    assert member_id(make_config(**BASE, integrator="adaptive", dt=1e-7)) != member_id(
        make_config(**BASE, integrator="adaptive", dt=1e-7, step_tol=0.001))
    with pytest.raises(ConfigError, match="'step_tol'.*integrator = 'adaptive'"):
        make_config(step_tol=0.05, integrator="fixed")
    with pytest.raises(ConfigError, match="'min_cycles'"):
        make_config(min_cycles=5, t_total=1e-3)
    with pytest.raises(ConfigError, match="largest stable step of the explicit springs and damping together"):
        make_config(integrator="adaptive", dt=5e-7, eta=3e6)


def test_a_run_of_too_few_slip_cycles_says_how_to_converge():
    """Issue 26: at epsilon = 1 a slip cycle lasts about a second; a run that reaches t_max with a few
    cycles in its window says so and what converges it (counted again here from the trace); a run
    with many cycles that reaches t_max does not get the advice."""
    long = sc.run(dict(N=31, theta=1.0, epsilon=1.0, start="steady", t_max=0.05, output_interval=1e-4, seed=1,
                       t_max_cycles=0.0))  # no extension past t_max (tests/physics/test_cycle_length.py)
    fd = long.f_d.values
    cycles = count_cycles(fd[steady_estimate(fd).start:])
    msg = long.attrs["message"]
    assert "t_max = 0.05 s reached" in msg and cycles < 5
    assert f"holds only {cycles} cycle(s) of f_d" in msg and "t_max_cycles" in msg and "min_cycles = 20" in msg
    # epsilon = 1e-2: many short slip events in the window (an unreachable target keeps it to t_max): no advice
    many = sc.run(dict(N=31, theta=0.5, start="steady", sem_target=1e-6, t_max=0.05, seed=1))
    fd = many.f_d.values
    assert count_cycles(fd[steady_estimate(fd).start:]) >= 5
    assert "t_max = 0.05 s reached" in many.attrs["message"] and "cycle(s)" not in many.attrs["message"]

"""Dead-weight drive: a constant force on the upper layer instead of the springs at v_d."""

import numpy as np
import pytest
from scipy.optimize import brentq

from slipchain import make_config, run
from slipchain.sweeps.definition import member_id


def _single_contact(dw, **kw):
    """N = 3, one contact (theta = 1/3), v* = v0 exactly (delta = 0): the total force N*F_b = dw*epsilon*f0."""
    return make_config(N=3, theta=1 / 3, delta=0.0, dead_weight=dw, t_total=4e-3, **kw)


@pytest.mark.parametrize("dw", [0.5, 0.9, 0.99])
def test_single_contact_reaches_the_analytic_steady_velocity(dw):
    cfg = _single_contact(dw)
    ds = run(cfg)
    a = ds.attrs
    assert a["status"] == "completed" and a["velocity_status"] == "ok", a["velocity_reason"]
    law, amp = cfg.contact_law, cfg.epsilon * cfg.f0
    # steady state: every block at v, so the one contact carries the whole load, f(v, v0) = dw*epsilon*f0
    v_exact = 10 ** brentq(lambda lv: law.force(np.array([10**lv]), cfg.v0)[0] / amp - dw, -12, np.log10(cfg.v0))
    assert abs(a["velocity"] - v_exact) <= 3 * a["velocity_sem"], (a["velocity"], v_exact, a["velocity_sem"])
    assert abs(a["velocity"] / v_exact - 1) < 0.05
    assert a["mu_star"] == dw and a["check_energy_balance_passed"] == 1


@pytest.mark.parametrize("eta_c", [1e5, 0.0])
def test_above_the_maximum_the_slider_runs_away(eta_c):
    a = run(_single_contact(1.02, eta_c=eta_c)).attrs
    assert a["velocity_status"] == "runaway" and np.isnan(a["velocity"])
    assert "runaway" in a["velocity_reason"]


def test_dead_weight_is_off_by_default_and_leaves_member_ids_unchanged():
    cfg = make_config()
    assert cfg.dead_weight is None
    # the id of a spring-drive config does not see the new option (stores written before it stay valid)
    assert member_id(cfg) == member_id(make_config(dead_weight=None))
    assert member_id(cfg) != member_id(make_config(dead_weight=0.9))
    with pytest.raises(Exception, match="config key 'dead_weight' has value -1.0"):
        make_config(dead_weight=-1.0)


# The slab's rigid top with a mass of its own (issue 29: the tester's plate, what sits on it and the hanging weight)

@pytest.mark.parametrize("top_mass", [1e-6, 4e-6])
def test_a_heavy_top_under_a_step_weight_accelerates_as_newton_says(top_mass):
    """A weight a hundred times the largest friction the contacts can give, applied at once to a slab
    whose top carries top_mass per block (a thousand blocks' mass and more): the plate and the blocks move
    together at F_b / (m + upper_mass) (momentum: the body's and the dampers' forces are internal, the
    contacts' at most 1 % of F_b), so X = F_b t**2 / (2 (m + upper_mass)); measured within 1.1 % in the
    first microsecond (the blocks catch up with the plate) and 0.3 % after."""
    from slipchain.model.system import build_system, dead_weight_force

    cfg = make_config(geometry="slab", N=8, Ly=8, N_L=5, theta=0.5, epsilon=1e-2, seed=0, integrator="fold", dt=1e-8,
                      output_interval=1e-6, t_total=2e-5, t_ramp=1e-6, dead_weight=100.0, start="rest",
                      top_mass=top_mass)
    assert cfg.upper_mass == pytest.approx(cfg.N_L * cfg.m + top_mass, rel=1e-15)
    ds = run(cfg, progress=False)
    t = ds.time.values
    want = dead_weight_force(build_system(cfg)) * t**2 / (2 * (cfg.m + cfg.upper_mass))
    rel = ds.X_mean.values / want - 1
    assert abs(rel[0]) < 0.015 and np.abs(rel[4:]).max() < 0.005, rel
    assert ds.attrs["check_energy_balance_passed"] == 1


def test_the_testers_top_is_the_load_and_the_hanging_weight():
    """top_mass = 'tester': (1 + mu_a) p0 a**2 / g per block with p0 = theta p_theta1 (absent: epsilon tau_f, so
    that p0 a**2 is the model's normal force per block epsilon f0 theta); its plate mode's
    stable step is the linear analysis' (heavier: not below the bare slab's); bad combinations are named."""
    from slipchain.model.config import ConfigError

    base = dict(geometry="slab", N=8, Ly=8, N_L=50, theta=0.4, dead_weight=0.8, epsilon=1.0, t_total=1e-3)
    cfg = make_config(**base, top_mass="tester", p_theta1=5e4)
    assert cfg.p_nominal == pytest.approx(2e4)
    assert cfg.upper_mass == pytest.approx(50 * cfg.m + 1.8 * 2e4 * 1e-8 / 9.80665, rel=1e-12)
    assert cfg.dt_stable >= make_config(**base).dt_stable
    # the default: the model's own normal stress epsilon tau_f at theta = 1 (p0 a**2 = epsilon f0 theta)
    assert make_config(**base, top_mass="tester").p_nominal * 1e-8 == pytest.approx(cfg.epsilon * cfg.f0 * 0.4)
    for bad, key in ((dict(top_mass="tester", dead_weight=None), "top_mass"), (dict(p_theta1=5e4), "p_theta1"),
                     (dict(top_mass="heavy"), "top_mass"), (dict(top_mass=-1.0), "top_mass"),
                     (dict(top_mass="tester", geometry="chain2d"), "top_mass")):
        with pytest.raises(ConfigError, match=f"config key '{key}'"):
            make_config(**{**base, **bad})


def test_certain_runaway_reads_both_halves_of_the_last_stretch():
    """certain_runaway on records of exact velocities (v0 10**delta = 1e-3 m/s: the branch's bound
    RUNAWAY_FACTOR v0 10**delta = 0.01 m/s): beyond it over both halves of the last RUNAWAY_WINDOW and
    faster over the second, a runaway; decelerating, or below the bound over the first half, or a record
    shorter than half the window, not."""
    from slipchain.results.schema import RUNAWAY_WINDOW, certain_runaway

    cfg = make_config(N=11, theta=1.0, delta=0.0, dead_weight=1.0, t_ramp=0.15, t_decide=0.2, t_max=0.3,
                      stop_at_runaway=True)
    t = np.arange(1, 4001) * 1e-5  # 40 ms: the window is the last 20 ms
    last = t > t[-1] - RUNAWAY_WINDOW

    def record(v_first, v_second):
        v = np.where(t <= t[-1] - 0.5 * RUNAWAY_WINDOW, v_first, v_second)
        return np.cumsum(v * 1e-5)

    assert "0.015 -> 0.03 m/s" in certain_runaway(cfg, t, record(0.015, 0.03))
    assert certain_runaway(cfg, t, record(0.03, 0.015)) is None  # slowing down
    assert certain_runaway(cfg, t, record(0.005, 0.05)) is None  # not yet beyond the branch over the first half
    assert certain_runaway(cfg, t[-500:], record(0.015, 0.03)[-500:]) is None  # 5 ms: too short to say
    assert last.sum() == 2000


def test_stop_at_runaway_ends_the_run_soon_after_the_onset_with_the_same_record():
    """Identical contacts loaded over 0.1 s to 1.2 times eq. (1)'s maximum: with stop_at_runaway the run
    stops at the certain runaway, within RUNAWAY_WINDOW of the onset (measured 10 ms here; on the tester's
    32 x 32 block 33 ms, against the 0.13 s the decision from t_decide took; docs/tester-3d), classified
    runaway; its record is
    the full run's up to there, bit for bit, so the onset read from it is the same."""
    from slipchain.analysis.traces import runaway_onset
    from slipchain.workflows.dead_weight import single_contact_maximum

    ident = dict(N=11, theta=1.0, delta=0.0, start="rest")
    f_max, _ = single_contact_maximum(make_config(**ident, t_total=5e-3))
    cfg = dict(ident, dead_weight=1.2 * f_max, t_ramp=0.1, t_decide=0.11, t_max=0.2, output_interval=1e-5)
    full, short = run(cfg), run(dict(cfg, stop_at_runaway=True))
    assert full.attrs["velocity_status"] == short.attrs["velocity_status"] == "runaway"
    assert "stop_at_runaway" in short.attrs["velocity_reason"] and full.time.values[-1] >= 0.11 - 1e-9
    n = short.time.size
    for v in ("X_mean", "x_mean", "f_d"):
        assert np.array_equal(full[v].values[:n], short[v].values), v
    ons = [runaway_onset(make_config(**c), ds.time.values, ds.X_mean.values, ds.x_mean.values)
           for c, ds in ((cfg, full), (dict(cfg, stop_at_runaway=True), short))]
    assert ons[0]["during_ramp"] and ons[0]["t_onset"] < short.time.values[-1] < ons[0]["t_onset"] + 0.02
    for key in ("mu_onset", "mu_onset_10", "mu_slip"):
        assert ons[0][key] == ons[1][key], key
    for bad in (dict(t_total=0.1), dict(t_decide=0.11, t_max=0.2), dict(t_ramp=1e-3, t_decide=0.11, t_max=0.2)):
        with pytest.raises(Exception, match="stop_at_runaway.*unless dead_weight and t_decide.*at least half"):
            make_config(**ident, dead_weight=0.5, **bad, stop_at_runaway=True)  # no decision, no ramp, a release
    assert member_id(make_config(**cfg)) == member_id(make_config(**cfg, stop_at_runaway=False))
    assert "stop_at_runaway" not in make_config(**cfg).to_toml()

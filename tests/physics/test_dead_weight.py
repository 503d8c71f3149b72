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

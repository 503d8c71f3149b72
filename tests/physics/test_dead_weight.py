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

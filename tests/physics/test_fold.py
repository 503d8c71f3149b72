"""integrator = 'fold' (issue 12, first part): the contact equation's folds, the branch the solver
keeps and the jump when a branch ends, identity with the fixed step below the unique-root limit,
and first-order convergence through slip events above it."""

import math

import numpy as np
import pytest

import slipchain as sc
from slipchain.engine import scheme as S
from slipchain.engine.backends import cpu as K
from slipchain.model.config import ConfigError, make_config
from slipchain.sweeps.definition import member_id


def _H(y, a, b, c, ra):
    return a * 10.0**y + b * np.exp(-c * y * y) - ra


def _dH(y, a, b, c):
    return math.log(10.0) * a * 10.0**y - 2.0 * c * y * b * np.exp(-c * y * y)


def test_fold_points_are_where_the_slope_vanishes_and_appear_at_the_unique_root_limit():
    cfg = make_config()
    law = cfg.contact_law
    vs = cfg.v0 * 10.0 ** (-cfg.delta)  # the slowest contact sets Config's unique-root limit
    limit = cfg.dt_unique_root_limit
    for dt, folds in ((0.98 * limit, False), (1.02 * limit, True), (10 * limit, True)):
        a, b = cfg.m * (1 + dt * cfg.eta_c) * vs, dt * cfg.epsilon * cfg.f0
        ya, yb = S.fold_points(np.array([a]), b, cfg.c)
        assert bool(np.isfinite(ya[0])) == folds
        if folds:
            assert 0 < ya[0] < yb[0]
            scale = math.log(10.0) * a * 10.0 ** yb[0]
            assert abs(_dH(ya[0], a, b, cfg.c)) < 1e-9 * scale and abs(_dH(yb[0], a, b, cfg.c)) < 1e-9 * scale
            mid = 0.5 * (ya[0] + yb[0])
            assert _dH(mid, a, b, cfg.c) < 0 < _dH(ya[0] - 0.1, a, b, cfg.c) and _dH(yb[0] + 0.1, a, b, cfg.c) > 0
    assert law.epsilon == cfg.epsilon


def test_fold_solver_keeps_its_branch_and_jumps_when_it_ends():
    """Three roots: the lower (sticking) one from a lower warm start, the upper (sliding) one from
    an upper start; past the lower branch's fold (|r| above H's local maximum) the jump to the
    upper root, and back below the upper fold the jump down. Every root solves the equation and
    has dH/dy > 0 (a stable branch)."""
    cfg = make_config()
    vs, dt = cfg.v0 * 10.0 ** (-cfg.delta), 20 * cfg.dt_unique_root_limit
    m_eff, b, c = cfg.m * (1 + dt * cfg.eta_c), dt * cfg.epsilon * cfg.f0, cfg.c
    a = m_eff * vs
    ya, yb = (float(v[0]) for v in S.fold_points(np.array([a]), b, c))
    h_max = _H(ya, a, b, c, 0.0)  # ra at which the lower root disappears
    h_min = _H(yb, a, b, c, 0.0)  # ra below which the upper root disappears
    assert h_min < h_max

    def solve(ra, y0):
        u, y, p, q = K.solve_contact_fold(ra, m_eff, b, c, vs, y0, 10.0**y0, math.exp(-c * y0 * y0), ya, yb)
        assert abs(_H(y, a, b, c, abs(ra))) < 1e-10 * abs(ra) and _dH(y, a, b, c) > 0
        assert u == pytest.approx(math.copysign(vs * 10.0**y, ra), rel=1e-12)
        return y

    ra3 = 0.5 * (h_min + h_max)  # three roots
    assert solve(ra3, ya - 0.5) < ya and solve(ra3, yb + 0.5) > yb
    assert solve(1.01 * h_max, ya - 0.5) > yb  # the lower branch ended: jump up
    assert solve(0.99 * h_min, yb + 0.5) < ya  # the upper branch ended: jump down
    assert solve(-ra3, ya - 0.5) < ya  # sign: same branch logic for r < 0
    # without folds it is the fixed-step solver
    y0 = 0.1
    args = (ra3, m_eff, b, c, vs, y0, 10.0**y0, math.exp(-c * y0 * y0))
    assert K.solve_contact_fold(*args, math.inf, -math.inf) == K.solve_contact(*args)


def test_fold_below_the_unique_root_limit_is_the_fixed_step_bit_for_bit():
    base = dict(N=31, theta=0.5, seed=3, t_total=1e-3, start="steady", dt=2e-8)
    a, b = sc.run(dict(base, integrator="fixed")), sc.run(dict(base, integrator="fold"))
    assert np.array_equal(a.f_d.values, b.f_d.values) and np.array_equal(a.x.values, b.x.values)
    assert member_id(make_config(**base, integrator="fixed")) != member_id(make_config(**base, integrator="fold"))


def test_fold_converges_through_slip_events_above_the_unique_root_limit():
    """Steady start, N = 31: slip events within the first millisecond (f_d drops by up to 65 %).
    f_d(t) of the fold integrator at dt = 5e-8 and 1e-7 (1.4 and 2.8 times the unique-root limit)
    against the fixed step at dt = 2.5e-9: first order, the error halves with dt."""
    base = dict(N=31, theta=0.5, seed=3, t_total=1e-3, output_interval=1e-5, start="steady")
    ref = sc.run(dict(base, dt=2.5e-9, integrator="fixed")).f_d.values
    assert np.diff(ref).min() < -0.3 * ref.max()  # there are slip events
    errs = [np.abs(sc.run(dict(base, dt=dt, integrator="fold")).f_d.values - ref).max() / ref.max()
            for dt in (5e-8, 1e-7)]
    assert errs[0] < 1e-2 and errs[0] < 0.6 * errs[1], errs


def test_fold_step_is_bounded_by_the_explicit_part_only():
    cfg = make_config(integrator="fold", dt=2e-7)  # 5.6 times the unique-root limit
    assert cfg.dt > cfg.dt_unique_root_limit
    with pytest.raises(ConfigError, match="several roots.*integrator = 'adaptive'.*or 'fold'"):
        make_config(dt=2e-7, integrator="fixed")
    with pytest.raises(ConfigError, match="dt < 6.866e-07 s, the largest stable step"):
        make_config(integrator="fold", dt=7e-7)  # the springs and damping together (6.9e-7 s), not 8.9e-7 s
    with pytest.raises(ConfigError, match="largest stable step"):
        make_config(integrator="fold", dt=5e-7, eta=3e6)
    with pytest.raises(ConfigError, match="'integrator'"):
        make_config(integrator="rk4")

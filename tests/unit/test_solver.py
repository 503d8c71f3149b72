"""The per-contact implicit equation m_eff*u + dt*f(u) = r against scipy's brentq."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from slipchain.engine.backends import cpu as K
from slipchain import make_config

CFG = make_config(integrator="fixed")  # the fixed step's solver: dt below the unique-root limit
M_EFF = CFG.m * (1 + CFG.dt * CFG.eta_c)
B = CFG.dt * CFG.epsilon * CFG.f0


def reference_velocity(r, vstar, c=CFG.c):
    """Root of m_eff*u + B*exp(-c log10(|u|/v*)^2) sign(u) = r, by brentq on log10|u|."""
    if r == 0:
        return 0.0
    ra = abs(r)

    def h(y):
        return M_EFF * vstar * 10**y + B * math.exp(-c * y * y) - ra

    y_hi = math.log10(ra / (M_EFF * vstar))
    y = brentq(h, -200.0, y_hi + 1e-12, xtol=1e-15, rtol=1e-15, maxiter=500)
    return math.copysign(vstar * 10**y, r)


@settings(max_examples=300)
@given(st.floats(-25.0, -8.0), st.sampled_from([-1.0, 1.0]), st.floats(-3.5, -2.5), st.floats(-30.0, 3.0))
def test_solve_contact_matches_brentq(log_r, sign, log_vstar, y_guess):
    r, vstar = sign * 10**log_r, 10**log_vstar
    p, q = math.exp(K.LN10 * y_guess), math.exp(-CFG.c * y_guess**2)
    u, y, p1, q1 = K.solve_contact(r, M_EFF, B, CFG.c, vstar, y_guess, p, q)
    expected = reference_velocity(r, vstar)
    assert u == pytest.approx(expected, rel=1e-8)
    # The returned solver state is consistent with the velocity.
    assert p1 == pytest.approx(abs(u) / vstar, rel=1e-12)
    assert q1 == pytest.approx(math.exp(-CFG.c * y * y), rel=1e-9)
    # The residual of the equation is small against its terms.
    resid = M_EFF * u + B * math.exp(-CFG.c * y * y) * math.copysign(1, u) - r
    assert abs(resid) <= 1e-8 * (abs(r) + B)


def test_coulomb_limit_c_zero():
    vstar = 1e-3
    u, *_ = K.solve_contact(0.5 * B, M_EFF, B, 0.0, vstar, 0.0, 1.0, 1.0)
    assert u == 0.0  # stuck: |r| below the threshold
    u, *_ = K.solve_contact(-3.0 * B, M_EFF, B, 0.0, vstar, 0.0, 1.0, 1.0)
    assert u == pytest.approx(-2.0 * B / M_EFF, rel=1e-14)


def test_zero_and_tiny_impulse():
    assert K.solve_contact(0.0, M_EFF, B, CFG.c, 1e-3, 0.0, 1.0, 1.0)[0] == 0.0
    u, *_ = K.solve_contact(1e-200, M_EFF, B, CFG.c, 1e-3, 0.0, 1.0, 1.0)
    assert 0.0 <= u < 1e-200 / M_EFF


def test_vectorised_newton_pass_agrees_with_scalar_solver():
    rng = np.random.default_rng(1)
    nc = 200
    vstar = 1e-3 * 10 ** rng.uniform(-0.5, 0.5, nc)
    u_true = 10 ** rng.uniform(-12, -2, nc)
    y_true = np.log10(u_true / vstar)
    ra = M_EFF * u_true + B * np.exp(-CFG.c * y_true**2)
    # Warm start near the root (as after one time step), some too far for one step.
    y0 = y_true + rng.normal(0, 1e-4, nc)
    y0[::10] += 0.5
    ys = np.stack([y0, 10**y0, np.exp(-CFG.c * y0**2)])
    unew, ok = np.empty(nc), np.empty(nc, dtype=bool)
    K.newton_pass(nc, ra, vstar, ys, unew, ok, M_EFF, B, CFG.c)
    assert ok.sum() > 0.5 * nc and not ok[::10].any()
    np.testing.assert_allclose(unew[ok], u_true[ok], rtol=1e-8)
    for k in np.flatnonzero(~ok):
        u, *_ = K.solve_contact(ra[k], M_EFF, B, CFG.c, vstar[k], ys[0, k], ys[1, k], ys[2, k])
        assert u == pytest.approx(u_true[k], rel=1e-8)

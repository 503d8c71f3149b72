"""Eq. (1): limits, symmetry, derivative against finite differences, extreme inputs."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipchain import make_config

LAW = make_config().contact_law  # epsilon=1e-2, f0=0.065 N, c=0.1, m=1e-9 kg, eta_c=1e5 1/s


def test_zero_velocity_and_peak():
    assert LAW.force(0.0, 1e-3) == 0.0
    # At u = v*: xi = 0, so f = epsilon*f0 + m*eta_c*v*.
    assert LAW.force(1e-3, 1e-3) == pytest.approx(LAW.amplitude + LAW.m * LAW.eta_c * 1e-3, rel=1e-15)
    # One decade away: exp(-c) of the peak.
    assert LAW.force(1e-2, 1e-3) - LAW.m * LAW.eta_c * 1e-2 == pytest.approx(LAW.amplitude * np.exp(-0.1), rel=1e-14)


@given(st.floats(1e-30, 1e3), st.floats(1e-6, 1e0))
def test_odd_in_velocity(u, vstar):
    assert LAW.force(-u, vstar) == -LAW.force(u, vstar)
    assert LAW.derivative(-u, vstar) == LAW.derivative(u, vstar)


@settings(max_examples=200)
@given(st.floats(-8.0, 3.0), st.floats(-4.0, -2.0))
def test_derivative_matches_finite_difference(log_u, log_vstar):
    u, vstar = 10.0**log_u, 10.0**log_vstar
    h = u * 1e-6
    fd = (LAW.force(u + h, vstar) - LAW.force(u - h, vstar)) / (2 * h)
    assert LAW.derivative(u, vstar) == pytest.approx(fd, rel=1e-5, abs=1e-9 * abs(LAW.derivative(u, vstar)) + 1e-12)


def test_extreme_inputs_are_finite_and_silent():
    u = np.array([0.0, 5e-324, 1e-300, 1e-30, 1e300, 1.7e308, -5e-324, -1.7e308])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f = LAW.force(u, 1e-3)
        d = LAW.derivative(u, 1e-3)
    assert np.all(np.isfinite(f)) and np.all(np.isfinite(d))
    # Far below v*, the law goes to zero faster than any power of u; its slope tends to m*eta_c.
    assert abs(f[1]) < 1e-300 and d[1] == pytest.approx(LAW.m * LAW.eta_c)


def test_average_over_contacts():
    vstars = np.array([3e-4, 1e-3, 2e-3])
    u = np.array([1e-4, 1e-3])
    avg = LAW.average(u, vstars)
    expected = np.array([np.mean([LAW.force(v, s) for s in vstars]) for v in u])
    np.testing.assert_allclose(avg, expected, rtol=1e-15)
    with pytest.raises(ValueError, match="empty"):
        LAW.average(u, [])


def test_max_weakening_slope_matches_numerical_derivative():
    vstar = 10**-3.5
    u = np.logspace(-3.5, 0, 200_001)
    # Without contact damping the derivative is that of the velocity-dependent part alone.
    law0 = make_config(eta_c=0.0).contact_law
    numerical = -law0.derivative(u, vstar).min()
    assert law0.max_weakening_slope(vstar) == pytest.approx(numerical, rel=1e-6)
    # MODEL.md: about 0.014*epsilon*f0/v* N s/m, at u ~ 2.7 v*.
    assert numerical * vstar / law0.amplitude == pytest.approx(0.014, rel=0.05)
    assert u[np.argmin(law0.derivative(u, vstar))] / vstar == pytest.approx(2.7, rel=0.05)

"""Convergence in dt at the documented order (1), and agreement with solve_ivp (Radau)."""

import numpy as np
import pytest

from slipchain import build_system, initial_state, make_config, simulate
from slipchain.engine.reference import reference_fd

WINDOW = dict(N=11, theta=4 / 11, v0=3e-3, delta=0.4, start="steady", t_total=2e-5, output_interval=1e-6,
              integrator="fixed")  # the scheme's own order


def _system(dt):
    # Four contacts with v* in [1.2, 7.5] v_d: steady sliding is stable; the steady start is not
    # an exact equilibrium, so the window holds a damped transient of springs and contacts.
    return build_system(make_config(**WINDOW, dt=dt))


@pytest.fixture(scope="module")
def runs():
    return {dt: simulate(_system(dt)).f_d.values for dt in (2e-8, 1e-8, 5e-9, 1.25e-9)}


def test_first_order_convergence_of_fd(runs):
    ref = runs[1.25e-9]
    errs = [np.max(np.abs(runs[dt] - ref)) for dt in (2e-8, 1e-8, 5e-9)]
    # Against a reference 4x finer than the smallest dt, a first-order error e ~ C dt gives
    # ratios (16-1)/(8-1) ~ 2.1 and (8-1)/(4-1) ~ 2.3.
    assert 1.8 < errs[0] / errs[1] < 2.5
    assert 1.9 < errs[1] / errs[2] < 2.8


def test_kernel_agrees_with_solve_ivp(runs):
    system = _system(2e-8)
    fd_ref, res = reference_fd(system, initial_state(system), 1e-6, 20)
    scale = np.max(np.abs(fd_ref))
    err_fine = np.max(np.abs(runs[1.25e-9] - fd_ref))
    err_coarse = np.max(np.abs(runs[2e-8] - fd_ref))
    assert err_fine < 5e-5 * scale
    # The independent reference sees the same first-order error: 16x smaller dt, ~16x smaller error.
    assert 10 < err_coarse / err_fine < 25

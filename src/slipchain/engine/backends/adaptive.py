"""integrator = 'adaptive' (issue 12): the fold-aware scheme with a step that doubles while nothing happens.

At the physical contact stiffness (epsilon = 1) a slip cycle is a few milliseconds of slip and
about a second of reloading, during which every contact sits on its sticking branch and the
chain creeps. The fold-aware contact solve (:func:`~slipchain.engine.scheme.solve_contact_fold`)
has no step limit of its own, so the step is bounded only by the explicit springs and dampers
(Config.dt_stable, their linear stability limit together; the largest level stays within 0.9 of
it, issue 26). The adaptive stepper (:func:`.compose.adaptive_stepper`, composed with every
body) runs the scheme of :mod:`slipchain.engine.scheme` unchanged (the CPU's compiled parts:
:mod:`.cpu`) with a step h = dt * 2**k, k = 0 ... ``Config.step_levels``; this module holds its
controller's parts:

* **Error estimate.** For a first-order step the local velocity error is ~ h**2/2 |du/dt'|; it is
  estimated from two consecutive steps as ``err = h/2 * max_i |a_i^n - a_i^(n-1)|`` over both
  chains' blocks, a_i^n = (u_i^(n+1) - u_i^n)/h (at creep ~0; at a slip event, or while fast modes
  ring, large).
* **Control.** A step above level 0 with err > tol (``step_tol * v_d``, m/s) is rejected: the
  state is still the step's start (the positions move only after acceptance; the contacts' solver
  state is restored) and the step is taken again at the level where the estimate, falling by 4
  per halving, meets tol. So a slip event starts on a fine step. After an accepted step with
  err < tol/8 the level rises by one.
* **Time grid.** A step of level k starts only where the base-step count within the output sample
  is a multiple of 2**k and ends within the sample: the samples (and the drive, v_d t with t the
  base-step count times dt) are those of the fixed step. Each sample starts at level 0 with no
  estimate, so that nothing but the batch's arrays carries from one sample to the next: a run
  resumed from a checkpoint is bit for bit the uninterrupted one.
* **Sums** (f_d per sample, per-contact sums, works) are weighted by the step: in base steps, so
  the recorder's averages are time averages.

``step_tol`` -> 0 gives the fold integrator at dt (every step at level 0): tests/physics/test_adaptive.py.
"""

from __future__ import annotations

import numba as nb

from ..scheme import C_F, C_SLOW, C_U, C_U2, N_YS_STATE, Y_FA, Y_FB
from .cpu import contact_power

STEP_UP = 0.125  # raise the level when err < STEP_UP * tol (doubling the step multiplies err by ~4)


@nb.njit
def _weighted_contact_sums(nc, fk, uk, ca, slow, w):
    """Per-contact sums as :func:`.cpu._contact_sums`, each step counted ``w`` times (its base steps);
    returns sum f*u. Kept apart: that one is compiled with fastmath (sums contracted to FMA), which
    with w != 1 would change this kernel's sums in their last bits. The power sum f*u is the fixed
    step's (:func:`.cpu.contact_power`): at w = 1 both steppers give the same contact work, bit for
    bit (issue 26: it was summed here in strict order, and differed in the last bit)."""
    for k in range(nc):
        ca[C_F, k] += w * fk[k]
        ca[C_U, k] += w * uk[k]
        ca[C_U2, k] += w * uk[k] * uk[k]
        ca[C_SLOW, k] += w if abs(uk[k]) < slow else 0.0
    return contact_power(nc, fk, uk)


@nb.njit
def _grid_level(level, j, sample_steps):
    """The highest level up to ``level`` whose step starts on its grid (j base steps into the sample,
    a multiple of 2**level) and ends within the sample (module docstring, "Time grid")."""
    while level > 0 and (j % (1 << level) != 0 or j + (1 << level) > sample_steps):
        level -= 1
    return level


@nb.njit
def _load_folds(nc, ys, folds_level):
    """The contacts' folds at this level's step (``folds_level``: (2, C)) into the solver's input rows."""
    for k in range(nc):
        ys[Y_FA, k] = folds_level[0, k]
        ys[Y_FB, k] = folds_level[1, k]


@nb.njit
def _copy_solver_state(nc, src, dst):
    """The contacts' solver state (its first N_YS_STATE rows: y, 10**y, exp(-c y^2)) from ``src`` to
    ``dst``: kept before a step that may be rejected, put back when it is."""
    for i in range(N_YS_STATE):
        for k in range(nc):
            dst[i, k] = src[i, k]


@nb.njit
def _rejected_level(level, err, tol):
    """After a rejected step: the level where the estimate, falling by 4 per halving, meets tol."""
    while level > 0 and err > tol:
        level -= 1
        err *= 0.25
    return level


@nb.njit
def _error(n, ur, Ur, un, Un, aprev, h):
    """h/2 max |a^n - a^(n-1)| over both chains, a^n = (u^(n+1) - u^n)/h, a^(n-1) in ``aprev``."""
    err = 0.0
    for i in range(n):
        err = max(err, abs((un[i] - ur[i]) / h - aprev[i]), abs((Un[i] - Ur[i]) / h - aprev[n + i]))
    return 0.5 * h * err


@nb.njit
def _keep_acceleration(n, ur, Ur, un, Un, aprev, h):
    """Store a^n = (u^(n+1) - u^n)/h of an accepted step in ``aprev``."""
    for i in range(n):
        aprev[i] = (un[i] - ur[i]) / h
        aprev[n + i] = (Un[i] - Ur[i]) / h


__all__ = ["STEP_UP"]

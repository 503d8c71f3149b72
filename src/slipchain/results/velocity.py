"""Steady sliding velocity from a distance trace, with its uncertainty; runaway detection.

The slider starts from rest and accelerates until the friction force ``mu(v)*M*g`` balances the
hanging weight ``M'*g`` (Fig. 1 of the paper). On the rising branch of mu(v) it then slides at a
steady velocity; above the first maximum of mu(v) no balance exists and it keeps accelerating
(``runaway``): the set-up only measures the rising branch.

Algorithm (all choices are constants below):

1. Candidate windows ``[t_k, t_end]`` start at ``t_k = t_0 + k*T/10``, k = 0..6, so a window
   always holds at least the last 40 % of the record.
2. On each window fit ``x = a + b*tau + c*tau**2`` (least squares, tau = t - mid-window). The
   velocity change across the window is ``dv = 2*c*W`` (W its length). The window is steady when
   the change is small (``|dv| <= 1 %`` of ``b``) or not significant (``|dv| <= 3 SE(dv)``).
3. The first steady window (the earliest start: the longest window) gives the velocity: the slope
   of a straight-line fit, and its standard error from the residuals, inflated by
   ``sqrt((1+rho)/(1-rho))`` for a positive lag-1 autocorrelation ``rho`` of the residuals
   (correlated noise, e.g. unresolved stick-slip, carries less information than white noise),
   combined in quadrature, when the window's velocity change ``dv`` is significant, with
   ``|dv|/sqrt(12)``, the spread of a velocity that drifts by ``dv`` across the window (what is
   left of the start-up transient).
   A window counts only if the slider moves: ``b > 3 SE(b)``.
4. No steady window: ``runaway`` if the last window accelerates significantly (c > 0); else
   ``no-steady`` (decelerating or irregular). A slider that does not move is ``no-steady`` too.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

N_STARTS = 7  # candidate window starts: 0, 10, ..., 60 % of the record
REL_TOL = 0.01  # a window is steady if its velocity changes by at most this fraction...
SIGMAS = 3.0  # ...or the change is not significant at this many standard errors



class VelocityStatus(StrEnum):
    """Outcome of :func:`steady_velocity` (str-valued: files and tables hold the plain words)."""

    OK = "ok"
    RUNAWAY = "runaway"
    NO_STEADY = "no-steady"


OK, RUNAWAY, NO_STEADY = VelocityStatus.OK, VelocityStatus.RUNAWAY, VelocityStatus.NO_STEADY


@dataclass(frozen=True)
class VelocityFit:
    status: str  # ok | runaway | no-steady
    velocity: float  # m/s (NaN unless ok)
    sem: float  # m/s
    t_start: float  # start of the steady window, s
    n_points: int  # points in the window
    reason: str
    change: float = float("nan")  # ok: relative velocity change dv/b across the steady window


def _poly_fit(tau: np.ndarray, x: np.ndarray, deg: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least squares polynomial (coefficients low order first), covariance, residuals."""
    A = np.vander(tau, deg + 1, increasing=True)
    coef, *_ = np.linalg.lstsq(A, x, rcond=None)
    resid = x - A @ coef
    dof = max(tau.size - (deg + 1), 1)
    s2 = float(resid @ resid) / dof
    cov = s2 * np.linalg.pinv(A.T @ A)
    return coef, cov, resid


def _sd(variance: float) -> float:
    """The standard deviation of a fitted coefficient from its variance. A trace the polynomial fits
    exactly (a run that slides at constant velocity to the last bit) has a variance of zero, which
    the pseudo-inverse returns as a round-off of either sign: that is zero, not a NaN."""
    return float(np.sqrt(max(float(variance), 0.0)))


def _in_se(value: float, se: float) -> str:
    """``value`` in units of its standard error, for a message (a fit without noise has none)."""
    return f"{value / se:.1f} SE" if se > 0 else "a fit without noise"


def _lag1(resid: np.ndarray) -> float:
    r = resid - resid.mean()
    den = float(r @ r)
    return float(r[:-1] @ r[1:]) / den if den > 0 else 0.0


def window_start(t: np.ndarray, k: int) -> float:
    """Where the k-th candidate window of :func:`steady_velocity` starts: k tenths of the record in (k < N_STARTS)."""
    return t[0] + k * (t[-1] - t[0]) / 10


def steady_velocity(t: np.ndarray, x: np.ndarray, rel_tol: float = REL_TOL) -> VelocityFit:
    """Find the steady-sliding window of one trace and fit the velocity (see module docstring;
    ``rel_tol`` the small velocity change of step 2, REL_TOL for the tester)."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    last = None
    for k in range(N_STARTS):
        t_k = window_start(t, k)
        sel = t >= t_k
        tt, xx = t[sel], x[sel]
        if tt.size < 10:
            break
        mid = 0.5 * (tt[0] + tt[-1])
        W = tt[-1] - tt[0]
        coef, cov, _ = _poly_fit(tt - mid, xx, 2)
        b, c = coef[1], coef[2]
        dv, se_dv = 2 * c * W, 2 * W * _sd(cov[2, 2])
        moving = b > SIGMAS * _sd(cov[1, 1])
        last = (moving, b, dv, se_dv, W)
        if moving and (abs(dv) <= rel_tol * b or abs(dv) <= SIGMAS * se_dv):
            lin, lcov, resid = _poly_fit(tt - mid, xx, 1)
            rho = _lag1(resid)
            inflate = np.sqrt((1 + rho) / (1 - rho)) if 0 < rho < 1 else 1.0
            drift = dv / np.sqrt(12.0) if abs(dv) > SIGMAS * se_dv else 0.0  # a real (significant) drift
            sem = float(np.hypot(_sd(lcov[1, 1]) * inflate, drift))
            return VelocityFit(OK, float(lin[1]), sem, float(t_k), int(tt.size),
                               f"steady from t = {t_k:.4g} s ({tt.size} points); velocity change over the window "
                               f"{dv / b:+.1%}", float(dv / b))
    if last is None:
        return VelocityFit(NO_STEADY, float("nan"), float("nan"), float("nan"), 0, "too few points for a window")
    moving, b, dv, se_dv, W = last
    if not moving:
        return VelocityFit(NO_STEADY, float("nan"), float("nan"), float("nan"), 0,
                           f"the slider does not move forward in the last {W:.3g} s (velocity {b:.3g} m/s, not "
                           f"significantly above 0)")
    if dv > 0:
        return VelocityFit(RUNAWAY, float("nan"), float("nan"), float("nan"), 0,
                           f"runaway: the velocity still rises by {dv / b:+.0%} ({_in_se(dv, se_dv)}) over the last "
                           f"{W:.3g} s, as above the maximum of mu(v)")
    return VelocityFit(NO_STEADY, float("nan"), float("nan"), float("nan"), 0,
                       f"no steady sliding: the velocity changes by {dv / b:+.0%} ({_in_se(dv, se_dv)}) over the "
                       f"last {W:.3g} s")


__all__ = ["NO_STEADY", "OK", "RUNAWAY", "VelocityFit", "VelocityStatus", "steady_velocity", "window_start"]

"""The frictional contact law, eq. (1) of Braun et al., EPL 113, 56002 (2016).

    f(u, v*) = epsilon*f0*exp(-c*xi)*sign(u) + m*eta_c*u,   xi = (log10(|u|/v*))**2     (1a, 1b)

with f(0, v*) = 0, the limit of (1a) as u -> 0 (the exponential vanishes faster than any
power of |u|). Paper symbols: epsilon = our ``epsilon``, f0 = a**2*tau_f, c, eta_c, v_i^* = ``vstar``.

Every function is vectorised over ``u`` and ``vstar`` and is safe at u = 0, for |u| down to the
smallest subnormal and up to the largest finite float (no NaN, no overflow warnings): the
exponentials are evaluated in log space.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

LN10 = float(np.log(10.0))


@dataclass(frozen=True)
class ContactLaw:
    """Parameters of eq. (1). Holds numbers only; kernels receive these numbers, not the object.

    Attributes
    ----------
    epsilon : the paper's scaling factor varepsilon (1e-2 in the paper).
    f0 : a**2 * tau_f, the force scale [N].
    c : the width parameter c of the Gaussian in log10-velocity.
    m : the interface-block mass m [kg], multiplying the contact damping.
    eta_c : the contact damping rate eta_c [1/s].
    """

    epsilon: float
    f0: float
    c: float
    m: float
    eta_c: float

    @property
    def amplitude(self) -> float:
        """epsilon*f0 [N], the peak of the velocity-dependent part of f."""
        return self.epsilon * self.f0

    def force(self, u: ArrayLike, vstar: ArrayLike) -> np.ndarray:
        """f(u, v*) of eq. (1) [N]; odd in u, zero at u = 0."""
        u = np.asarray(u, dtype=float)
        au = np.abs(u)
        y = _log10_ratio(au, vstar)
        g = np.exp(-self.c * y * y)  # exp(-huge) underflows cleanly to 0
        return self.amplitude * g * np.sign(u) + self.m * self.eta_c * u

    def derivative(self, u: ArrayLike, vstar: ArrayLike) -> np.ndarray:
        """df/du [N s/m]; even in u, equal to m*eta_c at u = 0 (the limit).

        d/du [exp(-c y^2) sign(u)] = -2 c y exp(-c y^2) / (|u| ln 10),  y = log10(|u|/v*),
        evaluated as exp(log ...) so that tiny |u| neither overflows nor gives 0*inf.
        """
        u = np.asarray(u, dtype=float)
        au = np.abs(u)
        y = _log10_ratio(au, vstar)
        with np.errstate(divide="ignore"):
            log_mag = (
                np.log(self.amplitude)
                - self.c * y * y
                + np.log(2.0 * self.c * np.abs(y) / LN10)
                - np.log(np.where(au > 0, au, 1.0))
            )
        mag = np.where((au > 0) & (y != 0), np.exp(np.minimum(log_mag, 700.0)), 0.0)
        return -np.sign(y) * mag + self.m * self.eta_c

    def average(self, u: ArrayLike, vstar_set: ArrayLike) -> np.ndarray:
        """<f(u, v*_i)> = (1/N_c) sum_i f(u, v*_i): the dashed curve of Fig. 5. Shape of ``u``."""
        u = np.asarray(u, dtype=float)
        vs = np.asarray(vstar_set, dtype=float).ravel()
        if vs.size == 0:
            raise ValueError("average over an empty set of vstar: expected at least one contact")
        return self.force(u[..., None], vs).mean(axis=-1)

    def max_weakening_slope(self, vstar: float) -> float:
        """max over u > v* of -df/du (without the damping term) [N s/m].

        The weakening branch sets the largest time step for which the per-contact implicit
        equation m*u + dt*f(u) = r has a single root (docs/numerics.md).
        """
        y = np.linspace(1e-6, 20.0, 200_001)
        slope = 2.0 * self.c * y * np.exp(-self.c * y * y - LN10 * y) / LN10
        return float(self.amplitude * slope.max() / vstar)


def _log10_ratio(au: np.ndarray, vstar: ArrayLike) -> np.ndarray:
    """log10(|u|/v*), with -inf replaced by a finite value far below any relevant velocity."""
    with np.errstate(divide="ignore"):
        y = np.log10(au) - np.log10(np.asarray(vstar, dtype=float))
    # At |u| = 0 the law is defined by its limit; y = -1e6 makes exp(-c y^2) exactly 0.
    return np.where(au > 0, y, -1e6)

"""The slider's bulk as rubber (issue 28): a generalized Maxwell solid with a Prony series and
temperature by WLF time-temperature superposition.

Relaxation modulus (config ``material = "prony"``)::

    E(t) = E_inf + sum_j E_j exp(-t / tau_j),     E_inf = E (the config's E: the relaxed modulus,
                                                   the paper's 10 MPa), E_0 = E_inf + sum_j E_j (glassy)

so that the storage and loss moduli at angular frequency omega are (the Prony formulas)::

    E'(omega)  = E_inf + sum_j E_j (omega tau_j)^2 / (1 + (omega tau_j)^2)
    E''(omega) =         sum_j E_j  omega tau_j    / (1 + (omega tau_j)^2)

Every spring of the bulk scales with the same E(t)/E_inf: in the chains K = E a, K_L = N_L E a,
K_T = G a / N_L and, on the 2-D lattice, K_Y, K_LY (G = E / 2(1 + nu), nu fixed). The drive springs
K_d stay elastic at the relaxed value: they stand for the tester's drive (its arm, its load cell),
not for the rubber, and f_d = K_d (drive - X) stays the measured force. So each bulk spring of
extension e carries the force ``K (e + sum_j r_j q_j)``, r_j = E_j / E_inf, with one internal
variable per term obeying ``dq_j/dt = de/dt - q_j/tau_j``; by linearity the engine keeps one
displacement-like field per term and layer, ``xi_j`` (the blocks' displacement history seen
through term j), and the bulk force is the elastic stencil applied to ``x + sum_j r_j xi_j``.

Update (recursive convolution; exact for a displacement linear within the step, stable for any
step)::

    xi_j(t + h) = a_j xi_j(t) + tau_j (1 - a_j) (x(t + h) - x(t)) / h,     a_j = exp(-h / tau_j)

(tau_j >> h: xi_j follows x, the unrelaxed spring; tau_j << h: xi_j -> tau_j u, a dashpot of
coefficient E_j tau_j). The energy held by the Maxwell arms is ``sum_j r_j U_b(xi_j)`` with U_b the
bulk springs' elastic energy; what the arms dissipate over a run, W_bulk (negative), closes the
energy balance (:func:`slipchain.results.checks.stored_energy`).

Temperature (WLF, Williams-Landel-Ferry 1955): ``log10 a_T = -C1 (T - T_ref) / (C2 + T - T_ref)``
and every tau_j is multiplied by a_T (colder: slower). The contact law's v0 is **not** shifted:
it is a config key fitted at the temperature of the run (the paper fits Fig. 5's law at each
temperature); a user who wants it shifted sets v0 accordingly (:func:`shift_factor`).

The default compound (:data:`DEFAULT_COMPOUND`) is **synthetic**, not a measured one (no public
Prony table of a tread compound with numbers was found): E_inf = the paper's 10 MPa, glassy
modulus 1 GPa (typical of filled SBR below Tg), ten terms one per decade, tau_j = 1e-9 ... 1 s at
20 °C with E_j proportional to tau_j^-0.3 (a power-law transition, E' ~ omega^0.3): E'(1 Hz) =
12 MPa, E'(1 MHz) = 168 MPa, tan delta peaks at 0.5 near 1 MHz; Tg = -45 °C (an SBR tread) with
the universal WLF constants 17.44 and 51.6 K at Tg, i.e. C1 = 7.72, C2 = 116.6 K at 20 °C.
docs/guide/viscoelastic.md says more.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

T_REF = 20.0  # °C, reference temperature of the default compound's Prony terms
TG = -45.0  # °C, glass transition of the synthetic SBR tread compound
WLF_TG = (17.44, 51.6)  # the 'universal' WLF constants at Tg (C1, C2 in K)


def wlf_at(t_ref: float, tg: float = TG, c1g: float = WLF_TG[0], c2g: float = WLF_TG[1]) -> tuple[float, float]:
    """WLF constants (C1, C2) referred to ``t_ref`` from those at Tg: C2 = C2g + t_ref - Tg, C1 = C1g C2g / C2."""
    c2 = c2g + (t_ref - tg)
    return c1g * c2g / c2, c2


def _default_terms() -> tuple[tuple[float, ...], tuple[float, ...]]:
    k = np.arange(-9, 1)
    w = 10.0 ** (-0.3 * k)
    e = w / w.sum() * (1e9 - 10e6)
    return tuple(float(f"{x:.6g}") for x in e), tuple(float(f"1e{j}") for j in k)


@dataclass(frozen=True)
class Compound:
    """Prony terms (E_j in Pa, tau_j in s at T_ref in °C) and WLF constants (C1, C2 in K)."""

    E: tuple[float, ...]
    tau: tuple[float, ...]
    T_ref: float
    C1: float
    C2: float


DEFAULT_COMPOUND = Compound(*_default_terms(), T_REF, *wlf_at(T_REF))


def shift_factor(T: float, T_ref: float, C1: float, C2: float) -> float:
    """a_T of WLF: tau(T) = a_T tau(T_ref); ValueError where C2 + T - T_ref <= 0 (below WLF's range)."""
    d = T - T_ref
    if C2 + d <= 0.0:
        raise ValueError(f"temperature {T:g} °C is outside WLF's range (C2 + T - T_ref = {C2 + d:g} K <= 0)")
    return 10.0 ** (-C1 * d / (C2 + d))


def storage_loss(freq_hz, E_inf: float, E: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """E'(f), E''(f) [Pa] of the Prony series at frequencies ``freq_hz`` (module docstring)."""
    x = 2.0 * np.pi * np.asarray(freq_hz, dtype=float)[..., None] * np.asarray(tau)
    E = np.asarray(E)
    return E_inf + np.sum(E * x * x / (1.0 + x * x), axis=-1), np.sum(E * x / (1.0 + x * x), axis=-1)


def relaxation(t, E_inf: float, E: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """E(t) [Pa] of the Prony series."""
    return E_inf + np.sum(np.asarray(E) * np.exp(-np.asarray(t, dtype=float)[..., None] / np.asarray(tau)), axis=-1)


def terms(cfg) -> tuple[np.ndarray, np.ndarray]:
    """(r_j = E_j / E_inf, tau_j at the config's temperature) of a config with material = 'prony'."""
    a = shift_factor(cfg.temperature, cfg.T_ref, cfg.wlf_C1, cfg.wlf_C2)
    return np.asarray(cfg.prony_E) / cfg.E, np.asarray(cfg.prony_tau) * a


def stiffness_ratio(cfg) -> float:
    """E_0 / E_inf: how much stiffer the bulk is at frequencies far above 1/min(tau) (1 if elastic)."""
    if cfg.material != "prony":
        return 1.0
    return 1.0 + float(np.sum(cfg.prony_E)) / cfg.E


def arm_kernel(kern: np.ndarray, dead) -> np.ndarray:
    """The kernel a**2 k(q) (rfft2 grid; leading axes: rows) the Maxwell arms of a slab or half-space act
    through: the body's ``kern`` where it is the rubber's, linear in the modulus -- every q on the slab
    under the dead weight (``dead``, per row: the clamped top is the plate), every q but 0 under the
    spring drive (the half-space: k(0) = kappa_d is the drive springs' alone). A copy."""
    out = np.array(kern, copy=True)
    out[..., 0, 0] = np.where(dead, out[..., 0, 0], 0.0)
    return out


def exponential_weights(h: float, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(a_j, tau_j (1 - a_j) / h) of the update over a step h (module docstring)."""
    a = np.exp(-h / np.asarray(tau))
    return a, np.asarray(tau) * -np.expm1(-h / np.asarray(tau)) / h


__all__ = ["DEFAULT_COMPOUND", "T_REF", "TG", "Compound", "arm_kernel", "exponential_weights", "relaxation", "shift_factor",
           "stiffness_ratio", "storage_loss", "terms", "wlf_at"]

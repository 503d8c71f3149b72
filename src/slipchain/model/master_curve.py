"""A measured master curve (E' and E'' against frequency) fitted to Prony terms with pyvisco (issue 28).

Input: a CSV with two header rows, pyvisco's convention for a tensile master curve in the
frequency domain at one reference temperature::

    f,E_stor,E_loss
    Hz,MPa,MPa
    0.001,10.2,0.31
    ...

(moduli in Pa, kPa, MPa or GPa; storage and loss in the same unit). The fit is pyvisco's
(``pyvisco`` 2.1, BSD-3-Clause; github.com/NatLabRockies/pyvisco): relaxation times one per decade over the
window rounded out to whole decades, then the moduli *and* the times optimised together by
least squares on E'/E_0 and E''/E_0 (``prony.fit(..., opt=True)``; the collocation fit without
optimisation puts the relaxed modulus into the slowest term). E_0 is the storage modulus at the
highest frequency and E_inf = E_0 (1 - sum alpha_j) the relaxed one. Terms the fit sets to zero
or to less than 1e-6 E_0 (:data:`NEGLIGIBLE`: noise at the window's edges, ~500 Pa beside
1 GPa for the default compound's curve) are dropped; E_inf = E_0 (1 - sum of all alpha_j).

The result is a :class:`Fit` whose :meth:`Fit.toml` is a config fragment: ``material = "prony"``,
``E`` = E_inf (the relaxed modulus sets the springs K, K_L, K_T and the drive springs, see
:mod:`slipchain.model.viscoelastic`), ``prony_E``, ``prony_tau``, ``T_ref`` and the WLF constants
(a master curve at one temperature does not determine them: the user gives C1 and C2 of the
measured shift, else the default compound's universal constants at its Tg, referred to T_ref
(:func:`~slipchain.model.viscoelastic.wlf_at`), are written, and said so in the file).

pyvisco is imported only here (it is an optional dependency, installed by ``make`` without its
Jupyter GUI stack, see requirements-nodeps.txt); without it :func:`fit_master_curve` raises
:class:`MasterCurveError` saying how to install it.
"""

from __future__ import annotations

import contextlib
import io
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .viscoelastic import Compound, storage_loss, wlf_at

NEGLIGIBLE = 1e-6  # a fitted term with E_j / E_0 below this is dropped (fit noise at the window's edges)
PASCALS = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}


class MasterCurveError(ValueError):
    """A master curve that cannot be read or fitted: the message names the file, the column or value, and what was expected."""


@dataclass(frozen=True)
class Fit:
    """Prony terms fitted to a master curve (SI units), with the fit's worst errors over the data
    relative to the complex modulus |E*| (the fit is a least-squares fit of E'/E_0 and E''/E_0: a
    loss modulus a million times below E_0, in the rubbery tail, is not resolved relative to itself)."""

    E_inf: float
    E: tuple[float, ...]
    tau: tuple[float, ...]
    T_ref: float
    C1: float
    C2: float
    wlf_given: bool
    source: str
    err_storage: float  # max |E'_fit - E'_data| / |E*_data| over the data
    err_loss: float  # max |E''_fit - E''_data| / |E*_data| over the data
    freq: np.ndarray = field(repr=False, compare=False)
    storage: np.ndarray = field(repr=False, compare=False)
    loss: np.ndarray = field(repr=False, compare=False)

    @property
    def compound(self) -> Compound:
        return Compound(self.E, self.tau, self.T_ref, self.C1, self.C2)

    def toml(self) -> str:
        """A config fragment (valid on its own: ``slipchain run compound.toml``) with the fitted compound."""
        wlf = ("given" if self.wlf_given else "not determined by one master curve: universal constants at the "
               "default compound's Tg; replace C1, C2 by those of your shift")
        lines = [
            f"# Prony terms fitted with pyvisco to the master curve {self.source} (slipchain material fit)",
            f"# worst error over the data, relative to |E*|: E' {self.err_storage:.2%}, E'' {self.err_loss:.2%}",
            'material = "prony"',
            f"E = {self.E_inf:.8g}  # Pa: the relaxed modulus E_inf",
            "prony_E = [" + ", ".join(f"{x:.8g}" for x in self.E) + "]  # Pa",
            "prony_tau = [" + ", ".join(f"{x:.8g}" for x in self.tau) + "]  # s at T_ref",
            f"T_ref = {self.T_ref:g}  # °C",
            f"wlf_C1 = {self.C1:.8g}  # {wlf}",
            f"wlf_C2 = {self.C2:.8g}  # K",
        ]
        return "\n".join(lines) + "\n"


def master_curve_csv(freq_hz, storage_pa, loss_pa, unit: str = "MPa") -> str:
    """The CSV text of a master curve in pyvisco's format (two header rows), moduli in ``unit``."""
    s = PASCALS[unit]
    rows = "".join(f"{f:.10e},{a / s:.10e},{b / s:.10e}\n" for f, a, b in zip(freq_hz, storage_pa, loss_pa))
    return f"f,E_stor,E_loss\nHz,{unit},{unit}\n" + rows


def _read(path: Path, T_ref: float):
    from pyvisco import load, master

    try:
        data = load.file(path)
    except FileNotFoundError:
        raise MasterCurveError(f"master curve {str(path)!r} does not exist; expected a CSV file "
                               "(header rows 'f,E_stor,E_loss' and 'Hz,MPa,MPa')") from None
    try:
        df, units = load.user_master(data, "freq", T_ref, "E")
    except KeyError as e:
        raise MasterCurveError(f"master curve {str(path)!r}: {e.args[0] if e.args else e}; expected header rows "
                               "'f,E_stor,E_loss' and 'Hz,<unit>,<unit>' with <unit> one of Pa, kPa, MPa, GPa") from None
    except Exception as e:  # noqa: BLE001 - pandas' many parse errors
        raise MasterCurveError(f"master curve {str(path)!r} cannot be read ({type(e).__name__}: {e}); expected "
                               "a CSV with header rows 'f,E_stor,E_loss' and 'Hz,<unit>,<unit>'") from None
    if len(df) < 3:
        raise MasterCurveError(f"master curve {str(path)!r} has {len(df)} data rows; expected at least 3")
    for col in ("f", "E_stor", "E_loss"):
        v = np.asarray(df[col], dtype=float)
        bad = np.flatnonzero(~(np.isfinite(v) & (v > 0)))
        if bad.size:
            raise MasterCurveError(f"master curve {str(path)!r}: column {col!r} has value {float(v[bad[0]])!r} in data row "
                                   f"{bad[0] + 1}; expected numbers > 0")
    f = np.asarray(df["f"], dtype=float)
    if not np.all(np.diff(f) > 0):
        raise MasterCurveError(f"master curve {str(path)!r}: column 'f' is not strictly increasing; expected "
                               "frequencies from low to high")
    return master.smooth(df, 1), PASCALS[units["E_stor"]]


def fit_master_curve(path: str | Path, T_ref: float, C1: float | None = None, C2: float | None = None,
                     n_terms: int = 0) -> Fit:
    """Prony terms fitted with pyvisco to the master curve in ``path`` (module docstring).

    ``T_ref`` (°C) is the master curve's reference temperature; ``C1``, ``C2`` its WLF constants
    (absent: the universal constants at the default compound's Tg, referred to T_ref); ``n_terms`` the number of Prony terms (0: one per decade).
    """
    path = Path(path)
    if (C1 is None) != (C2 is None):
        raise MasterCurveError(f"WLF constants: C1 = {C1!r}, C2 = {C2!r}; expected both or neither")
    if not (math.isfinite(T_ref)):
        raise MasterCurveError(f"T_ref has value {T_ref!r}; expected a temperature in °C")
    if not (isinstance(n_terms, int) and n_terms >= 0):
        raise MasterCurveError(f"n_terms has value {n_terms!r}; expected an integer >= 0 (0: one per decade)")
    try:
        from pyvisco import prony
    except ImportError:  # pragma: no cover - make installs it
        raise MasterCurveError("fitting a master curve needs pyvisco; install it without its GUI stack: "
                               "pip install --no-deps pyvisco (see requirements-nodeps.txt)") from None
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        # pyvisco 2.1 uses pandas' inplace keywords (deprecated in pandas 3) and prints its optimiser's progress
        warnings.simplefilter("ignore", DeprecationWarning)
        warnings.simplefilter("ignore", FutureWarning)
        df, scale = _read(path, T_ref)
        dis = prony.discretize(df, "round", n_terms)
        result, _ = prony.fit(dis, df, opt=True)
    terms = result["df_terms"].sort_values("tau_i")
    E0 = float(result["E_0"]) * scale
    keep = terms["alpha_i"].to_numpy() > NEGLIGIBLE
    tau = terms["tau_i"].to_numpy()[keep]
    E = terms["E_i"].to_numpy()[keep] * scale
    E_inf = E0 * (1.0 - float(terms["alpha_i"].sum()))
    if not E_inf > 0:
        raise MasterCurveError(f"master curve {str(path)!r}: the fit's relaxed modulus E_inf = {E_inf:g} Pa; expected > 0 "
                               "(the data must reach the rubbery plateau at their lowest frequency)")
    f = np.asarray(df["f"], dtype=float)
    e1, e2 = np.asarray(df["E_stor"], dtype=float) * scale, np.asarray(df["E_loss"], dtype=float) * scale
    s1, s2 = storage_loss(f, E_inf, E, tau)
    mag = np.hypot(e1, e2)
    if C1 is None:
        C1, C2 = wlf_at(T_ref)
        wlf_given = False
    else:
        wlf_given = True
    return Fit(E_inf=E_inf, E=tuple(float(x) for x in E), tau=tuple(float(x) for x in tau), T_ref=float(T_ref),
               C1=float(C1), C2=float(C2), wlf_given=wlf_given,
               source=path.name, err_storage=float(np.max(np.abs(s1 - e1) / mag)),
               err_loss=float(np.max(np.abs(s2 - e2) / mag)), freq=f, storage=e1, loss=e2)


__all__ = ["Fit", "MasterCurveError", "PASCALS", "fit_master_curve", "master_curve_csv"]

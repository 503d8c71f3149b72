"""The rubber's moduli (issue 28): E', E'' and tan delta against frequency at given temperatures,
with the frequencies at which the slider's slip events and its creep load the bulk marked;
and a master curve beside the Prony terms fitted to it (``slipchain material show|fit``)."""

from __future__ import annotations

import os

import numpy as np

from ..model.viscoelastic import Compound, shift_factor, storage_loss
from .common import pyplot, save_figure

EVENT_TIME = 1e-5  # s: a slip event's duration (issue 28: ~1e-5 s)
CREEP_TIME = 1.0  # s: the creep between events (~1 s at theta = 1, v_d = v0, epsilon = 1)


def moduli_table(compound: Compound, E_inf: float, temperatures, freq_hz) -> dict[str, np.ndarray]:
    """E', E'' [Pa] and tan delta at each temperature (rows) and frequency (columns), the Prony
    formulas with tau_j shifted by WLF's a_T (:mod:`slipchain.model.viscoelastic`)."""
    T = np.atleast_1d(np.asarray(temperatures, dtype=float))
    aT = np.array([shift_factor(t, compound.T_ref, compound.C1, compound.C2) for t in T])
    E1 = np.empty((T.size, len(freq_hz)))
    E2 = np.empty_like(E1)
    for i, a in enumerate(aT):
        E1[i], E2[i] = storage_loss(freq_hz, E_inf, np.asarray(compound.E), np.asarray(compound.tau) * a)
    return {"T": T, "a_T": aT, "f": np.asarray(freq_hz, dtype=float), "E_storage": E1, "E_loss": E2, "tan_delta": E2 / E1}


def plot_moduli(table: dict, out: str | os.PathLike, title: str, event_time: float = EVENT_TIME,
                creep_time: float = CREEP_TIME, stem: str = "material"):
    """(a) E' (solid) and E'' (dashed) and (b) tan delta against frequency, one colour per
    temperature, with f = 1/event_time and 1/creep_time marked; OUT/STEM.png and .pdf."""
    plt = pyplot()
    fig, (a, b) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    f = table["f"]
    for i, T in enumerate(table["T"]):
        c = f"C{i}"
        a.loglog(f, table["E_storage"][i] / 1e6, color=c, label=f"E' at {T:g} °C")
        a.loglog(f, table["E_loss"][i] / 1e6, color=c, ls="--", label=f"E'' at {T:g} °C")
        b.semilogx(f, table["tan_delta"][i], color=c, label=f"{T:g} °C")
    for ax in (a, b):
        for x, what in ((1 / creep_time, f"creep, 1/({creep_time:g} s)"), (1 / event_time, f"slip events, 1/({event_time:g} s)")):
            ax.axvline(x, color="0.5", lw=0.8, ls=":")
            if ax is a:
                ax.annotate(what, (x, 0.02), xycoords=("data", "axes fraction"), rotation=90, va="bottom", ha="right",
                            fontsize=8, color="0.3")
    a.set_ylabel("modulus (MPa)")
    a.legend(fontsize=8, ncol=2)
    a.set_title(title, fontsize=9)
    b.set_xlabel("frequency f (Hz)")
    b.set_ylabel(r"tan $\delta$ = E''/E'")
    b.legend(fontsize=8)
    return save_figure(fig, out, stem)


def plot_fit(fit, out: str | os.PathLike, stem: str = "master_curve_fit"):
    """The master curve's data (points) and the fitted Prony series (lines): E', E'' against frequency."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    f = np.geomspace(fit.freq.min(), fit.freq.max(), 400)
    s1, s2 = storage_loss(f, fit.E_inf, np.asarray(fit.E), np.asarray(fit.tau))
    ax.loglog(fit.freq, fit.storage / 1e6, "o", ms=3, color="C0", label="E' (data)")
    ax.loglog(fit.freq, fit.loss / 1e6, "s", ms=3, color="C1", label="E'' (data)")
    ax.loglog(f, s1 / 1e6, color="C0", label=f"E' ({len(fit.E)} Prony terms, worst {fit.err_storage:.1%})")
    ax.loglog(f, s2 / 1e6, color="C1", label=f"E'' (worst {fit.err_loss:.1%})")
    ax.set_xlabel(f"frequency f (Hz) at T_ref = {fit.T_ref:g} °C")
    ax.set_ylabel("modulus (MPa)")
    ax.set_title(f"{fit.source}: Prony series fitted with pyvisco", fontsize=9)
    ax.legend(fontsize=8)
    return save_figure(fig, out, stem)


__all__ = ["CREEP_TIME", "EVENT_TIME", "moduli_table", "plot_fit", "plot_moduli"]

"""Figures of the tester analysis: mu(v) per pressure (Figs. 2 and 3 style), and model beside experiment."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pandas as pd

from ..tester.analysis import GROUP, OK, RUNAWAY, pressure_group
from .common import pyplot, save_figure


def _stem(prefix: str, key: tuple) -> str:
    text = "_".join(f"{v:g}C" if isinstance(v, float) else str(v) for v in key)
    return prefix + "_" + re.sub(r"[^A-Za-z0-9.+-]+", "-", text)


def plot_mu_v(table: pd.DataFrame, peaks: pd.DataFrame, out: str | os.PathLike) -> list[Path]:
    """One figure per (surface, compound, temperature): mu versus log v, one colour per pressure."""
    plt = pyplot()
    paths: list[Path] = []
    usable = table[table["status"].isin([OK, RUNAWAY])].copy()
    usable["p_group"] = usable["pressure_Pa"].map(pressure_group)
    for key, g in usable.groupby(GROUP, sort=True):
        fig, ax = plt.subplots(figsize=(6.2, 4.4))
        pressures = sorted(g["p_group"].unique())
        colors = plt.cm.viridis(np.linspace(0, 0.85, len(pressures)))
        ok_all = g[g["status"] == OK]
        v_right = ok_all["velocity_m_s"].max() * 3 if len(ok_all) else 1.0
        for p, color in zip(pressures, colors):
            gp = g[g["p_group"] == p]
            ok = gp[gp["status"] == OK].sort_values("velocity_m_s")
            ax.errorbar(ok["velocity_m_s"], ok["mu"], xerr=ok["velocity_sem_m_s"].fillna(0), yerr=ok["mu_sem"],
                        color=color, marker="o", ms=4, lw=1, capsize=2, label=f"p0 = {p / 1e3:.3g} kPa")
            if len(ok):
                top = ok.loc[ok["mu"].idxmax()]
                ax.plot(top["velocity_m_s"], top["mu"], marker="*", ms=13, color=color, mec="k", zorder=5)
            run = gp[gp["status"] == RUNAWAY]
            if len(run):
                ax.plot(np.full(len(run), v_right), run["mu"], marker=">", ls="none", color=color, mfc="white")
        ax.plot([], [], marker="*", ms=10, color="gray", mec="k", ls="none", label="first maximum (largest steady mu)")
        ax.plot([], [], marker=">", color="gray", mfc="white", ls="none", label="runaway runs (mu above the maximum)")
        ax.set_xscale("log")
        ax.set_xlabel("v (m/s)")
        ax.set_ylabel(r"$\mu = M'/M$")
        ax.set_title(", ".join(f"{v:g} °C" if isinstance(v, float) else str(v) for v in key), fontsize=10)
        ax.legend(fontsize=7, loc="upper left")
        paths += save_figure(fig, out, _stem("mu_v", key))
    return paths


def plot_model_vs_experiment(table: pd.DataFrame, overlay: dict[str, tuple[float, dict]], out: str | os.PathLike) -> list[Path]:
    """Measured mu(v) per surface with the model's mu_star(v_d) curves, each surface's curves scaled
    by its fitted factor (``overlay``: :func:`slipchain.analysis.experiment.model_overlay`); the
    legend gives the factor."""
    plt = pyplot()
    ok = table[table["status"] == OK].copy()
    ok["p_group"] = ok["pressure_Pa"].map(pressure_group)
    paths: list[Path] = []
    for surface, g in ok.groupby("surface", sort=True):
        fig, ax = plt.subplots(figsize=(6.2, 4.4))
        pressures = sorted(g["p_group"].unique())
        colors = plt.cm.viridis(np.linspace(0, 0.85, len(pressures)))
        for p, color in zip(pressures, colors):
            gp = g[g["p_group"] == p].sort_values("velocity_m_s")
            ax.errorbar(gp["velocity_m_s"], gp["mu"], yerr=gp["mu_sem"], color=color, marker="o", ms=4, ls="none",
                        capsize=2, label=f"measured, p0 = {p / 1e3:.3g} kPa")
        if surface in overlay:
            s, curves = overlay[surface]
            styles = ["-", "--", "-.", ":"]
            for i, (label, (cv, cm)) in enumerate(curves.items()):
                ax.plot(cv, s * cm, color="tab:red", ls=styles[i % 4], lw=1.5, label=f"model mu_star{'' if label == 'model' else ', ' + label} (x {s:.3g})")
        ax.set_xscale("log")
        ax.set_xlabel("v (m/s)")
        ax.set_ylabel(r"$\mu$ (model: scale $\times\ \mu^*$)")
        ax.set_title(f"{surface}: experiment and model", fontsize=10)
        ax.legend(fontsize=7, loc="upper left")
        paths += save_figure(fig, out, _stem("model_vs_experiment", (surface,)))
    return paths


__all__ = ["plot_model_vs_experiment", "plot_mu_v"]

"""Figures of the tester analysis: mu(v) per pressure (Figs. 2 and 3 style), and model beside experiment."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from ..figures import _pyplot, _save
from .analysis import GROUP, OK, RUNAWAY, pressure_group


def _stem(prefix: str, key: tuple) -> str:
    text = "_".join(f"{v:g}C" if isinstance(v, float) else str(v) for v in key)
    return prefix + "_" + re.sub(r"[^A-Za-z0-9.+-]+", "-", text)


def plot_mu_v(table: pd.DataFrame, peaks: pd.DataFrame, out: str | os.PathLike) -> list[Path]:
    """One figure per (surface, compound, temperature): mu versus log v, one colour per pressure."""
    plt = _pyplot()
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
        paths += _save(fig, out, _stem("mu_v", key))
    return paths


def model_curves(sweep: xr.Dataset) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """mu_star(v_d) curves from a sweep Dataset with a ``v_d`` dimension, averaged over seeds.

    One curve per combination of the other swept values (e.g. per theta); label -> (v, mu_star).
    """
    from ..reproduction import main_selection, seed_average

    if "v_d" not in sweep.dims:
        raise ValueError(f"the sweep has dimensions {list(sweep.dims)}; a model curve needs v_d")
    sel = {k: v for k, v in main_selection(sweep).items() if sweep.sizes[k] > 1}
    avg = seed_average(sweep.sel(sel) if sel else sweep)
    other = [d for d in avg["mu"].dims if d != "v_d"]
    curves = {}
    stacked = avg["mu"].stack(_c=other) if other else avg["mu"].expand_dims(_c=[0])
    for i in range(stacked.sizes["_c"]):
        c = stacked.isel(_c=i)
        label = ", ".join(f"{d} = {c[d].item():g}" for d in other) if other else "model"
        ok = np.isfinite(c.values)
        if ok.sum() >= 2:
            curves[label] = (c["v_d"].values[ok], c.values[ok])
    return curves


def fit_scale(v: np.ndarray, mu: np.ndarray, curve: tuple[np.ndarray, np.ndarray]) -> float:
    """Least-squares factor s with mu ~ s*mu_star(v), mu_star interpolated in log v inside its range."""
    cv, cm = curve
    inside = (v >= cv.min()) & (v <= cv.max())
    if inside.sum() == 0:
        return float("nan")
    m = np.interp(np.log10(v[inside]), np.log10(cv), cm)
    return float(np.sum(m * mu[inside]) / np.sum(m * m))


def plot_model_vs_experiment(table: pd.DataFrame, sweep: xr.Dataset | None, out: str | os.PathLike) -> list[Path]:
    """Measured mu(v) per surface with the model's mu_star(v_d) curves, scaled by one fitted factor per surface.

    The factor is fitted (least squares, steady runs inside the model's velocity range) to the
    mean of the model curves, and applied to every curve; the legend gives it.
    """
    plt = _pyplot()
    ok = table[table["status"] == OK].copy()
    ok["p_group"] = ok["pressure_Pa"].map(pressure_group)
    curves = model_curves(sweep) if sweep is not None else {}
    paths: list[Path] = []
    for surface, g in ok.groupby("surface", sort=True):
        fig, ax = plt.subplots(figsize=(6.2, 4.4))
        pressures = sorted(g["p_group"].unique())
        colors = plt.cm.viridis(np.linspace(0, 0.85, len(pressures)))
        for p, color in zip(pressures, colors):
            gp = g[g["p_group"] == p].sort_values("velocity_m_s")
            ax.errorbar(gp["velocity_m_s"], gp["mu"], yerr=gp["mu_sem"], color=color, marker="o", ms=4, ls="none",
                        capsize=2, label=f"measured, p0 = {p / 1e3:.3g} kPa")
        if curves:
            v_common = np.unique(np.concatenate([c[0] for c in curves.values()]))
            mean_curve = (v_common, np.nanmean([np.interp(np.log10(v_common), np.log10(c[0]), c[1], left=np.nan,
                                                          right=np.nan) for c in curves.values()], axis=0))
            good = np.isfinite(mean_curve[1])
            s = fit_scale(g["velocity_m_s"].to_numpy(), g["mu"].to_numpy(), (mean_curve[0][good], mean_curve[1][good]))
            styles = ["-", "--", "-.", ":"]
            for i, (label, (cv, cm)) in enumerate(curves.items()):
                ax.plot(cv, s * cm, color="tab:red", ls=styles[i % 4], lw=1.5, label=f"model mu_star{'' if label == 'model' else ', ' + label} (x {s:.3g})")
        ax.set_xscale("log")
        ax.set_xlabel("v (m/s)")
        ax.set_ylabel(r"$\mu$ (model: scale $\times\ \mu^*$)")
        ax.set_title(f"{surface}: experiment and model", fontsize=10)
        ax.legend(fontsize=7, loc="upper left")
        paths += _save(fig, out, _stem("model_vs_experiment", (surface,)))
    return paths


__all__ = ["fit_scale", "model_curves", "plot_model_vs_experiment", "plot_mu_v"]

"""Figures 5 and 6 of the paper, drawn from Datasets (never from live simulations).

* Fig. 5: :func:`plot_fig5` draws :func:`slipchain.analysis.fig6.contact_law_dataset` (eq. (1),
  f(v, v0), for several contact dampings and the contact average) on a log-v axis, in units of
  epsilon*f0.
* Fig. 6: :func:`plot_fig6` draws seed-averaged mu_star versus theta
  (:func:`slipchain.analysis.fig6.fig6_figure_data` of a sweep Dataset):
  eta_c = omega0 blue circles, 0.3 omega0 red diamonds, 0.1 omega0 black squares (as the paper),
  filled for v_d1 = v0, open for v_d2; N = 1001 as stars; the dashed line f(v_d2, v0)/(epsilon f0).

Every plot is written as PNG and PDF.
"""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

from .common import ETA_STYLE, pyplot, save_figure


def plot_fig5(ds: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """Fig. 5: the contact law for the dampings of the paper and the contact average."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.2))
    styles = {0.0: ("0.4", ":", r"$\eta_c = 0$"), 1.0: ("black", "-", r"$\eta_c = \omega_0$"),
              0.3: ("tab:blue", "-", r"$\eta_c = 0.3\,\omega_0$"), 0.1: ("tab:red", "-", r"$\eta_c = 0.1\,\omega_0$")}
    v = ds["v"].values
    for k in ds["eta_c_factor"].values:
        color, ls, label = styles.get(float(k), ("gray", "-", f"eta_c = {k:g} omega0"))
        ax.plot(v, ds["f"].sel(eta_c_factor=k), color=color, ls=ls, label=label)
    ax.plot(v, ds["f_average"], color="tab:green", ls="--",
            label=rf"$\langle f(v, v_i^*)\rangle$, N = {ds.attrs['N']}, $\theta$ = {ds.attrs['theta']:g} "
                  rf"($\eta_c$ = {ds.attrs['eta_c_average'] / ds.attrs['omega0']:g} $\omega_0$)")
    ax.axvline(ds.attrs["v0"], color="0.8", lw=0.8, zorder=0)
    ax.set_xscale("log")
    ax.set_xlabel("v (m/s)")
    ax.set_ylabel(r"$f(v, v_0) / (\varepsilon f_0)$")
    ax.set_ylim(0, 2.0)
    ax.set_xlim(v[0], v[-1])
    ax.set_title("Fig. 5: contact force law, eq. (1)")
    ax.legend(fontsize=8, loc="upper left")
    return save_figure(fig, out, "fig5")


def plot_fig6(data: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """Fig. 6: seed-averaged mu_star versus theta (``data``: :func:`slipchain.analysis.fig6.fig6_figure_data`)."""
    from matplotlib.lines import Line2D

    plt = pyplot()
    avg = data
    v_values = sorted(avg["v_d"].values.tolist())
    v_d1, v_d2 = avg.attrs["v_d1"], avg.attrs["v_d2"]
    ns = avg["N"].values.tolist() if "N" in avg.dims else [None]
    n_main = avg.attrs["n_main"] or None
    fig, ax = plt.subplots(figsize=(8.2, 4.8))
    handles = []
    for ec in sorted(avg["eta_c"].values.tolist(), reverse=True):
        factor = round(ec / avg.attrs["omega0"], 3)
        color, marker = ETA_STYLE.get(factor, ("tab:gray", "^"))
        handles.append(Line2D([], [], color=color, marker=marker, label=rf"$\eta_c$ = {factor:g} $\omega_0$"))
        for vd in sorted(v_values, reverse=True):
            filled = vd == v_d1
            for n in ns:
                cur = avg.sel(eta_c=ec, v_d=vd, **({} if n is None else {"N": n})).dropna("theta", subset=["mu"])
                if cur.sizes["theta"] == 0:
                    continue
                big = n is not None and n != n_main
                ax.errorbar(cur["theta"], cur["mu"], yerr=cur["err"], color=color, marker="*" if big else marker,
                            ms=11 if big else 6, mfc=color if filled else "white", mec=color, ls="-" if not big else "none",
                            lw=0.8, capsize=2, zorder=3 if big else 2)
    handles.append(Line2D([], [], color="0.3", marker="o", ls="none", label=f"filled: $v_{{d1}}$ = {v_d1:g} m/s"))
    if v_d2 != v_d1:
        handles.append(Line2D([], [], color="0.3", marker="o", mfc="white", ls="none",
                              label=f"open: $v_{{d2}}$ = {v_d2:g} m/s"))
    if len(ns) > 1:
        handles.append(Line2D([], [], color="0.3", marker="*", ms=11, ls="none",
                              label="stars: N = " + ", ".join(str(n) for n in ns if n != n_main)))
    if v_d2 != v_d1:
        line = avg.attrs["dashed_line"]
        ax.axhline(line, color="0.3", ls="--", lw=1)
        handles.append(Line2D([], [], color="0.3", ls="--", label=rf"$f(v_{{d2}}, v_0)/(\varepsilon f_0)$ = {line:.3f}"))
    ax.set_xlabel(r"$\theta$ (proportional to the load)")
    ax.set_ylabel(r"$\mu^* = \langle f_d \rangle / (\varepsilon f_0 \theta)$")
    ax.set_xlim(0, 1.05)
    n_base = avg.attrs.get("n_base")
    n_text = f"N = {n_main}" if n_main is not None else (f"N = {n_base}" if n_base else "")
    eps = avg.attrs.get("epsilon", 1e-2)
    eps_text = rf"$\varepsilon$ = {eps:g}" if eps != 1e-2 else ""  # the paper's value goes unsaid
    parts = [x for x in (n_text, avg.attrs["held"], eps_text) if x]
    ax.set_title("Fig. 6: friction versus load" + (f" ({', '.join(parts)})" if parts else ""),
                 fontsize=10)
    ax.legend(handles=handles, fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    return save_figure(fig, out, "fig6")


__all__ = ["plot_fig5", "plot_fig6"]

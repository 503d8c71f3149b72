"""Fig. 6 in 3-D (issue 13), drawn from the tables of :mod:`slipchain.analysis.geometry`.

(a) v_d1 and (b) v_d2: seed-averaged mu_star versus theta for the chain (N = 301, the paper's
model), the 2-D chains and the slab at their main size (filled), the 32 x 32 finite-size check
(open); (c) the load effect mu_star(theta_max)/mu_star(theta_min) at v_d1 against the slab's
thickness H/(L a), the half-space at the right edge, the chains as horizontal bands, and the
paper's criterion 0.8 (a drop of more than 20 %) dashed. PNG and PDF.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..analysis.geometry import main_mask
from .common import pyplot, save_figure

STYLE = {"chain": ("black", "s", "chain (paper), N = {N}"), "chain2d": ("tab:blue", "o", "2-D chains, {N} x {Ly}"),
         "slab": ("tab:red", "D", "slab H = {N_L} a, {N} x {Ly}"), "halfspace": ("tab:green", "^", "half-space, {N} x {Ly}")}


def _label(geo: str, size) -> str:
    return STYLE[geo][2].format(N=int(size[0]), Ly=int(size[1]), N_L=int(size[2]))


def plot_fig6_3d(table: pd.DataFrame, drop: pd.DataFrame, attrs: dict, out: str | os.PathLike) -> list[Path]:
    """The three panels of the module docstring, as OUT/fig6-3d.png and .pdf."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.4), gridspec_kw={"width_ratios": [1, 1, 0.9]})
    main = attrs["main"]
    for ax, (name, v) in zip(axes[:2], (("v_d1", attrs["v_d1"]), ("v_d2", attrs["v_d2"]))):
        at_v = table[np.isclose(table["v_d"], v)]
        for geo in STYLE:
            if geo not in main:
                continue
            color, marker, _ = STYLE[geo]
            rows = at_v[at_v["geometry"] == geo]
            size = main[geo]
            is_main = main_mask(rows, main)
            m = rows[is_main]
            if len(m):
                ax.errorbar(m["theta"], m["mu"], m["err"], color=color, marker=marker, ms=5, capsize=2,
                            label=_label(geo, size))
            small = rows[(~is_main) & (rows["N"] < size[0]) & (rows["N_L"] == size[2])]
            for (n, ly), s in small.groupby(["N", "Ly"]):
                ax.errorbar(s["theta"], s["mu"], s["err"], color=color, marker=marker, mfc="white", ls=":", ms=5,
                            capsize=2, label=f"{geo}, {int(n)} x {int(ly)}")
        if name == "v_d2" and np.isfinite(attrs.get("dashed_line", np.nan)):
            ax.axhline(attrs["dashed_line"], color="0.4", ls="--", lw=1, label=r"$f(v_{d2}, v_0)/(\varepsilon f_0)$")
        ax.set_xlabel(r"$\theta$ (load)")
        ax.set_ylabel(r"$\mu^*$")
        ax.set_title(f"({'ab'[name == 'v_d2']}) {name} = {v:g} m/s")
        ax.set_xlim(0, 1.05)
        ax.legend(fontsize=7, loc="lower left")
    ax = axes[2]
    d1 = drop[np.isclose(drop["v_d"], attrs["v_d1"])]
    slabs = d1[d1["geometry"] == "slab"].sort_values("H_over_L")
    slab_main = slabs[slabs["N"] == main.get("slab", (0,))[0]]
    if len(slab_main):
        ax.errorbar(slab_main["H_over_L"], slab_main["ratio"], slab_main["ratio_err"], color=STYLE["slab"][0],
                    marker="D", capsize=2, label=f"slab, {int(slab_main['N'].iloc[0])} x {int(slab_main['Ly'].iloc[0])}")
    xmax = 4.0
    bad = attrs.get("not_completed")
    if bad is not None and len(bad) and "N_L" in bad:
        for (nl, n), _ in bad[(bad["geometry"] == "slab") & np.isclose(bad["v_d"], attrs["v_d1"])].groupby(["N_L", "N"]):
            ax.annotate(f"H/(La) = {nl / n:.3g}:\nno steady state\nat the largest theta", (nl / n, 0.95),
                        fontsize=7, ha="center", color=STYLE["slab"][0])
    half = d1[d1["geometry"] == "halfspace"]
    if len(half):
        ax.errorbar([xmax], half["ratio"].iloc[:1], half["ratio_err"].iloc[:1], color=STYLE["halfspace"][0],
                    marker="^", capsize=2, label=r"half-space ($H \to \infty$, drawn at the edge)")
    for geo in ("chain", "chain2d"):
        if geo not in main:
            continue
        r = d1[(d1["geometry"] == geo).to_numpy() & main_mask(d1, main)]
        if len(r):
            y, e = float(r["ratio"].iloc[0]), float(r["ratio_err"].iloc[0])
            ax.axhspan(y - e, y + e, color=STYLE[geo][0], alpha=0.2)
            ax.axhline(y, color=STYLE[geo][0], lw=1, label=_label(geo, main[geo]))
    ax.axhline(0.8, color="0.4", ls="--", lw=1, label="0.8: a drop of 20 % (paper, chain)")
    ax.set_xscale("log")
    ax.set_xlim(0.01, xmax * 1.5)
    ax.set_xlabel(r"slab thickness $H / (L a)$")
    ax.set_ylabel(r"$\mu^*(\theta_{max}) / \mu^*(\theta_{min})$ at $v_{d1}$")
    ax.set_title("(c) the load effect against the slab's thickness")
    ax.legend(fontsize=7, loc="best")
    eps = attrs.get("epsilon", 1e-2)
    eps_text = r"10^{-2}" if eps == 1e-2 else f"{eps:g}"
    fig.suptitle("Fig. 6 in 3-D: a 2-D interface under 2-D chains and under an elastic slab "
                 rf"($\eta_c = 0.1\,\omega_0$, $\varepsilon = {eps_text}$)", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, out, "fig6-3d")


__all__ = ["plot_fig6_3d"]


def plot_slip_maps(field, events, out: str | os.PathLike) -> list[Path]:
    """Maps of the displacement field x - v_d t (mean removed) on a 2-D interface just before and
    just after the largest slip event (by moment) of a recording, and their difference (the event's
    slip), as OUT/slip-maps.png and .pdf. ``field``: :func:`slipchain.analysis.mechanism.record_field`
    with ``positions=True``; ``events``: its :func:`~slipchain.analysis.mechanism.slip_events`."""
    plt = pyplot()
    lx, ly = int(field.attrs["Lx"]), int(field.attrs["Ly"])
    k = int(np.argmax(events["event_moment"].values))
    t0 = float(events["event_start"].values[k])
    t1 = t0 + float(events["event_duration"].values[k])
    times = field["time"].values
    i0 = max(0, int(np.searchsorted(times, t0)) - 1)
    i1 = min(times.size - 1, int(np.searchsorted(times, t1)))
    x = field["slip_field"].values
    before = (x[i0] - x[i0].mean()).reshape(lx, ly) * 1e9
    after = (x[i1] - x[i1].mean()).reshape(lx, ly) * 1e9
    slip = (x[i1] - x[i0]).reshape(lx, ly) * 1e9 + field.attrs["v_d"] * (times[i1] - times[i0]) * 1e9
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))
    lim = max(np.abs(before).max(), np.abs(after).max())
    for ax, data, title, cmap, vmin in ((axes[0], before, f"before, t = {times[i0] * 1e3:.3f} ms", "RdBu_r", -lim),
                                        (axes[1], after, f"after, t = {times[i1] * 1e3:.3f} ms", "RdBu_r", -lim),
                                        (axes[2], slip, "slip of the event", "viridis", 0.0)):
        im = ax.imshow(data.T, origin="lower", cmap=cmap, vmin=vmin, vmax=lim if vmin < 0 else None,
                       extent=(0, lx, 0, ly), aspect="equal")
        ax.set_xlabel("x (blocks, sliding direction)")
        ax.set_ylabel("y (blocks)")
        ax.set_title(title, fontsize=9)
        fig.colorbar(im, ax=ax, shrink=0.8, label="nm")
    fig.suptitle(f"{field.attrs['geometry']} {lx} x {ly}, theta = {field.attrs['theta']:.3g}: the largest event "
                 f"(area {events['event_size'].values[k]} blocks, {float(events['event_duration'].values[k]) * 1e3:.3f} "
                 f"ms, M0 = {float(events['event_moment'].values[k]):.3g} N m); x - v_d t, mean removed", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, out, "slip-maps")

"""Fig. 6 with the viscoelastic slider (issue 28), drawn from :mod:`slipchain.analysis.rubber`.

(a) v_d1 and (b) v_d2: seed-averaged mu_star versus theta, one colour per contact damping eta_c
(the paper's Fig. 6 symbols), one line style per variant (the elastic model solid, the rubber at
20 °C dashed, at 11 °C dotted); (c) the load effect mu_star(theta_max)/mu_star(theta_min) at v_d1
and v_d2 per variant and eta_c, with the paper's criterion 0.8 dashed (with one drive velocity in the
store, panels (a) and (b) the load effect). PNG and PDF.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from .common import ETA_STYLE, pyplot, save_figure

LINES = ("-", "--", ":", "-.")


def plot_rubber(table: pd.DataFrame, drop: pd.DataFrame, attrs: dict, out: str | os.PathLike) -> list[Path]:
    """The three panels of the module docstring, as OUT/fig6-rubber.png and .pdf."""
    plt = pyplot()
    speeds = (("v_d1", attrs["v_d1"]), ("v_d2", attrs["v_d2"]))
    if np.isclose(attrs["v_d1"], attrs["v_d2"]):  # one drive velocity (presets/fig6-rubber-slab.toml): no (b)
        speeds = speeds[:1]
    fig, axes = plt.subplots(1, len(speeds) + 1, figsize=(4.7 * len(speeds) + 4.6, 4.4),
                             gridspec_kw={"width_ratios": [1] * len(speeds) + [0.9]})
    w0 = attrs["omega0"]
    variants = list(dict.fromkeys(table["variant"]))
    style = {v: LINES[i % len(LINES)] for i, v in enumerate(variants)}
    for ax, (name, v) in zip(axes[:-1], speeds):
        at = table[np.isclose(table["v_d"], v)]
        for (var, ec), cur in at.groupby(["variant", "eta_c"], sort=False):
            color, marker = ETA_STYLE.get(round(ec / w0, 6), ("0.5", "x"))
            elastic = var == "elastic"
            ax.errorbar(cur["theta"], cur["mu"], cur["err"], color=color, marker=marker, ms=4, capsize=2,
                        ls=style[var], mfc=color if elastic else "white",
                        label=f"{var}, eta_c = {ec / w0:g} omega0")
        ax.set_xlabel(r"$\theta$ (load)")
        ax.set_ylabel(r"$\mu^*$")
        ax.set_title(f"({'ab'[name == 'v_d2']}) {name} = {v:g} m/s")
        ax.set_xlim(0, 1.05)
        ax.legend(fontsize=6, loc="best", ncol=1)
    ax = axes[-1]
    xs, labels = [], []
    for i, var in enumerate(variants):
        for j, (name, v) in enumerate(speeds):
            x = i * (len(speeds) + 1) + j
            cur = drop[(drop["variant"] == var) & np.isclose(drop["v_d"], v)]
            for k, (_, r) in enumerate(cur.sort_values("eta_c", ascending=False).iterrows()):
                color, marker = ETA_STYLE.get(round(r["eta_c"] / w0, 6), ("0.5", "x"))
                ax.errorbar(x + 0.15 * (k - 1), r["ratio"], r["ratio_err"], color=color, marker=marker, ms=5,
                            capsize=2, ls="none", mfc=color if var == "elastic" else "white")
            xs.append(x)
            labels.append(f"{var.replace('prony ', '')}\n{name}")
    ax.axhline(0.8, color="0.4", ls="--", lw=1)
    ax.axhline(1.0, color="0.7", lw=0.8)
    ax.set_xticks(xs, labels, fontsize=7)
    ax.set_xlim(min(xs) - 0.7, max(xs) + 0.7)  # room for the dampings' offsets at the ends
    ax.set_ylabel(r"$\mu^*(\theta_{max}) / \mu^*(\theta_{min})$")
    ax.set_title(f"({'bc'[len(speeds) - 1]}) the load effect (0.8: the paper's 20 %)")
    fig.tight_layout()
    return save_figure(fig, out, "fig6-rubber")


__all__ = ["plot_rubber"]

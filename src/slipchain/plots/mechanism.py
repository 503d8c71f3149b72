"""Figures of the mechanism and of sweeps beyond the paper: stick-slip, events and spectra; mu_star(v_d);
the dead-weight drive; epsilon. Functions take Datasets and only draw.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from ..analysis.statistics import base_config
from .common import ETA_STYLE, pyplot, save_figure


def plot_mechanism(avg: xr.Dataset, analyses: list[xr.Dataset], out: str | os.PathLike) -> list[Path]:
    """Stick-slip fraction versus theta, per-contact forces, event sizes and spectra (low and high theta).

    ``avg``: :func:`slipchain.analysis.mechanism.stick_slip_average` of a Fig. 6-like store;
    ``analyses``: the stored analyses of :func:`slipchain.analysis.mechanism.mechanism_members`.
    """
    plt = pyplot()
    paths: list[Path] = []
    omega0 = avg.attrs["omega0"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    v_values = sorted(avg["v_d"].values.tolist(), reverse=True)
    for ec in sorted(avg["eta_c"].values.tolist(), reverse=True) if "eta_c" in avg.dims else [None]:
        factor = round(ec / omega0, 3) if ec is not None else avg.attrs["eta_c"] / omega0
        color, marker = ETA_STYLE.get(factor, ("tab:gray", "^"))
        for vd in v_values:
            cur = avg.sel(v_d=vd, **({} if ec is None else {"eta_c": ec})).dropna("theta", subset=["mu"])
            filled = vd == max(v_values)
            ax.errorbar(cur["theta"], cur["mu"], yerr=cur["err"], color=color, marker=marker,
                        mfc=color if filled else "white", lw=0.8, capsize=2,
                        label=rf"$\eta_c$ = {factor:g} $\omega_0$, $v_d$ = {vd:g} m/s")
    ax.set_xlabel(r"$\theta$")
    ax.set_ylabel("fraction of contacts that stick-slip")
    ax.set_ylim(-0.03, 1.03)
    ax.set_title("Stick-slip fraction versus load (slow fraction >= 5 % of the steady time)", fontsize=9)
    ax.legend(fontsize=7, loc="center right")
    paths += save_figure(fig, out, "mechanism_stick_slip")

    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    v_top = max((a.attrs["v_d"] for a in analyses), default=0.0)
    styles = {(a.attrs["v_d"], a.attrs["theta"]): ("-" if a.attrs["theta"] >= 0.5 else "--",
                                                    "tab:red" if a.attrs["v_d"] == v_top else "tab:blue")
              for a in analyses}
    for a in analyses:
        ls, color = styles[(a.attrs["v_d"], a.attrs["theta"])]
        label = rf"$v_d$ = {a.attrs['v_d']:g}, $\theta$ = {a.attrs['theta']:.2g}"
        # per-contact mean force against v*, and the isolated-contact value f(v_d, v*)
        amp = a.attrs["amplitude"]
        order = np.argsort(a["vstar"].values)
        axes[0].plot(a["vstar"].values, a["force_mean"].values / amp, ls="none",
                     marker="o" if a.attrs["theta"] >= 0.5 else "x", ms=3, color=color, alpha=0.6, label=label)
        axes[0].plot(a["vstar"].values[order], a["force_single"].values[order] / amp, color=color, lw=0.8, ls=":")
        # event sizes
        if a.sizes.get("event", 0):
            sizes = a["event_size"].values[~a["event_truncated"].values.astype(bool)]
            if sizes.size:
                bins = np.unique(np.round(np.geomspace(1, max(sizes.max(), 2) + 1, 20)))
                h, e = np.histogram(sizes, bins=bins)
                centers = np.sqrt(e[:-1] * e[1:])
                density = h / np.diff(e) / a.attrs["duration"]
                ok = h > 0
                axes[1].plot(centers[ok], density[ok], marker="o", ls=ls, color=color,
                             label=f"{label}: {sizes.size} events")
        f = a["frequency"].values[1:]
        axes[2].plot(f, a["psd_u"].values[1:], color=color, ls=ls, lw=1, label=label)
    axes[0].set_xscale("log")
    from matplotlib.ticker import NullFormatter

    axes[0].xaxis.set_minor_formatter(NullFormatter())
    axes[0].set_xlabel(r"$v^*_i$ (m/s)")
    axes[0].set_ylabel(r"time-averaged contact force / $(\varepsilon f_0)$")
    axes[0].set_title(r"per contact (dotted: isolated contact, $f(v_d, v^*_i)$)", fontsize=9)
    axes[0].legend(fontsize=7)
    axes[1].set_xscale("log")
    axes[1].set_yscale("log")
    axes[1].set_xlabel("event size (blocks)")
    axes[1].set_ylabel("events per bin width per second")
    axes[1].set_title("slip events (u > 2 v_d, connected in space and time)", fontsize=9)
    axes[1].legend(fontsize=7)
    axes[2].set_xscale("log")
    axes[2].set_yscale("log")
    axes[2].set_xlabel("frequency (Hz)")
    axes[2].set_ylabel(r"PSD of $u_i$ ((m/s)$^2$/Hz), mean over blocks")
    axes[2].set_title("interface velocity spectra (Welch, Hann)", fontsize=9)
    axes[2].legend(fontsize=7)
    paths += save_figure(fig, out, "mechanism_contacts_events_spectra")

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for a in analyses:
        ls, color = styles[(a.attrs["v_d"], a.attrs["theta"])]
        label = rf"$v_d$ = {a.attrs['v_d']:g}, $\theta$ = {a.attrs['theta']:.2g}"
        f = a["frequency"].values[1:]
        axes[0].plot(f, a["psd_f_d"].values[1:], color=color, ls=ls, lw=1, label=label)
        axes[1].plot(f, a["psd_acoustic"].values[1:], color=color, ls=ls, lw=1, label=label)
    for ax, what in zip(axes, (r"$f_d(t)$ (N$^2$/Hz)", r"$A(t) = \sum_i f(u_i, v^*_i)$ (N$^2$/Hz)")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("PSD of " + what)
        ax.legend(fontsize=7)
    paths += save_figure(fig, out, "mechanism_force_spectra")
    return paths


def plot_velocity(data: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """mu_star versus v_d (log axis), one curve per theta: the model's Figs. 2 and 3
    (``data``: :func:`slipchain.analysis.mechanism.velocity_figure_data`)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    thetas = data["theta"].values.tolist() if "theta" in data.dims else [None]
    colors = plt.cm.viridis(np.linspace(0, 0.85, len(thetas)))
    for th, color in zip(thetas, colors):
        cur = (data.sel(theta=th) if th is not None else data).dropna("v_d", subset=["mu"])
        ax.errorbar(cur["v_d"], cur["mu"], yerr=cur["err"], color=color, marker="o", capsize=2,
                    label=rf"$\theta$ = {th:g}" if th is not None else "model")
    ax.plot(data["v"], data["law"], color="0.5", ls=":", label=r"$f(v, v_0)/(\varepsilon f_0)$")
    ax.axvline(data.attrs["vstar_min"], color="0.7", lw=0.8, ls="--", label=r"smallest $v^*$ = $v_0\,10^{-\delta}$")
    ax.set_xscale("log")
    ax.set_xlabel(r"$v_d$ (m/s)")
    ax.set_ylabel(r"$\mu^*$")
    ax.set_title(r"$\mu^*(v_d)$ at several loads" + (f" ({data.attrs['held']})" if data.attrs["held"] else ""),
                 fontsize=10)
    ax.legend(fontsize=8)
    return save_figure(fig, out, "velocity")


def plot_dead_weight(ds: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """mu(v) measured as the tester does: applied mu_a (dead_weight) against the steady velocity, per theta.

    Runaway members are drawn at the right edge (open triangles) at their applied mu_a.
    """
    plt = pyplot()
    if "dead_weight" not in ds.dims:
        raise ValueError(f"the sweep has dimensions {list(ds.dims)}; a dead-weight figure needs dead_weight")
    cfg = base_config(ds)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    other = [d for d in ds.dims if d not in ("dead_weight", "theta")]
    sub = ds.isel({d: 0 for d in other}) if other else ds
    thetas = sub["theta"].values.tolist() if "theta" in sub.dims else [None]
    colors = plt.cm.viridis(np.linspace(0, 0.85, len(thetas)))
    v_ok = ds["velocity"].values[np.isfinite(ds["velocity"].values)]
    v_edge = v_ok.max() * 3 if v_ok.size else 1.0
    for th, color in zip(thetas, colors):
        cur = sub.sel(theta=th) if th is not None else sub
        mu = cur["dead_weight"].values
        v, e = cur["velocity"].values, cur["velocity_sem"].values
        ok = np.isfinite(v)
        label = rf"$\theta$ = {th:g}" if th is not None else "model"
        if ok.any():
            ax.errorbar(v[ok], mu[ok], xerr=e[ok], color=color, marker="o", capsize=2, label=label + ": steady")
        run = cur["velocity_status"].values == "runaway"
        if run.any():
            ax.plot(np.full(run.sum(), v_edge), mu[run], marker=">", ls="none", color=color, mfc="white",
                    label=label + ": runaway")
    vv = np.geomspace(max(v_ok.min() / 3, 1e-9) if v_ok.size else 1e-7, v_edge, 200)
    ax.plot(vv, cfg.contact_law.force(vv, cfg.v0) / (cfg.epsilon * cfg.f0), color="0.5", ls=":",
            label=r"$f(v, v_0)/(\varepsilon f_0)$")
    ax.set_xscale("log")
    ax.set_xlabel("steady velocity (m/s)")
    ax.set_ylabel(r"applied $\mu^*$ (dead weight)")
    ax.set_title("Dead-weight drive: mu(v) measured as the tester does", fontsize=10)
    ax.legend(fontsize=7)
    return save_figure(fig, out, "dead_weight")


DRAWN = ("ok", "runaway", "no-steady")  # the tester's classifications that the grid figure draws


def grid_panels(ev: "pd.DataFrame", by: str) -> list:
    """The values of ``by`` that get a panel in :func:`plot_dead_weight_grid`: those with a drawn run
    (:data:`DRAWN`), numbers in order, then strings."""
    drawn = ev[ev["velocity_status"].isin(DRAWN)]
    return sorted(drawn[by].unique(), key=lambda x: (isinstance(x, str), x if isinstance(x, str) else float(x)))


def plot_dead_weight_grid(ev: "pd.DataFrame", by: str, out: str | os.PathLike) -> list[Path]:
    """Figs. 2-3 from a grid of dead-weight runs, one panel per value of ``by`` (e.g. the ramp t_ramp):
    applied mu_a against the steady velocity the tester's analysis measured, per theta (each seed its
    own line); runaways at the right edge (open triangles), runs held without a steady velocity by
    t_max ('no-steady': creeping, or still ringing) at the left edge (crosses). ``ev``: the rows of
    :func:`slipchain.workflows.dead_weight.store_evaluations`; runs that failed or did not run are
    not drawn (the caller says how many), and a value none of whose runs is drawn has no panel (e.g. a
    ramp whose runs are all still to run)."""
    plt = pyplot()
    values = grid_panels(ev, by)
    fig, axes = plt.subplots(1, len(values), figsize=(4.2 * len(values) + 1.4, 4.4), sharey=True, squeeze=False)
    thetas = sorted(ev["theta"].unique())
    colors = dict(zip(thetas, plt.cm.viridis(np.linspace(0, 0.85, len(thetas)))))
    v = ev["velocity_m_s"].to_numpy(dtype=float)
    v_ok = v[np.isfinite(v) & (ev["velocity_status"] == "ok").to_numpy()]
    lo_edge, hi_edge = (v_ok.min() / 4, v_ok.max() * 4) if v_ok.size else (1e-7, 1e-3)
    for ax, value in zip(axes[0], values):
        cur = ev[ev[by] == value]
        for th in thetas:
            c = colors[th]
            at = cur[np.isclose(cur["theta"], th)]
            for _, g in at.groupby("seed"):
                ok = g[g["velocity_status"] == "ok"].sort_values("mu_a")
                if len(ok):
                    ax.plot(ok["velocity_m_s"], ok["mu_a"], marker="o", color=c, ms=4)
            run = at[at["velocity_status"] == "runaway"]
            held = at[at["velocity_status"] == "no-steady"]
            step = 1.3 ** thetas.index(th)  # each load its own column at the edges (markers would hide each other)
            ax.plot(np.full(len(run), hi_edge * step), run["mu_a"], marker=">", ls="none", color=c, mfc="white")
            ax.plot(np.full(len(held), lo_edge / step), held["mu_a"], marker="x", ls="none", color=c)
        ax.set_xscale("log")
        ax.set_xlim(lo_edge / 1.3 ** len(thetas), hi_edge * 1.3 ** len(thetas))
        ax.set_xlabel("steady velocity (m/s)")
        ax.set_title(f"{by} = {value:g}" if isinstance(value, (int, float, np.number)) else f"{by} = {value}",
                     fontsize=9)
    axes[0][0].set_ylabel(r"applied $\mu_a$ (dead weight)")
    Line2D = plt.matplotlib.lines.Line2D
    handles = [Line2D([], [], marker="o", ms=4, color=colors[th], label=rf"$\theta$ = {th:g}") for th in thetas]
    handles += [Line2D([], [], marker=">", ls="none", color="0.3", mfc="white", label="runaway (right edge)"),
                Line2D([], [], marker="x", ls="none", color="0.3", label="held, no steady\nvelocity (left edge)")]
    fig.subplots_adjust(right=1.0 - 1.3 / fig.get_figwidth())
    fig.legend(handles=handles, fontsize=7, loc="center left", bbox_to_anchor=(1.0 - 1.25 / fig.get_figwidth(), 0.5),
               frameon=False)
    fig.suptitle("Dead-weight runs read as the tester reads them: mu(v) per load", fontsize=10)
    return save_figure(fig, out, "dead_weight_grid")


def plot_epsilon(avg: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """mu_star versus theta for each epsilon (the contact-force scale of eq. 1), from
    :func:`slipchain.analysis.statistics.epsilon_table`."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8.4, 4.4))
    colors = plt.cm.plasma(np.linspace(0, 0.8, avg.sizes["epsilon"]))
    for eps, color in zip(avg["epsilon"].values, colors):
        cur = avg.sel(epsilon=eps).dropna("theta", subset=["mu"])
        ax.errorbar(cur["theta"], cur["mu"], yerr=cur["err"], color=color, marker="o", capsize=2,
                    label=rf"$\varepsilon$ = {eps:g} (dt = {float(cur['dt_used']) if 'dt_used' in cur.coords else 0:g} s)")
    ax.set_xlabel(r"$\theta$")
    ax.set_ylabel(r"$\mu^*$")
    ax.set_title(r"The load effect for several $\varepsilon$ ($v_d = v_0$)", fontsize=10)
    ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)  # clear of the curves
    return save_figure(fig, out, "epsilon")


__all__ = ["DRAWN", "grid_panels", "plot_dead_weight", "plot_dead_weight_grid", "plot_epsilon", "plot_mechanism", "plot_velocity"]

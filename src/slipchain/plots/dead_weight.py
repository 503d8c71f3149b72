"""The experiment's observable from the model (issue 14): Figs. 2-3 of the paper as the model sees
them, and the model fitted to tester data.

:func:`plot_mu_max`: (a) mu(v) under a dead weight per theta, on the tester figure's axes: every
steady dead-weight run (applied mu_a against its measured velocity), runaways at the right edge,
the seed-mean mu_max as a bar, and the rising branch every contact would follow sliding steadily
(eq. 1 averaged over v*, dashed); (b) mu_max(theta)/mu_max(theta_min) with its standard error,
beside the spring-drive maximum of mu_star(v_d) (the velocity sweep) on the same scale.
:func:`plot_fit`: per tester group, the data per pressure with the fitted model's curves
(:mod:`slipchain.analysis.fit`) and the observed against the fitted maxima.
:func:`plot_velocity_traces`: the slider's velocity against time per run, one panel per load
(:mod:`slipchain.analysis.traces`): the release's overshoot, the top's ringing, creep or runaway.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..analysis.statistics import ratios_to_first
from ..analysis.traces import HELD, STEADY, UNDECIDED, rows_matching
from ..tester.analysis import OK, RUNAWAY, pressure_group
from .common import pyplot, save_figure


def spring_drive_maxima(index_csv: str | os.PathLike) -> pd.DataFrame:
    """The spring-drive maximum per theta from a velocity sweep's index (v_d, theta, seed, mu_star):
    the largest seed-mean mu_star over v_d, its standard error (seed scatter) and the ratio to the
    smallest theta's."""
    t = pd.read_csv(index_csv)
    missing = [c for c in ("v_d", "theta", "seed", "mu_star") if c not in t.columns]
    if missing:
        raise ValueError(f"{str(index_csv)!r} lacks column(s) {missing}; expected the index of a sweep over v_d and theta "
                         "(e.g. docs/mechanism/velocity-index.csv)")
    g = t.groupby(["theta", "v_d"])["mu_star"].agg(["mean", "std", "count"]).reset_index()
    rows = []
    for theta, gt in g.groupby("theta"):
        top = gt.loc[gt["mean"].idxmax()]
        se = float(top["std"]) / np.sqrt(top["count"]) if top["count"] > 1 else np.nan
        rows.append({"theta": theta, "mu_max": float(top["mean"]), "mu_max_se": se, "v_d": float(top["v_d"])})
    return ratios_to_first(pd.DataFrame(rows))


def plot_mu_max(summary: pd.DataFrame, evaluations: pd.DataFrame, branch: tuple[np.ndarray, np.ndarray],
                spring: pd.DataFrame | None, out: str | os.PathLike) -> list[Path]:
    """The two panels (module docstring); ``branch`` = (v, mu) of the all-steady rising branch."""
    plt = pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.4), gridspec_kw={"width_ratios": [1.35, 1]})
    thetas = sorted(evaluations["theta"].unique())
    colors = dict(zip(thetas, plt.cm.viridis(np.linspace(0, 0.85, len(thetas)))))
    ok = evaluations[evaluations["velocity_status"] == OK]
    run = evaluations[evaluations["velocity_status"] == RUNAWAY]
    held = evaluations[evaluations["velocity_status"] == HELD]  # a plan with held = true (workflows.dead_weight)
    moving = pd.concat([ok, held])
    v_lo = moving["velocity_m_s"].min() if len(moving) else 1e-6
    v_hi = moving["velocity_m_s"].max() if len(moving) else 1e-3
    x_edge = v_hi * 3
    bv, bm = branch
    sel = (bv >= v_lo / 2) & (bv <= v_hi * 1.5)
    ax.plot(bv[sel], bm[sel], "k--", lw=1, label="every contact sliding steadily (eq. 1 averaged over v*)")
    for th in thetas:
        c = colors[th]
        o = ok[ok["theta"] == th]
        ax.plot(o["velocity_m_s"], o["mu_a"], "o", ms=3.5, color=c, alpha=0.8, ls="none",
                label=f"theta = {th:g}: steady (all seeds)")
        h = held[held["theta"] == th]
        if len(h):
            ax.plot(h["velocity_m_s"], h["mu_a"], "o", ms=4, mfc="none", color=c, ls="none")
        r = run[run["theta"] == th]
        if len(r):
            ax.plot(np.full(len(r), x_edge) * (1 + 0.08 * thetas.index(th)), r["mu_a"], ">", ms=4, color=c, ls="none")
        srow = summary[summary["theta"] == th]
        if len(srow):
            s = srow.iloc[0]
            ax.errorbar([s["v_max_m_s"]], [s["mu_max"]], yerr=[s["mu_max_se"]], fmt="_", ms=16, mew=2, color=c,
                        capsize=3)
    ax.plot([], [], ">", color="gray", ls="none", label="runaway (drawn at the right edge)")
    if len(held):
        ax.plot([], [], "o", mfc="none", color="gray", ls="none", label="held: still creeping at the run's end (end velocity)")
    ax.plot([], [], "_", color="gray", ms=12, mew=2, ls="none", label="mu_max (seed mean ± SE) at v_max")
    ax.set_xscale("log")
    ax.set_xlabel("v (m/s)")
    ax.set_ylabel(r"applied $\mu_a$ (dead weight)")
    ax.set_title("(a) model under a dead weight: mu(v) on the rising branch", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")  # the branch rises to the right: slow and heavy is empty
    bx.errorbar(summary["theta"], summary["ratio_to_theta_min"], yerr=summary["ratio_se"], fmt="o-", color="tab:red",
                capsize=3, label="dead weight: mu_max (bisection, ± SE)")
    if spring is not None and len(spring):
        bx.errorbar(spring["theta"], spring["ratio_to_theta_min"], yerr=spring["ratio_se"].fillna(0), fmt="s--",
                    color="tab:blue", capsize=3, label="spring drive: max over v_d of mu_star")
    bx.axhline(1.0, color="gray", lw=0.8)
    bx.set_xscale("log")
    bx.set_xlabel(r"$\theta$ (load)")
    bx.set_ylabel(r"maximum / maximum at the smallest $\theta$")
    bx.set_title("(b) the first maximum against load", fontsize=10)
    bx.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, out, "mu_max")


def plot_fit(runs: pd.DataFrame, fits: list, out: str | os.PathLike) -> list[Path]:
    """Per fitted group: measured mu(v) per pressure with the fitted curves; observed vs fitted maxima."""
    from ..tester.analysis import GROUP

    plt = pyplot()
    paths: list[Path] = []
    for f in fits:
        g = runs
        for k, v in zip(GROUP, f.group):
            g = g[g[k] == v]
        g = g.assign(p_group=g["pressure_Pa"].map(pressure_group))
        fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.4), gridspec_kw={"width_ratios": [1.4, 1]})
        pressures = sorted(g["p_group"].unique())
        colors = plt.cm.viridis(np.linspace(0, 0.85, len(pressures)))
        ok = g[(g["status"] == OK) & (g["velocity_m_s"] > 0)]
        v = np.geomspace(ok["velocity_m_s"].min() / 3, ok["velocity_m_s"].max() * 3, 400)
        for p, c in zip(pressures, colors):
            gp = ok[ok["p_group"] == p]
            ax.errorbar(gp["velocity_m_s"], gp["mu"], yerr=gp["mu_sem"], xerr=gp["velocity_sem_m_s"].fillna(0),
                        fmt="o", ms=4, color=c, capsize=2, label=f"measured, p0 = {p / 1e3:.3g} kPa")
            rp = g[(g["p_group"] == p) & (g["status"] == RUNAWAY)]
            ax.plot(np.full(len(rp), v[-1]), rp["mu"], ">", color=c, ms=5, ls="none")
            mu, v_top, mu_top = f.curve(float(gp["pressure_Pa"].mean() if len(gp) else p), v)
            ax.plot(v, mu, "-", color=c, lw=1.3)
            ax.plot([v_top], [mu_top], "*", color=c, ms=10)
        ax.plot([], [], "k-", label="fitted model (ends at its maximum, *)")
        ax.plot([], [], ">", color="gray", ls="none", label="runaway (right edge)")
        ax.set_xscale("log")
        ax.set_xlim(1e-8, None)
        ax.set_ylim(0.25, 1.02)  # below, the elastic rate taken off is the velocity itself: noise about zero
        ax.set_xlabel("v (m/s)")
        ax.set_ylabel(r"$\mu$")
        e = f.params
        ax.set_title(f"{' / '.join(str(x) for x in f.group)}: F = {e['F'].value:.3g}, v0 = {e['v0'].value:.2g} m/s, "
                     f"delta = {e['delta'].value:.2g}, p_ref = {e['p_ref'].value / 1e3:.3g} kPa", fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
        pr = f.pressures
        has = np.isfinite(pr["m_obs"])
        bx.errorbar(pr["pressure_Pa"][has] / 1e3, pr["m_obs"][has], yerr=pr["m_obs_se"][has], fmt="o", color="k",
                    capsize=3, label="observed maximum (between steady and runaway)")
        bx.plot(pr["pressure_Pa"] / 1e3, pr["mu_steady_max"], "v", color="gray", ls="none", label="largest steady mu")
        bx.plot(pr["pressure_Pa"] / 1e3, pr["mu_max_fitted"], "s-", color="tab:red", label="fitted model")
        bx.set_xlabel("p0 (kPa)")
        bx.set_ylabel(r"$\mu_{max}$")
        bx.set_title(f"fall of the maximum: fitted {f.fall_fitted.value:.1%} ± {f.fall_fitted.se:.1%}, observed "
                     f"{f.fall_observed.value:.1%} ± {f.fall_observed.se:.1%}", fontsize=9)
        bx.legend(fontsize=7)
        fig.tight_layout()
        stem = "fit_" + "-".join(str(x).replace(" ", "_").replace("/", "_") for x in f.group)
        paths += save_figure(fig, out, stem)
    return paths


STATUS_STYLE = {STEADY: "-", RUNAWAY: "--", HELD: ":", UNDECIDED: "-."}  # a run's outcome, by line style


def plot_velocity_traces(traces: pd.DataFrame, onsets: pd.DataFrame, window: float, out: str | os.PathLike) -> list[Path]:
    """The top's velocity against time, one panel per theta (a row of panels per release time t_ramp and
    contact damping eta_c where the runs have several, so that one weight's colour means one run per panel), one line per run coloured
    by its applied mu_a, styled by its outcome (:func:`slipchain.analysis.traces.run_outcome`: solid
    steady, dashed runaway, dotted held, dash-dotted undecided); the decision's start (t_decide) and the
    ramp's end as vertical lines. The velocity axis is symmetric-logarithmic (linear within 1e-5 m/s of
    zero): the release's overshoot, the creep and the ringing through zero on one axis. Each runaway's
    onset read during the ramp (``onsets``) is a black dot at its time. ``traces``, ``onsets``:
    :func:`slipchain.analysis.traces.velocity_traces`."""
    plt = pyplot()
    thetas = sorted(traces["theta"].unique())
    ramps = sorted(traces.groupby(["t_ramp", "eta_c"], dropna=False).groups)  # a row per release (and damping)
    releases = traces["t_ramp"].nunique(dropna=False) > 1
    dampings = traces["eta_c"].nunique() > 1
    fig, axes = plt.subplots(len(ramps), len(thetas), figsize=(4.0 * len(thetas) + 1.6, 0.4 + 3.8 * len(ramps)),
                             sharey=True, squeeze=False)
    weights = sorted(traces["mu_a"].unique())
    cmap = plt.cm.plasma(np.linspace(0.0, 0.85, max(len(weights), 2)))
    colors = dict(zip(weights, cmap))
    outcome = dict(zip(onsets["member_id"], onsets["outcome"]))
    for row, (t_ramp, eta_c) in zip(axes, ramps):
        for ax, th in zip(row, thetas):
            panel = {"theta": th, "t_ramp": t_ramp, "eta_c": eta_c}
            cur = traces[rows_matching(traces, panel)]
            for (mu_a, _seed, _id), g in cur.groupby(["mu_a", "seed", "member_id"]):
                ax.plot(g["t"], g["v"], color=colors[mu_a], ls=STATUS_STYLE[outcome[_id]], lw=1.0)
            on = onsets[rows_matching(onsets, panel) & onsets["during_ramp"].astype(bool)]
            for _, r in on.iterrows():
                g = cur[cur["member_id"] == r["member_id"]]
                ax.plot(r["t_onset"], np.interp(r["t_onset"], g["t"], g["v"]), "o", color="k", ms=3, zorder=5)
            for key, style in (("t_decide", ":"), ("t_ramp", "--")):
                for value in cur[key].dropna().unique():
                    if value > 2 * window:  # a ramp within the first window is the weight at once
                        ax.axvline(value, color="0.6", ls=style, lw=0.8)
            ax.set_yscale("symlog", linthresh=1e-5)
            ax.axhline(0.0, color="0.8", lw=0.6)
            ax.set_xlabel("time (s)")
            release = "" if not releases else (
                ", weight at once" if pd.isna(t_ramp) or not t_ramp > 2 * window else f", released over {t_ramp:g} s")
            damping = rf", $\eta_c$ = {eta_c:g}/s" if dampings else ""
            ax.set_title(rf"$\theta$ = {th:g}{release}{damping}", fontsize=9)
        row[0].set_ylabel(f"velocity of the top over {window * 1e3:g} ms (m/s)")
    Line2D = plt.matplotlib.lines.Line2D
    handles = [Line2D([], [], color=colors[w], label=rf"$\mu_a$ = {w:g}") for w in weights]
    handles += [Line2D([], [], color="0.3", ls=ls, label=label) for ls, label in
                (("-", "steady"), ("--", "runaway"), (":", "held (back on the branch)"), ("-.", "undecided"))]
    handles += [Line2D([], [], color="0.6", ls=":", lw=0.8, label="decision from"),
                Line2D([], [], color="0.6", ls="--", lw=0.8, label="ramp's end"),
                Line2D([], [], marker="o", ls="none", color="k", ms=3, label="runaway's onset")]
    fig.subplots_adjust(right=1.0 - 1.5 / fig.get_figwidth(), hspace=0.35)
    fig.legend(handles=handles, fontsize=7, loc="center left", bbox_to_anchor=(1.0 - 1.45 / fig.get_figwidth(), 0.5),
               frameon=False)
    fig.suptitle("The hanging weight's pull read as a tester's distance record: velocity against time", fontsize=10)
    return save_figure(fig, out, "velocity_traces")


def plot_branches(branch: pd.DataFrame, onsets: pd.DataFrame, out: str | os.PathLike) -> list[Path]:
    """Figs. 2-3 from slowly loaded runs: mu against the interface's slip velocity (log; ``v_slip``, the
    elastic loading rate of the contact-free sites taken off) as each run's ramp traced it (:func:`slipchain.analysis.traces.ramp_branch`), one panel per interface, temperature and contact damping,
    one line per run coloured by theta; a runaway's branch ends at its onset (a black dot: mu_max); each
    steady run's tester reading (its weight against its steady velocity, ``onsets`` rows with outcome
    steady) as an open circle of its load's colour."""
    plt = pyplot()
    groups = sorted(branch.groupby(["N", "temperature", "eta_c"], dropna=False).groups)
    dampings = branch["eta_c"].nunique() > 1
    fig, axes = plt.subplots(1, len(groups), figsize=(4.2 * len(groups) + 1.4, 4.2), sharey=True, squeeze=False)
    thetas = sorted(branch["theta"].unique())
    colors = dict(zip(thetas, plt.cm.viridis(np.linspace(0.0, 0.9, max(len(thetas), 2)))))
    for ax, (n, temp, eta_c) in zip(axes[0], groups):
        group = {"N": n, "temperature": temp, "eta_c": eta_c}
        cur = branch[rows_matching(branch, group)]
        for (th, _id), g in cur.groupby(["theta", "member_id"]):
            g = g[g["v_slip"] > 0]
            ax.plot(g["v_slip"], g["mu"], color=colors[th], lw=0.8, alpha=0.8)
            on = onsets[(onsets["member_id"] == _id) & onsets["during_ramp"].astype(bool)]
            if len(on) and len(g):
                ax.plot(g["v_slip"].iloc[-1], g["mu"].iloc[-1], "o", color="k", ms=3, zorder=5)
        same = onsets[rows_matching(onsets, group) & (onsets["outcome"] == STEADY) & onsets["velocity"].notna()]
        for _, r in same.iterrows():
            ax.plot(r["velocity"], r["mu_a"], "o", mfc="none", mec=colors.get(r["theta"], "0.3"), ms=6, zorder=6)
        ax.set_xscale("log")
        ax.set_xlabel("slip velocity of the interface (m/s)")
        label = f"{n:g} x {n:g}" + ("" if pd.isna(temp) else f", {temp:g} °C") + (rf", $\eta_c$ = {eta_c:g}/s" if dampings else "")
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel(r"applied $\mu_a$ (the weight while it rises)")
    Line2D = plt.matplotlib.lines.Line2D
    handles = [Line2D([], [], color=colors[t], label=rf"$\theta$ = {t:g}") for t in thetas]
    handles += [Line2D([], [], marker="o", ls="none", color="k", ms=3, label="runaway's onset (mu_max)"),
                Line2D([], [], marker="o", ls="none", mfc="none", mec="0.3", ms=6, label="steady run (tester)")]
    fig.subplots_adjust(right=1.0 - 1.4 / fig.get_figwidth())
    fig.legend(handles=handles, fontsize=7, loc="center left", bbox_to_anchor=(1.0 - 1.35 / fig.get_figwidth(), 0.5),
               frameon=False)
    fig.suptitle("mu(v) on the rising branch as the slowly rising weight traces it (Figs. 2-3's axes)", fontsize=10)
    return save_figure(fig, out, "branches")


__all__ = ["STATUS_STYLE", "plot_branches", "plot_velocity_traces", "plot_fit", "plot_mu_max", "spring_drive_maxima"]

"""Figures 5 and 6 of the paper, drawn from Datasets (never from live simulations).

* Fig. 5: :func:`contact_law_dataset` evaluates eq. (1), f(v, v0), for several contact dampings
  and the contact average <f(v, v*_i)> over the v*_i of one realisation (N = 1001, theta = 1);
  :func:`plot_fig5` draws it on a log-v axis, in units of epsilon*f0.
* Fig. 6: :func:`plot_fig6` draws seed-averaged mu_star versus theta from a sweep Dataset:
  eta_c = omega0 blue circles, 0.3 omega0 red diamonds, 0.1 omega0 black squares (as the paper),
  filled for v_d1 = v0, open for v_d2; N = 1001 as stars; the dashed line f(v_d2, v0)/(epsilon f0).

Every plot is written as PNG and PDF.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from .config import Config, make_config
from .io import atomic_write
from .reproduction import base_config, dashed_line, drive_velocities, fig6_table, main_n, main_selection

FIG5_ETA_FACTORS = (0.0, 1.0, 0.3, 0.1)  # eta_c / omega0, the curves of Fig. 5
ETA_STYLE = {1.0: ("tab:blue", "o"), 0.3: ("tab:red", "D"), 0.1: ("black", "s")}  # Fig. 6 symbols


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def contact_law_dataset(config: Config | None = None, *, N: int = 1001, theta: float = 1.0, seed: int = 0,
                        v_min: float = 1e-7, v_max: float = 1.0, points: int = 600) -> xr.Dataset:
    """eq. (1) on a log-v grid: f(v, v0) for each eta_c of Fig. 5 and the contact average.

    The average <f(v, v*_i)> = N_c^-1 sum_i f(v, v*_i) uses the v*_i of the realisation
    (``N``, ``theta``, ``seed``) and the config's eta_c.
    """
    from .system import build_system

    cfg = config or make_config()
    v = np.geomspace(v_min, v_max, points)
    scale = cfg.epsilon * cfg.f0
    curves = np.array([cfg.with_updates(eta_c=k * cfg.omega0).contact_law.force(v, cfg.v0) / scale
                       for k in FIG5_ETA_FACTORS])
    system = build_system(cfg.with_updates(N=N, theta=theta, seed=seed))
    avg = cfg.contact_law.average(v, system.vstar) / scale
    return xr.Dataset(
        {"f": (("eta_c_factor", "v"), curves, {"long_name": "f(v, v0)/(epsilon f0), eq. (1)"}),
         "f_average": ("v", avg, {"long_name": "<f(v, v*_i)>/(epsilon f0) over the contacts of one realisation"})},
        coords={"v": ("v", v, {"units": "m/s"}), "eta_c_factor": list(FIG5_ETA_FACTORS)},
        attrs={"N": N, "theta": theta, "seed": seed, "n_contacts": system.n_contacts, "eta_c_average": cfg.eta_c,
               "omega0": cfg.omega0, "v0": cfg.v0, "config": cfg.to_toml()},
    )


def _save(fig, out: str | os.PathLike, stem: str) -> list[Path]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        p = out / f"{stem}.{ext}"
        with atomic_write(p) as tmp:
            fig.savefig(tmp, dpi=150, bbox_inches="tight", format=ext)
        paths.append(p)
    _pyplot().close(fig)
    return paths


def plot_fig5(ds: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """Fig. 5: the contact law for the dampings of the paper and the contact average."""
    plt = _pyplot()
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
    return _save(fig, out, "fig5")


def plot_fig6(ds: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """Fig. 6: seed-averaged mu_star versus theta from a sweep Dataset (see module docstring)."""
    plt = _pyplot()
    cfg = base_config(ds)
    avg, sel = fig6_table(ds)
    v_values = sorted(avg["v_d"].values.tolist())
    v_d1, v_d2 = drive_velocities(cfg, v_values)
    ns = avg["N"].values.tolist() if "N" in avg.dims else [None]
    n_main = main_n(avg)
    fig, ax = plt.subplots(figsize=(8.2, 4.8))
    handles = []
    from matplotlib.lines import Line2D

    for ec in sorted(avg["eta_c"].values.tolist(), reverse=True):
        factor = round(ec / cfg.omega0, 3)
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
        line = dashed_line(cfg, v_d2)
        ax.axhline(line, color="0.3", ls="--", lw=1)
        handles.append(Line2D([], [], color="0.3", ls="--", label=rf"$f(v_{{d2}}, v_0)/(\varepsilon f_0)$ = {line:.3f}"))
    ax.set_xlabel(r"$\theta$ (proportional to the load)")
    ax.set_ylabel(r"$\mu^* = \langle f_d \rangle / (\varepsilon f_0 \theta)$")
    ax.set_xlim(0, 1.05)
    extra = ", ".join(f"{k} = {v:g}" for k, v in sel.items())
    n_text = f"N = {n_main}" if n_main is not None else ""
    ax.set_title("Fig. 6: friction versus load" + (f" ({', '.join(x for x in (n_text, extra) if x)})"), fontsize=10)
    ax.legend(handles=handles, fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    return _save(fig, out, "fig6")


__all__ = ["contact_law_dataset", "plot_fig5", "plot_fig6"]


# --- the mechanism (issue 5) ----------------------------------------------------------------------
def plot_mechanism(stick_slip: xr.Dataset, analyses: list[xr.Dataset], out: str | os.PathLike) -> list[Path]:
    """Stick-slip fraction versus theta, per-contact forces, event sizes and spectra (low and high theta).

    ``stick_slip``: :func:`slipchain.mechanism.stick_slip_dataset` of a Fig. 6-like store;
    ``analyses``: the stored analyses of :func:`slipchain.mechanism.mechanism_members`.
    """
    from .reproduction import seed_average

    plt = _pyplot()
    paths: list[Path] = []
    cfg = base_config(stick_slip)
    sel = main_selection(stick_slip)
    avg = seed_average(stick_slip.sel(sel) if sel else stick_slip)
    if "N" in avg.dims:
        avg = avg.sel(N=main_n(avg))
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    v_values = sorted(avg["v_d"].values.tolist(), reverse=True)
    for ec in sorted(avg["eta_c"].values.tolist(), reverse=True) if "eta_c" in avg.dims else [None]:
        factor = round(ec / cfg.omega0, 3) if ec is not None else cfg.eta_c / cfg.omega0
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
    paths += _save(fig, out, "mechanism_stick_slip")

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
    paths += _save(fig, out, "mechanism_contacts_events_spectra")

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
    paths += _save(fig, out, "mechanism_force_spectra")
    return paths


def plot_velocity(ds: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """mu_star versus v_d (log axis), one curve per theta: the model's Figs. 2 and 3."""
    from .reproduction import seed_average

    plt = _pyplot()
    sel = main_selection(ds)
    avg = seed_average(ds.sel(sel) if sel else ds)
    cfg = base_config(ds)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    other = [d for d in avg["mu"].dims if d not in ("v_d", "theta")]
    sub = avg.isel({d: 0 for d in other}) if other else avg
    thetas = sub["theta"].values.tolist() if "theta" in sub.dims else [None]
    colors = plt.cm.viridis(np.linspace(0, 0.85, len(thetas)))
    for th, color in zip(thetas, colors):
        cur = (sub.sel(theta=th) if th is not None else sub).dropna("v_d", subset=["mu"])
        ax.errorbar(cur["v_d"], cur["mu"], yerr=cur["err"], color=color, marker="o", capsize=2,
                    label=rf"$\theta$ = {th:g}" if th is not None else "model")
    v = np.geomspace(float(avg["v_d"].min()), float(avg["v_d"].max()), 200)
    ax.plot(v, cfg.contact_law.force(v, cfg.v0) / (cfg.epsilon * cfg.f0), color="0.5", ls=":",
            label=r"$f(v, v_0)/(\varepsilon f_0)$")
    ax.axvline(cfg.v0 * 10 ** -cfg.delta, color="0.7", lw=0.8, ls="--",
               label=r"smallest $v^*$ = $v_0\,10^{-\delta}$")
    ax.set_xscale("log")
    ax.set_xlabel(r"$v_d$ (m/s)")
    ax.set_ylabel(r"$\mu^*$")
    ax.set_title(r"$\mu^*(v_d)$ at several loads" + (f" ({', '.join(f'{d} = {sub[d].item():g}' for d in other)})"
                                                      if other else ""), fontsize=10)
    ax.legend(fontsize=8)
    return _save(fig, out, "velocity")


def plot_dead_weight(ds: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """mu(v) measured as the tester does: applied mu_a (dead_weight) against the steady velocity, per theta.

    Runaway members are drawn at the right edge (open triangles) at their applied mu_a.
    """
    plt = _pyplot()
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
    return _save(fig, out, "dead_weight")


def epsilon_table(ds: xr.Dataset) -> xr.Dataset:
    """Seed-averaged mu_star on (epsilon, theta): each epsilon at the time step it was run with."""
    from .reproduction import seed_average

    avg = seed_average(ds)
    if "dt" in avg.dims:  # every epsilon has its own dt: keep, per epsilon, the dt that has data
        picks = []
        for eps in avg["epsilon"].values:
            cur = avg.sel(epsilon=eps)
            best = int(np.argmax(cur["n"].sum("theta").values))
            picks.append(cur.isel(dt=best).drop_vars("dt").assign_coords(dt_used=cur["dt"].values[best]))
        avg = xr.concat(picks, dim="epsilon", coords="different", compat="equals", join="outer")
    return avg


def plot_epsilon(ds: xr.Dataset, out: str | os.PathLike) -> list[Path]:
    """mu_star versus theta for each epsilon (the contact-force scale of eq. 1)."""
    plt = _pyplot()
    avg = epsilon_table(ds)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    colors = plt.cm.plasma(np.linspace(0, 0.8, avg.sizes["epsilon"]))
    for eps, color in zip(avg["epsilon"].values, colors):
        cur = avg.sel(epsilon=eps).dropna("theta", subset=["mu"])
        ax.errorbar(cur["theta"], cur["mu"], yerr=cur["err"], color=color, marker="o", capsize=2,
                    label=rf"$\varepsilon$ = {eps:g} (dt = {float(cur['dt_used']) if 'dt_used' in cur.coords else 0:g} s)")
    ax.set_xlabel(r"$\theta$")
    ax.set_ylabel(r"$\mu^*$")
    ax.set_title(r"The load effect for several $\varepsilon$ ($v_d = v_0$)", fontsize=10)
    ax.legend(fontsize=8)
    return _save(fig, out, "epsilon")

"""Figs. 5 and 6 of the paper as numbers: the contact law curves, and the paper's Fig. 6 claims measured on a sweep.

* Fig. 5: :func:`contact_law_dataset` evaluates eq. (1), f(v, v0), for several contact dampings
  and the contact average <f(v, v*_i)> over the v*_i of one realisation (N = 1001, theta = 1).
* Fig. 6: input is the sweep Dataset of a store (:meth:`slipchain.sweeps.store.Store.dataset`)
  with at least the dimensions ``theta``, ``eta_c`` and ``v_d`` (``N`` and ``seed`` optional).
  Any other swept dimension (the presets add ``dt`` and ``sem_target`` for convergence evidence)
  is held at its most populated value for the figure and the claims (:func:`fig6_table`), and its
  other values are compared with that one (:func:`convergence`). Seed means and their errors:
  :func:`slipchain.analysis.statistics.seed_average`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from ..model.config import Config, make_config
from ..model.system import build_system
from ..results.schema import Status
from .statistics import base_config, drive_velocities, fmt_value, load_drops, main_average, main_n, main_selection

V_D2_TOLERANCE = 0.03  # issue acceptance: every mu_star within 3 % of the dashed line at v_d2
DROP_RATIO_MAX = 0.8  # issue acceptance: mu_star(theta=1) <= 0.8 mu_star(theta_min) at v_d1, eta_c = 0.1 omega0
FIG5_ETA_FACTORS = (0.0, 1.0, 0.3, 0.1)  # eta_c / omega0, the curves of Fig. 5


def contact_law_dataset(config: Config | None = None, *, N: int = 1001, theta: float = 1.0, seed: int = 0,
                        v_min: float = 1e-7, v_max: float = 1.0, points: int = 600) -> xr.Dataset:
    """eq. (1) on a log-v grid: f(v, v0) for each eta_c of Fig. 5 and the contact average.

    The average <f(v, v*_i)> = N_c^-1 sum_i f(v, v*_i) uses the v*_i of the realisation
    (``N``, ``theta``, ``seed``) and the config's eta_c.
    """
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


def dashed_line(cfg: Config, v_d2: float, eta_c: float | None = None) -> float:
    """f(v_d2, v0)/(epsilon*f0): the paper's dashed line in Fig. 6 (per contact)."""
    law = cfg.with_updates(eta_c=cfg.eta_c if eta_c is None else eta_c).contact_law
    return float(law.force(np.array([v_d2]), cfg.v0)[0] / (cfg.epsilon * cfg.f0))


def fig6_table(ds: xr.Dataset) -> tuple[xr.Dataset, dict[str, Any]]:
    """Seed-averaged mu_star on (N, theta, eta_c, v_d) at the main values of any other dimension."""
    return main_average(ds)


def fig6_figure_data(ds: xr.Dataset) -> xr.Dataset:
    """What Fig. 6 draws: the seed-averaged table of :func:`fig6_table` (``mu``, ``err``, ``n``) with,
    in its attrs, v_d1 and v_d2, the dashed line f(v_d2, v0)/(epsilon f0) (NaN with one v_d), the
    main chain length (0 if N is not swept; n_base: the base config's), epsilon, omega0 and the values at
    which other dimensions are held."""
    cfg = base_config(ds)
    avg, sel = fig6_table(ds)
    v_d1, v_d2 = drive_velocities(cfg, avg["v_d"].values)
    return avg.assign_attrs(v_d1=v_d1, v_d2=v_d2, dashed_line=dashed_line(cfg, v_d2) if v_d2 != v_d1 else float("nan"),
                            n_main=main_n(avg) or 0, n_base=cfg.N, epsilon=cfg.epsilon, omega0=cfg.omega0,
                            held=", ".join(f"{k} = {fmt_value(v)}" for k, v in sel.items()))


@dataclass
class Claim:
    """One statement of the paper, what we measured, and whether the issue's criterion holds."""

    paper: str
    measured: str
    criterion: str
    passed: bool | None
    numbers: dict[str, Any] = field(default_factory=dict)


def evaluate(ds: xr.Dataset) -> list[Claim]:
    """The paper's Fig. 6 claims, measured on the sweep Dataset."""
    cfg = base_config(ds)
    avg, _ = fig6_table(ds)
    n_main = main_n(avg)
    main = avg.sel(N=n_main) if n_main is not None else avg
    v_d1, v_d2 = drive_velocities(cfg, main["v_d"].values)
    eta_values = sorted(main["eta_c"].values.tolist())
    claims: list[Claim] = []

    # 1. v_d2: load independent, near the dashed line.
    if v_d2 != v_d1:
        devs, rows = [], []
        for ec in eta_values:
            line = dashed_line(cfg, v_d2, ec)
            cur = main.sel(v_d=v_d2, eta_c=ec).dropna("theta", subset=["mu"])
            for th in cur["theta"].values:
                mu = float(cur["mu"].sel(theta=th))
                devs.append(mu / line - 1.0)
                rows.append((ec, float(th), mu, float(cur["err"].sel(theta=th))))
        ratios = [(d["eta_c"], d["ratio"], d["ratio_err"]) for d in load_drops(main.sel(v_d=v_d2).sortby("eta_c"), "eta_c")]
        line = dashed_line(cfg, v_d2)
        worst = max(devs, key=abs) if devs else float("nan")
        mean_dev = float(np.mean(devs)) if devs else float("nan")
        ratio_text = "; ".join(f"eta_c = {eta_label(ec)}: {r:.3f} ± {e:.3f}" for ec, r, e in ratios)
        claims.append(Claim(
            paper=f"At v_d2 = {v_d2:g} m/s friction is almost independent of load and lies near the dashed line "
                  f"f(v_d2, v0)/(epsilon f0) = {line:.4f}.",
            measured=(f"{len(devs)} points (N = {n_main if n_main is not None else cfg.N}): mu_star/line - 1 from {min(devs):+.2%} to {max(devs):+.2%} "
                      f"(mean {mean_dev:+.2%}); mu_star(theta_max)/mu_star(theta_min): {ratio_text}.") if devs else "no data",
            criterion=f"every mu_star within {V_D2_TOLERANCE:.0%} of the dashed line",
            passed=bool(devs) and abs(worst) <= V_D2_TOLERANCE,
            numbers={"line": line, "max_abs_deviation": abs(worst), "mean_deviation": mean_dev, "points": rows,
                     "ratios": ratios},
        ))

    # 2. v_d1: mu_star falls with theta, more for smaller eta_c.
    drops = load_drops(main.sel(v_d=v_d1).sortby("eta_c"), "eta_c")  # per eta_c, ascending: smallest and largest theta, their ratio
    if drops:
        smallest = min(drops, key=lambda d: d["eta_c"])
        by_eta = sorted(drops, key=lambda d: d["eta_c"])
        ordered = all(a["ratio"] < b["ratio"] for a, b in zip(by_eta, by_eta[1:]))
        text = "; ".join(f"eta_c = {eta_label(d['eta_c'])}: {d['mu_min_theta']:.3f} ± {d['err_min_theta']:.3f} at theta = "
                         f"{d['theta_min']:g} -> {d['mu_max_theta']:.3f} ± {d['err_max_theta']:.3f} at theta = "
                         f"{d['theta_max']:g}, ratio {d['ratio']:.3f} ± {d['ratio_err']:.3f} "
                         f"(drop {1 - d['ratio']:.1%})" for d in by_eta)
        claims.append(Claim(
            paper=f"At v_d1 = v0 = {v_d1:g} m/s mu_star falls by more than 20 % as theta (load) grows; "
                  "the smaller eta_c, the stronger the fall.",
            measured=text + (". Drops ordered by eta_c: yes." if ordered else ". Drops ordered by eta_c: NO.")
            + f" At eta_c = {eta_label(smallest['eta_c'])} the ratio is {(DROP_RATIO_MAX - smallest['ratio']) / smallest['ratio_err']:+.1f} "
              f"of its error below {DROP_RATIO_MAX}.",
            criterion=f"mu_star(theta_max)/mu_star(theta_min) <= {DROP_RATIO_MAX} at eta_c = {eta_label(smallest['eta_c'])}, "
                      "and the drop larger for smaller eta_c",
            passed=smallest["ratio"] <= DROP_RATIO_MAX and ordered,
            numbers={"drops": drops, "ordered": ordered},
        ))

    # 3. N = 1001 agrees with N = 301.
    if "N" in avg.dims and avg.sizes["N"] >= 2:
        rows = []
        big = [n for n in avg["N"].values.tolist() if n != n_main]
        for nb in big:
            pair = avg.sel(N=[n_main, nb])
            both = pair["mu"].notnull().all("N")
            for idx in zip(*np.nonzero(both.values)):
                point = {d: pair[d].values[i].item() for d, i in zip(both.dims, idx)}
                a, b = pair.sel(N=n_main, **point), pair.sel(N=nb, **point)
                diff = float(b["mu"] - a["mu"])
                ea, eb = float(a["err"]), float(b["err"])
                rows.append({**point, "N": nb, "mu_main": float(a["mu"]), "err_main": ea, "mu_big": float(b["mu"]),
                             "err_big": eb, "diff": diff, "z": diff / math.hypot(ea, eb), "overlap": abs(diff) <= ea + eb})
        n_ok = sum(r["overlap"] for r in rows)
        worst = max(rows, key=lambda r: abs(r["z"])) if rows else None
        claims.append(Claim(
            paper="The N = 1001 points (stars) lie on the N = 301 results.",
            measured=(f"{n_ok} of {len(rows)} points have overlapping error bars; |difference| / combined error: "
                      f"median {np.median([abs(r['z']) for r in rows]):.2f}, largest {abs(worst['z']):.2f} "
                      f"(theta = {worst['theta']:g}, eta_c = {eta_label(worst['eta_c'])}, v_d = {worst['v_d']:g})") if rows
            else "no points with both sizes",
            criterion="error bars of N = 1001 and N = 301 overlap at every shared point",
            passed=bool(rows) and n_ok == len(rows),
            numbers={"rows": rows},
        ))
    return claims


def convergence(ds: xr.Dataset) -> list[dict[str, Any]]:
    """Members at a non-main value of an extra dimension (dt, sem_target, ...) against the main value.

    Compared per seed (same disorder), so the difference measures the numerical effect alone:
    z = (mu_alt - mu_main)/hypot(sem_alt, sem_main).
    """
    sel = main_selection(ds)
    rows = []
    for d, main_value in sel.items():
        others = {k: v for k, v in sel.items() if k != d}
        sub = ds.sel(others) if others else ds
        for alt in sub[d].values.tolist():
            if alt == main_value:
                continue
            a, b = sub.sel({d: main_value}), sub.sel({d: alt})
            ok = (a["status"] == Status.COMPLETED) & (b["status"] == Status.COMPLETED)
            for idx in zip(*np.nonzero(ok.values)):
                point = {k: a[k].values[i].item() for k, i in zip(ok.dims, idx)}
                ma, mb = a.sel(point), b.sel(point)
                diff = float(mb["mu_star"] - ma["mu_star"])
                se = math.hypot(float(ma["mu_star_sem"]), float(mb["mu_star_sem"]))
                rows.append({"dim": d, "main": main_value, "alt": alt, **point, "mu_main": float(ma["mu_star"]),
                             "mu_alt": float(mb["mu_star"]), "diff": diff, "z": diff / se if se > 0 else float("nan")})
    return rows


def eta_label(ec: float) -> str:
    """eta_c in units of omega0 = 1e6 1/s (the paper's labels)."""
    return f"{ec / 1e6:g} omega0"


__all__ = ["Claim", "DROP_RATIO_MAX", "FIG5_ETA_FACTORS", "V_D2_TOLERANCE", "contact_law_dataset", "convergence",
           "dashed_line", "eta_label", "evaluate", "fig6_figure_data", "fig6_table"]

"""Fig. 6 of the paper from a sweep Dataset: seed averages, the paper's claims, the report.

Input is the sweep Dataset of a store (:meth:`slipchain.store.Store.dataset`) with at least the
dimensions ``theta``, ``eta_c`` and ``v_d`` (``N`` and ``seed`` optional). Any other swept
dimension (the presets add ``dt`` and ``sem_target`` for convergence evidence) is held at its
most populated value for the figure and the claims, and its other values are compared with that
one in the report's convergence section.

Error bars combine seeds and time: for ``n`` completed seeds with values ``mu_k`` and time
standard errors ``s_k``, the error of the seed mean is
``sqrt(max(var_k(mu_k)/n, mean_k(s_k**2)/n))`` (``var`` with ddof = 1): the scatter between
seeds already contains the time noise; the second term keeps the error honest when a few seeds
agree by chance. With one seed it is that seed's time error.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from .config import Config
from .sweep import make_sweep

FIG6_DIMS = ("N", "theta", "eta_c", "v_d", "seed")
MAIN_N = 301
V_D2_TOLERANCE = 0.03  # issue acceptance: every mu_star within 3 % of the dashed line at v_d2
DROP_RATIO_MAX = 0.8  # issue acceptance: mu_star(theta=1) <= 0.8 mu_star(theta_min) at v_d1, eta_c = 0.1 omega0


def base_config(ds: xr.Dataset) -> Config:
    """The sweep's base config, from the definition stored in the Dataset's attrs."""
    return make_sweep(tomllib.loads(ds.attrs["definition"])).base


def main_selection(ds: xr.Dataset) -> dict[str, Any]:
    """For each swept dimension outside Fig. 6's, the value with the most completed members."""
    done = ds["status"] == "completed"
    sel = {}
    for d in ds.dims:
        if d in FIG6_DIMS:
            continue
        counts = done.sum([x for x in ds.dims if x != d])
        sel[d] = ds[d].values[int(np.argmax(counts.values))].item()
    return sel


def main_n(ds: xr.Dataset) -> int | None:
    """The chain length of the main curves: N = 301 if swept, else the first N (None if N is not swept)."""
    if "N" not in ds.dims:
        return None
    values = ds["N"].values.tolist()
    return MAIN_N if MAIN_N in values else int(values[0])


def drive_velocities(cfg: Config, v_values) -> tuple[float, float]:
    """(v_d1, v_d2): the swept drive velocity closest to v0 (log scale), and the smallest."""
    values = sorted(float(v) for v in v_values)
    return min(values, key=lambda v: abs(math.log(v / cfg.v0))), values[0]


def seed_average(ds: xr.Dataset) -> xr.Dataset:
    """mu_star averaged over ``seed`` (completed members only), error from seeds and time."""
    ok = ds["status"] == "completed"
    mu = ds["mu_star"].where(ok)
    sem = ds["mu_star_sem"].where(ok)
    if "seed" not in ds.dims:
        return xr.Dataset({"mu": mu, "err": sem, "n": ok.astype(int)})
    n = ok.sum("seed")
    mean = mu.mean("seed")
    var = mu.var("seed", ddof=1)
    time_part = (sem**2).mean("seed") / n
    seed_part = (var / n).fillna(0.0)
    err = np.sqrt(np.maximum(seed_part, time_part))
    return xr.Dataset({"mu": mean.where(n > 0), "err": err.where(n > 0), "n": n})


def dashed_line(cfg: Config, v_d2: float, eta_c: float | None = None) -> float:
    """f(v_d2, v0)/(epsilon*f0): the paper's dashed line in Fig. 6 (per contact)."""
    law = cfg.with_updates(eta_c=cfg.eta_c if eta_c is None else eta_c).contact_law
    return float(law.force(np.array([v_d2]), cfg.v0)[0] / (cfg.epsilon * cfg.f0))


def fig6_table(ds: xr.Dataset) -> tuple[xr.Dataset, dict[str, Any]]:
    """Seed-averaged mu_star on (N, theta, eta_c, v_d) at the main values of any other dimension."""
    sel = main_selection(ds)
    sub = ds.sel(sel) if sel else ds
    return seed_average(sub), sel


@dataclass
class Claim:
    """One statement of the paper, what we measured, and whether the issue's criterion holds."""

    paper: str
    measured: str
    criterion: str
    passed: bool | None
    numbers: dict[str, Any] = field(default_factory=dict)


def _ratio(a: float, ea: float, b: float, eb: float) -> tuple[float, float]:
    r = a / b
    return r, abs(r) * math.hypot(ea / a, eb / b)


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
        devs, rows, ratios = [], [], []
        for ec in eta_values:
            line = dashed_line(cfg, v_d2, ec)
            cur = main.sel(v_d=v_d2, eta_c=ec).dropna("theta", subset=["mu"])
            for th in cur["theta"].values:
                mu = float(cur["mu"].sel(theta=th))
                devs.append(mu / line - 1.0)
                rows.append((ec, float(th), mu, float(cur["err"].sel(theta=th))))
            if cur.sizes["theta"] >= 2:
                first, last = cur.isel(theta=0), cur.isel(theta=-1)
                ratios.append((ec, *_ratio(float(last["mu"]), float(last["err"]), float(first["mu"]), float(first["err"]))))
        line = dashed_line(cfg, v_d2)
        worst = max(devs, key=abs) if devs else float("nan")
        mean_dev = float(np.mean(devs)) if devs else float("nan")
        ratio_text = "; ".join(f"eta_c = {_eta(ec)}: {r:.3f} ± {e:.3f}" for ec, r, e in ratios)
        claims.append(Claim(
            paper=f"At v_d2 = {v_d2:g} m/s friction is almost independent of load and lies near the dashed line "
                  f"f(v_d2, v0)/(epsilon f0) = {line:.4f}.",
            measured=(f"{len(devs)} points (N = {n_main}): mu_star/line - 1 from {min(devs):+.2%} to {max(devs):+.2%} "
                      f"(mean {mean_dev:+.2%}); mu_star(theta_max)/mu_star(theta_min): {ratio_text}.") if devs else "no data",
            criterion=f"every mu_star within {V_D2_TOLERANCE:.0%} of the dashed line",
            passed=bool(devs) and abs(worst) <= V_D2_TOLERANCE,
            numbers={"line": line, "max_abs_deviation": abs(worst), "mean_deviation": mean_dev, "points": rows,
                     "ratios": ratios},
        ))

    # 2. v_d1: mu_star falls with theta, more for smaller eta_c.
    drops = []
    for ec in eta_values:
        cur = main.sel(v_d=v_d1, eta_c=ec).dropna("theta", subset=["mu"])
        if cur.sizes["theta"] < 2:
            continue
        first, last = cur.isel(theta=0), cur.isel(theta=-1)
        r, e = _ratio(float(last["mu"]), float(last["err"]), float(first["mu"]), float(first["err"]))
        drops.append({"eta_c": ec, "theta_min": float(first["theta"]), "theta_max": float(last["theta"]),
                      "mu_min_theta": float(first["mu"]), "err_min_theta": float(first["err"]),
                      "mu_max_theta": float(last["mu"]), "err_max_theta": float(last["err"]), "ratio": r, "ratio_err": e})
    if drops:
        smallest = min(drops, key=lambda d: d["eta_c"])
        by_eta = sorted(drops, key=lambda d: d["eta_c"])
        ordered = all(a["ratio"] < b["ratio"] for a, b in zip(by_eta, by_eta[1:]))
        text = "; ".join(f"eta_c = {_eta(d['eta_c'])}: {d['mu_min_theta']:.3f} ± {d['err_min_theta']:.3f} at theta = "
                         f"{d['theta_min']:g} -> {d['mu_max_theta']:.3f} ± {d['err_max_theta']:.3f} at theta = "
                         f"{d['theta_max']:g}, ratio {d['ratio']:.3f} ± {d['ratio_err']:.3f} "
                         f"(drop {1 - d['ratio']:.1%})" for d in by_eta)
        claims.append(Claim(
            paper=f"At v_d1 = v0 = {v_d1:g} m/s mu_star falls by more than 20 % as theta (load) grows; "
                  "the smaller eta_c, the stronger the fall.",
            measured=text + (". Drops ordered by eta_c: yes." if ordered else ". Drops ordered by eta_c: NO.")
            + f" At eta_c = {_eta(smallest['eta_c'])} the ratio is {(DROP_RATIO_MAX - smallest['ratio']) / smallest['ratio_err']:+.1f} "
              f"of its error below {DROP_RATIO_MAX}.",
            criterion=f"mu_star(theta_max)/mu_star(theta_min) <= {DROP_RATIO_MAX} at eta_c = {_eta(smallest['eta_c'])}, "
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
                      f"(theta = {worst['theta']:g}, eta_c = {_eta(worst['eta_c'])}, v_d = {worst['v_d']:g})") if rows
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
            ok = (a["status"] == "completed") & (b["status"] == "completed")
            for idx in zip(*np.nonzero(ok.values)):
                point = {k: a[k].values[i].item() for k, i in zip(ok.dims, idx)}
                ma, mb = a.sel(point), b.sel(point)
                diff = float(mb["mu_star"] - ma["mu_star"])
                se = math.hypot(float(ma["mu_star_sem"]), float(mb["mu_star_sem"]))
                rows.append({"dim": d, "main": main_value, "alt": alt, **point, "mu_main": float(ma["mu_star"]),
                             "mu_alt": float(mb["mu_star"]), "diff": diff, "z": diff / se if se > 0 else float("nan")})
    return rows


def _eta(ec: float) -> str:
    return f"{ec / 1e6:g} omega0"


def report_markdown(ds: xr.Dataset, claims: list[Claim], conv: list[dict[str, Any]], *, command: str,
                    wall_time_s: float | None, figures: list[str]) -> str:
    """The reproduction report: each claim of the paper next to what we measured."""
    cfg = base_config(ds)
    n_done = int((ds["status"] == "completed").sum())
    n_total = int((ds["status"] != "absent").sum())
    members_wall = float(ds["wall_time_s"].where(ds["status"] == "completed").sum())
    lines = [
        "# Reproduction of Fig. 6: friction versus load",
        "",
        "Braun, Steenwyk, Warhadpande and Persson, \"On the dependency of friction on load: Theory and experiment\", "
        "EPL 113, 56002 (2016), two-chain model as in MODEL.md.",
        "",
        f"- Command: `{command}`",
        f"- Sweep `{ds.attrs.get('sweep_name')}` (digest {ds.attrs.get('sweep_digest')}): {n_done} of {n_total} members "
        f"completed; the sum of the members' run times is {members_wall / 60:.1f} CPU-minutes"
        + (f"; wall time of the sweep {wall_time_s / 60:.1f} min with {ds.attrs.get('workers', '?')} local worker "
           f"process(es) ({ds.attrs.get('invocations', 1)} invocation(s) that ran members, from the store's "
           "invocations.jsonl)." if wall_time_s is not None else "."),
        f"- Base: epsilon = {cfg.epsilon:g}, dt = {cfg.dt:g} s, start = {cfg.start}, automatic run length until "
        f"SE(mu_star) <= {cfg.sem_target:g} (at most t_max = {cfg.t_max:g} s), slipchain {_versions(ds)}.",
        "- Error bars: seed mean of mu_star, error sqrt(max(var_seeds/n, mean(SE_time^2)/n)).",
        "",
        "## The paper's claims and what we measured",
        "",
        "| paper | measured | criterion | holds |",
        "|---|---|---|---|",
    ]
    for c in claims:
        holds = "n/a" if c.passed is None else ("yes" if c.passed else "**no**")
        lines.append(f"| {c.paper} | {c.measured} | {c.criterion} | {holds} |")
    lines += ["", "## mu_star versus theta (seed means)", ""]
    lines += _table(ds)
    if conv:
        lines += ["", "## Convergence evidence", "",
                  "The same seeds rerun with a changed numerical parameter; z = difference / combined time SE.", "",
                  "| parameter | main -> alternative | points | mean difference | largest abs z |", "|---|---|---|---|---|"]
        groups: dict[tuple, list] = {}
        for r in conv:
            groups.setdefault((r["dim"], r["main"], r["alt"], r["v_d"]), []).append(r)
        for (d, m, a, vd), rs in groups.items():
            lines.append(f"| {d} (v_d = {vd:g}) | {m:g} -> {a:g} | {len(rs)} | {np.mean([r['diff'] for r in rs]):+.4f} | "
                         f"{max(abs(r['z']) for r in rs):.2f} |")
    not_done = list(zip(*np.nonzero(((ds["status"] != "completed") & (ds["status"] != "absent")).values)))
    if not_done:
        lines += ["", "## Members not completed", ""]
        for idx in not_done:
            point = ", ".join(f"{d} = {ds[d].values[i].item():g}" for d, i in zip(ds["status"].dims, idx))
            lines.append(f"- {point}: {ds['status'].values[idx]}. {ds['message'].values[idx]}")
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(lines) + "\n"


def _versions(ds: xr.Dataset) -> str:
    vals = sorted({v for v in ds["slipchain_version"].values.ravel().tolist() if v})
    return ", ".join(vals) or "?"


def _table(ds: xr.Dataset) -> list[str]:
    avg, sel = fig6_table(ds)
    extra = ", ".join(f"{k} = {v:g}" for k, v in sel.items())
    lines = [f"At {extra}." if extra else "", ""] if extra else []
    ns = avg["N"].values.tolist() if "N" in avg.dims else [None]
    header = "| N | v_d | theta | " + " | ".join(f"eta_c = {_eta(ec)}" for ec in avg["eta_c"].values) + " |"
    lines += [header, "|---" * (3 + avg.sizes["eta_c"]) + "|"]
    for n in ns:
        sub_n = avg.sel(N=n) if n is not None else avg
        for vd in sorted(sub_n["v_d"].values.tolist(), reverse=True):
            for th in sub_n["theta"].values:
                cells = []
                for ec in sub_n["eta_c"].values:
                    c = sub_n.sel(v_d=vd, theta=th, eta_c=ec)
                    cells.append("" if not np.isfinite(float(c["mu"])) else
                                 f"{float(c['mu']):.4f} ± {float(c['err']):.4f} ({int(c['n'])})")
                if any(cells):
                    lines.append(f"| {n} | {vd:g} | {th:g} | " + " | ".join(cells) + " |")
    lines += ["", "(number of seeds in brackets)"]
    return lines


__all__ = ["Claim", "FIG6_DIMS", "base_config", "convergence", "dashed_line", "drive_velocities", "evaluate",
           "fig6_table", "main_n", "main_selection", "report_markdown", "seed_average"]

"""Fig. 6 in 3-D (issue 13) as numbers: mu_star(theta) per geometry, the load effect, its finite-size
and slab-thickness dependence.

Input: the sweep Dataset of a store (:meth:`slipchain.sweeps.store.Store.dataset`) that sweeps
``geometry``, ``theta`` and ``v_d`` (``N``, ``Ly``, ``N_L`` and ``seed`` as the preset
``presets/fig6-3d.toml`` does). Seed means and errors: :func:`.statistics.seed_average`. The
*main* size of a geometry is its most populated (N, Ly, N_L) at the main velocity v_d1 = v0; the
load effect is mu_star(theta_max)/mu_star(theta_min) at that size (the paper's Fig. 6 drop:
below 0.8 at v_d1 for the chain).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from ..results.observables import count_cycles, whole_cycle_mean
from ..results.schema import Status
from .statistics import base_config, drive_velocities, ratio, seed_average

GEOMETRY_ORDER = ("chain", "chain2d", "slab", "halfspace")
SIZE_KEYS = ("N", "Ly", "N_L")


def geometry_table(ds: xr.Dataset) -> pd.DataFrame:
    """Seed-averaged mu_star, one row per swept point with data: columns geometry, N, Ly, N_L (where
    swept), theta, v_d, mu, err, n, plus L_x a (``box``, m) and H/(L a) (``H_over_L``; inf for the
    half-space, NaN for the chains)."""
    avg = seed_average(ds)
    table = avg.to_dataframe().reset_index().dropna(subset=["mu"])
    cfg = base_config(ds)
    for key in ("geometry", *SIZE_KEYS):  # not swept: the base config's (a store of one geometry)
        if key not in table:
            table[key] = getattr(cfg, key)
    table["n"] = table["n"].astype(int)
    table["box"] = table["N"] * cfg.a
    slabs = table["geometry"] == "slab"
    table["H_over_L"] = np.where(slabs, table["N_L"] / table["N"],
                                 np.where(table["geometry"] == "halfspace", np.inf, np.nan))
    order = {g: i for i, g in enumerate(GEOMETRY_ORDER)}
    table = table.sort_values(["geometry", "N", "Ly", "N_L", "v_d", "theta"], key=lambda c: c.map(order) if
                              c.name == "geometry" else c)
    return table.reset_index(drop=True)[["geometry", "N", "Ly", "N_L", "theta", "v_d", "mu", "err", "n", "box",
                                         "H_over_L"]]


def main_sizes(table: pd.DataFrame, v_d1: float) -> dict[str, tuple[int, int, int]]:
    """Per geometry, the (N, Ly, N_L) with the most rows at v_d1 (the largest N among equals)."""
    out = {}
    for geo, rows in table[np.isclose(table["v_d"], v_d1)].groupby("geometry", sort=False):
        counts = rows.groupby(list(SIZE_KEYS)).size()
        best = counts[counts == counts.max()].index
        out[geo] = max(best, key=lambda k: (k[0] * k[1], k[2] == 5))
    return out


def drops(table: pd.DataFrame) -> pd.DataFrame:
    """mu_star(theta_max)/mu_star(theta_min) with its error for every (geometry, N, Ly, N_L, v_d)
    with at least two theta."""
    rows = []
    for key, cur in table.groupby(["geometry", *SIZE_KEYS, "v_d"], sort=False):
        cur = cur.sort_values("theta")
        if len(cur) < 2:
            continue
        a, b = cur.iloc[0], cur.iloc[-1]
        r, e = ratio(b["mu"], b["err"], a["mu"], a["err"])
        rows.append(dict(zip(["geometry", *SIZE_KEYS, "v_d"], key), theta_min=a["theta"], mu_theta_min=a["mu"],
                         err_theta_min=a["err"], theta_max=b["theta"], mu_theta_max=b["mu"],
                         err_theta_max=b["err"], ratio=r, ratio_err=e, H_over_L=a["H_over_L"]))
    return pd.DataFrame(rows)


def not_completed(ds: xr.Dataset) -> pd.DataFrame:
    """The members that ran but did not complete: their coordinates, status and message."""
    frame = ds[["status", "message"]].to_dataframe().reset_index()
    grid = (Status.COMPLETED, Status.ABSENT, Status.MISSING)
    return frame[~frame["status"].isin([str(s) for s in grid])].reset_index(drop=True)


def fig6_3d_data(ds: xr.Dataset) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """The table, the drops, and attrs: v_d1, v_d2, the main size of each geometry, the dashed line
    f(v_d2, v0)/(epsilon f0) of Fig. 6 and the members that did not complete."""
    from .fig6 import dashed_line

    cfg = base_config(ds)
    table = geometry_table(ds)
    v_d1, v_d2 = drive_velocities(cfg, np.unique(table["v_d"].values))
    return table, drops(table), {"v_d1": v_d1, "v_d2": v_d2, "main": main_sizes(table, v_d1), "a": cfg.a,
                                 "epsilon": cfg.epsilon, "integrator": cfg.integrator,
                                 "dashed_line": dashed_line(cfg, v_d2), "not_completed": not_completed(ds)}


# A point slips as a whole (the paper's system-size events) where the samples in which f_d falls carry at
# least this share of the interface's advance: every block then moves in the events, not in the reloading.
WHOLE_SLIP_SHARE = 0.9


def sawtooth(run: xr.Dataset) -> dict[str, float]:
    """f_d(t) of one driven run in its steady window (t > t_transient) read as a stick-slip sawtooth.

    ``cycles``: :func:`slipchain.results.observables.count_cycles` of f_d; ``period`` (s): the window's
    length over the cycles (NaN without one); ``swing``: (99th - 1st percentile of f_d)/mean f_d, about 2
    for a sawtooth that falls to zero, near 0 for steady sliding; ``event_share``: the share of the
    interface's advance (``x_mean``, the mean interface block displacement) made in the samples in which
    f_d falls, about 1/2 for noise about a mean and 1 where all motion happens in the slip events (at or
    above :data:`WHOLE_SLIP_SHARE`: the whole interface slips together); ``phase_bias``: the window's mean of f_d
    (mu_star's: the window is the same) over its mean over whole cycles
    (:func:`slipchain.results.observables.whole_cycle_mean`) less 1, NaN with fewer than two falls. Where the whole
    interface stick-slips the window cuts the sawtooth at some phase, which moves mu_star by up to about
    swing/(2 cycles), an error its batch-means SE does not hold (docs/performance.md, "Samples of 5 ms"); this
    column says by how much, per point."""
    t = run["time"].values
    keep = t > float(run.attrs.get("t_transient", 0.0))
    f, x, t = run["f_d"].values[keep], run["x_mean"].values[keep], t[keep]
    if f.size < 3:
        return {"cycles": 0, "period": float("nan"), "swing": float("nan"), "event_share": float("nan"),
                "phase_bias": float("nan")}
    cycles = count_cycles(f)
    lo, hi = np.percentile(f, [1, 99])
    dx, falling = np.diff(x), np.diff(f) < 0
    advance = dx.sum()
    return {"cycles": cycles, "period": (t[-1] - t[0]) / cycles if cycles else float("nan"),
            "swing": float((hi - lo) / f.mean()),
            "event_share": float(dx[falling].sum() / advance) if advance > 0 else float("nan"),
            "phase_bias": float(f.mean() / whole_cycle_mean(f) - 1.0)}


def sawtooth_table(rows: list[dict]) -> pd.DataFrame:
    """Seed means of :func:`sawtooth` per (geometry, theta, v_d): ``rows`` holds one dict per run with those
    keys, ``seed`` and the stats; ``cycles`` is summed over the seeds, ``n`` counts them."""
    if not rows:
        return pd.DataFrame(columns=["geometry", "theta", "v_d", "n", "cycles", "period", "swing", "event_share",
                                     "phase_bias", "whole"])
    frame = pd.DataFrame(rows)
    out = frame.groupby(["geometry", "theta", "v_d"], sort=False).agg(
        n=("seed", "size"), cycles=("cycles", "sum"), period=("period", "mean"), swing=("swing", "mean"),
        event_share=("event_share", "mean"), phase_bias=("phase_bias", "mean")).reset_index()
    out["whole"] = out["event_share"] >= WHOLE_SLIP_SHARE
    order = {g: i for i, g in enumerate(GEOMETRY_ORDER)}
    return out.sort_values(["geometry", "v_d", "theta"], key=lambda c: c.map(order) if c.name == "geometry"
                           else c).reset_index(drop=True)


def steppers(configs) -> dict[str, list[tuple[str, float, float]]]:
    """The step of each run (:func:`.reports.step_text`) and the points (geometry, theta, v_d) it made, in
    the order of first appearance."""
    from .reports import step_text

    out: dict[str, list[tuple[str, float, float]]] = {}
    for c in configs:
        point = (c.geometry, c.theta, c.v_d)
        if point not in (pts := out.setdefault(step_text(c), [])):
            pts.append(point)
    return out


def _points_text(points: list[tuple[str, float, float]]) -> str:
    groups: dict[tuple[str, float], list[float]] = {}
    for geo, theta, v_d in points:
        groups.setdefault((geo, v_d), []).append(theta)
    return "; ".join(f"{geo}, {v_d:g}: {', '.join(f'{t:g}' for t in sorted(ths))}"
                     for (geo, v_d), ths in sorted(groups.items(), key=lambda kv: (GEOMETRY_ORDER.index(kv[0][0]),
                                                                                   -kv[0][1])))


def _pct(x: float) -> str:
    return "" if np.isnan(x) else f"{100 * x:+.2f}"


def _fmt(mu: float, err: float) -> str:
    return f"{mu:.3f} ± {err:.3f}"


def main_mask(frame: pd.DataFrame, main: dict[str, tuple[int, int, int]]) -> np.ndarray:
    """Rows of a table or drops frame at the main size (N, Ly, N_L) of their geometry (:func:`main_sizes`)."""
    return np.array([tuple(int(v) for v in r[1:]) == tuple(int(v) for v in main.get(r[0], ()))
                     for r in frame[["geometry", *SIZE_KEYS]].itertuples(index=False)], dtype=bool)


def report_markdown(table: pd.DataFrame, drop: pd.DataFrame, attrs: dict, *, command: str = "",
                    wall: str = "") -> str:
    """report.md: the main Fig. 6-in-3-D table, the load effect per geometry and velocity, the
    finite-size check and the slab-thickness dependence."""
    v_d1, v_d2, main = attrs["v_d1"], attrs["v_d2"], attrs["main"]
    eps = attrs.get("epsilon", 1e-2)
    sweep = f" ({attrs['sweep']})" if attrs.get("sweep") and eps != 1e-2 else ""  # titles apart (test_docs)
    lines = ["# Fig. 6 in 3-D: mu_star(theta) on a 2-D interface (issue 13)" if eps == 1e-2 else
             f"# Fig. 6 in 3-D at epsilon = {eps:g}{sweep}: mu_star(theta) on a 2-D interface", ""]
    if command:
        lines += [f"Command: `{command}`" + (f" ({wall})" if wall else ""), ""]
    done, total = attrs.get("completed", (0, 0))
    if done < total:
        lines += [f"**Partial**: {done} of the sweep's {total} members completed; the tables and the figure hold "
                  "those (rerun the command when the sweep has finished).", ""]
    steps = attrs.get("steppers") or {}  # :func:`steppers` of the completed members
    if len(steps) > 1:  # a preset that picks each point's stepper (fig6-3d-eps1-128-fast)
        lines += [f"epsilon = {eps:g}; the step differs per point:", "", "| step | points (geometry, v_d: theta) |",
                  "|---|---|"]
        lines += [f"| {text} | {_points_text(points)} |" for text, points in steps.items()]
        lines.append("")
    elif steps:  # one step for every point: the members' own (a grid may override the base's integrator)
        lines += [f"epsilon = {eps:g}, {next(iter(steps))}.", ""]
    elif "epsilon" in attrs:  # no completed member to read the step from: the base's integrator
        lines += [f"epsilon = {attrs['epsilon']:g}, integrator = '{attrs['integrator']}'.", ""]
    lines += ["Seed means ± SE (seeds and time, `analysis.statistics.seed_average`); mu_star = <f_d>/(epsilon f0 "
              "theta), theta = N_c/(N Ly).", "", "## mu_star(theta) at the main size of each geometry", ""]
    mains = table[main_mask(table, main)]
    for v in sorted(mains["v_d"].unique(), reverse=True):
        name = "v_d1" if np.isclose(v, v_d1) else "v_d2" if np.isclose(v, v_d2) else f"v_d = {v:g}"
        cur = mains[np.isclose(mains["v_d"], v)]
        geos = [g for g in GEOMETRY_ORDER if g in set(cur["geometry"])]
        heads = [f"{g} ({'x'.join(str(int(x)) for x in main[g][:2])}, N_L {int(main[g][2])})" for g in geos]
        lines += [f"{name} = {v:g} m/s:", "", "| theta | " + " | ".join(heads) + " |",
                  "|---|" + "---|" * len(geos)]
        for th in sorted(cur["theta"].unique()):
            cells = []
            for g in geos:
                r = cur[(cur["geometry"] == g) & np.isclose(cur["theta"], th)]
                cells.append(_fmt(r["mu"].iloc[0], r["err"].iloc[0]) if len(r) else "")
            lines.append(f"| {th:g} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["## The load effect: mu_star(theta_max) / mu_star(theta_min)", "",
              "| geometry | N x Ly | N_L | H/(L a) | v_d | theta | ratio |", "|---|---|---|---|---|---|---|"]
    for _, r in drop.iterrows():
        hl = "" if np.isnan(r["H_over_L"]) else ("inf" if np.isinf(r["H_over_L"]) else f"{r['H_over_L']:.3g}")
        lines.append(f"| {r['geometry']} | {int(r['N'])} x {int(r['Ly'])} | {int(r['N_L'])} | {hl} | {r['v_d']:g} | "
                     f"{r['theta_min']:g} -> {r['theta_max']:g} | {_fmt(r['ratio'], r['ratio_err'])} |")
    lines.append("")
    saw = attrs.get("sawtooth")
    if saw is not None and len(saw):
        lines += ["## The sawtooth per point (main size)", "",
                  "f_d(t) in each run's steady window (`analysis.geometry.sawtooth`; means over the seeds, cycles "
                  "summed): the period is the window over the cycles; the swing is f_d's 1st-99th percentile range "
                  "over its mean (about 2 for a sawtooth falling to zero, near 0 for steady sliding); the event "
                  "share is the share of the interface's advance made in the samples in which f_d falls (1/2 for "
                  f"noise, 1 when every block moves only in the events; 'whole' at {WHOLE_SLIP_SHARE:g} or more). "
                  "The window's phase is the window's mean of f_d (mu_star's) over its mean over whole cycles, less 1 "
                  "(`observables.whole_cycle_mean`): where the whole interface slips, the part of mu_star that the "
                  "window's cut through the sawtooth adds, which mu_star's standard error does not hold.",
                  "", "| geometry | v_d | theta | seeds | cycles | period (s) | swing | event share | slips as a whole "
                  "| window's phase (%) |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for _, r in saw.iterrows():
            lines.append(f"| {r['geometry']} | {r['v_d']:g} | {r['theta']:g} | {int(r['n'])} | {int(r['cycles'])} | "
                         f"{r['period']:.3g} | {r['swing']:.2f} | {r['event_share']:.2f} | "
                         f"{'yes' if r['whole'] else 'no'} | {_pct(r['phase_bias'])} |")
        lines.append("")
    bad = attrs.get("not_completed")
    if bad is not None and len(bad):
        lines += ["## Members that did not complete (left out of the means)", "",
                  "| " + " | ".join(c for c in bad.columns if c != "message") + " | reason |",
                  "|" + "---|" * len(bad.columns)]
        for _, r in bad.iterrows():
            cells = [f"{v:g}" if isinstance(v, float) else str(v) for k, v in r.items() if k != "message"]
            lines.append("| " + " | ".join(cells) + f" | {str(r['message']).replace('|', '/')} |")
        lines.append("")
    return "\n".join(lines)


__all__ = ["GEOMETRY_ORDER", "WHOLE_SLIP_SHARE", "drops", "fig6_3d_data", "geometry_table", "main_mask", "main_sizes",
           "report_markdown", "sawtooth", "sawtooth_table", "steppers"]

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
    lines = ["# Fig. 6 in 3-D: mu_star(theta) on a 2-D interface (issue 13)" if eps == 1e-2 else
             f"# Fig. 6 in 3-D at epsilon = {eps:g}: mu_star(theta) on a 2-D interface", ""]
    if command:
        lines += [f"Command: `{command}`" + (f" ({wall})" if wall else ""), ""]
    if "epsilon" in attrs:
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


__all__ = ["GEOMETRY_ORDER", "drops", "fig6_3d_data", "geometry_table", "main_mask", "main_sizes", "report_markdown"]

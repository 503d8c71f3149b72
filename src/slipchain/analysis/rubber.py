"""Fig. 6 with the viscoelastic slider (issue 28) as numbers: mu_star(theta) per material and
temperature beside the paper's elastic model on the same grid, and the load effect of each.

Input: the sweep Dataset of a store with ``material = 'prony'`` sweeping ``theta``, ``v_d`` and
``seed``, and ``temperature`` and ``eta_c`` where they vary (presets/fig6-rubber.toml), and that of its elastic twin sweeping
the same but ``temperature`` (presets/fig6-rubber-elastic.toml). Seed means and errors:
:func:`.statistics.seed_average`. The load effect is mu_star(theta_max)/mu_star(theta_min) per
variant, eta_c and v_d (the paper's Fig. 6 claim: below 0.8, a fall of more than 20 %, at v_d1).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from .geometry import not_completed
from .statistics import base_config, drive_velocities, ratio, seed_average

ELASTIC = "elastic"


def variant_name(material: str, temperature: float | None) -> str:
    return ELASTIC if material == ELASTIC else f"prony {temperature:g} °C"


def rubber_table(rubber: xr.Dataset, elastic: xr.Dataset | None) -> pd.DataFrame:
    """Seed-averaged mu_star, one row per (variant, eta_c, v_d, theta) with data: columns variant,
    temperature (NaN for the elastic), eta_c, v_d, theta, mu, err, n. The elastic twin's rows only at
    the (v_d, eta_c) the rubber has (a twin such as presets/fig6-3d-eps1.toml may sweep more)."""
    frames = []
    for ds in (rubber, elastic):
        if ds is None:
            continue
        cfg = base_config(ds)
        t = seed_average(ds).to_dataframe().reset_index().dropna(subset=["mu"])
        if "eta_c" not in t:
            t["eta_c"] = cfg.eta_c
        if "v_d" not in t:  # one drive velocity, in the base config (presets/fig6-rubber-slab.toml)
            t["v_d"] = cfg.v_d
        if "temperature" not in t:
            t["temperature"] = cfg.temperature if cfg.material == "prony" else np.nan
        t["variant"] = [variant_name(cfg.material, x) for x in t["temperature"]]
        frames.append(t)
    if len(frames) == 2:  # the twin where the rubber has data: its velocities and dampings (a twin store may hold more)
        rub, el = frames
        keep = np.zeros(len(el), dtype=bool)
        for v, ec in {(v, ec) for v, ec in zip(rub["v_d"], rub["eta_c"])}:
            keep |= np.isclose(el["v_d"], v) & np.isclose(el["eta_c"], ec)
        frames[1] = el[keep]
    table = pd.concat(frames, ignore_index=True)
    table["n"] = table["n"].astype(int)
    table = table.sort_values(["temperature", "eta_c", "v_d", "theta"], ascending=[False, False, False, True],
                              na_position="first")
    return table.reset_index(drop=True)[["variant", "temperature", "eta_c", "v_d", "theta", "mu", "err", "n"]]


def rubber_drops(table: pd.DataFrame) -> pd.DataFrame:
    """mu_star(theta_max)/mu_star(theta_min) with its error per (variant, eta_c, v_d) with two theta or more."""
    rows = []
    for (variant, eta_c, v_d), cur in table.groupby(["variant", "eta_c", "v_d"], sort=False):
        cur = cur.sort_values("theta")
        if len(cur) < 2:
            continue
        a, b = cur.iloc[0], cur.iloc[-1]
        r, e = ratio(b["mu"], b["err"], a["mu"], a["err"])
        rows.append({"variant": variant, "eta_c": eta_c, "v_d": v_d, "theta_min": a["theta"], "mu_theta_min": a["mu"],
                     "err_theta_min": a["err"], "theta_max": b["theta"], "mu_theta_max": b["mu"],
                     "err_theta_max": b["err"], "ratio": r, "ratio_err": e})
    return pd.DataFrame(rows)


def rubber_data(rubber: xr.Dataset, elastic: xr.Dataset | None) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """The table, the drops and attrs (v_d1, v_d2, omega0, the members that did not complete)."""
    cfg = base_config(rubber)
    if cfg.material != "prony":
        raise ValueError(f"the viscoelastic store has material = {cfg.material!r}; expected 'prony'")
    if elastic is not None and base_config(elastic).material != ELASTIC:
        raise ValueError(f"the elastic store has material = {base_config(elastic).material!r}; expected 'elastic'")
    table = rubber_table(rubber, elastic)
    v_d1, v_d2 = drive_velocities(cfg, np.unique(table["v_d"].values))
    bad = [not_completed(ds) for ds in (rubber, elastic) if ds is not None]
    return table, rubber_drops(table), {"v_d1": v_d1, "v_d2": v_d2, "omega0": cfg.omega0, "geometry": cfg.geometry,
                                        "epsilon": cfg.epsilon, "not_completed": pd.concat(bad, ignore_index=True)}


def _fmt(mu: float, err: float) -> str:
    return f"{mu:.3f} ± {err:.3f}"


def report_markdown(table: pd.DataFrame, drop: pd.DataFrame, attrs: dict, *, command: str = "") -> str:
    """report.md: the load effect per variant, eta_c and velocity, then mu_star(theta) per variant."""
    v_d1, v_d2, w0 = attrs["v_d1"], attrs["v_d2"], attrs["omega0"]
    variants = list(dict.fromkeys(table["variant"]))
    geometry = attrs.get("geometry", "chain")
    where = "" if geometry == "chain" else f" on geometry '{geometry}'"
    eps = attrs.get("epsilon", 1e-2)
    where += "" if eps == 1e-2 else f", epsilon = {eps:g}"  # the paper's epsilon unsaid (every page has its own title)
    lines = [f"# Fig. 6 with a viscoelastic slider{where} (issue 28)", ""]
    if command:
        lines += [f"Command: `{command}`", ""]
    elastic = ("the paper's model (springs at E = 10 MPa, pair damping eta = 0.3 omega0)" if geometry == "chain" else
               f"the elastic body of geometry '{geometry}' (E = 10 MPa; the slab and half-space: radiation damping)")
    lines += [f"Seed means ± SE (seeds and time, `analysis.statistics.seed_average`). `elastic`: {elastic}; "
              "`prony T`: the default (synthetic) compound at temperature T, eta = 0 (docs/guide/viscoelastic.md). "
              "Same grid, step, start and run length.", "",
              "## The load effect: mu_star(theta_max) / mu_star(theta_min)", "",
              "| v_d | eta_c / omega0 | theta | " + " | ".join(variants) + " |",
              "|---|---|---|" + "---|" * len(variants)]
    for v in sorted(drop["v_d"].unique(), reverse=True):
        name = "v_d1" if np.isclose(v, v_d1) else "v_d2" if np.isclose(v, v_d2) else f"{v:g}"
        for ec in sorted(drop["eta_c"].unique(), reverse=True):
            cur = drop[np.isclose(drop["v_d"], v) & np.isclose(drop["eta_c"], ec)]
            if not len(cur):
                continue
            th = f"{cur['theta_min'].min():g} -> {cur['theta_max'].max():g}"
            cells = [_fmt(r["ratio"].iloc[0], r["ratio_err"].iloc[0]) if len(r := cur[cur["variant"] == var]) else ""
                     for var in variants]
            lines.append(f"| {name} | {ec / w0:g} | {th} | " + " | ".join(cells) + " |")
    lines.append("")
    for v in sorted(table["v_d"].unique(), reverse=True):
        name = "v_d1" if np.isclose(v, v_d1) else "v_d2" if np.isclose(v, v_d2) else f"v_d = {v:g}"
        lines += [f"## mu_star(theta) at {name} = {v:g} m/s", "",
                  "| eta_c / omega0 | theta | " + " | ".join(variants) + " |", "|---|---|" + "---|" * len(variants)]
        at = table[np.isclose(table["v_d"], v)]
        for ec in sorted(at["eta_c"].unique(), reverse=True):
            for th in sorted(at["theta"].unique()):
                cur = at[np.isclose(at["eta_c"], ec) & np.isclose(at["theta"], th)]
                cells = [_fmt(r["mu"].iloc[0], r["err"].iloc[0]) if len(r := cur[cur["variant"] == var]) else ""
                         for var in variants]
                lines.append(f"| {ec / w0:g} | {th:g} | " + " | ".join(cells) + " |")
        lines.append("")
    bad = attrs.get("not_completed")
    if bad is not None and len(bad):
        lines += ["## Members that did not complete (left out of the means)", ""]
        for _, r in bad.iterrows():
            point = ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}" for k, v in r.items()
                              if k not in ("message", "status"))
            lines.append(f"- {point}: {r['status']}: {str(r['message'])}")
        lines.append("")
    return "\n".join(lines)


__all__ = ["ELASTIC", "report_markdown", "rubber_data", "rubber_drops", "rubber_table", "variant_name"]

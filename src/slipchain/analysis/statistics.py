"""Statistics over a sweep Dataset: seed means with honest errors, the main values of extra dimensions, ratios.

Input is the sweep Dataset of a store (:meth:`slipchain.sweeps.store.Store.dataset`).

Error bars combine seeds and time: for ``n`` completed seeds with values ``mu_k`` and time
standard errors ``s_k``, the error of the seed mean is
``sqrt(max(var_k(mu_k)/n, mean_k(s_k**2)/n))`` (``var`` with ddof = 1): the scatter between
seeds already contains the time noise; the second term keeps the error honest when a few seeds
agree by chance. With one seed it is that seed's time error.
"""

from __future__ import annotations

import math
import tomllib
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from ..model.config import Config
from ..results.schema import Status
from ..sweeps.definition import make_sweep

FIG6_DIMS = ("N", "theta", "eta_c", "v_d", "seed")  # the dimensions of Fig. 6; any other is held at its main value
MAIN_N = 301


def fmt_value(v: Any) -> str:
    """A swept value for reports: numbers in %g, anything else (``start``, ``integrator``) as it is."""
    return f"{v:g}" if isinstance(v, (int, float, np.number)) and not isinstance(v, bool) else str(v)


def base_config(ds: xr.Dataset) -> Config:
    """The sweep's base config, from the definition stored in the Dataset's attrs."""
    return make_sweep(tomllib.loads(ds.attrs["definition"]), legacy=True).base


def main_selection(ds: xr.Dataset) -> dict[str, Any]:
    """For each swept dimension outside Fig. 6's, the value with the most completed members."""
    done = ds["status"] == Status.COMPLETED
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
    ok = ds["status"] == Status.COMPLETED
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


def main_average(ds: xr.Dataset) -> tuple[xr.Dataset, dict[str, Any]]:
    """Seed averages (:func:`seed_average`) with every dimension outside Fig. 6's held at its main
    value (:func:`main_selection`); returns the averages and the values held."""
    sel = main_selection(ds)
    return seed_average(ds.sel(sel) if sel else ds), sel


def ratio(a, ea, b, eb):
    """a/b with its error from the relative errors of a and b in quadrature (numbers or arrays)."""
    r = a / b
    return r, abs(r) * np.hypot(ea / a, eb / b)




def ratios_to_first(table):
    """A table (theta, mu_max, mu_max_se; rows sorted by theta) with mu_max / mu_max of its first
    row and the error of that :func:`ratio`, as columns ratio_to_theta_min and ratio_se."""
    r, se = ratio(table["mu_max"], table["mu_max_se"], table["mu_max"].iloc[0], table["mu_max_se"].iloc[0])
    return table.assign(ratio_to_theta_min=r, ratio_se=se)


def epsilon_table(ds: xr.Dataset) -> xr.Dataset:
    """Seed-averaged mu_star on (epsilon, theta): each epsilon at the time step it was run with."""
    avg = seed_average(ds)
    if "dt" in avg.dims:  # every epsilon has its own dt: keep, per epsilon, the dt that has data
        picks = []
        for eps in avg["epsilon"].values:
            cur = avg.sel(epsilon=eps)
            best = int(np.argmax(cur["n"].sum("theta").values))
            picks.append(cur.isel(dt=best).drop_vars("dt").assign_coords(dt_used=cur["dt"].values[best]))
        avg = xr.concat(picks, dim="epsilon", coords="different", compat="equals", join="outer")
    return avg


EPSILON_COLUMNS = ("epsilon", "dt", "theta", "seed", "status", "mu_star", "mu_star_sem")


def epsilon_rows(ds: xr.Dataset) -> pd.DataFrame:
    """The members of a sweep Dataset as rows for the combined epsilon figure (:func:`epsilon_frame_table`):
    epsilon and dt from the base config where not swept, and only the rows at the epsilon
    study's held values, v_d = v0 and eta_c = 0.1 omega0, where the sweep varies them."""
    cfg = base_config(ds)
    df = ds[["mu_star", "mu_star_sem", "status"]].to_dataframe().reset_index()
    for key, held in (("v_d", cfg.v0), ("eta_c", 0.1 * cfg.omega0)):
        if key in df:
            df = df[np.isclose(df[key].astype(float), held, rtol=1e-9)]
    for key in ("epsilon", "dt"):
        if key not in df:
            df[key] = getattr(cfg, key)
    if "seed" not in df:
        df["seed"] = cfg.seed
    return df[list(EPSILON_COLUMNS)]


def epsilon_frame_table(frame: pd.DataFrame) -> xr.Dataset:
    """:func:`epsilon_table` of rows from several sources (stores by :func:`epsilon_rows`, or sweep
    index CSVs with the columns EPSILON_COLUMNS): seed averages on (epsilon, theta), each epsilon at
    the dt with the most data. Two rows for one (epsilon, dt, theta, seed) are an error."""
    missing = [c for c in EPSILON_COLUMNS if c not in frame]
    if missing:
        raise ValueError(f"the epsilon rows lack column(s) {missing}; expected {list(EPSILON_COLUMNS)}")
    key = ["epsilon", "dt", "theta", "seed"]
    dup = frame.duplicated(key)
    if dup.any():
        raise ValueError(f"two sources give the same (epsilon, dt, theta, seed): {frame[dup][key].values.tolist()[:3]}")
    ds = frame.set_index(key).to_xarray()
    ds["status"] = ds["status"].fillna(Status.ABSENT.value).astype(str)
    return epsilon_table(ds)


def load_drops(avg: xr.Dataset, dim: str) -> list[dict[str, float]]:
    """For each value of ``dim`` in a seed average with a ``theta`` dimension: mu_star at the
    smallest and the largest theta with data, and their ratio with its error."""
    rows = []
    for value in avg[dim].values:
        cur = avg.sel({dim: value}).dropna("theta", subset=["mu"])
        if cur.sizes["theta"] < 2:
            continue
        a, b = cur.isel(theta=0), cur.isel(theta=-1)
        r, e = ratio(float(b["mu"]), float(b["err"]), float(a["mu"]), float(a["err"]))
        rows.append({dim: value.item(), "theta_min": float(a["theta"]), "mu_min_theta": float(a["mu"]),
                     "err_min_theta": float(a["err"]), "theta_max": float(b["theta"]), "mu_max_theta": float(b["mu"]),
                     "err_max_theta": float(b["err"]), "ratio": r, "ratio_err": e})
    return rows


__all__ = ["EPSILON_COLUMNS", "FIG6_DIMS", "MAIN_N", "base_config", "drive_velocities", "epsilon_frame_table", "fmt_value",
           "epsilon_rows", "epsilon_table", "load_drops", "main_average", "main_n",
           "main_selection", "ratio", "ratios_to_first", "seed_average"]

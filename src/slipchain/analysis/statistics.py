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
import xarray as xr

from ..model.config import Config
from ..results.schema import Status
from ..sweeps.definition import make_sweep

FIG6_DIMS = ("N", "theta", "eta_c", "v_d", "seed")  # the dimensions of Fig. 6; any other is held at its main value
MAIN_N = 301


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


__all__ = ["FIG6_DIMS", "MAIN_N", "base_config", "drive_velocities", "epsilon_table", "load_drops", "main_average", "main_n",
           "main_selection", "ratio", "ratios_to_first", "seed_average"]

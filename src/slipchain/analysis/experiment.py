"""The model beside the experiment: mu_star(v_d) curves from a sweep, scaled to measured mu(v) per surface.

The model's mu_star and the tester's mu differ by a surface-dependent factor (the model's
epsilon f0 and the real contact geometry), so one least-squares factor per surface
(:func:`fit_scale`) maps the model onto the measurement; the factor is reported, never hidden.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from ..tester.analysis import OK
from .statistics import main_selection, seed_average


def model_curves(sweep: xr.Dataset) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """mu_star(v_d) curves from a sweep Dataset with a ``v_d`` dimension, averaged over seeds.

    One curve per combination of the other swept values (e.g. per theta); label -> (v, mu_star).
    """
    if "v_d" not in sweep.dims:
        raise ValueError(f"the sweep has dimensions {list(sweep.dims)}; a model curve needs v_d")
    sel = {k: v for k, v in main_selection(sweep).items() if sweep.sizes[k] > 1}
    avg = seed_average(sweep.sel(sel) if sel else sweep)
    other = [d for d in avg["mu"].dims if d != "v_d"]
    curves = {}
    stacked = avg["mu"].stack(_c=other) if other else avg["mu"].expand_dims(_c=[0])
    for i in range(stacked.sizes["_c"]):
        c = stacked.isel(_c=i)
        label = ", ".join(f"{d} = {c[d].item():g}" for d in other) if other else "model"
        ok = np.isfinite(c.values)
        if ok.sum() >= 2:
            curves[label] = (c["v_d"].values[ok], c.values[ok])
    return curves


def fit_scale(v: np.ndarray, mu: np.ndarray, curve: tuple[np.ndarray, np.ndarray]) -> float:
    """Least-squares factor s with mu ~ s*mu_star(v), mu_star interpolated in log v inside its range."""
    cv, cm = curve
    inside = (v >= cv.min()) & (v <= cv.max())
    if inside.sum() == 0:
        return float("nan")
    m = np.interp(np.log10(v[inside]), np.log10(cv), cm)
    return float(np.sum(m * mu[inside]) / np.sum(m * m))


def model_overlay(table: pd.DataFrame, sweep: xr.Dataset | None) -> dict[str, tuple[float, dict]]:
    """Per surface of the steady runs in ``table``: (scale s, model curves) with the factor fitted
    (least squares, steady runs inside the model's velocity range) to the mean of the model
    curves and applied to every curve. Empty without a sweep."""
    curves = model_curves(sweep) if sweep is not None else {}
    if not curves:
        return {}
    v_common = np.unique(np.concatenate([c[0] for c in curves.values()]))
    mean = np.nanmean([np.interp(np.log10(v_common), np.log10(c[0]), c[1], left=np.nan, right=np.nan)
                       for c in curves.values()], axis=0)
    good = np.isfinite(mean)
    ok = table[table["status"] == OK]
    out = {}
    for surface, g in ok.groupby("surface", sort=True):
        s = fit_scale(g["velocity_m_s"].to_numpy(), g["mu"].to_numpy(), (v_common[good], mean[good]))
        out[surface] = (s, curves)
    return out


__all__ = ["fit_scale", "model_curves", "model_overlay"]

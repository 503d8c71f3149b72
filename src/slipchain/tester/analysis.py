"""From runs to mu(v) per pressure, the first maxima, and a test of the paper's load claim.

Per run (Fig. 1 of the paper, the Leonardo da Vinci set-up): ``mu = M'/M`` with
``SE(mu) = mu*sqrt((dM'/M')**2 + (dM/M)**2)`` (``dM = dM' = mass_uncertainty_kg``, independent);
``p0 = M*g/A0``; the velocity from the trace (:mod:`slipchain.tester.velocity`) or, without a
trace, the ``velocity_m_s`` of the runs table (its uncertainty then unknown, NaN).

Groups are (surface, compound, temperature); pressures within a group are grouped to 3
significant digits. For each pressure the **first maximum** of mu(v): the set-up only measures
the rising branch (above the maximum the slider runs away), so ``mu_max`` is the largest mu that
still slid steadily and ``v_max`` its velocity; the smallest mu of a runaway run at that pressure
bounds the true maximum from above (``mu_runaway_min``), up to the run-to-run scatter of the
surface (which can put it below ``mu_max``).

**The load test** (paper: near the maximum mu falls with p0, well below it it does not). For
each group, with ``xi = log10(v/v_ref)`` and ``v_ref`` the median of the pressures' ``v_max``,
two bands of steady runs:

* near the maximum: ``xi >= -NEAR_DECADES`` (within half a decade below v_ref, or above);
* well below: ``xi <= -FAR_DECADES`` (at least 1.5 decades below).

In each band an ordinary least-squares fit ``mu = b0 + b1*xi + b2*xi**2 + beta*p0`` (the
quadratic absorbs the shape of mu(v), beta is the load effect, in 1/MPa) gives ``beta`` with a
95 % confidence interval from Student's t with n - 4 degrees of freedom (n - 3 with a linear
shape when the band holds fewer than 8 runs). The claim holds when the near-band interval lies
below zero and the low-band interval contains zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .inputs import Run
from ..results.velocity import NO_STEADY, OK, RUNAWAY, steady_velocity

G = 9.81
NEAR_DECADES = 0.5
FAR_DECADES = 1.5
CONFIDENCE = 0.95
INVALID, NO_VELOCITY = "invalid", "no-velocity"

RUNS_COLUMNS = ["run_id", "surface", "compound", "temperature_C", "pressure_Pa", "velocity_m_s", "velocity_sem_m_s",
                "mu", "mu_sem", "status", "reason"]


def mu_with_uncertainty(slider_kg: float, hanging_kg: float, dm_kg: float) -> tuple[float, float]:
    """mu = M'/M and its standard error from independent mass uncertainties dm (both masses)."""
    mu = hanging_kg / slider_kg
    return mu, mu * float(np.hypot(dm_kg / hanging_kg, dm_kg / slider_kg))


def analyze_runs(runs: list[Run]) -> pd.DataFrame:
    """One row per run: pressure, velocity, mu with uncertainties, status and reason."""
    rows = []
    for r in runs:
        row = {"run_id": r.run_id, "surface": r.surface, "compound": r.compound, "temperature_C": r.temperature_C,
               "pressure_Pa": np.nan, "velocity_m_s": np.nan, "velocity_sem_m_s": np.nan, "mu": np.nan,
               "mu_sem": np.nan, "status": OK, "reason": ""}
        if r.problems:
            row.update(status=INVALID, reason="; ".join(r.problems))
            rows.append(row)
            continue
        row["pressure_Pa"] = r.slider_mass_kg * G / r.nominal_area_m2
        row["mu"], row["mu_sem"] = mu_with_uncertainty(r.slider_mass_kg, r.hanging_mass_kg, r.mass_uncertainty_kg)
        if r.time_s is not None:
            fit = steady_velocity(r.time_s, r.distance_m)
            row.update(status=fit.status, reason=fit.reason)
            if fit.status == OK:
                row.update(velocity_m_s=fit.velocity, velocity_sem_m_s=fit.sem)
        elif np.isfinite(r.velocity_m_s):
            row.update(velocity_m_s=r.velocity_m_s, reason="velocity from the runs table (no trace; uncertainty unknown)")
        else:
            row.update(status=NO_VELOCITY, reason="no trace and no velocity_m_s in the runs table")
        rows.append(row)
    return pd.DataFrame(rows, columns=RUNS_COLUMNS)


def pressure_group(p: float) -> float:
    """Pressures equal to 3 significant digits form one group."""
    return float(f"{p:.3g}")


def _groups(table: pd.DataFrame) -> pd.DataFrame:
    t = table[table["status"].isin([OK, RUNAWAY])].copy()
    t["pressure_group_Pa"] = t["pressure_Pa"].map(pressure_group)
    return t


GROUP = ["surface", "compound", "temperature_C"]


def maxima(table: pd.DataFrame) -> pd.DataFrame:
    """Per group and pressure: the first maximum of mu(v) as the set-up sees it (module docstring)."""
    rows = []
    for key, g in _groups(table).groupby(GROUP + ["pressure_group_Pa"], sort=True):
        ok = g[g["status"] == OK]
        run = g[g["status"] == RUNAWAY]
        row = dict(zip(GROUP + ["pressure_Pa"], key))
        row.update(n_steady=len(ok), n_runaway=len(run), mu_max=np.nan, mu_max_sem=np.nan, v_max=np.nan,
                   v_max_sem=np.nan, mu_runaway_min=run["mu"].min() if len(run) else np.nan)
        if len(ok):
            top = ok.loc[ok["mu"].idxmax()]
            row.update(mu_max=top["mu"], mu_max_sem=top["mu_sem"], v_max=top["velocity_m_s"],
                       v_max_sem=top["velocity_sem_m_s"])
        rows.append(row)
    return pd.DataFrame(rows)


@dataclass
class BandTest:
    band: str
    n: int
    beta_per_MPa: float
    ci_low: float
    ci_high: float
    p_value: float

    @property
    def decreasing(self) -> bool:
        return self.ci_high < 0

    @property
    def consistent_with_zero(self) -> bool:
        return self.ci_low <= 0 <= self.ci_high


def _band_fit(xi: np.ndarray, p_mpa: np.ndarray, mu: np.ndarray, band: str) -> BandTest | None:
    n = xi.size
    if n < 5 or np.unique(p_mpa).size < 2:
        return None
    cols = [np.ones(n), xi, xi**2] if n >= 8 else [np.ones(n), xi]
    X = np.column_stack(cols + [p_mpa])
    coef, *_ = np.linalg.lstsq(X, mu, rcond=None)
    resid = mu - X @ coef
    dof = n - X.shape[1]
    s2 = float(resid @ resid) / dof
    cov = s2 * np.linalg.pinv(X.T @ X)
    beta, se = float(coef[-1]), float(np.sqrt(cov[-1, -1]))
    from scipy import stats  # here, not at the top: its import costs ~0.8 s, paid by every figure command before

    tq = stats.t.ppf(0.5 + CONFIDENCE / 2, dof)
    p = float(2 * stats.t.sf(abs(beta / se), dof)) if se > 0 else 0.0
    return BandTest(band, n, beta, beta - tq * se, beta + tq * se, p)


@dataclass
class LoadTest:
    group: tuple
    v_ref: float
    near: BandTest | None
    far: BandTest | None

    @property
    def claim_holds(self) -> bool | None:
        if self.near is None or self.far is None:
            return None
        return self.near.decreasing and self.far.consistent_with_zero


def load_tests(table: pd.DataFrame, peaks: pd.DataFrame) -> list[LoadTest]:
    """The paper's claim tested per group (module docstring)."""
    out = []
    ok = table[table["status"] == OK]
    for key, g in ok.groupby(GROUP, sort=True):
        pk = peaks
        for k, v in zip(GROUP, key):
            pk = pk[pk[k] == v]
        v_ref = float(np.nanmedian(pk["v_max"])) if len(pk) else np.nan
        if not np.isfinite(v_ref):
            out.append(LoadTest(key, v_ref, None, None))
            continue
        xi = np.log10(g["velocity_m_s"].to_numpy() / v_ref)
        p = g["pressure_Pa"].to_numpy() / 1e6
        mu = g["mu"].to_numpy()
        near, far = xi >= -NEAR_DECADES, xi <= -FAR_DECADES
        out.append(LoadTest(key, v_ref, _band_fit(xi[near], p[near], mu[near], "near the maximum"),
                            _band_fit(xi[far], p[far], mu[far], "well below the maximum")))
    return out


def summary_markdown(table: pd.DataFrame, peaks: pd.DataFrame, tests: list[LoadTest], figures: list[str]) -> str:
    counts = table["status"].value_counts().to_dict()
    lines = ["# Friction-tester analysis", "",
             f"{len(table)} runs: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ".", "",
             "Status: `ok` steady sliding found; `runaway` still accelerating (above the first maximum of mu(v), "
             "excluded from mu(v)); `no-steady` no steady window; `invalid` bad input (reason names file, line, "
             "column); `no-velocity` neither trace nor velocity. Every run and its reason is in runs.csv.", "",
             "## First maximum per pressure", "",
             "| surface | compound | T (°C) | p0 (kPa) | steady runs | runaway runs | mu_max | v_max (m/s) | smallest runaway mu |",
             "|---|---|---|---|---|---|---|---|---|"]
    for _, r in peaks.iterrows():
        lines.append(f"| {r['surface']} | {r['compound']} | {r['temperature_C']:g} | {r['pressure_Pa'] / 1e3:.1f} | "
                     f"{r['n_steady']} | {r['n_runaway']} | {r['mu_max']:.4f} ± {r['mu_max_sem']:.4f} | "
                     f"{r['v_max']:.3g} | {r['mu_runaway_min']:.4f} |")
    lines += ["", "## Does friction fall with load near the maximum, and only there?", "",
              f"Fit per band: mu = b0 + b1 xi + b2 xi^2 + beta p0, xi = log10(v/v_ref), v_ref = median v_max of the "
              f"pressures; near band xi >= -{NEAR_DECADES}, low band xi <= -{FAR_DECADES}; "
              f"{CONFIDENCE:.0%} confidence intervals.", ""]
    for t in tests:
        name = ", ".join(f"{k} = {v}" for k, v in zip(GROUP, t.group))
        lines.append(f"**{name}** (v_ref = {t.v_ref:.3g} m/s):")
        for b in (t.near, t.far):
            if b is None:
                lines.append("- a band has too few runs (at least 5, at two pressures or more) for a fit")
                continue
            verdict = ("falls with load" if b.decreasing else
                       "no significant load dependence" if b.consistent_with_zero else "rises with load")
            lines.append(f"- {b.band}: beta = {b.beta_per_MPa:+.3f} per MPa, {CONFIDENCE:.0%} CI "
                         f"[{b.ci_low:+.3f}, {b.ci_high:+.3f}], p = {b.p_value:.2g}, n = {b.n} runs: {verdict}.")
        holds = t.claim_holds
        lines.append(f"- The paper's claim (falls near the maximum, not well below): "
                     f"{'not testable' if holds is None else 'supported' if holds else 'not supported'}.")
        lines.append("")
    if figures:
        lines += ["## Figures", ""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(lines) + "\n"


__all__ = ["pressure_group", "BandTest", "LoadTest", "NO_STEADY", "RUNS_COLUMNS", "analyze_runs", "load_tests", "maxima",
           "mu_with_uncertainty", "summary_markdown"]

"""The model fitted to friction-tester data (issue 14, item 3): p_ref, v0, delta and a force scale.

**The fitted model**, per tester group (surface, compound, temperature), with parameters
``F`` (force scale), ``v0``, ``delta`` and ``p_ref`` (theta = p0 / p_ref, the model's load):

* the rising branch, where under a dead weight every contact slides steadily at the slider's
  velocity v (eq. 1 of the paper averaged over log10 v* uniform on [log10 v0 - delta, log10 v0 + delta])::

      mu(v) = F * g(v / v0; delta),
      g(x; delta) = sqrt(pi/c) / (4 delta) * [erf(sqrt(c) (log10 x + delta)) - erf(sqrt(c) (log10 x - delta))]

  (g -> exp(-c log10(x)**2) as delta -> 0; the contact damping m eta_c v / (epsilon f0), below
  1e-6 here, is left out; ``c`` is the model's, 0.1);
* the maximum, the largest mu with steady sliding (the tester's first maximum)::

      mu_max(p0) = F * g_max(delta) * r(p0 / p_ref),     g_max(delta) = g(1; delta),

  with ``r(theta) = mu_max_model(theta) / g_max(delta_model)`` from a ``slipchain mu-max`` result
  (:class:`ModelMaxima`): the model's own lowering of the maximum by collective stick-slip,
  piecewise linear in log10(theta) between the thetas it was run at and held at the end values
  outside them (the fit says which pressures fell outside). Assumption, stated: the relative
  lowering r does not depend on v0 and delta (the model was run at one v0 and delta); F, v0 and
  delta then act on the mean-field curve exactly.

Steady points above the model's maximum cannot exist in the model; their residuals say so.

**Least squares** (``scipy.optimize.least_squares``, trust-region reflective; ``p_ref`` bounded
so that every theta = p0/p_ref lies within the thetas the model was run at, or, when the
pressures span more than those, so that theta <= 1) in (F, log10 v0, delta, log10 p_ref) on two
kinds of residual:

* each steady run: ``(mu_i - F g(v_i)) / s_i`` with the effective variance
  ``s_i**2 = mu_sem_i**2 + (dmu/dln v * v_sem_i / v_i)**2`` (velocity errors through the slope);
* each pressure with both steady and runaway runs: the maximum lies between the largest steady mu
  and the smallest runaway mu; ``(m_obs - mu_max(p0)) / s`` with m_obs their midpoint and
  ``s**2 = (gap/2)**2/3 + sem**2`` (uniform within the gap) plus the model's own error of
  ``F g_max r`` (the seed scatter of its mu_max, interpolated like r). Without a runaway a pressure bounds
  the maximum from below only and gives no maximum residual.

**Run-to-run scatter**: a real surface differs a little from run to run (the synthetic tester
plants 2 %); the per-run errors (masses, velocity fit) do not contain it. A relative scatter
``sigma`` is added in quadrature to every run's error, ``(sigma mu_i)**2``, and set so that the
steady runs' chi2 equals their degrees of freedom (n - 3), alternating with the fit until it
changes by less than 2 % (at most 4 rounds); it is reported.

**Uncertainties**: covariance ``(J^T J)^-1`` at the optimum (pseudo-inverse: a parameter the data
do not determine gets an infinite error), multiplied by chi2/dof when that exceeds 1 (the
run-to-run scatter of real surfaces is not in the per-run errors); 95 % confidence intervals from
Student's t with dof = residuals - 4; v0 and p_ref are fitted in log10 and their intervals are
symmetric there. **The load effect**: the fitted fall of the maximum from the smallest to the
largest pressure, 1 - mu_max(p_hi)/mu_max(p_lo), with its CI (delta method), beside the observed
one (largest steady mu at each, with the same gap-based errors).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

from ..tester.analysis import GROUP, OK, RUNAWAY, pressure_group
from .statistics import ratio

CONFIDENCE = 0.95
PARAMS = ("F", "v0", "delta", "p_ref")
LOG_PARAMS = ("v0", "p_ref")  # fitted as log10


class FitError(ValueError):
    """Input the fit cannot use (names what is missing and what was expected)."""


def g(v: np.ndarray, v0: float, delta: float, c: float = 0.1) -> np.ndarray:
    """The mean-field rising branch g(v/v0; delta) (module docstring), in units of epsilon f0."""
    x = np.log10(np.asarray(v, float) / v0)
    if delta < 1e-9:
        return np.exp(-c * x * x)
    s = math.sqrt(c)
    return math.sqrt(math.pi / c) / (4 * delta) * (special.erf(s * (x + delta)) - special.erf(s * (x - delta)))


def g_max(delta: float, c: float = 0.1) -> float:
    """g at v = v0, its maximum."""
    return float(g(np.array(1.0), 1.0, delta, c))


def dg_dlnv(v: np.ndarray, v0: float, delta: float, c: float = 0.1) -> np.ndarray:
    """d g / d ln v (the slope that carries velocity errors into mu)."""
    x = np.log10(np.asarray(v, float) / v0)
    if delta < 1e-9:
        return -2 * c * x * np.exp(-c * x * x) / math.log(10)
    return (np.exp(-c * (x + delta) ** 2) - np.exp(-c * (x - delta) ** 2)) / (2 * delta * math.log(10))


@dataclass(frozen=True)
class ModelMaxima:
    """The model's dead-weight maximum per theta (a ``slipchain mu-max`` result) as the lowering r(theta)."""

    theta: np.ndarray
    r: np.ndarray  # mu_max(theta) / g_max(delta_model)
    r_se: np.ndarray
    c: float = 0.1
    source: str = ""

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        lt = np.log10(np.clip(np.asarray(theta, float), 1e-300, None))
        return np.interp(lt, np.log10(self.theta), self.r)

    def se(self, theta: np.ndarray) -> np.ndarray:
        """The standard error of r, interpolated like r."""
        lt = np.log10(np.clip(np.asarray(theta, float), 1e-300, None))
        return np.interp(lt, np.log10(self.theta), self.r_se)

    def outside(self, theta: np.ndarray) -> np.ndarray:
        theta = np.asarray(theta, float)
        return (theta < self.theta.min() * (1 - 1e-9)) | (theta > self.theta.max() * (1 + 1e-9))


def model_maxima(path: str | os.PathLike) -> ModelMaxima:
    """Read a ``slipchain mu-max`` output directory (mu_max_summary.csv and plan.toml)."""
    from ..model.config import ConfigError, make_config, read_toml

    folder = Path(path)
    summary_csv, plan_file = folder / "mu_max_summary.csv", folder / "plan.toml"
    for f in (summary_csv, plan_file):
        if not f.is_file():
            raise FitError(f"model {str(folder)!r} has no {f.name}; expected the output directory of "
                           "`slipchain mu-max` (mu_max_summary.csv and plan.toml)")
    try:
        table = pd.read_csv(summary_csv)
    except (OSError, ValueError) as e:
        raise FitError(f"{str(summary_csv)!r} cannot be read: {e}") from None
    missing = [c for c in ("theta", "mu_max", "mu_max_se") if c not in table.columns]
    if missing:
        raise FitError(f"{str(summary_csv)!r} lacks column(s) {missing}; expected a mu_max_summary.csv of `slipchain mu-max`")
    table = _numeric(table, ("theta", "mu_max", "mu_max_se"), str(summary_csv))
    table = table[np.isfinite(table["mu_max"])].sort_values("theta")
    if ((table["theta"] <= 0) | (table["theta"] > 1)).any() or (table["mu_max"] <= 0).any():
        raise FitError(f"{str(summary_csv)!r} has theta outside (0, 1] or mu_max <= 0; expected a mu_max_summary.csv "
                       "of `slipchain mu-max`")
    if table["theta"].nunique() < 2:
        raise FitError(f"{str(summary_csv)!r} has mu_max at {table['theta'].nunique()} theta value(s); the load "
                       "dependence needs at least 2 (run `slipchain mu-max` with several --theta)")
    try:
        base = make_config(dict(read_toml(plan_file).get("base", {})))
    except ConfigError as e:
        raise FitError(f"{str(plan_file)!r}: {e}") from None
    gm = g_max(base.delta, base.c)
    return ModelMaxima(table["theta"].to_numpy(float), table["mu_max"].to_numpy(float) / gm,
                       table["mu_max_se"].to_numpy(float) / gm, base.c, str(folder))


def _numeric(table: pd.DataFrame, columns, source: str) -> pd.DataFrame:
    """The columns as numbers; FitError naming the first cell that is not one (empty cells stay NaN)."""
    table = table.copy()
    for col in columns:
        num = pd.to_numeric(table[col], errors="coerce")
        bad = table[col].notna() & num.isna()
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise FitError(f"{source}: column {col!r} has {table[col].iloc[i]!r} in data row {i + 1}; expected a number")
        table[col] = num.astype(float)
    return table


@dataclass
class Estimate:
    value: float
    se: float
    ci_low: float
    ci_high: float


@dataclass
class FitResult:
    """The fit of one tester group."""

    group: tuple
    params: dict[str, Estimate]
    chi2: float
    dof: int
    scale: float  # the factor applied to the covariance (chi2/dof if > 1, else 1)
    scatter: float  # the relative run-to-run scatter added to every run's error (estimated)
    pressures: pd.DataFrame  # per pressure: theta, residuals, observed and fitted maxima
    fall_fitted: Estimate  # 1 - mu_max(p_hi)/mu_max(p_lo) of the fitted model
    fall_observed: Estimate
    converged: bool
    message: str
    maxima: ModelMaxima  # the model's maxima it was fitted with
    notes: list[str] = field(default_factory=list)

    def curve(self, p0: float, v: np.ndarray) -> tuple[np.ndarray, float, float]:
        """The fitted model at pressure p0: mu on ``v`` (NaN past the maximum), and (v_max, mu_max)."""
        F, v0, delta, p_ref = (self.params[k].value for k in PARAMS)
        return _curve(F, v0, delta, p_ref, p0, v, self.maxima)


def _curve(F, v0, delta, p_ref, p0, v, maxima: ModelMaxima):
    mu_top = F * g_max(delta, maxima.c) * float(maxima(p0 / p_ref))
    # the end of the steady branch: where F g = mu_top, below v0
    if mu_top >= F * g_max(delta, maxima.c):
        v_top = v0
    else:
        v_top = 10 ** optimize.brentq(lambda lv: F * float(g(10**lv, v0, delta, maxima.c)) - mu_top,
                                      math.log10(v0) - 30, math.log10(v0))
    mu = F * g(v, v0, delta, maxima.c)
    return np.where(np.asarray(v) <= v_top, mu, np.nan), v_top, mu_top


def _prepare(g_runs: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    steady = g_runs[(g_runs["status"] == OK) & np.isfinite(g_runs["velocity_m_s"]) & (g_runs["velocity_m_s"] > 0)]
    rows = []
    for p, grp in g_runs.groupby("pressure_group_Pa"):
        ok, run = grp[grp["status"] == OK], grp[grp["status"] == RUNAWAY]
        row = {"pressure_Pa": float(grp["pressure_Pa"].mean()), "n_steady": len(ok), "n_runaway": len(run),
               "mu_steady_max": np.nan, "mu_runaway_min": np.nan, "m_obs": np.nan, "m_obs_se": np.nan}
        if len(ok):
            top = ok.loc[ok["mu"].idxmax()]
            row["mu_steady_max"] = float(top["mu"])
        if len(run):
            row["mu_runaway_min"] = float(run["mu"].min())
        if len(ok) and len(run):
            lo, hi = row["mu_steady_max"], row["mu_runaway_min"]
            sem = float(np.hypot(top["mu_sem"], run.loc[run["mu"].idxmin(), "mu_sem"]))
            row["m_obs"] = 0.5 * (lo + hi)
            row["m_obs_se"] = float(np.hypot(abs(hi - lo) / 2 / math.sqrt(3), sem))
        rows.append(row)
    return steady, pd.DataFrame(rows).sort_values("pressure_Pa", ignore_index=True)


def fit_group(runs: pd.DataFrame, maxima: ModelMaxima, group: tuple = ()) -> FitResult:
    """Fit one group's runs (rows of an analysed ``runs.csv``) to the model (module docstring)."""
    runs = runs.copy()
    runs["pressure_group_Pa"] = runs["pressure_Pa"].map(pressure_group)
    steady, press = _prepare(runs)
    if len(steady) < 3:
        raise FitError(f"group {group}: {len(steady)} steady run(s) with a velocity; the fit needs at least 3")
    if len(press) < 2:
        raise FitError(f"group {group}: runs at {len(press)} pressure; p_ref needs at least 2 pressures")
    v, mu = steady["velocity_m_s"].to_numpy(float), steady["mu"].to_numpy(float)
    mu_sem = np.nan_to_num(steady["mu_sem"].to_numpy(float), nan=0.0)
    v_sem = np.nan_to_num(steady["velocity_sem_m_s"].to_numpy(float), nan=0.0)
    with_max = press[np.isfinite(press["m_obs"])]
    p_max = float(press["pressure_Pa"].max())
    c = maxima.c
    floor = 1e-3 * float(np.median(np.abs(mu)))  # keeps s > 0 for noiseless input

    def unpack(q):
        return q[0], 10 ** q[1], q[2], 10 ** q[3]

    def residuals(q, scatter):
        F, v0, delta, p_ref = unpack(q)
        model = F * g(v, v0, delta, c)
        slope = F * dg_dlnv(v, v0, delta, c)
        s = np.sqrt(mu_sem**2 + (slope * v_sem / v) ** 2 + (scatter * mu) ** 2 + floor**2)
        r_steady = (mu - model) / s
        th = with_max["pressure_Pa"].to_numpy(float) / p_ref
        gm = F * g_max(delta, c)
        mmod = gm * maxima(th)
        m_obs = with_max["m_obs"].to_numpy(float)
        s_max = np.sqrt(with_max["m_obs_se"].to_numpy(float) ** 2 + (scatter * m_obs) ** 2 + (gm * maxima.se(th)) ** 2)
        r_max = (m_obs - mmod) / s_max
        return np.concatenate([r_steady, r_max])

    def scatter_for(q) -> float:
        """The relative run-to-run scatter that makes the steady runs' chi2 equal their dof (0 if it already is below)."""
        target = max(len(steady) - 3, 1)

        def excess(sc):
            return float(np.sum(residuals(q, sc)[: len(steady)] ** 2)) - target

        return 0.0 if excess(0.0) <= 0 else optimize.brentq(excess, 0.0, 10.0, xtol=1e-6)

    # p_ref keeps every theta = p0/p_ref inside the thetas the model was run at, when their span allows
    p_min = float(press["pressure_Pa"].min())
    pr_lo, pr_hi = p_max / maxima.theta.max(), p_min / maxima.theta.min()
    span_note = None
    if not pr_hi > pr_lo * (1 + 1e-9):
        pr_lo, pr_hi = p_max, p_max * 1e6
        span_note = (f"the pressures span {p_max / p_min:.3g}x, more than the model's thetas "
                     f"({maxima.theta.max() / maxima.theta.min():.3g}x): some thetas fall outside them")
    lower = np.array([1e-6, math.log10(v.min()) - 6, 0.0, math.log10(pr_lo)])
    upper = np.array([1e6, math.log10(v.max()) + 6, 10.0, math.log10(pr_hi)])
    # start: F from the largest steady mu, v0 a little above its velocity, delta 0.5, p_ref mid-range
    top = int(np.argmax(mu))
    q0 = np.array([mu[top] / g_max(0.5, c), math.log10(v[top]) + 0.3, 0.5, 0.5 * (lower[3] + upper[3])])
    q0 = np.clip(q0, lower + 1e-9, upper - 1e-9)
    scatter = 0.0
    for _ in range(4):  # fit, then estimate the run-to-run scatter from the steady residuals, refit
        best = None
        for d0 in (0.5, 0.1, 1.5):  # a few starts in delta (the residuals are not convex in it)
            start = q0.copy()
            start[2] = d0
            sol = optimize.least_squares(residuals, start, bounds=(lower, upper), x_scale="jac", method="trf",
                                         args=(scatter,))
            if best is None or sol.cost < best.cost:
                best = sol
        sol = best
        new_scatter = scatter_for(sol.x)
        if abs(new_scatter - scatter) <= 0.02 * max(new_scatter, 1e-12):
            scatter = new_scatter
            break
        scatter, q0 = new_scatter, sol.x
    res = sol.fun
    n, k = res.size, 4
    dof = max(n - k, 1)
    chi2 = float(res @ res)
    scale = max(chi2 / dof, 1.0)
    J = sol.jac
    cov = np.linalg.pinv(J.T @ J) * scale
    # a direction the data do not fix (flat r, or a parameter at its bound): the parameters that take
    # part in the least determined direction (its right singular vector) get an infinite error
    _, singular, vt = np.linalg.svd(J, full_matrices=False)
    undetermined = singular.min() < 1e-8 * singular.max()
    notes = []
    if undetermined:
        notes.append("the data do not determine every parameter (near-singular Jacobian): see the infinite errors")
    tq = stats.t.ppf(0.5 + CONFIDENCE / 2, dof)
    params: dict[str, Estimate] = {}
    for i, name in enumerate(PARAMS):
        se = math.sqrt(cov[i, i]) if cov[i, i] > 0 else 0.0
        if undetermined and abs(vt[-1, i]) > 0.5:
            se = math.inf
        x = sol.x[i]
        lo_b = lower[i]  # an interval does not reach below the parameter's bound (delta >= 0)
        if name in LOG_PARAMS:
            params[name] = Estimate(10**x, 10**x * math.log(10) * se, 10 ** (x - tq * se), 10 ** (x + tq * se))
        else:
            params[name] = Estimate(x, se, max(x - tq * se, lo_b), x + tq * se)
    at_bound = [PARAMS[i] for i in range(k) if sol.active_mask[i] != 0]
    if at_bound:
        notes.append(f"at a bound of its range: {', '.join(at_bound)} (p_ref is bounded so that every theta = p0/p_ref "
                     f"lies within the model's thetas: {pr_lo / 1e3:.4g}-{pr_hi / 1e3:.4g} kPa)")
    if span_note:
        notes.append(span_note)
    F, v0, delta, p_ref = unpack(sol.x)
    theta = press["pressure_Pa"].to_numpy(float) / p_ref
    if maxima.outside(theta).any():
        out = ", ".join(f"{t:.3g}" for t in theta[maxima.outside(theta)])
        notes.append(f"theta = {out} outside the model's thetas [{maxima.theta.min():g}, {maxima.theta.max():g}]: r held "
                     "at its end value there")
    # per pressure: residuals of its steady runs, the observed and fitted maxima
    by_pressure = pd.Series(res[: len(steady)]).groupby(steady["pressure_group_Pa"].to_numpy(float))
    groups = press["pressure_Pa"].map(pressure_group)
    press = press.assign(
        theta=theta,
        mu_max_fitted=F * g_max(delta, c) * maxima(theta),
        steady_residual_mean=groups.map(by_pressure.apply(lambda r: float(r.to_numpy().mean()))).to_numpy(float),
        steady_residual_rms=groups.map(by_pressure.apply(lambda r: float(np.sqrt((r.to_numpy() ** 2).mean())))).to_numpy(float),
    )
    press["max_residual"] = (press["m_obs"] - press["mu_max_fitted"]) / press["m_obs_se"]
    # the fall of the maximum from the smallest to the largest pressure: fitted (delta method) and observed
    p_lo, p_hi = float(press["pressure_Pa"].iloc[0]), float(press["pressure_Pa"].iloc[-1])

    def fall(q):
        _, _, _, pr = unpack(q)
        return 1.0 - float(maxima(p_hi / pr) / maxima(p_lo / pr))

    grad = optimize.approx_fprime(sol.x, fall, 1e-6)
    se_fall = float(math.sqrt(max(grad @ cov @ grad, 0.0)))
    f_fit = fall(sol.x)
    fitted = Estimate(f_fit, se_fall, f_fit - tq * se_fall, f_fit + tq * se_fall)
    observed = _observed_fall(press, tq)
    return FitResult(group, params, chi2, dof, scale, scatter, press, fitted, observed, bool(sol.success), sol.message,
                     maxima, notes)


def _observed_fall(press: pd.DataFrame, tq: float) -> Estimate:
    lo, hi = press.iloc[0], press.iloc[-1]
    m_lo = lo["m_obs"] if np.isfinite(lo["m_obs"]) else lo["mu_steady_max"]
    m_hi = hi["m_obs"] if np.isfinite(hi["m_obs"]) else hi["mu_steady_max"]
    r, se = ratio(m_hi, hi["m_obs_se"], m_lo, lo["m_obs_se"])  # the error is NaN without a runaway at either end
    f = 1.0 - r
    return Estimate(float(f), float(se), float(f - tq * se), float(f + tq * se))


def fit_runs(runs: pd.DataFrame, maxima: ModelMaxima) -> list[FitResult]:
    """One fit per (surface, compound, temperature) group of an analysed runs table."""
    need = ["status", "pressure_Pa", "velocity_m_s", "velocity_sem_m_s", "mu", "mu_sem", *GROUP]
    missing = [c for c in need if c not in runs.columns]
    if missing:
        raise FitError(f"the runs table lacks column(s) {missing}; expected the runs.csv of `slipchain tester analyze`")
    runs = _numeric(runs, ["pressure_Pa", "velocity_m_s", "velocity_sem_m_s", "mu", "mu_sem"], "the runs table")
    usable = runs[runs["status"].isin([OK, RUNAWAY]) & np.isfinite(runs["pressure_Pa"]) & (runs["pressure_Pa"] > 0)
                  & np.isfinite(runs["mu"])]
    if usable.empty:
        raise FitError("the runs table has no steady or runaway run; nothing to fit")
    return [fit_group(grp, maxima, key if isinstance(key, tuple) else (key,))
            for key, grp in usable.groupby(GROUP, sort=True)]


def parameters_table(fits: list[FitResult]) -> pd.DataFrame:
    """fit.csv: one row per group and parameter (value, SE, 95 % CI), plus the load effect."""
    rows = []
    for f in fits:
        key = dict(zip(GROUP, f.group))
        for name, e in [*f.params.items(), ("fall_fitted", f.fall_fitted), ("fall_observed", f.fall_observed)]:
            rows.append({**key, "parameter": name, "value": e.value, "se": e.se, "ci_low": e.ci_low,
                         "ci_high": e.ci_high, "chi2": f.chi2, "dof": f.dof})
    return pd.DataFrame(rows)


def residuals_table(fits: list[FitResult]) -> pd.DataFrame:
    """residuals.csv: per group and pressure."""
    return pd.concat([f.pressures.assign(**dict(zip(GROUP, f.group))) for f in fits], ignore_index=True)


def predicts_fall(f: FitResult) -> str:
    """Does the fitted model predict the observed fall of the maximum? (overlap of the two CIs)."""
    a, b = f.fall_fitted, f.fall_observed
    if not (np.isfinite(b.value) and np.isfinite(b.se)):
        return "the data give no observed fall (no runaway at the smallest or largest pressure)"
    diff = a.value - b.value
    se = math.hypot(a.se, b.se)
    z = diff / se if se > 0 else math.inf
    verdict = "yes" if abs(z) <= 2 else "no"
    return (f"{verdict}: fitted fall {a.value:.1%} ± {a.se:.1%}, observed {b.value:.1%} ± {b.se:.1%} "
            f"(difference {diff:+.1%}, {abs(z):.1f} standard errors)")


def fit_markdown(fits: list[FitResult], runs_source: str, maxima: ModelMaxima, truth: dict | None = None) -> str:
    lines = [f"# The model fitted to tester data: {runs_source}", "",
             f"Runs: `{runs_source}`. Model maxima: `{maxima.source}` (theta {', '.join(f'{t:g}' for t in maxima.theta)}: "
             f"r = {', '.join(f'{r:.4f}' for r in maxima.r)}). Method: `slipchain.analysis.fit` (least squares on the "
             "mean-field rising branch and the model's maxima; 95 % CIs).", ""]
    for f in fits:
        lines += [f"## {' / '.join(str(x) for x in f.group)}", "",
                  f"chi2 = {f.chi2:.1f} for {f.dof} degrees of freedom (covariance scaled by {f.scale:.2f}); "
                  f"run-to-run scatter {f.scatter:.2%}; "
                  f"{'converged' if f.converged else 'NOT converged: ' + f.message}.", "",
                  "| parameter | value | SE | 95 % CI |" + (" planted |" if truth else ""),
                  "|---|---|---|---|" + ("---|" if truth else "")]
        for name, e in f.params.items():
            row = f"| {name} | {e.value:.4g} | {e.se:.2g} | [{e.ci_low:.4g}, {e.ci_high:.4g}] |"
            if truth:
                t = truth.get(name)
                row += f" {t:.4g} ({'inside' if t is not None and e.ci_low <= t <= e.ci_high else 'OUTSIDE'}) |"
            lines.append(row)
        lines += ["", "| p0 (kPa) | theta | steady runs | mean residual (SE) | observed max | fitted max |",
                  "|---|---|---|---|---|---|"]
        for r in f.pressures.itertuples():
            obs = f"{r.m_obs:.4f} ± {r.m_obs_se:.4f}" if np.isfinite(r.m_obs) else f">= {r.mu_steady_max:.4f}"
            lines.append(f"| {r.pressure_Pa / 1e3:.3g} | {r.theta:.3g} | {r.n_steady} | {r.steady_residual_mean:+.2f} | "
                         f"{obs} | {r.mu_max_fitted:.4f} |")
        lines += ["", f"Does the fitted model predict the measured fall of mu_max with pressure? {predicts_fall(f)}.", ""]
        lines += [f"Note: {n}." for n in f.notes]
        lines.append("")
    return "\n".join(lines)


@dataclass(frozen=True)
class ModelLaw:
    """The fitted model planted as the synthetic tester's mu(v, p0) (:mod:`slipchain.tester.synth`), so that a
    fit of the synthetic data can be checked against known F, v0, delta and p_ref: the mean-field
    rising branch F*g(v/v0; delta) up to the model's maximum F*g_max(delta)*r(p0/p_ref) (``r`` a
    :class:`~slipchain.analysis.fit.ModelMaxima`), then falling as the branch mirrored about its
    end (so that a weight above the maximum runs away)."""

    r: ModelMaxima
    F: float = 1.2
    v0: float = 3e-3
    delta: float = 0.7
    p_ref: float = 60e3
    factor: float = 1.0

    def _top(self, p0: float) -> tuple[float, float]:
        _, v_top, mu_top = _curve(self.F, self.v0, self.delta, self.p_ref, p0, np.array([self.v0]), self.r)
        return v_top, mu_top

    def mu(self, v: np.ndarray | float, p0: float) -> np.ndarray:
        v_top, _ = self._top(p0)
        v = np.maximum(np.asarray(v, float), 1e-300)
        mirrored = np.where(v <= v_top, v, v_top**2 / v)  # past the end: back down the branch
        return self.factor * self.F * g(mirrored, self.v0, self.delta, self.r.c)

    def maximum(self, p0: float) -> tuple[float, float]:
        v_top, mu_top = self._top(p0)
        return v_top, self.factor * mu_top

    def steady_velocity(self, mu_target: float, p0: float) -> float:
        v_max, mu_max = self.maximum(p0)
        if not mu_target < mu_max:
            raise ValueError(f"mu = {mu_target} is above the maximum {mu_max} at p0 = {p0}")
        return 10.0 ** optimize.brentq(lambda lv: float(self.mu(10.0**lv, p0)) - mu_target, np.log10(v_max) - 20,
                                       np.log10(v_max), xtol=1e-13)


__all__ = ["CONFIDENCE", "ModelLaw", "PARAMS", "Estimate", "FitError", "FitResult", "ModelMaxima", "dg_dlnv", "fit_group",
           "fit_markdown", "fit_runs", "g", "g_max", "model_maxima", "parameters_table", "predicts_fall",
           "residuals_table"]

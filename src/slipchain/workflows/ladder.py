"""The ladder of issue 29: the paper's model made realistic one step at a time, with the load effect
at each rung read from the results that measured it.

A ladder file (TOML, e.g. ``docs/ladder/ladder.toml``) lists the rungs in order, each adding one
realism step to the one before (chain, epsilon = 1e-2, elastic, spring drive -> dead weight ->
epsilon = 1 -> 2-D interface under a slab -> viscoelastic rubber -> the tester's thickness, top mass
and pull). A rung names its observable and where its numbers are; nothing is typed in by hand:

- ``kind = "mu-max"``: the output directory of ``slipchain mu-max`` (its ``mu_max.csv``): the
  friction maximum under a dead weight, mu_max, at the smallest and the largest load of its plan;
- ``kind = "table"``: a CSV with a ``theta`` column and either ``mu`` and ``err`` (a figure's
  table; ``mu_max`` and ``mu_max_se`` alike: the runaway onsets' ``mu_max.csv`` of ``slipchain figure
  traces``) or one ``mu_star`` per member (a sweep's index: seed means, SE = std/sqrt(n)), rows chosen
  by ``where`` (column = value): the observable at the smallest and the largest theta;
- ``kind = "evaluations"``: a CSV of dead-weight runs (theta, mu_a, velocity_status: a mu-max
  ``evaluations.csv``, or :func:`~slipchain.workflows.dead_weight.store_evaluations` of a sweep
  over ``dead_weight``; rows chosen by ``where`` as a table's): the bounds on mu_max that its runs
  give at each load, and the range of R they allow, no ratio. Only steady runs bound mu_max from
  below there; a table with an ``outcome`` column (``slipchain figure traces``' onsets.csv) counts its
  held runs too (:func:`slipchain.analysis.traces.run_outcome`: back on the rising branch by the run's end);
- ``kind = "none"``: not measured yet (``note`` says why and what stands in).

The load effect is the ratio R = obs(theta_max) / obs(theta_min) with its standard error by
propagation, sqrt((se_1/m_1)**2 + (se_2/m_2)**2) R (the two loads are independent realisations). A
load whose bisection did not decide (a refuted bracket, or no steady run within t_max) has no
mu_max: the rung then states the bounds its runs give (e.g. "runaway at mu_a = 0.5") and no ratio.
The paper's effect is R < 0.8 at v_d1 = v0 (Fig. 6); "no load effect" is R = 1.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..model.config import ConfigError, _message
from ..results.io import write_csv

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

KINDS = ("mu-max", "table", "evaluations", "none")


@dataclass
class Rung:
    """One rung: what it adds, what it measures, and where the numbers are (module docstring)."""

    name: str
    adds: str
    observable: str  # 'mu_max' (dead weight) or 'mu_star at v_d1' (spring drive)
    kind: str
    source: str | tuple[str, ...] = ""  # a path relative to the ladder file (kind 'evaluations': one or several)
    where: dict[str, Any] = field(default_factory=dict)
    note: str = ""


@dataclass
class Effect:
    """A rung's load effect: the observable at the smallest and largest load and their ratio."""

    theta_min: float = math.nan
    theta_max: float = math.nan
    low: float = math.nan
    low_se: float = math.nan
    high: float = math.nan
    high_se: float = math.nan
    ratio: float = math.nan
    ratio_se: float = math.nan
    bounds: str = ""  # what undecided loads' runs say instead of a value
    ratio_min: float = math.nan  # where a load is undecided: the range of R its runs allow (nan: unbounded)
    ratio_max: float = math.nan
    per_load: str = ""  # the observable at every load ("theta: value ± se", or the bounds)


def load_ladder(path: str | os.PathLike) -> list[Rung]:
    """The rungs of a ladder file; ConfigError naming the rung, key and value where one is off."""
    with open(path, "rb") as f:
        data = tomllib.load(f)
    rungs = []
    for i, r in enumerate(data.get("rung", [])):
        where = f"ladder {os.fspath(path)!r}, rung {i + 1}"
        for key in ("name", "adds", "observable", "kind"):
            if not isinstance(r.get(key), str) or not r[key]:
                raise ConfigError(f"{where}: " + _message(key, r.get(key), "a non-empty string"))
        if r["kind"] not in KINDS:
            raise ConfigError(f"{where}: " + _message("kind", r["kind"], " or ".join(repr(k) for k in KINDS)))
        if r["kind"] != "none" and not r.get("source"):
            raise ConfigError(f"{where}: " + _message("source", r.get("source"), f"a path (kind = {r['kind']!r})"))
        source = r.get("source", "")
        if isinstance(source, list):  # several CSVs of runs read as one (e.g. a grid continued by a second preset)
            if r["kind"] != "evaluations" or not source or not all(isinstance(s, str) and s for s in source):
                raise ConfigError(f"{where}: " + _message("source", source, "a path, or a list of paths with kind = "
                                                          "'evaluations'"))
            source = tuple(source)
        unknown = set(r) - {"name", "adds", "observable", "kind", "source", "where", "note"}
        if unknown:
            raise ConfigError(f"{where}: unknown key(s) {sorted(unknown)}")
        rungs.append(Rung(r["name"], r["adds"], r["observable"], r["kind"], source,
                          dict(r.get("where", {})), r.get("note", "")))
    if not rungs:
        raise ConfigError(f"ladder {os.fspath(path)!r}: " + _message("rung", None, "at least one [[rung]] table"))
    return rungs


def _ratio(e: Effect) -> Effect:
    if np.isfinite(e.low) and np.isfinite(e.high) and e.low != 0:
        e.ratio = e.high / e.low
        e.ratio_se = e.ratio * math.hypot(e.low_se / e.low, e.high_se / e.high)
    return e


def effect_of_mu_max(out: Path) -> Effect:
    """A ``slipchain mu-max`` output: seed means of mu_max at the plan's smallest and largest theta
    (``mu_max_summary``'s rule for the SE), or the bounds its undecided realisations' runs give."""
    import pandas as pd

    from .dead_weight import mu_max_summary

    table = pd.read_csv(out / "mu_max.csv")
    ev = pd.read_csv(out / "evaluations.csv")
    summary = mu_max_summary(table).set_index("theta")
    thetas = sorted(table["theta"].unique())
    seeds = {t: int(np.isclose(table["theta"], t).sum()) for t in thetas}
    e = Effect(theta_min=float(thetas[0]), theta_max=float(thetas[-1]))
    notes = []
    for theta, attr in ((thetas[0], "low"), (thetas[-1], "high")):
        if theta in summary.index:
            setattr(e, attr, float(summary.loc[theta, "mu_max"]))
            setattr(e, f"{attr}_se", float(summary.loc[theta, "mu_max_se"]))
        else:
            notes.append(f"theta = {theta:g}: {seeds[theta]} seed(s) undecided, {_bounds(ev, theta)}")
    e.bounds = "; ".join(notes)
    e.per_load = "; ".join(f"{t:g}: {summary.loc[t, 'mu_max']:.3f} ± {summary.loc[t, 'mu_max_se']:.3f} "
                           f"({int(summary.loc[t, 'seeds'])} of {seeds[t]} seeds)"
                           if t in summary.index else f"{t:g}: {_bounds(ev, t)}" for t in thetas)
    _ratio(e)
    if notes:
        _ratio_range(e, ev)
    return e


def _ratio_range(e: Effect, ev: "pd.DataFrame") -> Effect:
    """The range of R that the runs ``ev`` allow where a load has no mu_max (``e.low`` or ``e.high``
    NaN: its :func:`_interval` stands in; a decided load is its own point): R in [h0 / l1, h1 / l0],
    NaN for an end the runs leave open (no steady run at the smallest load: no upper end)."""
    (l0, l1), (h0, h1) = ((_interval(ev, t) if not np.isfinite(v) else (v, v))
                          for t, v in ((e.theta_min, e.low), (e.theta_max, e.high)))
    e.ratio_min = h0 / l1 if l1 > 0 else math.nan
    e.ratio_max = h1 / l0 if l0 > 0 and np.isfinite(h1) else math.nan
    return e


def _status(ev: "pd.DataFrame") -> tuple[str, tuple[str, ...]]:
    """The column that classifies a table's runs and the values that bound mu_max from below: the runs'
    ``outcome`` where the table has one (``slipchain figure traces``' onsets.csv: steady or held,
    :func:`slipchain.analysis.traces.run_outcome`), else the tester's ``velocity_status`` (steady only)."""
    from ..analysis.traces import BELOW

    return ("outcome", BELOW) if "outcome" in ev.columns else ("velocity_status", ("ok",))


def _interval(ev: "pd.DataFrame", theta: float) -> tuple[float, float]:
    """The bracket on the seed mean of mu_max that the runs at one load give, seed by seed (largest
    steady or held mu_a, or 0; smallest runaway mu_a, or inf: :func:`~slipchain.analysis.traces.seed_brackets`)
    and then their envelope: (the smallest lower end, the largest upper end)."""
    from ..analysis.traces import seed_brackets

    status, lower = _status(ev)
    b = seed_brackets(ev[np.isclose(ev["theta"], theta)], status=status, lower=lower)
    return float(b["lo"].min()), float(b["hi"].max())


def _bounds(ev: "pd.DataFrame", theta: float) -> str:
    """What the dead-weight runs at one load say about mu_max: the largest steady (and held) mu_a, the
    smallest runaway one, and those that decided nothing (not steady within t_max, failed, or not run yet: a
    store's member without a run file, :data:`.dead_weight.NOT_RUN`)."""
    from ..analysis.traces import HELD, STEADY
    from .dead_weight import outcome

    ev = ev[np.isclose(ev["theta"], theta)]
    status, lower = _status(ev)
    named = {"ok": STEADY, STEADY: STEADY, HELD: HELD}
    parts = []
    for s in lower:
        m = ev[ev[status] == s]["mu_a"]
        if len(m):
            parts.append(f"{named[s]} up to mu_a = {m.max():g}")
    run = ev[ev[status] == "runaway"]["mu_a"]
    if len(run):
        parts.append(f"runaway from mu_a = {run.min():g}")
    other = ev[~ev[status].isin([*lower, "runaway"])]
    if status == "velocity_status":
        other = other.assign(velocity_status=outcome(other))
    for s, g in other.groupby(status):
        parts.append(f"{s} at mu_a = {', '.join(f'{m:g}' for m in sorted(set(g['mu_a'])))}")
    return ", ".join(parts) if parts else "no runs"


def effect_of_evaluations(path: Path | list[Path], where: dict[str, Any] | None = None) -> Effect:
    """A CSV of dead-weight runs (or several, read as one), its rows chosen by ``where`` (column =
    value, as a table's: e.g. one ramp ``t_ramp`` of a sweep over several): the bounds on mu_max at
    every load (module docstring) and the range of R they allow between the smallest and the largest
    load (:func:`_ratio_range`; a run held but not steady bounds nothing unless the table says so in an
    ``outcome`` column, :func:`_status`), no ratio."""
    import pandas as pd

    paths = path if isinstance(path, list) else [path]
    ev = pd.concat([pd.read_csv(p) for p in paths], ignore_index=True)
    if "outcome" in ev.columns and "velocity_status" in ev.columns:  # a table of the tester's status alone beside
        # one of outcomes: its steady and runaway runs as they are, the rest undecided (nothing says held)
        said = ev["velocity_status"].map({"ok": "steady", "runaway": "runaway"}).fillna("undecided")
        ev["outcome"] = ev["outcome"].fillna(said)
    ev = _select(ev, where or {}, ", ".join(os.fspath(p) for p in paths))
    thetas = sorted(ev["theta"].unique())
    bounds = "; ".join(f"theta = {t:g}: {_bounds(ev, t)}" for t in thetas)
    return _ratio_range(Effect(theta_min=float(thetas[0]), theta_max=float(thetas[-1]), bounds=bounds,
                               per_load="; ".join(f"{t:g}: {_bounds(ev, t)}" for t in thetas)), ev)


def _select(d: "pd.DataFrame", where: dict[str, Any], path: str | Path) -> "pd.DataFrame":
    """The rows of table ``d`` (read from ``path``) where every ``where`` column has its value
    (numbers compared with np.isclose); ConfigError if a column is missing or nothing is left."""
    for key, value in where.items():
        if key not in d.columns:
            raise ConfigError(f"table {os.fspath(path)!r}: " + _message("where", where, f"columns of the table "
                                                                         f"({', '.join(d.columns)})"))
        d = d[np.isclose(d[key], value)] if isinstance(value, (int, float)) else d[d[key].astype(str) == str(value)]
    if d.empty:
        raise ConfigError(f"table {os.fspath(path)!r}: " + _message("where", where, "a selection with rows"))
    return d


def effect_of_table(path: Path, where: dict[str, Any]) -> Effect:
    """A CSV table (module docstring): mu_star at the smallest and largest theta of the rows chosen."""
    import pandas as pd

    d = _select(pd.read_csv(path), where, path)
    if "mu_max" in d.columns and "mu" not in d.columns:  # `slipchain figure traces`' mu_max.csv: the same shape
        d = d.rename(columns={"mu_max": "mu", "mu_max_se": "err"})
    if "mu" in d.columns:
        # a figure's table has one row per point: several at one theta are points of another dimension
        # (a geometry, a size), which ``where`` must choose, never averaged
        many = d[d.duplicated("theta", keep=False)]
        if len(many):
            varied = [c for c in d.columns if c not in ("theta", "mu", "err") and many[c].nunique(dropna=False) > 1]
            raise ConfigError(f"table {os.fspath(path)!r}: " + _message(
                "where", where, f"one row per theta (rows at theta = {many['theta'].iloc[0]:g} differ in "
                f"{', '.join(varied)}: choose with where)"))
        g = d.groupby("theta").agg(mu=("mu", "mean"), err=("err", "mean"))
    else:
        d = d[d["status"] == "completed"] if "status" in d.columns else d
        g = d.groupby("theta")["mu_star"].agg(["mean", "std", "count"])
        g = pd.DataFrame({"mu": g["mean"], "err": g["std"] / np.sqrt(g["count"])})
    lo, hi = g.index.min(), g.index.max()
    e = Effect(float(lo), float(hi), float(g.loc[lo, "mu"]), float(g.loc[lo, "err"]), float(g.loc[hi, "mu"]),
               float(g.loc[hi, "err"]), per_load="; ".join(f"{t:g}: {format_with_se(r.mu, r.err)}" for t, r in g.iterrows()))
    return _ratio(e)


def format_with_se(value: float, se: float) -> str:
    """``value ± se`` to three decimals; the value alone where there is no standard error (one realisation)."""
    return f"{value:.3f} ± {se:.3f}" if np.isfinite(se) else f"{value:.3f} (no SE: one realisation)"


def ladder_table(path: str | os.PathLike) -> "pd.DataFrame":
    """One row per rung: what it adds, its observable, the load effect (module docstring)."""
    import pandas as pd

    path = Path(path)
    rows = []
    for r in load_ladder(path):
        src = ([path.parent / s for s in r.source] if isinstance(r.source, tuple)
               else (path.parent / r.source) if r.source else None)
        if r.kind == "mu-max":
            e = effect_of_mu_max(src)
        elif r.kind == "table":
            e = effect_of_table(src, r.where)
        elif r.kind == "evaluations":
            e = effect_of_evaluations(src, r.where)
        else:
            e = Effect()
        rows.append({"rung": r.name, "adds": r.adds, "observable": r.observable, "theta_min": e.theta_min,
                     "theta_max": e.theta_max, "low": e.low, "low_se": e.low_se, "high": e.high, "high_se": e.high_se,
                     "ratio": e.ratio, "ratio_se": e.ratio_se, "ratio_min": e.ratio_min, "ratio_max": e.ratio_max,
                     "bounds": e.bounds, "per_load": e.per_load,
                     "source": "; ".join(r.source) if isinstance(r.source, tuple) else r.source, "note": r.note})
    return pd.DataFrame(rows)


def ladder_figure(table: "pd.DataFrame", out: str | os.PathLike) -> list[Path]:
    """The ladder as one figure: each rung's ratio R with its error bar (top rung first), R = 1 (no
    effect) and R = 0.8 (the paper's fall at v_d1) marked; rungs without a ratio say why in words."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    n = len(table)
    fig, ax = plt.subplots(figsize=(9.0, 0.62 * n + 1.6))
    y = np.arange(n)[::-1]
    colours = {"mu_max": "tab:blue"}
    for yi, (_, r) in zip(y, table.iterrows()):
        c = colours.get(r["observable"], "tab:red")
        if np.isfinite(r["ratio"]):
            ax.errorbar(r["ratio"], yi, xerr=r["ratio_se"], fmt="o", color=c, capsize=3)
            ax.annotate(format_with_se(r["ratio"], r["ratio_se"]), (r["ratio"], yi), textcoords="offset points",
                        xytext=(0, 7), ha="center", fontsize=7, color=c)
        elif (np.isfinite(r["ratio_min"]) and r["ratio_min"] > 0) or np.isfinite(r["ratio_max"]):  # a range from undecided loads
            a = r["ratio_min"] if np.isfinite(r["ratio_min"]) else 0.0
            b = r["ratio_max"] if np.isfinite(r["ratio_max"]) else 10.0
            ax.plot([a, b], [yi, yi], lw=4, alpha=0.5, color=c, solid_capstyle="butt")
            label = (f"R <= {b:.2f}" if a <= 0 else f"R >= {a:.2f}" if b == 10.0 else f"R in [{a:.2f}, {b:.2f}]")
            ax.annotate(f"{label} (bounds from runs without a mu_max)", (max(min(a, 2.4), 0.47), yi),
                        textcoords="offset points", xytext=(0, 7), fontsize=7, color=c)
        else:
            text = r["bounds"] if isinstance(r["bounds"], str) and r["bounds"] else (r["note"] or "not measured")
            ax.text(0.47, yi, _short(text), fontsize=6.5, va="center", color="0.35")
    ax.axvline(1.0, color="0.5", lw=0.8)
    ax.axvline(0.8, color="0.5", lw=0.8, ls="--")
    ax.set_yticks(y, [f"{r['rung']}\n({r['observable']}" + (f", theta {r['theta_min']:g}-{r['theta_max']:g})"
                                                             if np.isfinite(r['theta_min']) else ")")
                      for _, r in table.iterrows()], fontsize=7)
    finite = [v for v in table[["ratio", "ratio_min", "ratio_max"]].to_numpy().ravel() if np.isfinite(v)]
    ax.set_xlim(0.45, min(2.5, max([1.25] + [v + 0.1 for v in finite])))
    ax.set_ylim(-0.7, n - 0.3)
    ax.set_xlabel("load effect R = value at the largest theta / value at the smallest (1: none; dashed: the paper's 0.8)")
    ax.set_title("The ladder: the paper's model made realistic one step at a time", fontsize=10)
    fig.tight_layout()
    paths = [out / "ladder.png", out / "ladder.pdf"]
    for p in paths:
        fig.savefig(p, dpi=150)
    plt.close(fig)
    write_csv(table, out / "ladder.csv")
    return paths + [out / "ladder.csv"]


def _short(text: str, width: int = 95) -> str:
    """Wrap a note for the figure (two lines at most)."""
    import textwrap

    lines = textwrap.wrap(text, width)
    return "\n".join(lines[:2]) + (" …" if len(lines) > 2 else "")

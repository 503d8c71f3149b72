"""Figures from stores and tables, one function per ``slipchain figure`` command: open, check, compute, draw."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from ..analysis.experiment import model_overlay
from ..analysis.fig6 import contact_law_dataset, fig6_figure_data
from ..analysis.mechanism import velocity_figure_data
from ..analysis.reports import epsilon_lines
from ..analysis.statistics import epsilon_frame_table, epsilon_rows, epsilon_table
from ..model.config import ConfigError, load_config
from ..plots.mechanism import DRAWN, plot_dead_weight, plot_dead_weight_grid, plot_epsilon, plot_velocity
from ..plots.paper import plot_fig5, plot_fig6
from ..plots.tester import plot_model_vs_experiment
from ..results.io import write_csv
from ..results.schema import Status
from ..sweeps.definition import SweepError, SweepWarning
from ..sweeps.store import Store


def sweep_dataset(store: str | os.PathLike, needs: set[str], what: str) -> xr.Dataset:
    """The sweep Dataset of a store that sweeps at least ``needs``; SweepError naming what is missing.

    Members whose files cannot be read are left out (status ``unreadable``, like a missing member)
    with a SweepWarning naming them by id."""
    ds = Store.open(store).dataset()
    if not needs <= set(ds.dims):
        raise SweepError(f"store {str(store)!r} sweeps {list(ds.dims)}; {what} needs {', '.join(sorted(needs))}")
    bad = ds["status"].values == Status.UNREADABLE
    if bad.any():
        ids = sorted(ds["member_id"].values[bad].tolist())
        warnings.warn(f"store {str(store)!r}: {len(ids)} member file(s) cannot be read and are left out of {what}: "
                      f"{', '.join(ids)} (run the same `slipchain sweep` again to quarantine and rerun them)",
                      SweepWarning, stacklevel=2)
    return ds


def fig5(out: str | os.PathLike, config: str | os.PathLike | None = None, seed: int = 0) -> list[Path]:
    """Fig. 5 for the config at ``config`` (default: the paper's), contact average of realisation ``seed``."""
    return plot_fig5(contact_law_dataset(load_config(config), seed=seed), out)


def fig6(store: str | os.PathLike, out: str | os.PathLike) -> list[Path]:
    return plot_fig6(fig6_figure_data(sweep_dataset(store, {"theta", "eta_c", "v_d"}, "fig6")), out)


def fig6_3d(store: str | os.PathLike, out: str | os.PathLike, command: str = "", wall: str = "") -> list[Path]:
    """Fig. 6 in 3-D (issue 13): the figure, report.md, table.csv (seed means), drops.csv (the load
    effect per geometry, size and velocity) and sawtooth.csv (f_d's cycles per point at the main size)
    from a store sweeping theta and v_d (and geometry, or one geometry in its base config:
    presets/fig6-3d-eps1.toml)."""
    from ..analysis.geometry import fig6_3d_data, report_markdown, sawtooth, sawtooth_table, steppers
    from ..plots.geometry import plot_fig6_3d
    from ..results.io import write_csv, write_text_atomic

    table, drop, attrs = fig6_3d_data(sweep_dataset(store, {"theta", "v_d"}, "the Fig. 6-in-3-D figure"))
    saw = []  # the sawtooth of every completed run at its geometry's main size
    st = Store.open(store)
    done = st.completed_ids()
    for m in st.sweep.members:
        c = m.config
        if m.id in done and attrs["main"].get(c.geometry) == (c.N, c.Ly, c.N_L):
            saw.append(dict(geometry=c.geometry, theta=c.theta, v_d=c.v_d, seed=c.seed, **sawtooth(st.read_member(m))))
    attrs["sawtooth"] = sawtooth_table(saw)
    attrs["steppers"] = steppers(m.config for m in st.sweep.members if m.id in done)
    attrs["sweep"], attrs["completed"] = st.sweep.name, (len(st.sweep.members) - len(st.pending()), len(st.sweep.members))
    paths = plot_fig6_3d(table, drop, attrs, out)
    paths += [write_csv(frame, Path(out) / name, float_format="%.6g")
              for name, frame in (("table.csv", table), ("drops.csv", drop), ("sawtooth.csv", attrs["sawtooth"]))]
    return paths + [write_text_atomic(Path(out) / "report.md", report_markdown(table, drop, attrs, command=command,
                                                                             wall=wall))]


def rubber(store: str | os.PathLike, out: str | os.PathLike, elastic: str | os.PathLike | None = None,
           command: str = "") -> list[Path]:
    """Fig. 6 with the viscoelastic slider (issue 28): the figure, report.md, table.csv (seed means) and
    drops.csv (the load effect per variant, eta_c and velocity) from a store of material = 'prony'
    sweeping theta (and temperature, eta_c, v_d, or each in its base config), beside its elastic twin's
    store (``elastic``)."""
    from ..analysis.rubber import report_markdown, rubber_data
    from ..plots.rubber import plot_rubber
    from ..results.io import write_text_atomic

    need = {"theta"}
    rub = sweep_dataset(store, need, "the viscoelastic Fig. 6")
    ela = sweep_dataset(elastic, need, "the viscoelastic Fig. 6's elastic twin") if elastic is not None else None
    try:
        table, drop, attrs = rubber_data(rub, ela)
    except ValueError as e:
        raise SweepError(str(e)) from None
    paths = plot_rubber(table, drop, attrs, out)
    paths += [write_csv(frame, Path(out) / name, float_format="%.6g")
              for name, frame in (("table.csv", table), ("drops.csv", drop))]
    return paths + [write_text_atomic(Path(out) / "report.md", report_markdown(table, drop, attrs, command=command))]


def slip_maps(run: str | os.PathLike, out: str | os.PathLike, duration: float, interval: float) -> list[Path]:
    """Continue a 2-D run (a run file) for ``duration`` s recording u and x every ``interval`` s;
    draw the maps around its largest slip event; write events.csv (every cluster in (t, x, y))."""
    from ..analysis.mechanism import record_field, slip_events, state_from_run
    from ..model.config import ConfigError, config_from_toml
    from ..model.system import build_system
    from ..plots.geometry import plot_slip_maps
    from ..results.io import read_dataset, write_csv

    try:
        ds = read_dataset(run)
    except (OSError, ValueError) as err:
        raise ConfigError(f"--run {str(run)!r} is not a run file: {err}") from None
    cfg = config_from_toml(ds.attrs["config"])
    state = state_from_run(ds)
    if cfg.Ly < 2:
        raise ConfigError(f"--run {str(run)!r} has Ly = {cfg.Ly}; slip maps need a 2-D interface (Ly >= 2)")
    field = record_field(build_system(cfg), state, duration, interval, positions=True)
    events = slip_events(field)
    if events.sizes.get("event", 0) == 0:
        raise ConfigError(f"no block slipped faster than 2 v_d in {duration:g} s: record longer (--duration)")
    paths = plot_slip_maps(field, events, out)
    return paths + [write_csv(events.to_dataframe(), Path(out) / "events.csv", index=True, float_format="%.6g")]


def velocity(store: str | os.PathLike, out: str | os.PathLike) -> list[Path]:
    return plot_velocity(velocity_figure_data(sweep_dataset(store, {"v_d"}, "the velocity figure")), out)


def dead_weight(store: str | os.PathLike, out: str | os.PathLike) -> list[Path]:
    return plot_dead_weight(sweep_dataset(store, {"dead_weight"}, "the dead-weight figure"), out)


def traces(stores: list[str | os.PathLike], out: str | os.PathLike, window: float,
           redecide: list[float] | tuple[float, ...] = (), stop_at_runaway: bool = False,
           stop_when_held: bool = False, checkpoints: bool = False) -> tuple[list[Path], list[str]]:
    """The top's velocity against time of every run of dead-weight stores, over windows of ``window`` s,
    with each run's outcome and each runaway's onset (:mod:`slipchain.analysis.traces`): the figure,
    traces.csv (one row per window), onsets.csv (one row per run), mu_max.csv
    (:func:`~slipchain.analysis.traces.onset_summary`), brackets.csv (each protocol's bracket on mu_max
    from its steady, held and runaway weights: :func:`~slipchain.analysis.traces.protocol_brackets`), and
    where some runs were loaded slowly (not at once or in a release:
    :func:`~slipchain.analysis.traces.is_release`) the rising branch their ramps traced (branch.csv, the branches figure) checked
    against the steady runs (branch_check.csv) and read at fixed velocities (branch_mu.csv:
    :func:`~slipchain.analysis.traces.branch_summary`); with ``redecide`` (seconds), each run's automatic length
    replayed at each of those t_decide (:func:`~slipchain.analysis.traces.redecide`: redecide.csv; with
    ``stop_at_runaway`` or ``stop_when_held``, with that config on: a released runaway, or a held run, stopped over its
    top's ringing periods); with ``checkpoints``, also the runs not stored yet that the stop rules decide on their
    checkpointed records (their rows' ``source`` "checkpoint"; :func:`~slipchain.analysis.traces.velocity_traces`),
    so a bracket can count a run read by ``slipchain status`` before it is stored; returns the
    paths, a line on that check, one line per group of mu_max.csv, one per bracket and one per replayed t_decide."""
    from ..analysis.traces import branch_check, branch_summary, onset_summary, protocol_brackets, velocity_traces
    from ..analysis.traces import redecide as replay
    from ..plots.dead_weight import plot_branches, plot_velocity_traces

    frame, onsets, branch = velocity_traces(stores, window, checkpoints)
    summary = onset_summary(onsets)
    brackets = protocol_brackets(onsets)
    check = branch_check(branch, onsets[onsets["outcome"] == "steady"])
    at_v = branch_summary(branch)
    paths = plot_velocity_traces(frame, onsets, window, out)
    if len(branch):
        paths += plot_branches(branch, onsets, out)
    paths += [write_csv(frame, Path(out) / "traces.csv", float_format="%.6g"),
              write_csv(onsets, Path(out) / "onsets.csv", float_format="%.6g"),
              write_csv(summary, Path(out) / "mu_max.csv", float_format="%.6g"),
              write_csv(brackets, Path(out) / "brackets.csv", float_format="%.6g")]
    if len(branch):  # none where every run's weight came on at once or in a release
        paths += [write_csv(branch, Path(out) / "branch.csv", float_format="%.6g"),
                  write_csv(check, Path(out) / "branch_check.csv", float_format="%.6g"),
                  write_csv(at_v, Path(out) / "branch_mu.csv", float_format="%.6g")]
    replays = []
    if redecide:
        table, skipped = replay(stores, redecide, stop_at_runaway, stop_when_held)
        paths.append(write_csv(table, Path(out) / "redecide.csv", float_format="%.6g"))
        replays = [(t, table[table["t_decide_replay"] == t] if len(table) else table, skipped[float(t)]) for t in redecide]
    lines = []
    for t_decide, table, skipped in replays:
        if not len(table):
            lines.append(f"t_decide = {t_decide:g} s: no run to replay ({skipped} skipped: their ramps do not end before it)")
            continue
        run = table[table["outcome"] == "runaway"]
        stops = (f"; the runaways stop at {run['t_stop'].median():.3g} s (median) instead of {run['t_end'].median():.3g} s"
                 if len(run) else "")
        with_stop = "".join(f" with {k}" for k, on in (("stop_at_runaway", stop_at_runaway),
                                                        ("stop_when_held", stop_when_held)) if on)
        lines.append(f"t_decide = {t_decide:g} s replayed{with_stop} on {len(table)} runs: {int(table['agree'].sum())} on the same "
                     f"side of mu_max{stops}" + (f" ({skipped} skipped: their ramps do not end before it)" if skipped else "")
                     + " (redecide.csv)")
    several = onsets["eta_c"].nunique() > 1  # name the contact damping where the stores mix several

    def damping(r) -> str:
        return f", eta_c = {r['eta_c']:g}/s" if several else ""

    if len(check):
        r = check["ratio"]
        lines.append(f"the ramp's velocity at a steady run's weight over the steady velocity: median {r.median():.3f}, "
                     f"{r.min():.3f} to {r.max():.3f} ({len(check)} pairs; branch_check.csv)")
    for _, r in brackets.iterrows():
        bad = f"; {r['inconsistent']} seed(s) inconsistent" if r["inconsistent"] else ""
        lines.append(f"N = {r['N']:g}, {r['temperature']:g} °C{damping(r)}, ramp {r['t_ramp']:g} s, theta = {r['theta']:g}: mu_max in "
                     f"[{r['lo']:g}, {r['hi']:g}) ({r['per_seed']}{bad})")
    for _, r in summary.iterrows():
        se = f" ± {r['mu_max_se']:.4f}" if np.isfinite(r["mu_max_se"]) else ""
        rse = f" ± {r['R_se']:.4f}" if np.isfinite(r["R_se"]) else ""
        lines.append(f"N = {r['N']:g}, {r['temperature']:g} °C{damping(r)}, weight rising {r['rate']:g}/s, theta = {r['theta']:g}: mu_max "
                     f"{r['mu_max']:.4f}{se} ({int(r['runs'])} run(s); read at 10 v0 10**delta {r['mu_max_10']:.4f}); "
                     f"R = {r['R']:.4f}{rse} ({r['R_10']:.4f})")
    return paths, lines


def dead_weight_grid(stores: list[str | os.PathLike], by: str, out: str | os.PathLike,
                     tables: list[str | os.PathLike] = ()) -> tuple[list[Path], list[str]]:
    """The dead-weight figure of one or more grid stores, one panel per value of the config key ``by``
    (:func:`slipchain.plots.mechanism.plot_dead_weight_grid`; e.g. tester-16, its weight at once, beside
    tester-16-slow's ramps); their rows (``store_evaluations``, with ``by`` and a ``store`` column) into
    OUT/evaluations.csv. ``tables``: CSVs of such rows (e.g. a grid whose store is elsewhere), each
    with a ``by`` column. Returns the paths and a line per source saying how many runs were not drawn.
    ConfigError (nothing written) for a key that is not a config key or a table without its column."""
    from .dead_weight import outcome, store_evaluations

    sources = []
    for t in tables:
        d = pd.read_csv(t)
        missing = [c for c in (by, "theta", "seed", "mu_a", "velocity_status", "velocity_m_s") if c not in d.columns]
        if missing:
            raise ConfigError(f"table {os.fspath(t)!r} has no column {missing[0]!r}; expected the rows of "
                              f"store_evaluations with a column {by!r} (the value its runs had)")
        sources.append((Path(t).name, d.assign(message=d.get("message", pd.Series("", index=d.index)).astype(object).fillna(""))))
    sources += [(Path(st).name, store_evaluations(st, (by,))) for st in stores]
    parts, lines = [], []
    for name, ev in sources:
        ev = ev.assign(store=name)
        ev[by] = ev[by].astype(object).where(ev[by].notna(), "absent")  # e.g. no ramp: the weight at once
        bad = ev[~ev["velocity_status"].isin(DRAWN)]
        if len(bad):
            lines.append(f"{name}: {len(bad)} of {len(ev)} runs not drawn "
                         f"({', '.join(f'{k}: {n}' for k, n in outcome(bad).value_counts().items())})")
        parts.append(ev)
    ev = pd.concat(parts, ignore_index=True)
    paths = plot_dead_weight_grid(ev, by, out)
    return paths + [write_csv(ev, Path(out) / "evaluations.csv")], lines


def epsilon(store: str | os.PathLike | None, out: str | os.PathLike, *, more_stores: tuple = (),
            indexes: tuple = ()) -> tuple[list[Path], list[str]]:
    """The epsilon figure, and one line per epsilon with the drop of mu_star from the smallest theta to the largest.

    From one store sweeping epsilon and theta; or (issue 12: the figure extended to epsilon = 1)
    from several sources: stores sweeping theta (each at its base epsilon if epsilon is not swept;
    rows at v_d = v0 and eta_c = 0.1 omega0 where a store varies them) and sweep index CSVs
    (``indexes``, e.g. the committed docs/mechanism/epsilon-index.csv); the rows are written to
    epsilon-index.csv beside the figure."""
    if store is not None and not more_stores and not indexes:
        avg = epsilon_table(sweep_dataset(store, {"epsilon", "theta"}, "the epsilon figure"))
        return plot_epsilon(avg, out), epsilon_lines(avg)
    stores = ([store] if store is not None else []) + list(more_stores)
    frames = [epsilon_rows(sweep_dataset(s, {"theta"}, "the epsilon figure")) for s in stores]
    for path in indexes:
        if not Path(path).is_file():
            raise SweepError(f"index CSV {str(path)!r} does not exist")
        frame = pd.read_csv(path)
        if "member_id" in frame:
            frame = frame.drop(columns="member_id")
        frames.append(frame)
    if not frames:
        raise SweepError("the epsilon figure needs a store (--store) or an index CSV (--index)")
    rows = pd.concat(frames, ignore_index=True)
    try:
        avg = epsilon_frame_table(rows)
    except ValueError as e:
        raise SweepError(str(e)) from None
    paths = plot_epsilon(avg, out)
    paths.append(write_csv(rows.sort_values(["epsilon", "theta", "seed"]), Path(out) / "epsilon-index.csv"))
    return paths, epsilon_lines(avg)


def tester(runs: str | os.PathLike, store: str | os.PathLike | None = None,
           out: str | os.PathLike | None = None) -> list[Path]:
    """Measured mu(v) (``runs``: an output directory of ``slipchain tester analyze``) with the model's
    mu_star(v_d) curves from ``store``, one fitted scale factor per surface."""
    table_path = Path(runs) / "runs.csv"
    if not table_path.exists():
        raise FileNotFoundError(f"{table_path} does not exist; run `slipchain tester analyze ... --out {runs}` first")
    table = pd.read_csv(table_path)
    sweep = sweep_dataset(store, {"v_d"}, "a model curve") if store is not None else None
    return plot_model_vs_experiment(table, model_overlay(table, sweep), out or runs)


__all__ = ["dead_weight", "epsilon", "fig5", "fig6", "sweep_dataset", "tester", "velocity"]

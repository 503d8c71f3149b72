"""``slipchain figure ...``: the paper's and the mechanism's figures from stores and tables (PNG and PDF)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..model.config import ConfigError
from ..sweeps.definition import SweepError
from .common import fail, out, wrote

# The figure jobs (analysis, matplotlib, scipy) are imported when a figure command runs, not at
# start-up of every command: `slipchain run` imports only what it needs.

figure_app = typer.Typer(no_args_is_help=True, help="Draw the paper's figures from datasets (PNG and PDF).")

def _figures():
    from ..workflows import figures

    return figures


OutOpt = Annotated[Path, typer.Option("--out", help="Output directory.")]


@figure_app.command("fig5")
def fig5(
    out_dir: OutOpt,
    config: Annotated[Optional[Path], typer.Option("--config", help="Base config TOML (default: the paper's).")] = None,
    seed: Annotated[int, typer.Option("--seed", help="Disorder of the N = 1001 contact average.")] = 0,
) -> None:
    """Fig. 5: eq. (1) for eta_c = 0, omega0, 0.3 omega0, 0.1 omega0 and the contact average (N = 1001, theta = 1)."""
    try:
        wrote(_figures().fig5(out_dir, config, seed))
    except ConfigError as e:
        fail(str(e))


@figure_app.command("fig6")
def fig6(
    store: Annotated[Path, typer.Option("--store", help="Store of a Fig. 6 sweep (theta, eta_c, v_d; N, seed optional).")],
    out_dir: OutOpt,
) -> None:
    """Fig. 6: mu_star versus theta, three eta_c, two v_d, N = 1001 stars, the dashed line."""
    try:
        wrote(_figures().fig6(store, out_dir))
    except SweepError as e:
        fail(str(e))


@figure_app.command("fig6-3d")
def fig6_3d(
    store: Annotated[Path, typer.Option("--store", help="Store of a sweep over geometry, theta and v_d (presets/fig6-3d.toml).")],
    out_dir: OutOpt,
) -> None:
    """Fig. 6 in 3-D: mu_star versus theta for the chain, the 2-D chains and the slab, the load effect against the slab's thickness; report.md, table.csv, drops.csv."""
    try:
        wrote(_figures().fig6_3d(store, out_dir, command=f"slipchain figure fig6-3d --store {store} --out {out_dir}"))
    except SweepError as e:
        fail(str(e))


@figure_app.command("rubber")
def rubber(
    store: Annotated[Path, typer.Option("--store", help="Store of a sweep with material = 'prony' over theta and v_d (and temperature, eta_c) (presets/fig6-rubber.toml).")],
    out_dir: OutOpt,
    elastic: Annotated[Optional[Path], typer.Option("--elastic", help="Store of its elastic twin (presets/fig6-rubber-elastic.toml).")] = None,
) -> None:
    """Fig. 6 with a viscoelastic slider beside the elastic model: mu_star versus theta, the load effect; report.md, table.csv, drops.csv."""
    command = f"slipchain figure rubber --store {store}" + (f" --elastic {elastic}" if elastic else "") + f" --out {out_dir}"
    try:
        wrote(_figures().rubber(store, out_dir, elastic, command=command))
    except SweepError as e:
        fail(str(e))


@figure_app.command("slip-maps")
def slip_maps(
    run: Annotated[Path, typer.Option("--run", help="A run file (NetCDF) of a 2-D geometry (Ly >= 2).")],
    out_dir: OutOpt,
    duration: Annotated[float, typer.Option("--duration", min=1e-9, help="Seconds to record after the run's end.")] = 5e-3,
    interval: Annotated[float, typer.Option("--interval", min=1e-12, help="Sampling interval (s).")] = 1e-5,
) -> None:
    """Slip clusters in (t, x, y) of a 2-D run continued from its end, and maps of x - v_d t before and after the largest (events.csv)."""
    try:
        wrote(_figures().slip_maps(run, out_dir, duration, interval))
    except ConfigError as e:
        fail(str(e))


@figure_app.command("tester")
def tester(
    runs: Annotated[Path, typer.Option("--runs", help="Output directory of `slipchain tester analyze` (its runs.csv).")],
    store: Annotated[Optional[Path], typer.Option("--store", help="Sweep store with a v_d dimension (model curves).")] = None,
    out_dir: Annotated[Optional[Path], typer.Option("--out", help="Output directory (default: the --runs directory).")] = None,
) -> None:
    """Measured mu(v) with the model's mu_star(v_d) curves, one fitted scale factor per surface."""
    try:
        wrote(_figures().tester(runs, store, out_dir))
    except (SweepError, FileNotFoundError) as e:
        fail(str(e))


@figure_app.command("mechanism")
def mechanism(
    store: Annotated[Path, typer.Option("--store", help="Store of a Fig. 6-like sweep, analysed by `slipchain mechanism`.")],
    out_dir: OutOpt,
) -> None:
    """Stick-slip fraction versus theta, per-contact forces, event sizes and spectra; mechanism.md with the numbers."""
    try:
        from ..workflows.mechanism import mechanism_figures

        wrote(mechanism_figures(store, out_dir))
    except (SweepError, FileNotFoundError) as e:
        fail(str(e))


@figure_app.command("velocity")
def velocity(
    store: Annotated[Path, typer.Option("--store", help="Store of a sweep over v_d (e.g. presets/velocity.toml).")],
    out_dir: OutOpt,
) -> None:
    """mu_star versus v_d on a log axis, one curve per theta (the model's Figs. 2 and 3)."""
    try:
        wrote(_figures().velocity(store, out_dir))
    except SweepError as e:
        fail(str(e))


@figure_app.command("epsilon")
def epsilon(
    out_dir: OutOpt,
    store: Annotated[Optional[list[Path]], typer.Option("--store", help="Store of a sweep over epsilon and theta (presets/epsilon.toml); repeat it to combine stores (each at its base epsilon, e.g. presets/fig6-eps1.toml's).")] = None,
    index: Annotated[Optional[list[Path]], typer.Option("--index", help="Index CSV of an epsilon sweep (e.g. docs/mechanism/epsilon-index.csv), combined with the stores; repeatable.")] = None,
) -> None:
    """mu_star versus theta for each epsilon, and the drop from the smallest theta to the largest."""
    stores = list(store or [])
    try:
        paths, lines = _figures().epsilon(stores[0] if stores else None, out_dir, more_stores=tuple(stores[1:]),
                                          indexes=tuple(index or []))
    except SweepError as e:
        fail(str(e))
    wrote(paths)
    for line in lines:
        out.print(line)


@figure_app.command("dead-weight")
def dead_weight(
    out_dir: OutOpt,
    store: Annotated[Optional[list[Path]], typer.Option("--store", help="Store of a sweep over dead_weight (e.g. presets/dead-weight.toml); with --by, several.")] = None,
    by: Annotated[Optional[str], typer.Option("--by", help="A config key (e.g. t_ramp): one panel per value, from grid stores (held runs at the left edge); writes evaluations.csv.")] = None,
    table: Annotated[Optional[list[Path]], typer.Option("--table", help="With --by: a CSV of such runs (store_evaluations' rows with a column named by --by), beside the stores.")] = None,
) -> None:
    """Applied mu_star against the measured steady velocity per theta (runaways at the right edge)."""
    try:
        if by is None:
            if table:
                fail("--table needs --by (e.g. --by t_ramp)")
            if len(store or []) != 1:
                fail(f"--store given {len(store or [])} times; expected one store, or several with --by (e.g. --by t_ramp)")
            wrote(_figures().dead_weight(store[0], out_dir))
            return
        if not store and not table:
            fail("--by needs at least one --store or --table")
        paths, lines = _figures().dead_weight_grid(store or [], by, out_dir, table or [])
        wrote(paths)
        for line in lines:
            out.print(line)
    except (SweepError, ConfigError) as e:
        fail(str(e))


@figure_app.command("traces")
def traces(
    store: Annotated[list[Path], typer.Option("--store", help="Store of a sweep of dead-weight runs (e.g. presets/tester-16-long.toml); repeat it to read several.")],
    out_dir: OutOpt,
    window: Annotated[float, typer.Option("--window", help="Seconds over which each drawn velocity is the mean (the distance travelled over the window's length).")] = 0.02,
    redecide: Annotated[list[float], typer.Option("--redecide", help="Replay each run's automatic length as if its t_decide had been this many seconds (repeat it for several) and say whether each run's outcome stays on its side of mu_max (redecide.csv).")] = [],  # noqa: B006
    stop_at_runaway: Annotated[bool, typer.Option("--stop-at-runaway", help="With --redecide: replay with config stop_at_runaway on (a released runaway on the slab stopped over its top's last two ringing periods).")] = False,
    stop_when_held: Annotated[bool, typer.Option("--stop-when-held", help="With --redecide: replay with config stop_when_held on (a released slab stopped once its top is back on the rising branch for good).")] = False,
    checkpoints: Annotated[bool, typer.Option("--checkpoints", help="Also read the runs not stored yet whose checkpointed records the stop rules (stop_at_runaway, stop_when_held) decide, as `slipchain status` reads them (source 'checkpoint' in the CSVs).")] = False,
) -> None:
    """The top's velocity against time per run, one panel per theta; mu_max from where slowly loaded runs run away, and each protocol's bracket from its steady, held and runaway weights; traces.csv, onsets.csv, mu_max.csv, brackets.csv (with --redecide, redecide.csv)."""
    if not window > 0:
        fail(f"--window {window!r}: expected a positive number of seconds (e.g. 0.02)")
    bad = [t for t in redecide if not t > 0]
    if bad:
        fail(f"--redecide {bad[0]!r}: expected a positive number of seconds (e.g. 0.8)")
    for flag, on in (("--stop-at-runaway", stop_at_runaway), ("--stop-when-held", stop_when_held)):
        if on and not redecide:
            fail(f"{flag} without --redecide: expected --redecide T (the t_decide to replay it at)")
    try:
        paths, lines = _figures().traces(store, out_dir, window, redecide, stop_at_runaway, stop_when_held, checkpoints)
    except SweepError as e:
        fail(str(e))
    wrote(paths)
    for line in lines:
        out.print(line)


@figure_app.command("mu-max")
def mu_max(
    result: Annotated[Path, typer.Option("--from", help="Output directory of `slipchain mu-max`.")],
    out_dir: OutOpt,
    spring: Annotated[Optional[Path], typer.Option("--spring", help="Index CSV of a velocity sweep (e.g. docs/mechanism/velocity-index.csv): the spring-drive maximum beside.")] = None,
) -> None:
    """Figs. 2-3 from the model: mu(v) under a dead weight per theta, and mu_max(theta) beside the spring-drive maximum; report.md."""
    from ..model.config import ConfigError
    from ..workflows.dead_weight import mu_max_figure

    try:
        wrote(mu_max_figure(result, out_dir, spring))
    except ConfigError as e:
        fail(str(e))


@figure_app.command("ladder")
def ladder(
    ladder_file: Annotated[Path, typer.Option("--ladder", help="A ladder file (TOML: [[rung]] tables, e.g. docs/ladder/ladder.toml).")],
    out_dir: OutOpt,
) -> None:
    """The ladder of issue 29: the load effect at each realism step, one table (ladder.csv) and one figure."""
    from ..workflows.ladder import format_with_se, ladder_figure, ladder_table

    if not ladder_file.is_file():
        fail(f"--ladder {str(ladder_file)!r}: no such file; expected a ladder TOML file")
    try:
        table = ladder_table(ladder_file)
    except (ConfigError, OSError, KeyError) as e:
        fail(str(e))
    wrote(ladder_figure(table, out_dir))
    for _, r in table.iterrows():
        value = f"R = {format_with_se(r['ratio'], r['ratio_se'])}" if r["ratio"] == r["ratio"] else (r["bounds"] or r["note"])
        out.print(f"{r['rung']}: {value}")

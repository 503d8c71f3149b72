"""``slipchain sweep``, ``slipchain reproduce`` (the main job) and ``slipchain mechanism``: runs on Dask into a store."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console
from rich.table import Table

from ..engine.backends import BackendName
from ..results.schema import Status
from ..sweeps.catalogue import CATALOGUE, preset_files
from ..sweeps.definition import PRESETS, Preset, SweepError, load_sweep_definition
from ..sweeps.executor import SWEEP_CHECKPOINT_EVERY, StoreWriteError, SweepReport, run_sweep
from .common import (BackendOpt, BatchSizeOpt, DashboardOpt, ProgressOpt, SchedulerOpt, WorkersOpt, announce_dashboard, fail, out,
                     study_path, sweep_exit)


def sweep(
    definition: Annotated[Path, typer.Argument(help="Sweep TOML ([base] config plus [[grid]] tables of value lists), or "
                                              "the name of a shipped preset (`slipchain presets`).")],
    store: Annotated[Path, typer.Option("--store", help="Store directory (created; rerun to resume).")],
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    dashboard: DashboardOpt = False,
    backend: BackendOpt = BackendName.CPU,
    batch_size: BatchSizeOpt = None,
    checkpoint_every: Annotated[float, typer.Option(
        "--checkpoint-every", min=0.0, help="Wall-clock seconds between checkpoints of a running task, in STORE/checkpoints "
        "(a killed task resumes from its checkpoint).")] = SWEEP_CHECKPOINT_EVERY,
    dry_run: Annotated[bool, typer.Option("--dry-run", help="Check the sweep file and the store, say what would run, "
                                          "and stop: nothing is computed or written.")] = False,
    reuse: Annotated[Optional[list[Path]], typer.Option(
        "--reuse", help="Another store (repeatable) whose completed members of this sweep (same id: the same full "
        "config) are copied in instead of computed: extend a study in a new store.")] = None,
    only: Annotated[Optional[list[str]], typer.Option(
        "--only", help="KEY=VALUE (repeatable): run only the members at these sweep coordinates now (one key "
        "given twice: either value); the others stay pending for a later call.")] = None,
) -> None:
    """Run every member of a sweep on Dask, writing each to the store as it finishes; resumes."""
    definition = study_path(definition, "sweep file")
    selection = _only(only or [])
    if dry_run:
        _dry_run(definition, store, reuse or [], selection)
        return
    try:
        report = run_sweep(load_sweep_definition(definition), store, only=selection, scheduler=scheduler, n_workers=workers,
                           progress=progress, backend=backend, batch_size=batch_size, checkpoint_every=checkpoint_every,
                           announce=announce_dashboard(dashboard), reuse=reuse or ())
    except StoreWriteError as e:  # found while running (a full disk): what was stored is kept
        fail(str(e), code=1)
    except SweepError as e:
        fail(str(e))
    print_sweep_report(report)
    raise typer.Exit(sweep_exit(report))


def _only(items: list[str]) -> dict[str, list[str]]:
    """``--only KEY=VALUE`` options as {key: [values]}; a malformed one exits 2 naming it."""
    out_: dict[str, list[str]] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            fail(f"--only {item!r}: expected KEY=VALUE with KEY a sweep dimension (e.g. --only v_d=1e-3)")
        out_.setdefault(key.strip(), []).append(value.strip())
    return out_


def presets() -> None:
    """List the shipped presets by name: what each is for, its runs and its wall time on 2 cores."""
    files = preset_files()
    table = Table(title="slipchain presets (run by name: slipchain sweep NAME, slipchain mu-max NAME)")
    for col in ("name", "kind", "runs", "wall on 2 cores", "purpose"):
        table.add_column(col, justify="right" if col == "runs" else "left")
    for name in sorted(files, key=lambda n: (CATALOGUE[n].kind != "study", CATALOGUE[n].kind, n)):
        s = CATALOGUE[name]
        short = name.removeprefix("fig6-")
        alias = f" (reproduce --preset {short})" if short in PRESETS else ""
        table.add_row(name + alias, "validation campaign" if s.kind == "validation" else s.kind, str(s.runs),
                      s.wall_2_cores, s.purpose)
    out.print(table)


def status(
    store: Annotated[Path, typer.Option("--store", help="A sweep store (slipchain sweep --store), or a mu-max output "
                                        "directory (slipchain mu-max --out: each of its rounds); safe to read while it runs.")],
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object instead of the tables.")] = False,
) -> None:
    """Where a sweep store stands: each member stored (and what it found), in flight (how far its checkpoint has got,
    at what wall time, how fast it moves now), failed or pending, and whether a driver runs it now. Reads only."""
    from ..sweeps.status import driver_status, store_status
    from ..sweeps.store import DEFINITION
    from ..workflows.dead_weight import ROUNDS

    rounds = store / ROUNDS
    if store.is_dir() and not (store / DEFINITION).is_file() and not rounds.is_dir():
        fail(f"--store {str(store)!r}: neither a slipchain sweep store (no {DEFINITION} in it) nor a mu-max output "
             f"directory (no {ROUNDS}/ in it); expected a directory written by slipchain sweep or slipchain mu-max")
    try:
        if (store / DEFINITION).is_file() or not rounds.is_dir():
            found = [store_status(store)]
        else:  # a mu-max bisection: one store per round, in the order they were made
            found = [store_status(p) for p in sorted((q for q in rounds.iterdir() if (q / DEFINITION).is_file()),
                                                     key=lambda q: ((q / DEFINITION).stat().st_mtime, q.name))]
    except SweepError as e:
        fail(str(e))
    if as_json:
        if len(found) == 1 and not rounds.is_dir():
            sys.stdout.write(found[0].to_json() + "\n")
        else:
            sys.stdout.write(json.dumps({"path": str(store), "driver": driver_status(store),
                                         "rounds": [f.to_dict() for f in found]}, indent=1, default=str) + "\n")
        return
    for st in found:
        _print_status(st)
    if rounds.is_dir():
        out.print(f"mu-max output {str(store)!r}: {len(found)} rounds. Bisection driver: {driver_status(store)}.",
                  markup=False, highlight=False, soft_wrap=True)


def _print_status(st) -> None:
    from ..sweeps.status import IN_FLIGHT

    table = Table(title=f"slipchain status: {st.path} (sweep {st.sweep!r})")
    for col in ("member", "state", "t / t_max (s)", "wall (s)", "wall/sim", "outcome, message"):
        table.add_column(col, overflow="fold", justify="right" if col.startswith(("t ", "wall")) else "left")
    for m in st.members:
        t = "" if m.t_simulated is None else f"{m.t_simulated:.4g} / {m.t_max:g}"
        wall = "" if m.wall_time_s is None else f"{m.wall_time_s:,.0f}"
        rate = (f"{m.wall_time_s / m.t_simulated:,.0f}" if m.wall_time_s is not None and m.t_simulated else "")
        said = ", ".join(x for x in (m.outcome or (m.status if m.status != Status.COMPLETED else None), m.message) if x)
        if m.velocity is not None and m.velocity == m.velocity:  # (not nan)
            said = f"<X> moves at {m.velocity:.3g} m/s" + (f"; {said}" if said else "")
        table.add_row(m.label or "(single run)", m.state, t, wall, rate, said if len(said) <= 48 else said[:47] + "…")
    out.print(table)
    counts = ", ".join(f"{n} {k}" for k, n in st.counts().items() if n)
    out.print(f"{len(st.members)} members: {counts}. Driver: {st.driver}.", markup=False, highlight=False, soft_wrap=True)
    written = sorted(m.written for m in st.members if m.state == IN_FLIGHT and m.written)
    if written:
        out.print(f"Checkpoints written {written[0]}" + (f" to {written[-1]}" if written[-1] != written[0] else "") +
                  " (wall/sim: wall seconds per simulated second so far; <X>: the upper layer, the tester's top, over the last "
                  "10 ms; --json: member ids, messages in full).",
                  markup=False, highlight=False, soft_wrap=True)
    for m in st.members:
        if m.rules:
            out.print(f"{m.label or '(single run)'}: the stop rules (stop_at_runaway, stop_when_held) on its record so far: "
                      f"{m.rules}", markup=False, highlight=False, soft_wrap=True)
    if st.stray_checkpoints:
        out.print(f"{len(st.stray_checkpoints)} checkpoint(s) of no member of this sweep (batched differently; the "
                  f"next slipchain sweep prunes them): {', '.join(st.stray_checkpoints)}", markup=False, soft_wrap=True)
    for reason in st.unreadable_checkpoints:
        out.print(f"unreadable: {reason}", markup=False, highlight=False, soft_wrap=True)


def _dry_run(definition: Path, store: Path, reuse: list[Path], only: dict[str, list[str]]) -> None:
    from ..engine.memory import estimate_bytes
    from ..sweeps.store import Store, reuse_source

    try:
        sw = load_sweep_definition(definition)
        st = Store.open(store, sw, create=False)
        others = [reuse_source(p, store) for p in reuse]
        selected = sw.selection(only)
    except SweepError as e:
        fail(str(e))
    done = st.completed_ids()
    pending = {m.id for m in st.pending()}
    copied = set().union(*(pending & Store.open(o).completed_ids() for o in others))
    pending -= copied  # --reuse copies every member it can, selected or not
    left = 0
    if selected is not None:
        left = len(pending - selected)
        pending &= selected
    largest = max(sw.members, key=lambda m: estimate_bytes(m.config))
    copies = f"{len(copied)} would be copied from --reuse, " if reuse else ""
    later = f" ({left} pending outside --only left for later)" if selected is not None else ""
    out.print(f"sweep {sw.name!r}: {len(sw.members)} members over {', '.join(sw.dims) or 'no dimension'}; "
              f"{sum(m.id in done for m in sw.members)} already in {store}, {copies}{len(pending)} would run{later}. "
              f"Largest member: {largest.label()}, about {estimate_bytes(largest.config) / 2**20:,.0f} MiB. "
              "Dry run: nothing computed or written.", markup=False, highlight=False, soft_wrap=True)


def print_sweep_report(report: SweepReport, console: Console | None = None) -> None:
    """The end-of-sweep table: what ran, what was skipped, what failed and why."""
    console = console or out
    for note in report.notes:
        console.print(f"note: {note}", markup=False, highlight=False, soft_wrap=True)
    table = Table(title=f"slipchain sweep: {report.store}")
    table.add_column("members")
    table.add_column("count", justify="right")
    completed = [o for o in report.ran if o.status == Status.COMPLETED]
    table.add_row("ran, completed", str(len(completed)))
    table.add_row("ran, failed", str(len(report.failed)))
    table.add_row("skipped (already in the store)", str(len(report.skipped) - len(report.reused)))
    if report.reused:
        table.add_row("copied from --reuse stores", str(len(report.reused)))
    if report.quarantined:
        table.add_row("quarantined (unreadable file, rerun)", str(len(report.quarantined)))
    if report.deselected:
        table.add_row("left pending (outside --only)", str(report.deselected))
    table.add_row("not run" + (" (interrupted)" if report.interrupted else ""), str(report.not_run))
    table.add_row("total", str(report.total))
    table.add_row("wall time", f"{report.wall_time_s:.1f} s")
    console.print(table)
    if report.failed:
        ft = Table(title="failed members (rerun on the next invocation)")
        for col in ("member", "status", "reason"):
            ft.add_column(col, overflow="fold")
        for o in report.failed:
            ft.add_row(o.member.label(), o.status, o.message)
        console.print(ft)
    if report.quarantined:
        qt = Table(title=f"unreadable member files moved to {report.store / 'quarantine'} (their members were rerun)")
        for col in ("member id", "reason"):
            qt.add_column(col, overflow="fold")
        for mid, reason in report.quarantined:
            qt.add_row(mid, reason)
        console.print(qt)


def reproduce(
    preset: Annotated[Preset, typer.Option("--preset", help="quick (60 runs), paper (Fig. 6 in full), fold (the fold integrator's convergence table), eps1 (Fig. 6 at epsilon = 1), eps1-check, eps01 and adaptive (its convergence checks).")] = Preset.QUICK,
    store: Annotated[Optional[Path], typer.Option("--store", help="Store directory (default results/fig6-PRESET/store).")] = None,
    out_dir: Annotated[Optional[Path], typer.Option("--out", help="Figures and report (default results/fig6-PRESET).")] = None,
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    dashboard: DashboardOpt = False,
    backend: BackendOpt = BackendName.CPU,
) -> None:
    """The main job: the Fig. 6 sweep (resumable), Figs. 5 and 6, and report.md with the paper's claims."""
    from ..workflows.reproduce import reproduce as reproduce_job  # (figures and report: imported when used)

    command = " ".join(["slipchain", "reproduce", *sys.argv[2:]]) if len(sys.argv) > 1 else ""
    try:
        result = reproduce_job(preset, store, out_dir, scheduler=scheduler, n_workers=workers, progress=progress,
                               command=command, backend=backend, announce=announce_dashboard(dashboard))
    except StoreWriteError as e:
        fail(str(e), code=1)
    except SweepError as e:
        fail(str(e))
    print_sweep_report(result.sweep)
    if result.report is not None:
        out.print(f"report: {result.report}")
        for p in result.figures:
            out.print(f"figure: {p}")
    raise typer.Exit(sweep_exit(result.sweep))


def mechanism(
    store: Annotated[Path, typer.Option("--store", help="Store of a completed Fig. 6-like sweep.")],
    duration: Annotated[float, typer.Option("--duration", min=1e-6, help="Field recording length, s.")] = 1e-2,
    interval: Annotated[float, typer.Option("--interval", min=1e-9, help="Sampling interval of u_i(t), s.")] = 1e-6,
    force: Annotated[bool, typer.Option("--force", help="Redo analyses already in the store.")] = False,
    backend: BackendOpt = BackendName.CPU,
) -> None:
    """Field recordings, slip events and spectra of the lowest and highest theta at each v_d (into STORE/mechanism/)."""
    from ..workflows.mechanism import analyse_store  # (scipy's signal processing: imported when used)

    try:
        analyse_store(store, duration=duration, interval=interval, force=force, backend=backend,
                      on_member=lambda a: out.print(f"{'kept' if a.kept else 'wrote'} {a.path} ({a.member.label()})"))
    except (SweepError, ValueError, FloatingPointError) as e:
        fail(str(e))

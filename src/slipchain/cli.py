"""Command-line interface.

* ``slipchain run [CONFIG.toml] [--set name=value ...] [--out FILE.nc] [--json]``: one run.
* ``slipchain sweep SWEEP.toml --store PATH [--scheduler ADDRESS] [--workers N]``: a sweep on Dask.
* ``slipchain figure fig5 --out DIR`` and ``slipchain figure fig6 --store PATH --out DIR``.
* ``slipchain reproduce [--preset quick|paper] [--store PATH] [--out DIR]``: the main job.

Exit codes: 0 completed; 1 diverged or some members failed (results are still written, with
their messages); 2 rejected input (nothing written); 130 interrupted (finished work is kept).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Optional

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from .config import ConfigError, load_config
from .io import write_dataset, write_text_atomic
from .runner import SweepReport, run_sweep
from .simulation import COMPLETED, DIVERGED, INTERRUPTED, simulate, summary
from .sweep import PRESETS, SweepError, load_sweep_definition
from .system import build_system

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="The two-chain multi-contact friction model of Braun et al., EPL 113, 56002 (2016).")
err = Console(stderr=True)

EXIT_CODES = {COMPLETED: 0, DIVERGED: 1, INTERRUPTED: 130}


@app.callback()
def _main() -> None:
    """slipchain: simulate, sweep and plot the multi-contact friction model."""


@app.command()
def run(
    config: Annotated[Optional[Path], typer.Argument(help="TOML file with parameters (MODEL.md names, SI units).")] = None,
    set_: Annotated[list[str], typer.Option("--set", help="Override one parameter: name=value (repeatable).")] = [],
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the result Dataset to this NetCDF file.")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object with the headline numbers.")] = False,
    progress: Annotated[Optional[bool], typer.Option("--progress/--no-progress", help="Progress bar (default: on a terminal).")] = None,
    backend: Annotated[Optional[str], typer.Option("--backend", help="cpu, gpu or auto (overrides the config's backend).")] = None,
) -> None:
    """Run one realisation of the model and report mu_star with its standard error."""
    try:
        cfg = load_config(config, [*set_, *([f'backend="{backend}"'] if backend else [])])
    except ConfigError as e:
        err.print(f"error: {e}", markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(2)
    try:
        ds = simulate(build_system(cfg), progress=progress)
    except RuntimeError as e:  # e.g. backend 'gpu' without a GPU
        _fail(str(e))
    if out is not None:
        write_dataset(ds, out)
    info = summary(ds)
    if as_json:
        sys.stdout.write(json.dumps(info) + "\n")
    else:
        _print_summary(info, out)
    if info["status"] != COMPLETED:
        err.print(f"{info['status']}: {info['message']}", markup=False, highlight=False, soft_wrap=True)
    elif info["message"]:
        err.print(f"note: {info['message']}", markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(EXIT_CODES.get(info["status"], 1))


def _print_summary(info: dict, out: Path | None) -> None:
    table = Table(title="slipchain run", show_header=False)
    mu, sem = info["mu_star"], info["mu_star_sem"]
    table.add_row("mu_star", "n/a" if mu is None else f"{mu:.4f} ± {sem if sem is not None else float('nan'):.4f}")
    for key in ("theta", "n_contacts", "N", "v_d", "eta_c", "epsilon", "seed", "dt", "t_total", "t_transient", "steps",
                "wall_time_s", "status"):
        v = info[key]
        table.add_row(key, f"{v:.4g}" if isinstance(v, float) else str(v))
    if "velocity" in info:
        v, e = info["velocity"], info.get("velocity_sem")
        table.add_row("dead-weight velocity", f"{info['velocity_status']}" + ("" if v is None else f": {v:.5g} ± {e:.2g} m/s"))
    if out is not None:
        table.add_row("written to", str(out))
    Console().print(table)


def _fail(message: str) -> None:
    err.print(f"error: {message}", markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(2)


WorkersOpt = Annotated[Optional[int], typer.Option("--workers", min=1, help="Local cluster size (default: one process per core).")]
SchedulerOpt = Annotated[Optional[str], typer.Option("--scheduler", help="Address of an existing Dask scheduler, e.g. tcp://host:8786.")]
BackendOpt = Annotated[Optional[str], typer.Option("--backend", help="cpu, gpu or auto (overrides the config's backend).")]
ProgressOpt = Annotated[Optional[bool], typer.Option("--progress/--no-progress", help="Progress bar (default: on a terminal).")]


@app.command()
def sweep(
    definition: Annotated[Path, typer.Argument(help="Sweep TOML: [base] config plus [[grid]] tables of value lists.")],
    store: Annotated[Path, typer.Option("--store", help="Store directory (created; rerun to resume).")],
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    backend: BackendOpt = None,
    batch_size: Annotated[Optional[int], typer.Option("--batch-size", min=1, help="Members per task, advanced together (default 1; 256 on the GPU).")] = None,
) -> None:
    """Run every member of a sweep on Dask, writing each to the store as it finishes; resumes."""
    if backend not in (None, "cpu", "gpu", "auto"):
        _fail(f"option --backend has value {backend!r}; expected one of cpu, gpu, auto")
    try:
        sw = load_sweep_definition(definition)
        report = run_sweep(sw, store, scheduler=scheduler, n_workers=workers, progress=progress, backend=backend,
                           batch_size=batch_size)
    except SweepError as e:
        _fail(str(e))
    print_sweep_report(report)
    raise typer.Exit(_sweep_exit(report))


def _sweep_exit(report: SweepReport) -> int:
    return 130 if report.interrupted else (0 if report.ok else 1)


def print_sweep_report(report: SweepReport, console: Console | None = None) -> None:
    """The end-of-sweep table: what ran, what was skipped, what failed and why."""
    console = console or Console()
    table = Table(title=f"slipchain sweep: {report.store}")
    table.add_column("members")
    table.add_column("count", justify="right")
    completed = [o for o in report.ran if o.status == COMPLETED]
    table.add_row("ran, completed", str(len(completed)))
    table.add_row("ran, failed", str(len(report.failed)))
    table.add_row("skipped (already in the store)", str(len(report.skipped)))
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


def _wrote(paths) -> None:
    for p in paths:
        Console().print(f"wrote {p}")


def _sweep_dataset(store: Path, needs: set[str], what: str):
    """The sweep Dataset of a store that sweeps at least ``needs`` (clear error and exit 2 otherwise)."""
    from .store import Store

    try:
        ds = Store.open(store).dataset()
    except SweepError as e:
        _fail(str(e))
    if not needs <= set(ds.dims):
        _fail(f"store {str(store)!r} sweeps {list(ds.dims)}; {what} needs {', '.join(sorted(needs))}")
    return ds


figure_app = typer.Typer(no_args_is_help=True, help="Draw the paper's figures from datasets (PNG and PDF).")
app.add_typer(figure_app, name="figure")


@figure_app.command("fig5")
def figure_fig5(
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
    config: Annotated[Optional[Path], typer.Option("--config", help="Base config TOML (default: the paper's).")] = None,
    seed: Annotated[int, typer.Option("--seed", help="Disorder of the N = 1001 contact average.")] = 0,
) -> None:
    """Fig. 5: eq. (1) for eta_c = 0, omega0, 0.3 omega0, 0.1 omega0 and the contact average (N = 1001, theta = 1)."""
    from .figures import contact_law_dataset, plot_fig5

    try:
        cfg = load_config(config)
    except ConfigError as e:
        _fail(str(e))
    _wrote(plot_fig5(contact_law_dataset(cfg, seed=seed), out))


@figure_app.command("fig6")
def figure_fig6(
    store: Annotated[Path, typer.Option("--store", help="Store of a Fig. 6 sweep (theta, eta_c, v_d; N, seed optional).")],
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
) -> None:
    """Fig. 6: mu_star versus theta, three eta_c, two v_d, N = 1001 stars, the dashed line."""
    from .figures import plot_fig6

    ds = _sweep_dataset(store, {"theta", "eta_c", "v_d"}, "fig6")
    _wrote(plot_fig6(ds, out))


@figure_app.command("tester")
def figure_tester(
    runs: Annotated[Path, typer.Option("--runs", help="Output directory of `slipchain tester analyze` (its runs.csv).")],
    store: Annotated[Optional[Path], typer.Option("--store", help="Sweep store with a v_d dimension (model curves).")] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Output directory (default: the --runs directory).")] = None,
) -> None:
    """Measured mu(v) with the model's mu_star(v_d) curves, one fitted scale factor per surface."""
    import pandas as pd

    from .tester.plots import plot_model_vs_experiment

    table_path = runs / "runs.csv"
    if not table_path.exists():
        _fail(f"{table_path} does not exist; run `slipchain tester analyze ... --out {runs}` first")
    sweep_ds = _sweep_dataset(store, {"v_d"}, "a model curve") if store is not None else None
    _wrote(plot_model_vs_experiment(pd.read_csv(table_path), sweep_ds, out or runs))


@figure_app.command("mechanism")
def figure_mechanism(
    store: Annotated[Path, typer.Option("--store", help="Store of a Fig. 6-like sweep, analysed by `slipchain mechanism`.")],
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
) -> None:
    """Stick-slip fraction versus theta, per-contact forces, event sizes and spectra; mechanism.md with the numbers."""
    from .figures import plot_mechanism
    from .mechanism import load_mechanism, mechanism_summary, stick_slip_dataset
    from .store import Store

    try:
        st = Store.open(store)
        analyses = load_mechanism(st)
    except (SweepError, FileNotFoundError) as e:
        _fail(str(e))
    ss = stick_slip_dataset(st)
    paths = plot_mechanism(ss, analyses, out)
    report = write_text_atomic(out / "mechanism.md", mechanism_summary(ss, analyses) + "\n" + "\n".join(
        f"![{p.name}]({p.name})" for p in paths if p.suffix == ".png") + "\n")
    _wrote([*paths, report])


@figure_app.command("velocity")
def figure_velocity(
    store: Annotated[Path, typer.Option("--store", help="Store of a sweep over v_d (e.g. presets/velocity.toml).")],
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
) -> None:
    """mu_star versus v_d on a log axis, one curve per theta (the model's Figs. 2 and 3)."""
    from .figures import plot_velocity

    _wrote(plot_velocity(_sweep_dataset(store, {"v_d"}, "the velocity figure"), out))


@figure_app.command("epsilon")
def figure_epsilon(
    store: Annotated[Path, typer.Option("--store", help="Store of a sweep over epsilon and theta (presets/epsilon.toml).")],
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
) -> None:
    """mu_star versus theta for each epsilon, and the drop from the smallest theta to the largest."""
    from .figures import epsilon_table, plot_epsilon

    ds = _sweep_dataset(store, {"epsilon", "theta"}, "the epsilon figure")
    _wrote(plot_epsilon(ds, out))
    avg = epsilon_table(ds)
    for eps in avg["epsilon"].values:
        cur = avg.sel(epsilon=eps).dropna("theta", subset=["mu"])
        if cur.sizes["theta"] >= 2:
            a, b = cur.isel(theta=0), cur.isel(theta=-1)
            r = float(b["mu"] / a["mu"])
            e = r * float(np.hypot(a["err"] / a["mu"], b["err"] / b["mu"]))
            Console().print(f"epsilon = {eps:g}: mu_star {float(a['mu']):.4f} ± {float(a['err']):.4f} at theta = "
                            f"{float(a['theta']):g} -> {float(b['mu']):.4f} ± {float(b['err']):.4f} at theta = "
                            f"{float(b['theta']):g}; ratio {r:.3f} ± {e:.3f}")


@figure_app.command("dead-weight")
def figure_dead_weight(
    store: Annotated[Path, typer.Option("--store", help="Store of a sweep over dead_weight (e.g. presets/dead-weight.toml).")],
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
) -> None:
    """Applied mu_star against the measured steady velocity per theta (runaways at the right edge)."""
    from .figures import plot_dead_weight

    ds = _sweep_dataset(store, {"dead_weight"}, "the dead-weight figure")
    _wrote(plot_dead_weight(ds, out))


@app.command()
def mechanism(
    store: Annotated[Path, typer.Option("--store", help="Store of a completed Fig. 6-like sweep.")],
    duration: Annotated[float, typer.Option("--duration", min=1e-6, help="Field recording length, s.")] = 1e-2,
    interval: Annotated[float, typer.Option("--interval", min=1e-9, help="Sampling interval of u_i(t), s.")] = 1e-6,
    force: Annotated[bool, typer.Option("--force", help="Redo analyses already in the store.")] = False,
) -> None:
    """Field recordings, slip events and spectra of the lowest and highest theta at each v_d (into STORE/mechanism/)."""
    from .mechanism import MECHANISM, analyse_member, mechanism_members
    from .store import Store

    try:
        st = Store.open(store)
        members = mechanism_members(st)
    except SweepError as e:
        _fail(str(e))
    for m in members:
        path = st.path / MECHANISM / f"{m.id}.nc"
        if path.exists() and not force:
            Console().print(f"kept {path} ({m.label()})")
            continue
        try:
            analyse_member(st, m, duration=duration, interval=interval)
        except (ValueError, FloatingPointError) as e:
            _fail(f"{m.label()}: {e}")
        Console().print(f"wrote {path} ({m.label()})")


tester_app = typer.Typer(no_args_is_help=True, help="The paper's friction-tester experiment: analysis and synthetic data.")
app.add_typer(tester_app, name="tester")


@tester_app.command("analyze")
def tester_analyze(
    runs_csv: Annotated[Path, typer.Argument(help="Runs table (CSV).")],
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
    traces: Annotated[Optional[Path], typer.Option("--traces", help="Raw distance traces (CSV, long format).")] = None,
) -> None:
    """Steady velocity per trace, mu and p0 with uncertainties, maxima per pressure, the load test."""
    from .tester import TesterDataError, analyze

    try:
        result = analyze(runs_csv, traces, out)
    except TesterDataError as e:
        _fail(str(e))
    counts = result.runs["status"].value_counts().to_dict()
    table = Table(title=f"slipchain tester analyze: {out}")
    table.add_column("status")
    table.add_column("runs", justify="right")
    for k, v in sorted(counts.items()):
        table.add_row(k, str(v))
    Console().print(table)
    for t in result.tests:
        holds = t.claim_holds
        Console().print(f"{', '.join(map(str, t.group))}: load claim "
                        f"{'not testable' if holds is None else 'supported' if holds else 'not supported'}")
    Console().print(f"wrote {', '.join(str(p) for p in result.files.values())}")


@tester_app.command("synth")
def tester_synth(
    out: Annotated[Path, typer.Option("--out", help="Output directory.")],
    seed: Annotated[int, typer.Option("--seed", help="Random seed (noise, run-to-run scatter).")] = 0,
    load_effect: Annotated[float, typer.Option("--load-effect", help="Planted s: fractional fall of mu near its maximum per p_ref of pressure (0: none).")] = 0.15,
) -> None:
    """SYNTHETIC demo data: a simulated dead-weight tester (runs.csv, traces.csv, truth.csv, README.txt)."""
    from dataclasses import replace

    from .tester.synth import NOTICE, SynthSetup, write_synthetic

    setup = SynthSetup(seed=seed)
    paths = write_synthetic(out, replace(setup, law=replace(setup.law, s=load_effect)))
    err.print(NOTICE, markup=False, highlight=False, soft_wrap=True)
    Console().print(f"wrote {', '.join(str(p) for p in paths.values())}")


@app.command()
def reproduce(
    preset: Annotated[str, typer.Option("--preset", help=f"One of {', '.join(PRESETS)}.")] = "quick",
    store: Annotated[Optional[Path], typer.Option("--store", help="Store directory (default results/fig6-PRESET/store).")] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Figures and report (default results/fig6-PRESET).")] = None,
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    backend: BackendOpt = None,
) -> None:
    """The main job: the Fig. 6 sweep (resumable), Figs. 5 and 6, and report.md with the paper's claims."""
    from .reproduce import reproduce as _reproduce

    if preset not in PRESETS:
        _fail(f"option --preset has value {preset!r}; expected one of {', '.join(PRESETS)}")
    if backend not in (None, "cpu", "gpu", "auto"):
        _fail(f"option --backend has value {backend!r}; expected one of cpu, gpu, auto")
    command = " ".join(["slipchain", "reproduce", *sys.argv[2:]]) if len(sys.argv) > 1 else ""
    try:
        result = _reproduce(preset, store, out, scheduler=scheduler, n_workers=workers, progress=progress, command=command,
                            backend=backend)
    except SweepError as e:
        _fail(str(e))
    print_sweep_report(result.sweep)
    if result.report is not None:
        Console().print(f"report: {result.report}")
        for p in result.figures:
            Console().print(f"figure: {p}")
    raise typer.Exit(_sweep_exit(result.sweep))


def main() -> None:  # pragma: no cover - console entry point
    app()

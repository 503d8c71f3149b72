"""What the commands share: exit codes, the error console, options and their choices."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Annotated, NoReturn, Optional

import typer
from rich.console import Console

from ..engine import interrupts
from ..engine.backends import BackendName
from ..results.schema import Status
from ..sweeps.catalogue import find_study, missing_message
from ..sweeps.executor import SweepReport

err = Console(stderr=True)
out = Console()

# Exit codes: 0 completed; 1 diverged or some members failed (results are still written, with
# their messages); 2 rejected input (nothing written); 130 interrupted by Ctrl-C, 143 by SIGTERM
# (finished work is kept; :mod:`slipchain.engine.interrupts`).
EXIT_CODES = {Status.COMPLETED: 0, Status.DIVERGED: 1, Status.INTERRUPTED: 130}


def fail(message: str, code: int = 2) -> NoReturn:
    """The message on stderr as one ``error:`` line, then exit ``code`` (2: rejected input)."""
    err.print(f"error: {message}", markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def study_path(given: Path, what: str) -> Path:
    """A file as given, else the shipped preset of that name (:func:`~slipchain.sweeps.catalogue.find_study`);
    exit 2 naming ``what`` and the shipped names if neither."""
    found = find_study(given)
    if found is None:
        fail(missing_message(what, given))
    return found


def show_warnings() -> None:
    """Print slipchain's own warnings (SweepWarning: an unreadable member left out, ...) as one
    ``warning:`` line on stderr, without Python's source line; other warnings as Python shows them."""
    from ..sweeps.definition import SweepWarning

    default = warnings.showwarning
    if getattr(default, "slipchain", False):  # installed already (several commands in one process)
        return

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, SweepWarning):
            err.print(f"warning: {message}", markup=False, highlight=False, soft_wrap=True)
        else:
            default(message, category, filename, lineno, file, line)

    show.slipchain = True
    warnings.showwarning = show


def wrote(paths) -> None:
    for p in paths:
        out.print(f"wrote {p}")


def sweep_exit(report: SweepReport) -> int:
    return interrupts.exit_code() if report.interrupted else (0 if report.ok else 1)


def status_exit(status: Status) -> int:
    """The exit code of a run's status: :data:`EXIT_CODES`, 143 for a run interrupted by SIGTERM."""
    return interrupts.exit_code() if status == Status.INTERRUPTED else EXIT_CODES.get(status, 1)


BatchSizeOpt = Annotated[Optional[int], typer.Option("--batch-size", min=1, help="Runs per task, advanced together (default 1; 256 on the GPU): one kernel launch, or for slab runs one FFT per step.")]
WorkersOpt = Annotated[Optional[int], typer.Option("--workers", min=1, help="Local cluster size (default: one process per core).")]
SchedulerOpt = Annotated[Optional[str], typer.Option("--scheduler", help="Address of an existing Dask scheduler, e.g. tcp://host:8786.")]
BackendOpt = Annotated[BackendName, typer.Option("--backend", help="Where to compute: cpu, gpu (numba.cuda) or auto (the GPU if one is found).")]
DashboardOpt = Annotated[bool, typer.Option("--dashboard", help="Print the address of the Dask dashboard (on 127.0.0.1 for the local cluster) when the cluster starts.")]


def announce_dashboard(wanted: bool):
    """The ``announce`` callback of ``--dashboard``: one ``dashboard:`` line on stderr, else None."""
    if not wanted:
        return None
    return lambda link: err.print(f"dashboard: {link}", markup=False, highlight=False, soft_wrap=True)


ProgressOpt = Annotated[Optional[bool], typer.Option("--progress/--no-progress", help="Progress bar (default: on a terminal).")]

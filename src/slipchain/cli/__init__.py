"""The command line: one module per command group; each command parses, calls one library function, prints.

* ``slipchain run [CONFIG.toml] [--set name=value ...] [--out FILE.nc] [--json] [--backend cpu|gpu|auto]``: one run.
* ``slipchain sweep SWEEP.toml|NAME --store PATH [--scheduler ADDRESS] [--workers N] [--backend ...] [--dry-run]``:
  a sweep on Dask (NAME: a shipped preset, ``slipchain presets`` lists them).
* ``slipchain status --store PATH [--json]``: where a sweep store stands (stored, in flight with its checkpoint's
  simulated and wall time, failed, pending; the driver running it), read beside a running sweep.
* ``slipchain reproduce [--preset quick|paper|fold|eps1|eps1-check|eps01|adaptive] [--store PATH] [--out DIR]``: the main job.
* ``slipchain mu-max [PLAN.toml|NAME] --out DIR [--dry-run]``: mu_max(theta) under a dead weight by bisection.
* ``slipchain presets``: the shipped presets and plans by name, with their purpose, runs and wall time.
* ``slipchain mechanism --store PATH``; ``slipchain figure ...`` (``slipchain figure --help`` lists the figures);
  ``slipchain tester analyze|synth|fit``.
* ``slipchain material show [CONFIG.toml] [--T C ...] --out DIR``: the viscoelastic compound's E', E'', tan delta;
  ``slipchain material fit MASTER.csv --T-ref C --out DIR``: Prony terms fitted to a master curve (pyvisco).

Exit codes: 0 completed; 1 diverged or some members failed (results are still written, with
their messages); 2 rejected input (nothing written); 130 interrupted by Ctrl-C, 143 by SIGTERM
(a batch scheduler's time limit: handled as Ctrl-C; finished work and checkpoints are kept).
"""

from __future__ import annotations

from typing import Annotated

import typer

from ..engine.interrupts import sigterm_as_interrupt
from .common import EXIT_CODES, show_warnings
from .dead_weight import mu_max
from .figure import figure_app
from .material import material_app
from .run import run
from .sweep import mechanism, presets, print_sweep_report, reproduce, status, sweep
from .tester import tester_app

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="The two-chain multi-contact friction model of Braun et al., EPL 113, 56002 (2016).")


def _version(value: bool) -> None:
    if value:
        from .._version import __version__

        typer.echo(f"slipchain {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[bool, typer.Option("--version", callback=_version, is_eager=True,
                                          help="Print the version and exit.")] = False,
) -> None:
    """slipchain: simulate, sweep and plot the multi-contact friction model."""
    show_warnings()
    sigterm_as_interrupt()  # SIGTERM as Ctrl-C: message, checkpoints, exit 143


app.command()(run)
app.command()(sweep)
app.command()(status)
app.add_typer(figure_app, name="figure")
app.command()(mechanism)
app.add_typer(tester_app, name="tester")
app.add_typer(material_app, name="material")
app.command()(reproduce)
app.command("mu-max")(mu_max)
app.command()(presets)


def main() -> None:  # pragma: no cover - console entry point
    app()


__all__ = ["EXIT_CODES", "app", "main", "print_sweep_report"]

"""Command-line interface: ``slipchain run [CONFIG.toml] [--set name=value ...] [--out FILE.nc] [--json]``.

Exit codes: 0 completed; 1 diverged (the result is still written, with its message);
2 rejected configuration (nothing written); 130 interrupted (the partial result is written).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console
from rich.table import Table

from .config import ConfigError, load_config
from .io import write_dataset
from .simulation import COMPLETED, DIVERGED, INTERRUPTED, simulate, summary
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
) -> None:
    """Run one realisation of the model and report mu_star with its standard error."""
    try:
        cfg = load_config(config, set_)
    except ConfigError as e:
        err.print(f"error: {e}", markup=False, highlight=False, soft_wrap=True)
        raise typer.Exit(2)
    ds = simulate(build_system(cfg), progress=progress)
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
    if out is not None:
        table.add_row("written to", str(out))
    Console().print(table)


def main() -> None:  # pragma: no cover - console entry point
    app()

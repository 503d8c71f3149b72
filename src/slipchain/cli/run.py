"""``slipchain run``: one realisation, its headline numbers, optionally its Dataset."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.table import Table

from ..engine.backends import BackendName
from ..engine.simulate import run as run_model
from ..model.config import ConfigError, load_config
from ..results.io import write_dataset
from ..results.schema import Status, summary
from .common import EXIT_CODES, BackendOpt, ProgressOpt, err, fail, out


def run(
    config: Annotated[Optional[Path], typer.Argument(help="TOML file with parameters (MODEL.md names, SI units).")] = None,
    set_: Annotated[list[str], typer.Option("--set", help="Override one parameter: name=value (repeatable).")] = [],
    out_path: Annotated[Optional[Path], typer.Option("--out", help="Write the result Dataset to this NetCDF file.")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object with the headline numbers.")] = False,
    progress: ProgressOpt = None,
    backend: BackendOpt = BackendName.CPU,
) -> None:
    """Run one realisation of the model and report mu_star with its standard error."""
    try:
        cfg = load_config(config, set_)
    except ConfigError as e:
        fail(str(e))
    try:
        ds = run_model(cfg, backend=backend, progress=progress)
    except RuntimeError as e:  # e.g. backend 'gpu' without a GPU
        fail(str(e))
    if out_path is not None:
        write_dataset(ds, out_path)
    info = summary(ds)
    if as_json:
        sys.stdout.write(json.dumps(info) + "\n")
    else:
        _print_summary(info, out_path)
    if info["status"] != Status.COMPLETED:
        err.print(f"{info['status']}: {info['message']}", markup=False, highlight=False, soft_wrap=True)
    elif info["message"]:
        err.print(f"note: {info['message']}", markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(EXIT_CODES.get(info["status"], 1))


def _print_summary(info: dict, path: Path | None) -> None:
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
    if path is not None:
        table.add_row("written to", str(path))
    out.print(table)

"""``slipchain run``: one realisation, its headline numbers, optionally its Dataset."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.table import Table

from ..engine.backends import BackendName
from ..engine.checkpoint import CHECKPOINT_EVERY, CheckpointError, simulated_time
from ..engine.memory import check_memory
from ..engine.simulate import run as run_model
from ..model.config import ConfigError, load_config
from ..results.io import write_dataset
from ..results.schema import Status, summary
from .common import BackendOpt, ProgressOpt, err, fail, out, status_exit


def run(
    config: Annotated[Optional[Path], typer.Argument(help="TOML file with parameters (docs/model.md names, SI units).")] = None,
    set_: Annotated[list[str], typer.Option("--set", help="Override one parameter: name=value (repeatable).")] = [],
    out_path: Annotated[Optional[Path], typer.Option("--out", help="Write the result Dataset to this NetCDF file.")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object with the headline numbers.")] = False,
    progress: ProgressOpt = None,
    backend: BackendOpt = BackendName.CPU,
    checkpoint: Annotated[Optional[Path], typer.Option(
        "--checkpoint", help="Keep the run's full state in this file (written atomically); if it exists, resume "
        "from it (bit for bit). Removed once the run has finished and its result is written.")] = None,
    checkpoint_every: Annotated[float, typer.Option(
        "--checkpoint-every", min=0.0, help="Wall-clock seconds between checkpoints (0: after every chunk).")] = CHECKPOINT_EVERY,
    dry_run: Annotated[bool, typer.Option("--dry-run", help="Check the config (and that the run fits in memory), print "
                                          "it, and stop: nothing is run or written.")] = False,
) -> None:
    """Run one realisation of the model and report mu_star with its standard error."""
    try:
        cfg = load_config(config, set_)
        if dry_run:
            need = check_memory([cfg])
    except ConfigError as e:
        fail(str(e))
    if dry_run:
        length = f"t_total = {cfg.t_total:g} s" if cfg.t_total is not None else f"automatic length, at most {cfg.t_max:g} s"
        shape = f"N = {cfg.N}" if cfg.geometry == "chain" else f"{cfg.geometry} N x Ly = {cfg.N} x {cfg.Ly}"
        out.print(f"valid config: {shape}, {cfg.n_contacts} contacts, {length}, dt = {cfg.dt:g} s; about "
                  f"{need / 2**20:,.0f} MiB of memory. Dry run: nothing run or written.", markup=False, highlight=False,
                  soft_wrap=True)
        sys.stdout.write(cfg.to_toml())
        return
    if checkpoint is not None and checkpoint.exists():
        err.print(f"resuming from checkpoint {checkpoint} (t = {simulated_time(checkpoint):.6g} s simulated)",
                  markup=False, highlight=False, soft_wrap=True)
    try:
        ds = run_model(cfg, backend=backend, progress=progress, checkpoint=checkpoint, checkpoint_every=checkpoint_every)
    except (RuntimeError, CheckpointError, ConfigError) as e:  # backend 'gpu' without a GPU; another run's
        # checkpoint; a run too large for the memory (MemoryEstimateError)
        fail(str(e))
    if out_path is not None:
        try:
            write_dataset(ds, out_path)
        except OSError as e:  # a full disk: one line, no partial file; the checkpoint, if any, is kept
            keep = (f"the checkpoint {checkpoint} is kept: free space and run the same command to resume"
                    if checkpoint is not None else "free space and run again")
            fail(f"could not write {out_path}: {e.strerror or e}; no partial file is left; {keep}", code=1)
    info = summary(ds)
    if checkpoint is not None:
        if info["status"] == Status.INTERRUPTED:
            err.print(f"the checkpoint {checkpoint} is kept: run the same command to resume", markup=False,
                      highlight=False, soft_wrap=True)
        else:  # finished, and its result is written (or printed): the state is no longer needed
            checkpoint.unlink(missing_ok=True)
    if as_json:
        sys.stdout.write(json.dumps(info) + "\n")
    else:
        _print_summary(info, out_path)
    if info["status"] != Status.COMPLETED:
        err.print(f"{info['status']}: {info['message']}", markup=False, highlight=False, soft_wrap=True)
    elif info["message"]:
        err.print(f"note: {info['message']}", markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(status_exit(info["status"]))


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

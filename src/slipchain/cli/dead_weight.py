"""``slipchain mu-max``: the largest dead weight with steady sliding, per theta and seed (issue 14)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.table import Table

from ..model.config import ConfigError, load_config
from .common import BackendName, BackendOpt, WorkersOpt, fail, out, wrote


def mu_max(
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory (mu_max.csv, mu_max_summary.csv, cache/).")],
    config: Annotated[Optional[Path], typer.Argument(help="Base config TOML (give t_total: the length of each dead-weight run).")] = None,
    set_: Annotated[list[str], typer.Option("--set", help="Override one base parameter: name=value (repeatable).")] = [],
    theta: Annotated[list[float], typer.Option("--theta", help="Load values (repeatable).")] = [0.1, 1.0],
    seeds: Annotated[int, typer.Option("--seeds", min=1, help="Realisations per theta (seeds 0..n-1).")] = 4,
    lo: Annotated[float, typer.Option("--lo", help="Applied mu_a known to give steady sliding.")] = 0.3,
    hi: Annotated[float, typer.Option("--hi", help="Applied mu_a known to run away.")] = 1.5,
    tol: Annotated[float, typer.Option("--tol", help="Resolution of mu_max.")] = 0.005,
    workers: WorkersOpt = None,
    backend: BackendOpt = BackendName.CPU,
) -> None:
    """mu_max(theta) under a dead weight by bisection over mu_a, on a local Dask cluster; resumable (OUT/cache)."""
    from ..workflows.dead_weight import BracketError, mu_max_summary, mu_max_table
    from ..workflows.tester import write_csv

    try:
        base = load_config(config, set_)
        for t in theta:
            base.with_updates(theta=t)  # every theta valid for this base, before anything runs
        if base.t_total is None:
            raise ConfigError("config key 't_total' is absent; expected the length of each dead-weight run (s), "
                              "e.g. --set t_total=0.05")
        table = mu_max_table(base, list(theta), list(range(seeds)), lo=lo, hi=hi, tol=tol, cache=out_dir / "cache",
                             n_workers=workers, backend=backend)
    except ConfigError as e:  # rejected before anything ran: nothing written
        fail(str(e))
    except BracketError as e:  # found by running: the runs are kept in OUT/cache for the next call
        fail(str(e), code=1)
    summary = mu_max_summary(table)
    wrote([write_csv(table, out_dir / "mu_max.csv"), write_csv(summary, out_dir / "mu_max_summary.csv")])
    t = Table(title="slipchain mu-max (seed means)")
    for col in ("theta", "mu_max", "ratio to theta_min", "seeds", "v_max (m/s)"):
        t.add_column(col, justify="right")
    for r in summary.itertuples():
        t.add_row(f"{r.theta:g}", f"{r.mu_max:.4f} ± {r.mu_max_se:.4f}",
                  f"{r.ratio_to_theta_min:.4f} ± {r.ratio_se:.4f}", str(r.seeds), f"{r.v_max_m_s:.3g}")
    out.print(t)
    undecided = table[table["status"] != "ok"]
    if len(undecided):
        out.print(f"{len(undecided)} realisation(s) undecided (no-steady): give a longer t_total", markup=False)
        raise typer.Exit(1)

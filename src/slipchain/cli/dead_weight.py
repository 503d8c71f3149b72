"""``slipchain mu-max``: the largest dead weight with steady sliding, per theta and seed (issue 14)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.table import Table

from ..engine import interrupts
from ..model.config import ConfigError
from .common import (BackendName, BackendOpt, BatchSizeOpt, DashboardOpt, ProgressOpt, SchedulerOpt, WorkersOpt, announce_dashboard,
                     fail, out, study_path, wrote)


def mu_max(
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory (mu_max.csv, mu_max_summary.csv, evaluations.csv, plan.toml; every run in rounds/, one sweep store per round).")],
    plan: Annotated[Optional[Path], typer.Argument(help="A mu-max plan ([base] config and [bisection] settings), the name of a shipped one (mu-max), or a flat base config.")] = None,
    set_: Annotated[list[str], typer.Option("--set", help="Override one base parameter: name=value (repeatable).")] = [],
    theta: Annotated[Optional[list[float]], typer.Option("--theta", help="Load values (repeatable). [default: plan's, else 0.1 and 1]")] = None,
    seeds: Annotated[Optional[int], typer.Option("--seeds", help="Realisations per theta (seeds 0..n-1). [default: plan's, else 4]")] = None,
    lo: Annotated[Optional[float], typer.Option("--lo", help="Applied mu_a known to give steady sliding. [default: plan's, else 0.3]")] = None,
    hi: Annotated[Optional[float], typer.Option("--hi", help="Applied mu_a known to run away. [default: plan's, else 1.5]")] = None,
    tol: Annotated[Optional[float], typer.Option("--tol", help="Resolution of mu_max. [default: plan's, else 0.005]")] = None,
    scheduler: SchedulerOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    dashboard: DashboardOpt = False,
    backend: BackendOpt = BackendName.CPU,
    batch_size: BatchSizeOpt = None,
    dry_run: Annotated[bool, typer.Option("--dry-run", help="Check the plan, say what it would bisect, and stop: "
                                          "nothing is run or written.")] = False,
) -> None:
    """mu_max(theta) under a dead weight by bisection over mu_a, each round a sweep on Dask; resumable (OUT/rounds)."""
    from ..sweeps.definition import SweepError
    from ..sweeps.executor import StoreWriteError
    from ..workflows.dead_weight import BracketError, load_plan, run_plan

    if plan is not None:
        plan = study_path(plan, "mu-max plan")
    try:
        the_plan = load_plan(plan, set_, theta=theta or None, seeds=seeds, lo=lo, hi=hi, tol=tol)
        if dry_run:
            out.print(f"mu-max plan {the_plan.name!r}: theta {list(the_plan.theta)}, {the_plan.seeds} seed(s) each, "
                      f"mu_a bisected in [{the_plan.lo:g}, {the_plan.hi:g}] to {the_plan.tol:g}"
                      + (f", curve points {list(the_plan.curve)}" if the_plan.curve else "")
                      + f"; results would go to {out_dir}. Nothing run or written (--dry-run).")
            return
        result = run_plan(the_plan, out_dir, scheduler=scheduler, n_workers=workers, backend=backend, progress=progress,
                          announce=announce_dashboard(dashboard), batch_size=batch_size)
    except ConfigError as e:  # rejected before anything ran: nothing written
        fail(str(e))
    except (BracketError, StoreWriteError) as e:  # found by running: the finished runs are kept in OUT/rounds
        fail(str(e), code=1)
    except SweepError as e:  # another driver runs OUT, or OUT holds another sweep
        fail(str(e))
    except KeyboardInterrupt:
        fail(f"interrupted; every finished run is kept in {out_dir / 'rounds'}: run the same command again to resume",
             code=interrupts.exit_code())
    wrote([out_dir / f for f in ("mu_max.csv", "mu_max_summary.csv", "evaluations.csv", "plan.toml")])
    t = Table(title="slipchain mu-max (seed means)")
    for col in ("theta", "mu_max", "ratio to theta_min", "seeds", "v_max (m/s)"):
        t.add_column(col, justify="right")
    for r in result.summary.itertuples():
        t.add_row(f"{r.theta:g}", f"{r.mu_max:.4f} ± {r.mu_max_se:.4f}",
                  f"{r.ratio_to_theta_min:.4f} ± {r.ratio_se:.4f}", str(r.seeds), f"{r.v_max_m_s:.3g}")
    out.print(t)
    undecided = result.table[result.table["status"] != "ok"]
    if len(undecided):
        out.print(f"{len(undecided)} realisation(s) not decided (in mu_max.csv with their reason; the summary leaves "
                  "them out):", markup=False)
        for r in undecided.itertuples():
            out.print(f"  theta {r.theta:g} seed {r.seed}: {r.status}: {r.message}", markup=False)
        raise typer.Exit(1)

"""``slipchain tester analyze`` and ``slipchain tester synth``: the friction-tester experiment."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.table import Table

from ..tester.inputs import TesterDataError
from .common import err, fail, out

tester_app = typer.Typer(no_args_is_help=True, help="The paper's friction-tester experiment: analysis and synthetic data.")


@tester_app.command("analyze")
def analyze(
    runs_csv: Annotated[Path, typer.Argument(help="Runs table (CSV).")],
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")],
    traces: Annotated[Optional[Path], typer.Option("--traces", help="Raw distance traces (CSV, long format).")] = None,
) -> None:
    """Steady velocity per trace, mu and p0 with uncertainties, maxima per pressure, the load test."""
    from ..workflows.tester import analyze as analyze_job  # (scipy.stats, matplotlib: imported when used)

    try:
        result = analyze_job(runs_csv, traces, out_dir)
    except TesterDataError as e:
        fail(str(e))
    counts = result.runs["status"].value_counts().to_dict()
    table = Table(title=f"slipchain tester analyze: {out_dir}")
    table.add_column("status")
    table.add_column("runs", justify="right")
    for k, v in sorted(counts.items()):
        table.add_row(k, str(v))
    out.print(table)
    for t in result.tests:
        holds = t.claim_holds
        out.print(f"{', '.join(map(str, t.group))}: load claim "
                  f"{'not testable' if holds is None else 'supported' if holds else 'not supported'}")
    out.print(f"wrote {', '.join(str(p) for p in result.files.values())}")


@tester_app.command("synth")
def synth(
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory.")],
    seed: Annotated[int, typer.Option("--seed", help="Random seed (noise, run-to-run scatter).")] = 0,
    load_effect: Annotated[float, typer.Option("--load-effect", help="Planted s: fractional fall of mu near its maximum per p_ref of pressure (0: none).")] = 0.15,
) -> None:
    """SYNTHETIC demo data: a simulated dead-weight tester (runs.csv, traces.csv, truth.csv, README.txt)."""
    from ..tester.synth import NOTICE, SynthSetup, write_synthetic

    setup = SynthSetup(seed=seed)
    paths = write_synthetic(out_dir, replace(setup, law=replace(setup.law, s=load_effect)))
    err.print(NOTICE, markup=False, highlight=False, soft_wrap=True)
    out.print(f"wrote {', '.join(str(p) for p in paths.values())}")

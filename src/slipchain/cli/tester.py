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
    model: Annotated[Optional[Path], typer.Option("--model", help="Plant the fitted model of `tester fit` instead, with the maxima of this `slipchain mu-max` result.")] = None,
    f_scale: Annotated[float, typer.Option("--f-scale", help="With --model: the planted force scale F.")] = 1.2,
    v0: Annotated[float, typer.Option("--v0", help="With --model: the planted v0 (m/s).")] = 3e-3,
    delta: Annotated[float, typer.Option("--delta", help="With --model: the planted delta (decades).")] = 0.7,
    p_ref: Annotated[float, typer.Option("--p-ref", help="With --model: the planted p_ref (Pa); theta = p0/p_ref.")] = 60e3,
) -> None:
    """SYNTHETIC demo data: a simulated dead-weight tester (runs.csv, traces.csv, truth.csv, README.txt; with --model also planted.json)."""
    import json

    from ..results.io import write_text_atomic
    from ..tester.synth import NOTICE, SynthSetup, write_synthetic

    setup = SynthSetup(seed=seed)
    if model is None:
        paths = write_synthetic(out_dir, replace(setup, law=replace(setup.law, s=load_effect)))
    else:
        from ..analysis.fit import FitError, ModelLaw, model_maxima

        bad = [(k, x) for k, x in (("--f-scale", f_scale), ("--v0", v0), ("--p-ref", p_ref)) if not x > 0]
        bad += [("--delta", delta)] if not delta >= 0 else []
        if bad:
            fail(f"option {bad[0][0]} has value {bad[0][1]!r}; expected a number > 0 (>= 0 for --delta)")
        try:
            law = ModelLaw(model_maxima(model), F=f_scale, v0=v0, delta=delta, p_ref=p_ref)
        except FitError as e:
            fail(str(e))
        # runaways just above the maximum, so that the data bound it closely (the model's fall is small)
        paths = write_synthetic(out_dir, replace(setup, law=law, runaway_factors=(1.02, 1.05, 1.1)))
        paths["planted"] = write_text_atomic(Path(out_dir) / "planted.json", json.dumps(
            {"F": f_scale, "v0": v0, "delta": delta, "p_ref": p_ref, "model": str(model)}, indent=1) + "\n")
    err.print(NOTICE, markup=False, highlight=False, soft_wrap=True)
    out.print(f"wrote {', '.join(str(p) for p in paths.values())}")


@tester_app.command("fit")
def fit(
    runs_csv: Annotated[Path, typer.Argument(help="runs.csv of `slipchain tester analyze`.")],
    model: Annotated[Path, typer.Option("--model", help="A `slipchain mu-max` result (its mu_max_summary.csv and plan.toml).")],
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory (fit.csv, residuals.csv, fit.md, figures).")],
    truth: Annotated[Optional[Path], typer.Option("--truth", help="planted.json of `tester synth --model`: compare with the planted values.")] = None,
) -> None:
    """Fit the model to tester data: p_ref per surface, v0, delta and a force scale, with 95 % CIs."""
    from ..analysis.fit import FitError
    from ..workflows.tester import fit as fit_job

    try:
        result = fit_job(runs_csv, model, out_dir, truth)
    except FitError as e:
        fail(str(e))
    from ..analysis.fit import predicts_fall

    t = Table(title="slipchain tester fit (95 % CI)")
    for col in ("group", "F", "v0 (m/s)", "delta", "p_ref (kPa)", "predicts the fall?"):
        t.add_column(col, overflow="fold")
    verdicts = [predicts_fall(f) for f in result.fits]
    for f, verdict in zip(result.fits, verdicts):
        e = f.params
        ci = lambda k, s=1.0: f"{e[k].value / s:.4g} [{e[k].ci_low / s:.3g}, {e[k].ci_high / s:.3g}]"  # noqa: E731
        t.add_row(" / ".join(map(str, f.group)), ci("F"), ci("v0"), ci("delta"), ci("p_ref", 1e3), verdict.split(":")[0])
    out.print(t)
    for f, verdict in zip(result.fits, verdicts):
        out.print(f"{' / '.join(map(str, f.group))}: does the fitted model predict the measured fall of mu_max with "
                  f"pressure? {verdict}", markup=False)
    out.print(f"wrote {', '.join(str(p) for p in result.files)}")

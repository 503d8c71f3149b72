"""The friction-tester analysis as one job: read and check the inputs, steady velocity per trace,
mu and p0 with uncertainties, first maxima and the load test, figures; writes ``runs.csv``,
``maxima.csv``, ``summary.md`` and the figures (all atomically).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ..results.io import write_csv, write_text_atomic
from ..tester.analysis import LoadTest, analyze_runs, load_tests, maxima, summary_markdown
from ..tester.inputs import read_runs, read_traces
from ..plots.tester import plot_mu_v


@dataclass
class Analysis:
    runs: pd.DataFrame
    maxima: pd.DataFrame
    tests: list[LoadTest]
    files: dict[str, Path]


def analyze(runs_csv: str | os.PathLike, traces_csv: str | os.PathLike | None, out: str | os.PathLike) -> Analysis:
    """The whole analysis; raises TesterDataError only for input that cannot be read at all."""
    runs = read_runs(runs_csv)
    orphans = read_traces(traces_csv, runs) if traces_csv is not None else []
    table = analyze_runs(runs + orphans)
    peaks = maxima(table)
    tests = load_tests(table, peaks)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    figures = plot_mu_v(table, peaks, out)
    files = {"runs": write_csv(table, out / "runs.csv"), "maxima": write_csv(peaks, out / "maxima.csv")}
    text = summary_markdown(table, peaks, tests, [p.name for p in figures if p.suffix == ".png"])
    files["summary"] = write_text_atomic(out / "summary.md", text)
    for p in figures:
        files[p.name] = p
    return Analysis(table, peaks, tests, files)


@dataclass
class Fit:
    fits: list
    files: list[Path]


def fit(runs_csv: str | os.PathLike, model: str | os.PathLike, out: str | os.PathLike,
        truth: str | os.PathLike | None = None) -> Fit:
    """The model fitted to an analysed runs table (:mod:`slipchain.analysis.fit`): fit.csv,
    residuals.csv, fit.md and one figure per group in ``out``. FitError (nothing written) for input
    the fit cannot use."""
    import json

    from ..analysis.fit import FitError, fit_markdown, fit_runs, model_maxima, parameters_table, residuals_table
    from ..plots.dead_weight import plot_fit

    try:
        runs = pd.read_csv(runs_csv)
    except (OSError, ValueError) as e:
        raise FitError(f"runs table {str(runs_csv)!r} cannot be read: {e}") from None
    maxima = model_maxima(model)
    planted = None
    if truth is not None:
        try:
            planted = {k: float(v) for k, v in json.loads(Path(truth).read_text()).items() if k in ("F", "v0", "delta", "p_ref")}
        except (OSError, ValueError, TypeError) as e:
            raise FitError(f"--truth {str(truth)!r} cannot be read as planted.json: {e}") from None
    fits = fit_runs(runs, maxima)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = [write_csv(parameters_table(fits), out / "fit.csv"), write_csv(residuals_table(fits), out / "residuals.csv"),
             write_text_atomic(out / "fit.md", fit_markdown(fits, str(runs_csv), maxima, planted))]
    files += [p for p in plot_fit(runs, fits, out) if p.suffix == ".png"]
    return Fit(fits, files)


__all__ = ["Analysis", "Fit", "analyze", "fit", "write_csv"]

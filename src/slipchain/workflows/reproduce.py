"""The main job: run the Fig. 6 sweep, draw Figs. 5 and 6, write the Markdown report.

Data flow: preset (sweep definition) -> Dask sweep into the store (resumable) -> sweep Dataset
-> claims and convergence numbers -> figures and ``report.md``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..analysis.fig6 import contact_law_dataset, convergence, evaluate, fig6_figure_data
from ..analysis.reports import report_markdown
from ..analysis.statistics import base_config
from ..engine.backends import BackendName
from ..plots.paper import plot_fig5, plot_fig6
from ..results.io import write_text_atomic
from ..sweeps.definition import Preset, load_preset
from ..sweeps.executor import SweepReport, run_sweep
from ..sweeps.store import Store


@dataclass
class Reproduction:
    sweep: SweepReport
    report: Path | None
    figures: list[Path]


def default_paths(preset: str | Preset) -> tuple[Path, Path]:
    out = Path("results") / f"fig6-{Preset(preset).value}"
    return out / "store", out


def reproduce(preset: str | Preset = Preset.QUICK, store: str | os.PathLike | None = None,
              out: str | os.PathLike | None = None, *, scheduler: str | None = None, n_workers: int | None = None,
              progress: bool | None = None, command: str = "", backend: str | BackendName = BackendName.CPU,
              announce=None) -> Reproduction:
    """Run (or resume) the preset's sweep; if every member completed, make the figures and report.
    ``announce``: called with the Dask dashboard's address (:func:`slipchain.sweeps.executor.run_sweep`)."""
    sweep = load_preset(preset)
    d_store, d_out = default_paths(preset)
    store_path = Path(store) if store is not None else d_store
    out_path = Path(out) if out is not None else d_out
    st = Store.open(store_path, sweep)
    rep = run_sweep(sweep, st, scheduler=scheduler, n_workers=n_workers, progress=progress, backend=backend,
                    announce=announce)
    if rep.interrupted:
        return Reproduction(rep, None, [])
    return Reproduction(rep, *write_outputs(st, out_path, command=command or f"slipchain reproduce --preset {Preset(preset).value}"))


def write_outputs(st: Store, out: Path, *, command: str) -> tuple[Path, list[Path]]:
    """Figures 5 and 6 and report.md from what the store holds (failed members are listed)."""
    ds = st.dataset()
    runs = [r for r in st.invocations() if r.get("ran")]  # the invocations that ran members
    wall = sum(r.get("wall_time_s", 0.0) for r in runs)
    ds.attrs["invocations"] = len(runs)
    ds.attrs["workers"] = ", ".join(sorted({str(r.get("n_workers") or r.get("scheduler")) for r in runs}))
    figures = plot_fig5(contact_law_dataset(base_config(ds)), out) + plot_fig6(fig6_figure_data(ds), out)
    text = report_markdown(ds, evaluate(ds), convergence(ds), command=command, wall_time_s=wall or None,
                           figures=[p.name for p in figures if p.suffix == ".png"])
    return write_text_atomic(out / "report.md", text), figures


__all__ = ["Reproduction", "default_paths", "reproduce", "write_outputs"]

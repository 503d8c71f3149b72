"""Reports in Markdown: the Fig. 6 reproduction report, the mechanism summary, the epsilon table.

Each function takes Datasets (and the numbers computed in :mod:`slipchain.analysis.fig6`, :mod:`slipchain.analysis.mechanism`,
:mod:`slipchain.analysis.statistics`) and returns text; writing it is the caller's job.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..results.observables import SLOW_FRACTION
from ..results.schema import Status
from .fig6 import Claim, eta_label, fig6_table
from .mechanism import STICK_FRACTION, median_frequency, stick_slip_average
from .statistics import base_config, fmt_value, load_drops


def report_markdown(ds: xr.Dataset, claims: list[Claim], conv: list[dict[str, Any]], *, command: str,
                    wall_time_s: float | None, figures: list[str]) -> str:
    """The reproduction report: each claim of the paper next to what we measured."""
    cfg = base_config(ds)
    n_done = int((ds["status"] == Status.COMPLETED).sum())
    n_total = int((ds["status"] != "absent").sum())
    lines = [
        f"# Reproduction of Fig. 6 ({ds.attrs.get('sweep_name')}): friction versus load",
        "",
        "Braun, Steenwyk, Warhadpande and Persson, \"On the dependency of friction on load: Theory and experiment\", "
        "EPL 113, 56002 (2016), two-chain model as in docs/model.md.",
        "",
        f"- Command: `{command}`",
        f"- Sweep `{ds.attrs.get('sweep_name')}` (digest {ds.attrs.get('sweep_digest')}): {n_done} of {n_total} members "
        f"completed; {run_time_text(ds)}"
        + (f"; wall time of the sweep {wall_time_s / 60:.1f} min with {ds.attrs.get('workers', '?')} local worker "
           f"process(es) ({ds.attrs.get('invocations', 1)} invocation(s) that ran members, from the store's "
           "invocations.jsonl)." if wall_time_s is not None else "."),
        f"- Base: epsilon = {cfg.epsilon:g}, {step_text(cfg)}, start = {cfg.start}, automatic run length until "
        f"SE(mu_star) <= {cfg.sem_target:g} (at most t_max = {cfg.t_max:g} s), slipchain {_versions(ds)}.",
        "- Error bars: seed mean of mu_star, error sqrt(max(var_seeds/n, mean(SE_time^2)/n)).",
        "",
        "## The paper's claims and what we measured",
        "",
        "| paper | measured | criterion | holds |",
        "|---|---|---|---|",
    ]
    for c in claims:
        holds = "n/a" if c.passed is None else ("yes" if c.passed else "**no**")
        lines.append(f"| {c.paper} | {c.measured} | {c.criterion} | {holds} |")
    lines += ["", "## mu_star versus theta (seed means)", ""]
    lines += _table(ds)
    if conv:
        lines += ["", "## Convergence evidence", "",
                  "The same seeds rerun with a changed numerical parameter; z = difference / combined time SE.", "",
                  "| parameter | main -> alternative | points | mean difference | largest abs z |", "|---|---|---|---|---|"]
        groups: dict[tuple, list] = {}
        for r in conv:
            groups.setdefault((r["dim"], r["main"], r["alt"], r["v_d"]), []).append(r)
        for (d, m, a, vd), rs in groups.items():
            lines.append(f"| {d} (v_d = {vd:g}) | {fmt_value(m)} -> {fmt_value(a)} | {len(rs)} | {np.mean([r['diff'] for r in rs]):+.4f} | "
                         f"{max(abs(r['z']) for r in rs):.2f} |")
    not_done = list(zip(*np.nonzero(((ds["status"] != Status.COMPLETED) & (ds["status"] != Status.ABSENT)).values)))
    if not_done:
        lines += ["", "## Members not completed", ""]
        for idx in not_done:
            point = ", ".join(f"{d} = {fmt_value(ds[d].values[i].item())}" for d, i in zip(ds["status"].dims, idx))
            lines.append(f"- {point}: {ds['status'].values[idx]}. {ds['message'].values[idx]}")
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(lines) + "\n"


def run_time_text(ds: xr.Dataset) -> str:
    """How long the completed members took. A member computed on the GPU records the wall time of
    its batch (up to 256 members advanced together), so GPU members count each batch once."""
    done = (ds["status"] == Status.COMPLETED).values
    wall = np.nan_to_num(ds["wall_time_s"].values[done])
    on_gpu = (ds["backend"].values[done] == "gpu") if "backend" in ds else np.zeros(wall.shape, bool)
    text = f"the sum of the members' run times is {wall[~on_gpu].sum() / 60:.1f} CPU-minutes"
    if not on_gpu.any():
        return text
    batches = np.unique(wall[on_gpu])  # members of one batch share its wall time
    gpu = (f"{int(on_gpu.sum())} members ran on the GPU in {batches.size} batch(es) whose wall times add up to "
           f"{batches.sum() / 60:.1f} min (batches run concurrently; a member records its batch's wall time)")
    return gpu if on_gpu.all() else f"{text} ({int((~on_gpu).sum())} members); {gpu}"


def step_text(cfg) -> str:
    """Which step made the results (issue 26: the integrator is part of what a report states)."""
    if cfg.integrator == "adaptive":
        return (f"integrator = adaptive from dt = {cfg.dt:g} s (steps up to {cfg.dt * 2**cfg.step_levels:g} s, "
                f"step_tol = {cfg.step_tol:g})")
    if cfg.integrator == "implicit":
        above = "backward Euler" if cfg.implicit_scheme == "backward-euler" else "TR-BDF2"
        if cfg.geometry != "chain" and cfg.krylov_preconditioner != "jacobi":
            above += f" preconditioned '{cfg.krylov_preconditioner}'"
        return (f"integrator = implicit from dt = {cfg.dt:g} s (explicit steps up to {cfg.dt * 2**cfg.step_levels:g} s, "
                f"{above} above, step_tol = {cfg.step_tol:g})")
    return f"integrator = {cfg.integrator}, dt = {cfg.dt:g} s"


def _versions(ds: xr.Dataset) -> str:
    vals = sorted({v for v in ds["slipchain_version"].values.ravel().tolist() if v})
    return ", ".join(vals) or "?"


def _table(ds: xr.Dataset) -> list[str]:
    avg, sel = fig6_table(ds)
    extra = ", ".join(f"{k} = {fmt_value(v)}" for k, v in sel.items())
    lines = [f"At {extra}." if extra else "", ""] if extra else []
    ns = avg["N"].values.tolist() if "N" in avg.dims else [base_config(ds).N]  # N held: the base's
    header = "| N | v_d | theta | " + " | ".join(f"eta_c = {eta_label(ec)}" for ec in avg["eta_c"].values) + " |"
    lines += [header, "|---" * (3 + avg.sizes["eta_c"]) + "|"]
    for n in ns:
        sub_n = avg.sel(N=n) if "N" in avg.dims else avg
        for vd in sorted(sub_n["v_d"].values.tolist(), reverse=True):
            for th in sub_n["theta"].values:
                cells = []
                for ec in sub_n["eta_c"].values:
                    c = sub_n.sel(v_d=vd, theta=th, eta_c=ec)
                    cells.append("" if not np.isfinite(float(c["mu"])) else
                                 f"{float(c['mu']):.4f} ± {float(c['err']):.4f} ({int(c['n'])})")
                if any(cells):
                    lines.append(f"| {n} | {vd:g} | {th:g} | " + " | ".join(cells) + " |")
    lines += ["", "(number of seeds in brackets)"]
    return lines


def mechanism_summary(stick_slip: xr.Dataset, analyses: list[xr.Dataset]) -> str:
    """Markdown: what the mechanism figures show, in numbers."""
    avg = stick_slip_average(stick_slip)
    lines = ["# The mechanism: stick-slip, slip events, spectra", "",
             f"A contact stick-slips when it spends at least {STICK_FRACTION:.0%} of the steady time at |u| < "
             f"{SLOW_FRACTION:g} v_d. Seed means ± error (seeds and binomial).", "",
             "## Fraction of contacts that stick-slip", ""]
    dims = [d for d in ("v_d", "eta_c") if d in avg.dims]
    thetas = avg["theta"].values
    lines.append("| " + " | ".join(dims) + " | " + " | ".join(f"theta = {t:g}" for t in thetas) + " |")
    lines.append("|---" * (len(dims) + len(thetas)) + "|")
    stacked = avg.stack(_row=dims) if dims else avg.expand_dims(_row=[0])
    for i in range(stacked.sizes["_row"]):
        row = stacked.isel(_row=i)
        head = " | ".join(f"{row[d].item():g}" for d in dims)
        cells = " | ".join(f"{float(row['mu'].sel(theta=t)):.3f} ± {float(row['err'].sel(theta=t)):.3f}" for t in thetas)
        lines.append(f"| {head} | {cells} |")
    lines += ["", "## Detailed runs (field recording after the steady run)", "",
              "| run | mu_star | stick-slip fraction | events (complete) | events per ms | median size | largest | "
              "mean duration (us) | median frequency of the u spectrum (kHz) | std f_d / mean |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for a in analyses:
        n_ev = a.sizes.get("event", 0)
        full = ~a["event_truncated"].values.astype(bool) if n_ev else np.zeros(0, bool)
        sizes = a["event_size"].values[full] if n_ev else np.zeros(0)
        dur = a["event_duration"].values[full] if n_ev else np.zeros(0)
        fd = a["f_d_instant"].values
        lines.append(
            f"| v_d = {a.attrs['v_d']:g}, theta = {a.attrs['theta']:.3g}, eta_c = {a.attrs['eta_c']:g} | "
            f"{a.attrs['mu_star']:.4f} | {a.attrs['stick_slip_fraction']:.3f} ± {a.attrs['stick_slip_fraction_se']:.3f} | "
            f"{sizes.size} | {n_ev / (a.attrs['duration'] * 1e3):.1f} | "
            f"{np.median(sizes) if sizes.size else float('nan'):.0f} | {sizes.max() if sizes.size else 0} | "
            f"{dur.mean() * 1e6 if dur.size else float('nan'):.1f} | "
            f"{median_frequency(a['frequency'].values, a['psd_u'].values) / 1e3:.2f} | {fd.std() / fd.mean():.3f} |")
    lines += ["", f"Recording: {analyses[0].attrs['duration'] * 1e3:g} ms sampled every "
              f"{analyses[0].attrs['interval'] * 1e6:g} us; {analyses[0].attrs.get('welch', '')}." if analyses else ""]
    return "\n".join(lines) + "\n"


def epsilon_lines(avg: xr.Dataset) -> list[str]:
    """One line per epsilon of :func:`slipchain.analysis.statistics.epsilon_table`: mu_star at the
    smallest and the largest theta and their ratio (the load effect at that contact-force scale)."""
    return [f"epsilon = {d['epsilon']:g}: mu_star {d['mu_min_theta']:.4f} ± {d['err_min_theta']:.4f} at theta = "
            f"{d['theta_min']:g} -> {d['mu_max_theta']:.4f} ± {d['err_max_theta']:.4f} at theta = "
            f"{d['theta_max']:g}; ratio {d['ratio']:.3f} ± {d['ratio_err']:.3f}" for d in load_drops(avg, "epsilon")]


__all__ = ["epsilon_lines", "mechanism_summary", "report_markdown", "run_time_text", "step_text"]

"""``slipchain material show|fit``: the viscoelastic bulk's compound (issue 28)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import numpy as np
import typer
from rich.table import Table

from .common import fail, out, wrote

material_app = typer.Typer(no_args_is_help=True, help="The rubber of material = 'prony': plot its moduli, fit a master curve.")


def _prony_config(config: Optional[Path], set_: list[str]):
    """The config with material = 'prony' (the default compound unless the config gives Prony terms);
    exit 2 if the file or a --set asks for another material."""
    from ..model.config import ConfigError, load_config, parse_override, read_toml

    try:
        given = read_toml(config).get("material") if config is not None else None
        for item in set_:
            key, value = parse_override(item)
            given = value if key == "material" else given
        if given is not None and given != "prony":
            fail(f"config key 'material' has value {given!r}; expected 'prony' (slipchain material shows a viscoelastic compound)")
        return load_config(config, ['material="prony"', *set_])
    except ConfigError as e:
        fail(str(e))


@material_app.command("show")
def show(
    config: Annotated[Optional[Path], typer.Argument(help="TOML config with the compound (absent: the default compound).")] = None,
    set_: Annotated[list[str], typer.Option("--set", help="Override one parameter: name=value (repeatable).")] = [],
    temperatures: Annotated[list[float], typer.Option("--T", help="Temperature in °C (repeatable; absent: the config's).")] = [],
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory (material.png, material.pdf, material.csv).")] = Path("material"),
    event_time: Annotated[float, typer.Option("--event-time", help="A slip event's duration (s), marked at 1/t.")] = 1e-5,
    creep_time: Annotated[float, typer.Option("--creep-time", help="The creep between events (s), marked at 1/t.")] = 1.0,
    f_min: Annotated[float, typer.Option("--f-min", help="Lowest frequency plotted (Hz).")] = 1e-3,
    f_max: Annotated[float, typer.Option("--f-max", help="Highest frequency plotted (Hz).")] = 1e10,
) -> None:
    """Plot E', E'' and tan delta against frequency at each temperature (WLF-shifted Prony series)."""
    import pandas as pd

    from ..model.viscoelastic import Compound, shift_factor
    from ..plots.material import moduli_table, plot_moduli
    from ..results.io import write_text_atomic

    cfg = _prony_config(config, set_)
    for name, v in (("--event-time", event_time), ("--creep-time", creep_time), ("--f-min", f_min), ("--f-max", f_max)):
        if not (np.isfinite(v) and v > 0):
            fail(f"option {name} has value {v!r}; expected a number > 0")
    if not f_max > f_min:
        fail(f"option --f-max has value {f_max!r}; expected a frequency above --f-min ({f_min!r})")
    temps = list(temperatures) or [cfg.temperature]
    for T in temps:
        try:
            shift_factor(T, cfg.T_ref, cfg.wlf_C1, cfg.wlf_C2)
        except ValueError:
            fail(f"option --T has value {T!r}; expected a temperature above T_ref - C2 = {cfg.T_ref - cfg.wlf_C2:g} °C "
                 "(WLF's range)")
    compound = Compound(tuple(cfg.prony_E), tuple(cfg.prony_tau), cfg.T_ref, cfg.wlf_C1, cfg.wlf_C2)
    table = moduli_table(compound, cfg.E, temps, np.geomspace(f_min, f_max, 261))
    title = (f"{'default (synthetic) compound' if config is None and not set_ else 'compound of the config'}: "
             f"E_inf = {cfg.E / 1e6:g} MPa, {len(cfg.prony_E)} Prony terms, T_ref = {cfg.T_ref:g} °C, "
             f"WLF C1 = {cfg.wlf_C1:.3g}, C2 = {cfg.wlf_C2:.4g} K")
    paths = plot_moduli(table, out_dir, title, event_time, creep_time)
    rows = pd.DataFrame({"T": np.repeat(table["T"], table["f"].size), "f": np.tile(table["f"], table["T"].size),
                         "E_storage": table["E_storage"].ravel(), "E_loss": table["E_loss"].ravel(),
                         "tan_delta": table["tan_delta"].ravel()})
    paths.append(write_text_atomic(out_dir / "material.csv", rows.to_csv(index=False, float_format="%.8g")))
    at = moduli_table(compound, cfg.E, temps, [1 / creep_time, 1 / event_time])
    t = Table(title="slipchain material show")
    for col in ("T (°C)", "a_T", "E' creep (MPa)", "E' events (MPa)", "E''/E' events"):
        t.add_column(col, justify="right")
    for i, T in enumerate(at["T"]):
        t.add_row(f"{T:g}", f"{at['a_T'][i]:.3g}", f"{at['E_storage'][i, 0] / 1e6:.4g}", f"{at['E_storage'][i, 1] / 1e6:.4g}",
                  f"{at['tan_delta'][i, 1]:.3g}")
    out.print(t)
    wrote(paths)


@material_app.command("fit")
def fit(
    master_csv: Annotated[Path, typer.Argument(help="Master curve: CSV with header rows 'f,E_stor,E_loss' and 'Hz,MPa,MPa'.")],
    T_ref: Annotated[float, typer.Option("--T-ref", help="The master curve's reference temperature (°C).")],
    out_dir: Annotated[Path, typer.Option("--out", help="Output directory (compound.toml, master_curve_fit.png/.pdf).")],
    C1: Annotated[Optional[float], typer.Option("--C1", help="WLF C1 of the measured shift at T_ref.")] = None,
    C2: Annotated[Optional[float], typer.Option("--C2", help="WLF C2 (K) of the measured shift at T_ref.")] = None,
    terms: Annotated[int, typer.Option("--terms", help="Number of Prony terms (0: one per decade).")] = 0,
) -> None:
    """Fit Prony terms to a master curve with pyvisco; write them as a config fragment (compound.toml)."""
    from ..model.config import ConfigError, config_from_toml
    from ..model.master_curve import MasterCurveError, fit_master_curve
    from ..plots.material import plot_fit
    from ..results.io import write_text_atomic

    try:
        result = fit_master_curve(master_csv, T_ref, C1, C2, terms)
        text = result.toml()
        config_from_toml(text)  # the fragment is a valid config (E_inf, terms, WLF range) before anything is written
    except (MasterCurveError, ConfigError) as e:
        fail(str(e))
    paths = plot_fit(result, out_dir)
    paths.append(write_text_atomic(out_dir / "compound.toml", text))
    out.print(f"{len(result.E)} Prony terms, E_inf = {result.E_inf / 1e6:.4g} MPa, E_0 = "
              f"{(result.E_inf + sum(result.E)) / 1e6:.4g} MPa; worst error over the data, relative to |E*|: E' "
              f"{result.err_storage:.2%}, E'' {result.err_loss:.2%}" + ("" if result.wlf_given else
              "; WLF C1, C2 not given: universal constants written, replace them by your shift's"),
              markup=False, highlight=False)
    wrote(paths)


__all__ = ["fit", "material_app", "show"]

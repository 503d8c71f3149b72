"""Reading and checking friction-tester data: the runs table and the raw distance traces.

Runs table (CSV, one row per run)::

    run_id,surface,compound,temperature_C,slider_mass_kg,hanging_mass_kg,nominal_area_m2[,mass_uncertainty_kg][,velocity_m_s]

Traces (CSV, long format, any number of rows per run)::

    run_id,time_s,distance_m

What is an error and what excludes one run:

* a missing file, a missing required column, a trace row whose ``run_id`` is empty: an error
  (:class:`TesterDataError`) naming the file, the line and the column; nothing is analysed.
* anything wrong with one run (a non-numeric or non-positive mass, a negative uncertainty, a
  duplicate ``run_id``, a trace with non-numeric values, non-increasing time, too few points, a
  trace for a run that is not in the runs table): that run is excluded, and the reason, naming
  file, line and column, is written to its row of ``runs.csv``. The other runs go on.

Lines are counted as in a text editor: the header is line 1, the first data row line 2.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

RUN_COLUMNS = ("run_id", "surface", "compound", "temperature_C", "slider_mass_kg", "hanging_mass_kg", "nominal_area_m2")
OPTIONAL_RUN_COLUMNS = ("mass_uncertainty_kg", "velocity_m_s")
TRACE_COLUMNS = ("run_id", "time_s", "distance_m")
POSITIVE = ("slider_mass_kg", "hanging_mass_kg", "nominal_area_m2")
MIN_TRACE_POINTS = 20


class TesterDataError(ValueError):
    """Input that cannot be analysed at all; the message names file, line and column."""

    __test__ = False  # not a pytest test class despite its name


@dataclass
class Run:
    """One run of the tester as read from the runs table (and its trace, if any)."""

    run_id: str
    surface: str
    compound: str
    temperature_C: float
    slider_mass_kg: float
    hanging_mass_kg: float
    nominal_area_m2: float
    mass_uncertainty_kg: float = 0.0
    velocity_m_s: float = float("nan")
    line: int = 0
    problems: list[str] = field(default_factory=list)
    time_s: np.ndarray | None = None
    distance_m: np.ndarray | None = None


def _first_bad_byte(path: Path) -> str:
    """Where a file stops being UTF-8 (pandas decodes in buffers, so its own offsets are not the file's)."""
    data = path.read_bytes()
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        return f"byte 0x{data[e.start]:02x} at byte offset {e.start} (line {line})"
    return "a byte sequence that is not valid UTF-8"


def _read_csv(path: str | os.PathLike, required: tuple[str, ...]) -> pd.DataFrame:
    path = Path(path)
    if not path.exists():
        raise TesterDataError(f"{path}: file does not exist")
    try:
        df = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise TesterDataError(f"{path}: file is empty; expected a header line with columns {', '.join(required)}") from None
    except pd.errors.ParserError as e:
        raise TesterDataError(f"{path}: not a valid CSV file: {e}") from None
    except UnicodeDecodeError:
        raise TesterDataError(f"{path}: not UTF-8 text: {_first_bad_byte(path)}") from None
    except (IsADirectoryError, PermissionError) as e:
        raise TesterDataError(f"{path}: cannot be read: {e.strerror}") from None
    df.columns = [c.strip() for c in df.columns]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise TesterDataError(f"{path}, line 1: missing column(s) {', '.join(missing)}; "
                              f"found {', '.join(df.columns) or 'none'}; expected {', '.join(required)}")
    return df


def _number(raw: str, path: Path, line: int, column: str, problems: list[str], *, positive: bool = False,
            non_negative: bool = False, optional: bool = False) -> float:
    raw = raw.strip()
    if raw == "":
        if optional:
            return float("nan")
        problems.append(f"{path.name}, line {line}, column {column}: empty; expected a number")
        return float("nan")
    try:
        value = float(raw)
    except ValueError:
        problems.append(f"{path.name}, line {line}, column {column}: {raw!r} is not a number")
        return float("nan")
    if not np.isfinite(value):
        problems.append(f"{path.name}, line {line}, column {column}: {raw!r} is not a finite number")
    elif positive and value <= 0:
        problems.append(f"{path.name}, line {line}, column {column}: {value:g}; expected a number > 0")
    elif non_negative and value < 0:
        problems.append(f"{path.name}, line {line}, column {column}: {value:g}; expected a number >= 0")
    return value


def read_runs(path: str | os.PathLike) -> list[Run]:
    """The runs table; per-run problems are recorded on the run, not raised."""
    path = Path(path)
    df = _read_csv(path, RUN_COLUMNS)
    runs: list[Run] = []
    first_line: dict[str, int] = {}
    for i, row in enumerate(df.to_dict("records")):
        line = i + 2
        problems: list[str] = []
        rid = row["run_id"].strip()
        if not rid:
            problems.append(f"{path.name}, line {line}, column run_id: empty")
            rid = f"<line {line}>"
        nums = {c: _number(row[c], path, line, c, problems, positive=c in POSITIVE) for c in POSITIVE}
        temp = _number(row["temperature_C"], path, line, "temperature_C", problems)
        unc = _number(row.get("mass_uncertainty_kg", ""), path, line, "mass_uncertainty_kg", problems,
                      non_negative=True, optional=True)
        vel = _number(row.get("velocity_m_s", ""), path, line, "velocity_m_s", problems, positive=True, optional=True)
        if rid in first_line:
            problems.append(f"{path.name}, line {line}, column run_id: duplicate of line {first_line[rid]}")
            for r in runs:  # both rows are excluded: which one is right is not ours to guess
                if r.run_id == rid and not any("duplicate" in p for p in r.problems):
                    r.problems.append(f"{path.name}, line {r.line}, column run_id: duplicated on line {line}")
        else:
            first_line[rid] = line
        runs.append(Run(run_id=rid, surface=row["surface"].strip(), compound=row["compound"].strip(),
                        temperature_C=temp, mass_uncertainty_kg=0.0 if np.isnan(unc) else unc, velocity_m_s=vel,
                        line=line, problems=problems, **nums))
    return runs


def read_traces(path: str | os.PathLike, runs: list[Run]) -> list[Run]:
    """Attach each run's trace; returns placeholder runs for traces whose run_id is not in the table."""
    path = Path(path)
    df = _read_csv(path, TRACE_COLUMNS)
    df["_line"] = np.arange(len(df)) + 2
    empty = df["run_id"].str.strip() == ""
    if empty.any():
        line = int(df.loc[empty, "_line"].iloc[0])
        raise TesterDataError(f"{path}, line {line}, column run_id: empty; every trace row must name its run")
    df["run_id"] = df["run_id"].str.strip()
    by_id = {r.run_id: r for r in runs}
    orphans: list[Run] = []
    for rid, g in df.groupby("run_id", sort=False):
        lines = g["_line"].to_numpy()
        run = by_id.get(rid)
        if run is None:
            orphan = Run(run_id=rid, surface="", compound="", temperature_C=float("nan"), slider_mass_kg=float("nan"),
                         hanging_mass_kg=float("nan"), nominal_area_m2=float("nan"), line=0)
            orphan.problems.append(f"{path.name}, lines {lines[0]}-{lines[-1]}: trace of run {rid!r}, "
                                   "which is not in the runs table")
            orphans.append(orphan)
            continue
        t = pd.to_numeric(g["time_s"], errors="coerce").to_numpy(float)
        x = pd.to_numeric(g["distance_m"], errors="coerce").to_numpy(float)
        for col, arr in (("time_s", t), ("distance_m", x)):
            bad = ~np.isfinite(arr)
            if bad.any():
                k = int(np.argmax(bad))
                run.problems.append(f"{path.name}, line {lines[k]}, column {col}: {g[col].iloc[k]!r} is not a number")
        if run.problems:
            continue
        steps = np.diff(t)
        if (steps <= 0).any():
            k = int(np.argmax(steps <= 0)) + 1
            run.problems.append(f"{path.name}, line {lines[k]}, column time_s: {t[k]:g} s does not increase "
                                f"(previous row {t[k - 1]:g} s)")
            continue
        if t.size < MIN_TRACE_POINTS:
            run.problems.append(f"{path.name}, lines {lines[0]}-{lines[-1]}: {t.size} points; "
                                f"at least {MIN_TRACE_POINTS} are needed to find steady sliding")
            continue
        run.time_s, run.distance_m = t, x
    return orphans


__all__ = ["MIN_TRACE_POINTS", "OPTIONAL_RUN_COLUMNS", "RUN_COLUMNS", "Run", "TRACE_COLUMNS", "TesterDataError",
           "read_runs", "read_traces"]

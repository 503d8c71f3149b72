"""Structured fuzzing through the command line (issue 11, item 4).

Random but well-formed inputs, which get past the parsers into validation and analysis: TOML
configs and sweep files made by mutating valid ones (keys added, removed, given values of the
wrong type, out of range, non-finite, huge), and tester CSV tables of random shapes (columns
missing, reordered or unknown; cells empty, negative, non-finite, text with commas, quotes and
new lines; duplicate and unknown run ids; traces of random length and order). They go through
the CLI in this process (typer's runner). Allowed outcomes: a result (exit 0), or exit 2 with one
``error:`` line and nothing written. Never a traceback, never another exit code, never a file
left behind for rejected input. Configs the CLI accepts are also run (shortened) by the engine:
status completed or diverged with a message, never an exception.
"""

import csv
import io
import json
import math
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from slipchain import run
from slipchain.cli import app
from slipchain.model.config import Config, ConfigError, load_config, make_config
from slipchain.sweeps.definition import SweepError, load_sweep_definition
from slipchain.tester.inputs import OPTIONAL_RUN_COLUMNS, RUN_COLUMNS, TRACE_COLUMNS

EXAMPLES = int(os.environ.get("SLIPCHAIN_FUZZ_EXAMPLES", "60"))  # more for a long hunt (600 were run, see docs/reliability.md)
FUZZ = settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
runner = CliRunner()

# --- TOML from Python values (a test helper: the package only reads TOML) ---------------------------


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # JSON string escapes are TOML basic-string escapes
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


def toml_key(k: str) -> str:
    return k if k and all(c.isascii() and (c.isalnum() or c in "_-") for c in k) else json.dumps(k, ensure_ascii=False)


def toml_table(d: dict) -> str:
    return "".join(f"{toml_key(k)} = {toml_value(v)}\n" for k, v in d.items())


# --- strategies -------------------------------------------------------------------------------------

FIELDS = list(Config.model_fields)
TEXT = st.text(st.characters(exclude_categories=("Cs",)), max_size=12)  # (lone surrogates: tested by the byte fuzzers)
SCALAR = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-3, 3).map(lambda e: 10.0 ** e),  # near typical magnitudes
    st.integers(-5, 5000), st.integers(-2**63, 2**63 - 1),
    st.booleans(), TEXT, st.sampled_from(["rest", "steady", "", "1e-3"]),
)
VALUE = st.one_of(SCALAR, st.lists(SCALAR, max_size=3), st.dictionaries(TEXT, SCALAR, max_size=2))
KEY = st.one_of(st.sampled_from(FIELDS), TEXT)
BASE = {"N": 31, "theta": 0.5, "start": "steady", "v0": 0.01, "delta": 0.2, "t_total": 2e-4}


@st.composite
def mutated_config(draw) -> dict:
    d = dict(BASE)
    for k in draw(st.lists(st.sampled_from(list(BASE)), max_size=2)):
        d.pop(k, None)
    d.update(draw(st.dictionaries(KEY, VALUE, max_size=3)))
    return d


@st.composite
def mutated_sweep(draw) -> str:
    text = ""
    if draw(st.booleans()):
        text += f"name = {toml_value(draw(TEXT))}\n"
    text += "[base]\n" + toml_table(draw(st.one_of(st.just(BASE), mutated_config())))
    plausible = st.fixed_dictionaries({"theta": st.lists(st.floats(0.05, 1), min_size=1, max_size=3)},
                                      optional={"seed": st.lists(st.integers(0, 9), min_size=1, max_size=2),
                                                "eta_c": st.lists(st.floats(0, 1e6), min_size=1, max_size=2)})
    anything = st.dictionaries(KEY, st.one_of(st.lists(SCALAR, max_size=3), SCALAR), max_size=3)
    grids = draw(st.lists(st.one_of(plausible, plausible, anything), min_size=st_min(draw), max_size=2))
    if len(grids) == 1 and draw(st.booleans()):
        text += "[grid]\n" + toml_table(grids[0])
    else:
        text += "".join("[[grid]]\n" + toml_table(g) for g in grids)
    return text


CELL = st.one_of(
    st.floats(1e-3, 50).map(repr), st.floats(-50, 0).map(repr), st.sampled_from(["", "0", "nan", "inf", "-inf", "1e400"]),
    st.text(max_size=8), st.sampled_from(["a,b", 'say "x"', "two\nlines", " 1.5 ", "\u00b5"]),
)
RUN_ID = st.sampled_from(["R1", "R2", "R3", "", " R1 ", "X9"])


@st.composite
def csv_tables(draw) -> tuple[str, str | None]:
    cols = [c for c in RUN_COLUMNS if draw(st.floats(0, 1)) < 0.93]
    cols += [c for c in (*OPTIONAL_RUN_COLUMNS, "comment") if draw(st.booleans())]
    cols = draw(st.permutations(cols))
    rows = []
    for _ in range(draw(st.integers(0, 5))):
        rows.append([draw(RUN_ID) if c == "run_id" else draw(CELL) for c in cols])
    runs = _csv([cols, *rows])
    if not draw(st.booleans()):
        return runs, None
    tcols = draw(st.permutations([c for c in TRACE_COLUMNS if draw(st.floats(0, 1)) < 0.95]))
    trows = []
    for rid in draw(st.lists(RUN_ID, max_size=3)):
        n = draw(st.integers(0, 40))
        v, ordered = draw(st.floats(1e-6, 1.0)), draw(st.booleans())
        times = [0.05 * i for i in range(n)] if ordered else draw(st.lists(st.floats(-1, 5), min_size=n, max_size=n))
        for t in times:
            cell = {"run_id": rid, "time_s": repr(t), "distance_m": repr(v * t * t + 1e-4 * t)}
            if draw(st.floats(0, 1)) < 0.05:
                cell[draw(st.sampled_from(TRACE_COLUMNS))] = draw(CELL)
            trows.append([cell[c] for c in tcols])
    return runs, _csv([tcols, *trows])


def st_min(draw) -> int:
    return 0 if draw(st.floats(0, 1)) < 0.1 else 1  # sometimes no grid at all


def _csv(rows) -> str:
    buf = io.StringIO()
    csv.writer(buf).writerows(rows)
    return buf.getvalue()


PLAN_BASE = {"N": 11, "delta": 0.0, "t_decide": 0.01, "t_max": 0.1}
PLAN_BISECTION = {"theta": [0.5, 1.0], "seeds": 2, "lo": 0.5, "hi": 1.5, "tol": 0.005, "curve": [0.3]}


@st.composite
def mutated_plan(draw) -> str:
    """A mu-max plan ([base] and [bisection]) with keys removed, added or given odd values."""
    base, bisection = dict(PLAN_BASE), dict(PLAN_BISECTION)
    for k in draw(st.lists(st.sampled_from(list(PLAN_BASE)), max_size=2)):
        base.pop(k, None)
    for k in draw(st.lists(st.sampled_from(list(PLAN_BISECTION)), max_size=2)):
        bisection.pop(k, None)
    base.update(draw(st.dictionaries(KEY, VALUE, max_size=2)))
    bisection.update(draw(st.dictionaries(st.one_of(st.sampled_from(list(PLAN_BISECTION)), TEXT), VALUE, max_size=2)))
    text = f"name = {toml_value(draw(TEXT))}\n" if draw(st.booleans()) else ""
    if draw(st.floats(0, 1)) < 0.1:
        text += f"{toml_key(draw(TEXT) or 'x')} = {toml_value(draw(SCALAR))}\n"  # an unknown top-level key
    return text + "[base]\n" + toml_table(base) + "[bisection]\n" + toml_table(bisection)


# --- helpers ----------------------------------------------------------------------------------------


@contextmanager
def _workdir() -> Iterator[Path]:
    """A fresh directory per example (pytest's tmp_path is one per test, shared by all examples)."""
    with tempfile.TemporaryDirectory(prefix="slipchain-fuzz-") as d:
        yield Path(d)


def _rejected(result, *created: Path) -> None:
    """Exit 2, one clear line, no traceback, nothing written."""
    assert result.exit_code == 2, (result.exit_code, result.output, result.exception)
    assert isinstance(result.exception, SystemExit), result.exception
    assert result.stderr.startswith("error: ") and "Traceback" not in result.output + result.stderr
    for p in created:
        assert not p.exists(), f"{p} written for rejected input"


# --- the tests --------------------------------------------------------------------------------------


@FUZZ
@given(mutated_config())
def test_fuzzed_config_toml_is_run_or_rejected_with_exit_2(d):
    with _workdir() as work:
        path = work / "c.toml"
        path.write_text(toml_table(d))
        out = work / "run.nc"
        try:
            cfg = load_config(path)
        except ConfigError:
            event("config rejected")
            _rejected(runner.invoke(app, ["run", str(path), "--out", str(out)]), out)
            _rejected(runner.invoke(app, ["run", str(path), "--dry-run"]))
            return
        dry = runner.invoke(app, ["run", str(path), "--dry-run"])
        assert dry.exit_code == 0 and "valid config" in dry.output, (dry.output, dry.stderr, dry.exception)
        assert list(work.iterdir()) == [path]
        event("config accepted")
        _shortened_run_is_a_result(cfg)


def _shortened_run_is_a_result(cfg: Config) -> None:
    """An accepted config, cut to a few output intervals where that is cheap, runs to a status."""
    t = 3 * cfg.output_interval
    if cfg.N * t / cfg.dt > 2e7 or cfg.N > 5000:
        return
    try:
        short = make_config({**cfg.model_dump(), "t_total": t, "t_max": max(cfg.t_max, t)})
    except ConfigError:
        return
    ds = run(short)
    event(f"shortened run {ds.attrs['status']}")
    assert ds.attrs["status"] in ("completed", "diverged"), ds.attrs
    if ds.attrs["status"] == "diverged":
        assert ds.attrs["message"]


@FUZZ
@given(mutated_sweep())
def test_fuzzed_sweep_toml_is_accepted_or_rejected_with_exit_2(text):
    with _workdir() as work:
        path = work / "s.toml"
        path.write_text(text)
        store = work / "store"
        try:
            sw = load_sweep_definition(path)
        except SweepError:
            event("sweep rejected")
            _rejected(runner.invoke(app, ["sweep", str(path), "--store", str(store), "--no-progress"]), store)
            _rejected(runner.invoke(app, ["sweep", str(path), "--store", str(store), "--dry-run"]), store)
            return
        dry = runner.invoke(app, ["sweep", str(path), "--store", str(store), "--dry-run"])
        assert dry.exit_code == 0 and f"{len(sw.members)} members" in dry.output, (dry.output, dry.stderr, dry.exception)
        assert not store.exists()
        event("sweep accepted")


@FUZZ
@given(mutated_plan())
def test_fuzzed_mu_max_plan_is_accepted_or_rejected_with_exit_2(text):
    from slipchain.workflows.dead_weight import Plan, load_plan

    with _workdir() as work:
        path = work / "p.toml"
        path.write_text(text)
        out = work / "out"
        try:
            plan = load_plan(path)
        except ConfigError:
            event("plan rejected")
            _rejected(runner.invoke(app, ["mu-max", str(path), "--out", str(out)]), out)
            return
        # accepted: every setting has its type and range (running the bisections is tested elsewhere)
        assert isinstance(plan, Plan) and plan.seeds >= 1 and 0 < plan.lo < plan.hi and plan.tol > 0
        assert all(0 < t <= 1 for t in plan.theta) and all(m > 0 for m in plan.curve)
        event("plan accepted")


@settings(max_examples=max(1, EXAMPLES * 2 // 3), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(csv_tables())
def test_fuzzed_tester_tables_are_analysed_or_rejected_with_exit_2(tables):
    runs_text, traces_text = tables
    with _workdir() as work:
        runs = work / "runs.csv"
        runs.write_text(runs_text)
        args = ["tester", "analyze", str(runs), "--out", str(work / "out")]
        if traces_text is not None:
            (work / "traces.csv").write_text(traces_text)
            args += ["--traces", str(work / "traces.csv")]
        result = runner.invoke(app, args)
        event(f"tester exit {result.exit_code}")
        if result.exit_code == 2:
            _rejected(result, work / "out")
            assert "runs.csv" in result.stderr or "traces.csv" in result.stderr
        else:
            assert result.exit_code == 0, (result.exit_code, result.output, result.stderr, result.exception)
            assert (work / "out" / "runs.csv").exists() and (work / "out" / "summary.md").exists()


def test_the_generators_reach_both_outcomes():
    """The strategies are not degenerate: each produces accepted and rejected inputs."""
    from hypothesis import find

    def accepted(d):
        try:
            make_config(d)
            return True
        except ConfigError:
            return False

    find(mutated_config(), accepted, settings=settings(max_examples=500, database=None))
    find(mutated_config(), lambda d: not accepted(d), settings=settings(max_examples=500, database=None))
    with pytest.raises(TypeError):
        toml_value(None)

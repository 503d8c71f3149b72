"""Readers of user files under random input: a result or a clear error, never a traceback.

Random bytes (and random text) for every reader of a user file: the tester's runs.csv and
traces.csv, a config TOML, a sweep TOML. Allowed outcomes: a value, or the reader's own error
(TesterDataError, ConfigError, SweepError: the CLI turns them into one line and exit 2).
"""

import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from slipchain import ConfigError, load_config
from slipchain.sweeps.definition import SweepError, load_sweep_definition
from slipchain.tester.inputs import TesterDataError, read_runs, read_traces

FUZZ = settings(max_examples=150, suppress_health_check=[HealthCheck.too_slow])
HEADER = b"run_id,surface,compound,temperature_C,slider_mass_kg,hanging_mass_kg,nominal_area_m2\n"
CONTENT = st.one_of(st.binary(max_size=400), st.text(max_size=400).map(str.encode),
                    st.binary(max_size=300).map(lambda b: HEADER + b))


def _file(data: bytes, name: str) -> Path:
    d = Path(tempfile.mkdtemp())
    p = d / name
    p.write_bytes(data)
    return p


@FUZZ
@given(CONTENT)
def test_runs_csv_gives_runs_or_a_tester_data_error(data):
    try:
        runs = read_runs(_file(data, "runs.csv"))
    except TesterDataError as e:
        assert "runs.csv" in str(e)
    else:
        assert isinstance(runs, list)


@FUZZ
@given(CONTENT)
def test_traces_csv_gives_runs_or_a_tester_data_error(data):
    good = _file(HEADER + b"R1,asphalt,A,20,5.0,2.0,0.004\n", "runs.csv")
    try:
        out = read_traces(_file(data, "traces.csv"), read_runs(good))
    except TesterDataError as e:
        assert "traces.csv" in str(e)
    else:
        assert isinstance(out, list)


@FUZZ
@given(st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode)))
def test_config_toml_gives_a_config_or_a_config_error(data):
    try:
        load_config(_file(data, "c.toml"))
    except ConfigError as e:
        assert "c.toml" in str(e) or "config key" in str(e) or "invalid configuration" in str(e)


@FUZZ
@given(st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode),
                 st.binary(max_size=200).map(lambda b: b"[base]\nN = 11\n[[grid]]\n" + b)))
def test_sweep_toml_gives_a_sweep_or_a_sweep_error(data):
    try:
        load_sweep_definition(_file(data, "s.toml"))
    except SweepError as e:
        assert "s.toml" in str(e)

"""Validation: every bad input named with key, value and what is allowed; the CLI writes nothing."""

import math
import subprocess
import sys

import pytest

from slipchain import ConfigError, load_config, make_config


def test_defaults_are_the_papers_values():
    c = make_config()
    assert c.m == pytest.approx(1e-9)
    assert c.K == pytest.approx(1e3) and c.K_L == pytest.approx(5e3)
    assert c.K_T == pytest.approx(66.667, rel=1e-4) and c.K_d == pytest.approx(333.33, rel=1e-4)
    assert c.f0 == pytest.approx(0.065) and c.omega0 == pytest.approx(1e6)
    assert c.eta == pytest.approx(0.3 * c.omega0) and c.n_contacts == 301
    # MODEL.md: the unique-root limit is about 3e-8 s for the defaults.
    assert 2e-8 < c.dt_unique_root_limit < 4e-8 and c.dt < c.dt_unique_root_limit


BAD = [
    ({"theta": 0.0}, "theta", "(0, 1]"),
    ({"theta": 1.5}, "theta", "(0, 1]"),
    ({"theta": -0.1}, "theta", "(0, 1]"),
    ({"N": 2}, "N", ">= 3"),
    ({"N": 3.5}, "N", "integer"),
    ({"rho": 0.0}, "rho", "> 0"),
    ({"a": -1e-4}, "a", "> 0"),
    ({"E": 0.0}, "E", "> 0"),
    ({"v_d": 0.0}, "v_d", "> 0"),
    ({"v0": -1.0}, "v0", "> 0"),
    ({"dt": 0.0}, "dt", "> 0"),
    ({"dt": 1e-7}, "dt", "several roots"),
    ({"nu": -1.0}, "nu", "(-1, 0.5]"),
    ({"nu": 0.6}, "nu", "(-1, 0.5]"),
    ({"theta": "half"}, "theta", "number"),
    ({"v_d": True}, "v_d", "number"),
    ({"start": "running"}, "start", "'rest', 'steady'"),
    ({"theta": math.nan}, "theta", "(0, 1]"),
    ({"theta": 0.001}, "theta", "N_c = round(theta*N) >= 1"),
    ({"output_interval": 1e-9}, "output_interval", "at least dt"),
]


@pytest.mark.parametrize("data, key, allowed", BAD)
def test_bad_values_are_rejected_with_key_value_and_range(data, key, allowed):
    with pytest.raises(ConfigError) as exc:
        make_config(data)
    msg = str(exc.value)
    assert f"'{key}'" in msg and allowed in msg
    assert repr(data[key])[:6] in msg or str(data[key]) in msg


def test_unknown_key_lists_known_keys():
    with pytest.raises(ConfigError, match=r"unknown config key 'V0'.*known keys:.*v0"):
        make_config({"V0": 1e-3})


def test_toml_file_and_overrides(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('theta = 0.5\nN = 101\nstart = "steady"\neta_c = 300000\n')
    c = load_config(path, ["theta=0.25", "seed=7"])
    assert (c.theta, c.N, c.start, c.seed, c.eta_c) == (0.25, 101, "steady", 7, 3e5)
    assert load_config(None, ["start=rest"]).start == "rest"  # a bare word is read as a string
    # A config written out reads back equal.
    (tmp_path / "back.toml").write_text(c.to_toml())
    assert load_config(tmp_path / "back.toml") == c
    with pytest.raises(ConfigError, match="does not exist"):
        load_config(tmp_path / "missing.toml")
    (tmp_path / "bad.toml").write_text("theta = = 1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(tmp_path / "bad.toml")
    with pytest.raises(ConfigError, match="name=value"):
        load_config(None, ["theta"])


def test_config_is_frozen():
    c = make_config()
    with pytest.raises(Exception):
        c.theta = 0.5


def test_cli_rejects_bad_config_and_writes_nothing(tmp_path):
    out = tmp_path / "r.nc"
    proc = subprocess.run([sys.executable, "-m", "slipchain", "run", "--set", "theta=1.5", "--out", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "'theta'" in proc.stderr and "1.5" in proc.stderr and "(0, 1]" in proc.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []

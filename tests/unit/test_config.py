"""Validation: every bad input named with key, value and what is allowed; the CLI writes nothing."""

import math

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
    assert 2e-8 < c.dt_unique_root_limit < 4e-8
    # issue 26: the adaptive step by default, from dt = 1e-7 s (doubling twice, below 0.9 of the
    # stable step 6.9e-7 s); the fixed step's default is the paper's 2e-8 s, below the limit
    assert (c.integrator, c.dt, c.step_levels, c.dt_is_default) == ("adaptive", 1e-7, 2, True)
    f = make_config(integrator="fixed")
    assert f.dt == 2e-8 and f.dt < f.dt_unique_root_limit


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
    ({"dt": 1e-7, "integrator": "fixed"}, "dt", "several roots"),
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


def test_cli_rejects_bad_config_and_writes_nothing(tmp_path, slipchain_cli):
    out = tmp_path / "r.nc"
    proc = slipchain_cli("run", "--set", "theta=1.5", "--out", out)
    assert proc.returncode == 2
    assert "'theta'" in proc.stderr and "1.5" in proc.stderr and "(0, 1]" in proc.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_backend_is_not_a_config_key_but_old_files_with_it_still_load(tmp_path):
    from slipchain.model.config import config_from_toml
    from slipchain.sweeps.definition import make_sweep
    from slipchain.sweeps.store import Store

    with pytest.raises(ConfigError, match="config key 'backend' .* is no longer accepted: how a run is executed"):
        make_config(backend="gpu")
    # a run file of 0.1 carries `backend = "cpu"` in its config attribute
    old = make_config(theta=0.5).to_toml() + 'backend = "cpu"\n'
    assert config_from_toml(old) == make_config(theta=0.5)
    # a store written by 0.1 has backend in its sweep.toml's [base]; its member ids are what 0.1 computed
    sweep = make_sweep({"base": {"N": 11}, "grid": {"theta": [0.5, 1.0]}})
    store = tmp_path / "store"
    Store.open(store, sweep)
    text = (store / "sweep.toml").read_text().replace("[base]\n", '[base]\nbackend = "cpu"\n')
    (store / "sweep.toml").write_text(text)
    reopened = Store.open(store, sweep)
    assert [m.id for m in reopened.sweep.members] == [m.id for m in sweep.members]
    # frozen reference: the ids that 0.1 wrote into the committed index of the paper preset
    import csv
    from pathlib import Path

    from slipchain.sweeps.definition import load_preset

    index = Path(__file__).resolve().parents[1] / "data" / "fig6-paper-before-26-index.csv"  # docs/fig6-paper until issue 26
    frozen = {row["member_id"] for row in csv.DictReader(index.open())}
    # issue 26: the default is now the adaptive step; a store written before (its sweep.toml without
    # the integrator key) still means the fixed step and resumes with the ids it wrote
    old = tmp_path / "old-store"
    old.mkdir()
    (old / "sweep.toml").write_text((Path(__file__).parents[1] / "data" / "fig6-paper-before-26.toml").read_text())
    (old / "members").mkdir()
    (old / "failed").mkdir()
    stored = Store.open(old).sweep
    assert {m.id for m in stored.members} == frozen and len(frozen) == 368
    assert {m.config.integrator for m in stored.members} == {"fixed"}
    assert not frozen & {m.id for m in load_preset("paper").members}  # today's preset: other members


@pytest.mark.parametrize("delta", [309.0, 312.0, 1e300])
def test_delta_beyond_the_float_range_is_refused_by_name(delta):
    # Found by the CLI fuzzer: delta = 312 gave "dt < 0 s" (v* underflowed to 0), delta = 309 an
    # OverflowError traceback.
    with pytest.raises(ConfigError, match=r"config key 'delta' has value .*v0\*10\*\*-delta"):
        make_config(delta=delta)
    with pytest.raises(ConfigError, match="config key 'dt'"):  # ordinary floats: past the delta check, then dt's
        make_config(delta=100.0, integrator="fixed", dt=2e-8)

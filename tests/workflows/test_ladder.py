"""The ladder of issue 29 (slipchain.workflows.ladder): load effects read from result tables, with
their errors and, for undecided loads, the range the runs allow; the committed ladder draws."""

import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from slipchain.model.config import ConfigError
from slipchain.workflows.ladder import effect_of_evaluations, effect_of_mu_max, effect_of_table, ladder_table, load_ladder

ROOT = Path(__file__).resolve().parents[2]


def test_a_table_gives_the_ratio_of_its_extreme_loads_with_the_propagated_error(tmp_path):
    # a figure's table (mu, err), rows chosen by `where`
    t = pd.DataFrame({"v_d": [1e-3] * 3 + [3e-4] * 3, "theta": [0.05, 0.5, 1.0] * 2,
                      "mu": [0.9, 0.8, 0.72, 0.95, 0.95, 0.96], "err": [0.009, 0.01, 0.0072, 0.01, 0.01, 0.01]})
    t.to_csv(tmp_path / "t.csv", index=False)
    e = effect_of_table(tmp_path / "t.csv", {"v_d": 1e-3})
    assert (e.theta_min, e.theta_max, e.low, e.high) == (0.05, 1.0, 0.9, 0.72)
    assert e.ratio == pytest.approx(0.8)
    assert e.ratio_se == pytest.approx(0.8 * math.hypot(0.01, 0.01))
    # a sweep's index (one mu_star per member): seed means, SE = std/sqrt(n); failed members left out
    rng = np.random.default_rng(1)
    mu = {0.05: rng.normal(0.9, 0.01, 5), 1.0: rng.normal(0.7, 0.02, 4)}
    rows = [{"theta": th, "status": "completed", "mu_star": m} for th, ms in mu.items() for m in ms]
    rows.append({"theta": 1.0, "status": "diverged", "mu_star": 5.0})
    pd.DataFrame(rows).to_csv(tmp_path / "i.csv", index=False)
    e = effect_of_table(tmp_path / "i.csv", {})
    lo, hi = mu[0.05], mu[1.0]
    se = [np.std(x, ddof=1) / np.sqrt(len(x)) for x in (lo, hi)]
    assert e.ratio == pytest.approx(hi.mean() / lo.mean())
    assert e.ratio_se == pytest.approx(e.ratio * math.hypot(se[0] / lo.mean(), se[1] / hi.mean()))
    with pytest.raises(ConfigError, match="'where'"):
        effect_of_table(tmp_path / "t.csv", {"v_d": 5.0})
    with pytest.raises(ConfigError, match="columns of the table"):
        effect_of_table(tmp_path / "t.csv", {"eta_c": 1e5})
    # a figure's table with two points per theta that `where` leaves (here both velocities) is refused,
    # naming the column that tells them apart, never averaged (docs/fig6-3d-eps1/table.csv grew a
    # geometry column, and a rung that chose only v_d averaged the slab with the 2-D chains)
    with pytest.raises(ConfigError, match=r"one row per theta \(rows at theta = 0.05 differ in v_d"):
        effect_of_table(tmp_path / "t.csv", {})
    # the onsets' mu_max.csv (`slipchain figure traces`): mu_max and its SE per load, chosen by interface and ramp
    t.rename(columns={"v_d": "N", "mu": "mu_max", "err": "mu_max_se"}).assign(t_ramp=6.0).to_csv(tmp_path / "m.csv", index=False)
    e = effect_of_table(tmp_path / "m.csv", {"N": 1e-3, "t_ramp": 6.0})
    assert (e.low, e.high, e.ratio) == (0.9, 0.72, pytest.approx(0.8)) and e.ratio_se == pytest.approx(0.8 * math.hypot(0.01, 0.01))


def _mu_max_output(path: Path) -> None:
    """A mu-max output with theta = 1 decided (two seeds) and theta = 0.1 not: seed 0 steady at 0.5 and
    runaway at 0.8, seed 1 runaway already at 0.5 (a refuted bracket)."""
    path.mkdir()
    pd.DataFrame([
        {"theta": 0.1, "seed": 0, "status": "no-steady", "mu_max": np.nan, "lo": 0.5, "hi": 0.8, "v_max_m_s": 1e-6, "runs": 4},
        {"theta": 0.1, "seed": 1, "status": "bracket", "mu_max": np.nan, "lo": 0.5, "hi": 1.1, "v_max_m_s": np.nan, "runs": 2},
        {"theta": 1.0, "seed": 0, "status": "ok", "mu_max": 0.94, "lo": 0.93, "hi": 0.95, "v_max_m_s": 1e-4, "runs": 7},
        {"theta": 1.0, "seed": 1, "status": "ok", "mu_max": 0.92, "lo": 0.91, "hi": 0.93, "v_max_m_s": 1e-4, "runs": 7},
    ]).to_csv(path / "mu_max.csv", index=False)
    pd.DataFrame([
        {"theta": 0.1, "seed": 0, "mu_a": 0.5, "velocity_status": "ok"},
        {"theta": 0.1, "seed": 0, "mu_a": 1.1, "velocity_status": "runaway"},
        {"theta": 0.1, "seed": 0, "mu_a": 0.8, "velocity_status": "runaway"},
        {"theta": 0.1, "seed": 0, "mu_a": 0.65, "velocity_status": "no-steady"},
        {"theta": 0.1, "seed": 1, "mu_a": 0.5, "velocity_status": "runaway"},
        {"theta": 0.1, "seed": 1, "mu_a": 1.1, "velocity_status": "runaway"},
        {"theta": 1.0, "seed": 0, "mu_a": 0.93, "velocity_status": "ok"},
        {"theta": 1.0, "seed": 1, "mu_a": 0.91, "velocity_status": "ok"},
    ]).to_csv(path / "evaluations.csv", index=False)


def test_an_undecided_load_gives_the_bounds_and_the_range_of_the_ratio(tmp_path):
    _mu_max_output(tmp_path / "mm")
    e = effect_of_mu_max(tmp_path / "mm")
    assert math.isnan(e.low) and math.isnan(e.ratio)
    assert e.high == pytest.approx(0.93)
    # the summary's SE: the seed scatter, at least the bisection's half-width / sqrt(3 n)
    assert e.high_se == pytest.approx(max(np.std([0.94, 0.92], ddof=1) / np.sqrt(2), 0.01 / np.sqrt(6)))
    assert "theta = 0.1: 2 seed(s) undecided" in e.bounds and "runaway from mu_a = 0.5" in e.bounds
    assert "no-steady at mu_a = 0.65" in e.bounds
    # seed by seed: seed 0's mu_max in [0.5, 0.8], seed 1's in [0, 0.5]: their envelope [0, 0.8];
    # so R = 0.93 / mu_max(0.1) is at least 0.93/0.8 and unbounded above
    assert e.ratio_min == pytest.approx(0.93 / 0.8) and math.isnan(e.ratio_max)
    # a grid of runs: bounds at every load, no ratio
    ev = effect_of_evaluations(tmp_path / "mm" / "evaluations.csv")
    assert math.isnan(e.ratio) and ev.bounds.startswith("theta = 0.1: steady up to mu_a = 0.5, runaway from mu_a = 0.5")
    assert ev.bounds.endswith("theta = 1: steady up to mu_a = 0.93")
    # ... and the range of R its runs allow, by the same rule: at theta = 1 mu_max in [0.91, inf)
    # (the envelope of seed 0's [0.93, inf) and seed 1's [0.91, inf)), at 0.1 in [0, 0.8]
    assert ev.ratio_min == pytest.approx(0.91 / 0.8) and math.isnan(ev.ratio_max)


def test_a_grid_of_runs_over_several_ramps_is_read_one_ramp_at_a_time(tmp_path):
    """An evaluations rung with ``where`` (presets/ladder-eps1-slow-grid.toml sweeps the ramp too): the
    bounds come from the chosen ramp's runs alone; a column or value the table lacks is an error
    that names them."""
    pd.DataFrame([
        {"theta": 0.5, "seed": 0, "t_ramp": 2.0, "mu_a": 0.65, "velocity_status": "no-steady"},
        {"theta": 0.5, "seed": 0, "t_ramp": 2.0, "mu_a": 0.75, "velocity_status": "runaway"},
        {"theta": 0.5, "seed": 0, "t_ramp": 20.0, "mu_a": 0.75, "velocity_status": "ok"},
        {"theta": 0.5, "seed": 0, "t_ramp": 20.0, "mu_a": 0.85, "velocity_status": "runaway"},
    ]).to_csv(tmp_path / "g.csv", index=False)
    slow = effect_of_evaluations(tmp_path / "g.csv", {"t_ramp": 20.0})
    assert slow.bounds == "theta = 0.5: steady up to mu_a = 0.75, runaway from mu_a = 0.85"
    # one load is both ends: R in [0.75/0.85, 0.85/0.75]
    assert (slow.ratio_min, slow.ratio_max) == (pytest.approx(0.75 / 0.85), pytest.approx(0.85 / 0.75))
    # no runaway at one load: that end of the range stays open (NaN, as a mu-max rung's), never inf
    assert math.isnan(effect_of_evaluations(tmp_path / "g.csv", {"t_ramp": 20.0, "mu_a": 0.75}).ratio_max)
    fast = effect_of_evaluations(tmp_path / "g.csv", {"t_ramp": 2.0})
    assert fast.bounds == "theta = 0.5: runaway from mu_a = 0.75, no-steady at mu_a = 0.65"
    both = effect_of_evaluations(tmp_path / "g.csv")
    assert both.bounds == "theta = 0.5: steady up to mu_a = 0.75, runaway from mu_a = 0.75, no-steady at mu_a = 0.65"
    with pytest.raises(ConfigError, match="columns of the table"):
        effect_of_evaluations(tmp_path / "g.csv", {"t_decide": 2.5})
    with pytest.raises(ConfigError, match="a selection with rows"):
        effect_of_evaluations(tmp_path / "g.csv", {"t_ramp": 6.0})


def test_an_evaluations_rung_reads_several_csvs_as_one(tmp_path):
    """A grid continued by a second preset (tester-16-slow's 3-s ramp, then tester-16-slower's heavier
    weights): ``source`` may list both; the bounds and R's range are those of their rows together.
    A list is refused for other kinds, naming the key."""
    pd.DataFrame([
        {"theta": 0.05, "seed": 0, "t_ramp": 3.0, "mu_a": 0.95, "velocity_status": "ok", "velocity_m_s": 1e-4},
        {"theta": 1.0, "seed": 0, "t_ramp": 3.0, "mu_a": 0.95, "velocity_status": "ok", "velocity_m_s": 2e-4},
    ]).to_csv(tmp_path / "a.csv", index=False)
    pd.DataFrame([
        {"theta": 0.05, "seed": 0, "t_ramp": 3.0, "mu_a": 1.15, "velocity_status": "runaway"},
        {"theta": 1.0, "seed": 0, "t_ramp": 3.0, "mu_a": 1.05, "velocity_status": "runaway"},
        {"theta": 1.0, "seed": 0, "t_ramp": 3.0, "mu_a": 1.25, "velocity_status": "error", "message": "not run"},
        {"theta": 1.0, "seed": 0, "t_ramp": 3.0, "mu_a": 1.35, "velocity_status": "error", "message": "diverged"},
    ]).to_csv(tmp_path / "b.csv", index=False)
    assert math.isnan(effect_of_evaluations(tmp_path / "a.csv").ratio_max)  # alone: no runaway, R unbounded above
    both = effect_of_evaluations([tmp_path / "a.csv", tmp_path / "b.csv"], {"t_ramp": 3.0})
    # theta = 1 in [0.95, 1.05), theta = 0.05 in [0.95, 1.15): R in [0.95/1.15, 1.05/0.95]
    assert (both.ratio_min, both.ratio_max) == (pytest.approx(0.95 / 1.15), pytest.approx(1.05 / 0.95))
    # a store's member not run yet is said as such, not as a failure
    assert both.bounds.endswith("theta = 1: steady up to mu_a = 0.95, runaway from mu_a = 1.05, error at mu_a = 1.35, "
                                "not run at mu_a = 1.25"), both.bounds
    ladder = tmp_path / "l.toml"
    rung = '[[rung]]\nname = "a"\nadds = "b"\nobservable = "mu_max"\nkind = "{kind}"\nsource = ["a.csv", "b.csv"]\n'
    ladder.write_text(rung.format(kind="evaluations"))
    row = ladder_table(ladder).iloc[0]
    assert row["ratio_max"] == pytest.approx(1.05 / 0.95) and row["source"] == "a.csv; b.csv"
    ladder.write_text(rung.format(kind="table"))
    with pytest.raises(ConfigError, match=r"'source' has value \['a.csv', 'b.csv'\]; expected a path, or a list"):
        load_ladder(ladder)


def test_runs_with_an_outcome_count_held_weights_as_lower_bounds(tmp_path):
    """`slipchain figure traces`' onsets.csv (the tester's release: an outcome per run) as an evaluations
    rung: a held run bounds mu_max from below as a steady one does, an undecided one bounds nothing; the
    same runs read by the tester's status alone leave the held weights undecided."""
    rows = [(0.05, 0.85, "no-steady", "held"), (0.05, 0.9, "runaway", "runaway"), (0.5, 0.6, "no-steady", "held"),
            (0.5, 0.7, "runaway", "runaway"), (1.0, 0.75, "no-steady", "held"), (1.0, 0.8, "no-steady", "undecided"),
            (1.0, 0.85, "runaway", "runaway")]
    d = pd.DataFrame([{"N": 16, "theta": th, "seed": 0, "mu_a": m, "velocity_status": st, "outcome": o}
                      for th, m, st, o in rows])
    d.to_csv(tmp_path / "o.csv", index=False)
    e = effect_of_evaluations(tmp_path / "o.csv", {"N": 16})
    assert e.per_load == ("0.05: held up to mu_a = 0.85, runaway from mu_a = 0.9; 0.5: held up to mu_a = 0.6, runaway "
                          "from mu_a = 0.7; 1: held up to mu_a = 0.75, runaway from mu_a = 0.85, undecided at mu_a = 0.8")
    # theta = 1 in [0.75, 0.85), theta = 0.05 in [0.85, 0.9): R in [0.75/0.9, 0.85/0.85]
    assert (e.ratio_min, e.ratio_max) == (pytest.approx(0.75 / 0.9), pytest.approx(1.0))
    d.drop(columns="outcome").to_csv(tmp_path / "s.csv", index=False)
    s = effect_of_evaluations(tmp_path / "s.csv")
    assert s.per_load.startswith("0.05: runaway from mu_a = 0.9, no-steady at mu_a = 0.85") and s.ratio_min == pytest.approx(0.0)
    # beside a table of the tester's status alone (shorter runs: no outcome), its runs count as they are
    pd.DataFrame([{"theta": 1.0, "seed": 0, "mu_a": 0.8, "velocity_status": "runaway"},
                  {"theta": 0.05, "seed": 0, "mu_a": 0.88, "velocity_status": "no-steady"}]).to_csv(tmp_path / "t.csv", index=False)
    d.drop(columns="velocity_status").to_csv(tmp_path / "o2.csv", index=False)
    m = effect_of_evaluations([tmp_path / "o2.csv", tmp_path / "t.csv"])
    assert m.per_load.startswith("0.05: held up to mu_a = 0.85, runaway from mu_a = 0.9, undecided at mu_a = 0.88")
    assert (m.ratio_min, m.ratio_max) == (pytest.approx(0.75 / 0.9), pytest.approx(0.8 / 0.85))


def test_a_bad_ladder_file_names_the_rung_key_and_value(tmp_path, slipchain_cli):
    bad = tmp_path / "l.toml"
    bad.write_text('[[rung]]\nname = "a"\nadds = "b"\nobservable = "mu_max"\nkind = "guess"\nsource = "x"\n')
    with pytest.raises(ConfigError, match=r"rung 1: config key 'kind' has value 'guess'; expected 'mu-max' or"):
        load_ladder(bad)
    bad.write_text('[[rung]]\nname = "a"\nadds = "b"\nobservable = "mu_max"\nkind = "table"\n')
    with pytest.raises(ConfigError, match="'source' has value None"):
        load_ladder(bad)
    bad.write_text("")
    with pytest.raises(ConfigError, match="at least one"):
        load_ladder(bad)
    r = slipchain_cli("figure", "ladder", "--ladder", tmp_path / "none.toml", "--out", tmp_path / "o")
    assert r.returncode == 2 and "no such file" in r.stderr and not (tmp_path / "o").exists()


def test_the_committed_ladder_reads_every_rung_and_draws(tmp_path, slipchain_cli):
    """docs/ladder/ladder.toml: every source it names is committed and read; the figure is written."""
    table = ladder_table(ROOT / "docs" / "ladder" / "ladder.toml")
    assert len(table) == len(load_ladder(ROOT / "docs" / "ladder" / "ladder.toml"))
    first = table.iloc[0]  # the paper's model: mu_star at v_d1 falls by about 20 % (Fig. 6)
    assert first["ratio"] == pytest.approx(0.79, abs=0.02) and first["ratio_se"] < 0.01
    assert all(np.isfinite(r["ratio"]) or r["bounds"] or r["note"] for _, r in table.iterrows())
    r = slipchain_cli("figure", "ladder", "--ladder", ROOT / "docs" / "ladder" / "ladder.toml", "--out", tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "ladder.png").stat().st_size > 10_000 and (tmp_path / "ladder.csv").exists()
    assert pd.read_csv(tmp_path / "ladder.csv")["ratio"].iloc[0] == pytest.approx(first["ratio"])

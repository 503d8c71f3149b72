"""Sweep definitions and the store: parsing, validation, identity, refusal of a foreign store."""

import numpy as np
import pytest

from slipchain import make_config
from slipchain.sweeps.executor import error_dataset
from slipchain.sweeps.store import Store, open_sweep
from slipchain.sweeps.definition import SweepError, load_preset, load_sweep_definition, make_sweep, member_id

FAST = {"N": 31, "start": "steady", "v0": 0.01, "delta": 0.2, "t_total": 3e-3}


def test_product_and_union_of_grids():
    sw = make_sweep({"base": FAST, "grid": [
        {"N": [31], "theta": [0.5, 1.0], "seed": [0, 1, 2]},
        {"N": [61], "theta": [1.0], "seed": [0]},
    ]})
    assert sw.dims == ("N", "theta", "seed")
    assert sw.coords == {"N": [31, 61], "theta": [0.5, 1.0], "seed": [0, 1, 2]}
    assert len(sw.members) == 2 * 3 + 1
    m = sw.members[0]
    assert m.config.N == 31 and m.config.theta == 0.5 and m.config.seed == 0 and m.config.start == "steady"
    # integers are accepted for float parameters, as in config files
    assert make_sweep({"grid": {"theta": [1]}}).members[0].config.theta == 1.0


def test_member_id_is_a_content_hash():
    a = make_config(FAST)
    assert member_id(a) == member_id(make_config(dict(FAST)))
    assert member_id(a) != member_id(a.with_updates(seed=1))
    assert member_id(a) != member_id(a.with_updates(t_total=3.0000001e-3))
    # the same physics reached through base or grid has the same id
    s1 = make_sweep({"base": {**FAST, "theta": 0.5}, "grid": {"seed": [0]}})
    s2 = make_sweep({"base": FAST, "grid": {"theta": [0.5], "seed": [0]}})
    assert s1.members[0].id == s2.members[0].id


@pytest.mark.parametrize("data, words", [
    ({"grid": {"thetaa": [1.0]}}, ["unknown parameter 'thetaa'", "grid 1", "theta"]),
    ({"grid": {"theta": []}}, ["'theta'", "empty list"]),
    ({"grid": {"theta": [0.5, 0.5]}}, ["'theta'", "repeated"]),
    ({"grid": {"theta": [0.5, 1.5]}}, ["grid 1", "theta=1.5", "config key 'theta' has value 1.5", "(0, 1]"]),
    ({"grid": [{"theta": [1.0]}, {"seed": [1]}]}, ["grid 2", "same parameters"]),
    ({"base": {"N": -3}, "grid": {"seed": [0]}}, ["[base]", "config key 'N' has value -3"]),
    ({"base": FAST}, ["no [grid] table"]),
    ({"grid": {"seed": [0]}, "sweep": {}}, ["unknown top-level key", "sweep"]),
    ({"grid": {"backend": ["cpu"]}}, ["'backend' cannot be swept"]),
])
def test_bad_definitions_are_refused_with_the_key_and_value(data, words):
    with pytest.raises(SweepError) as e:
        make_sweep(data)
    for w in words:
        assert w in str(e.value)


def test_sweep_file_errors_name_the_file(tmp_path):
    with pytest.raises(SweepError, match="does not exist"):
        load_sweep_definition(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[grid]\ntheta = [0.5,\n")
    with pytest.raises(SweepError, match="bad.toml.*not valid TOML"):
        load_sweep_definition(bad)


def test_presets_define_fig6():
    quick, paper = load_preset("quick"), load_preset("paper")
    for sw in (quick, paper):
        assert {"N", "theta", "eta_c", "v_d", "seed"} <= set(sw.dims)
        assert set(sw.coords["eta_c"]) == {1e6, 3e5, 1e5} and set(sw.coords["v_d"]) == {1e-3, 3e-4}
        assert 301 in sw.coords["N"] and 1001 in sw.coords["N"]
    # issue 26: both run the default integrator (adaptive) at the default base step, the paper's
    # time-step grid at half of it
    for sw in (quick, paper):
        assert {m.config.integrator for m in sw.members} == {"adaptive"}
    assert {m.config.dt for m in quick.members} == {make_config().dt} and set(paper.coords["dt"]) == {1e-7, 5e-8}
    main = [m for m in paper.members if m.coords["N"] == 301 and m.coords["dt"] == 1e-7 and m.coords["sem_target"] == 0.01]
    thetas = sorted({m.coords["theta"] for m in main})
    assert len(thetas) >= 10 and thetas[0] == 0.05 and thetas[-1] == 1.0
    assert len(paper.coords["seed"]) >= 4
    assert len({m.coords["theta"] for m in paper.members if m.coords["N"] == 1001}) >= 3
    with pytest.raises(SweepError, match="preset 'huge' is unknown"):
        load_preset("huge")


def test_every_preset_loads_and_issue_12s_presets_cover_what_it_asks():
    from slipchain.sweeps.definition import PRESETS

    sweeps = {name: load_preset(name) for name in PRESETS}
    eps1 = sweeps["eps1"]
    assert eps1.base.epsilon == 1.0 and eps1.base.integrator == "adaptive" and eps1.base.N == 301
    assert eps1.base.start == "steady" and eps1.base.min_cycles > 0
    thetas = sorted(eps1.coords["theta"])
    assert len(thetas) >= 6 and thetas[0] == 0.05 and thetas[-1] == 1.0 and len(eps1.coords["seed"]) >= 2
    assert set(eps1.coords["eta_c"]) == {1e5, 1e6} and set(eps1.coords["v_d"]) == {1e-3, 3e-4}
    tol = sweeps["eps1-check"]
    assert sorted(tol.coords["step_tol"]) == [1e-3, 1e-2] and tol.base.epsilon == 1.0
    assert {m.config.step_tol for m in tol.members} == {1e-3, 1e-2}
    assert {m.config.start for m in tol.members} == {"rest", "steady"}
    eps01 = sweeps["eps01"]
    assert eps01.base.epsilon == 0.1 and eps01.base.dt == 2e-9 < eps01.base.dt_unique_root_limit
    assert set(eps01.coords["integrator"]) == {"fixed", "adaptive"}
    ada = sweeps["adaptive"]
    assert ada.base.epsilon == 1e-2 and ada.base.dt == 1e-8 and set(ada.coords["integrator"]) == {"fixed", "adaptive"}
    for sw in (tol, eps01, ada):  # the Fig. 6 corners
        assert sorted(set(sw.coords["theta"])) == [0.05, 1.0] and set(sw.coords["eta_c"]) == {1e5, 1e6}
        assert set(sw.coords["v_d"]) == {1e-3, 3e-4} and len(sw.coords["seed"]) == 2


def test_definition_round_trips_through_the_store(tmp_path):
    sw = make_sweep({"name": "rt", "base": FAST, "grid": [{"theta": [0.5, 1.0], "seed": [0]}, {"theta": [0.2], "seed": [3]}]})
    st = Store.open(tmp_path / "s", sw)
    again = Store.open(tmp_path / "s")
    assert again.sweep.digest == sw.digest and again.sweep.dims == sw.dims
    assert [m.id for m in again.sweep.members] == [m.id for m in sw.members]
    assert Store.open(tmp_path / "s", sw).path == st.path  # same definition: accepted


def test_a_store_of_another_sweep_is_refused(tmp_path):
    a = make_sweep({"name": "a", "base": FAST, "grid": {"theta": [0.5, 1.0]}})
    b = make_sweep({"name": "b", "base": FAST, "grid": {"theta": [0.5, 0.8]}})
    c = make_sweep({"name": "a", "base": {**FAST, "t_total": 4e-3}, "grid": {"theta": [0.5, 1.0]}})
    Store.open(tmp_path / "s", a)
    with pytest.raises(SweepError) as e:
        Store.open(tmp_path / "s", b)
    assert "different sweep definition" in str(e.value) and "theta: [0.5, 1.0] vs [0.5, 0.8]" in str(e.value)
    with pytest.raises(SweepError, match="base t_total: 0.003 vs 0.004"):
        Store.open(tmp_path / "s", c)
    other = tmp_path / "other"
    other.mkdir()
    (other / "data.txt").write_text("x")
    with pytest.raises(SweepError, match="not a slipchain sweep store"):
        Store.open(other, a)
    with pytest.raises(SweepError, match="not a slipchain sweep store"):
        open_sweep(tmp_path / "missing")


def test_store_files_and_dataset_statuses(tmp_path):
    """Writing by hand (no Dask): completed -> members/, failures -> failed/, Dataset statuses."""
    from slipchain import run

    sw = make_sweep({"base": FAST, "grid": [{"theta": [0.5, 1.0], "seed": [0, 1]}, {"theta": [0.2], "seed": [0]}]})
    st = Store.open(tmp_path / "s", sw)
    m_ok, m_err = sw.members[0], sw.members[1]
    ds = run(m_ok.config)
    assert ds.attrs["status"] == "completed"
    st.write_member(m_ok, ds)
    st.write_member(m_err, error_dataset(m_err, RuntimeError("boom")))
    assert st.completed_ids() == {m_ok.id} and st.failed_ids() == {m_err.id}
    assert [m.id for m in st.pending()] == [m.id for m in sw.members[1:]]
    out = st.dataset()
    assert dict(out.sizes) == {"theta": 3, "seed": 2}
    status = {(float(t), int(s)): str(out["status"].sel(theta=t, seed=s).item()) for t in (0.2, 0.5, 1.0) for s in (0, 1)}
    assert status == {(0.5, 0): "completed", (0.5, 1): "error", (1.0, 0): "missing", (1.0, 1): "missing",
                      (0.2, 0): "missing", (0.2, 1): "absent"}
    assert out["mu_star"].sel(theta=0.5, seed=0).item() == ds.attrs["mu_star"]
    assert np.isnan(out["mu_star"].sel(theta=0.5, seed=1).item())
    assert "RuntimeError: boom" in out["message"].sel(theta=0.5, seed=1).item()
    # the stored member is the whole run, with its point and the sweep it belongs to
    back = st.read_member(m_ok)
    assert back.attrs["sweep_theta"] == 0.5 and back.attrs["sweep_digest"] == sw.digest
    np.testing.assert_array_equal(back["f_d"].values, ds["f_d"].values)
    # a later success replaces the failure
    st.write_member(m_err, run(m_err.config))
    assert st.failed_ids() == set() and st.completed_ids() == {m_ok.id, m_err.id}
    index = (st.write_index()).read_text().splitlines()
    assert len(index) == 1 + len(sw.members) and index[0].startswith("member_id,theta,seed,status")


def test_every_shipped_preset_is_catalogued_and_found_by_name(tmp_path, monkeypatch):
    """Issue 30: the catalogue (slipchain presets) lists exactly the shipped files, a sweep's run count
    is its number of members, and a name is found from any folder (a path still wins)."""
    from slipchain.sweeps.catalogue import CATALOGUE, find_study, preset_files
    from slipchain.workflows.dead_weight import load_plan

    files = preset_files()
    assert set(files) == set(CATALOGUE)
    for name, path in files.items():
        study = CATALOGUE[name]
        assert study.kind in ("study", "validation", "plan") and study.purpose and study.wall_2_cores
        if study.kind == "plan":
            load_plan(path)
        else:
            assert len(load_sweep_definition(path).members) == study.runs, name
    monkeypatch.chdir(tmp_path)
    assert find_study("fig6-3d") == files["fig6-3d"] == find_study("fig6-3d.toml")
    assert find_study("quick") == files["fig6-quick"] and find_study("nonesuch") is None
    (tmp_path / "quick").write_text("")
    assert find_study("quick").resolve() == (tmp_path / "quick").resolve()


def test_a_study_extends_another_as_if_written_out_flat(tmp_path):
    """``extends``: the parent's tables laid under the child's key by key, its grids and name replaced;
    members, ids and digest those of the flat file the child stands for. The shipped variants resolve
    to the sweeps their committed stores recorded flat (the store's own sweep.toml: a frozen reference)."""
    import tomllib
    from pathlib import Path

    from slipchain.sweeps.catalogue import preset_files, read_study
    from slipchain.workflows.dead_weight import load_plan

    (tmp_path / "parent.toml").write_text('name = "parent"\n[base]\nN = 31\nstart = "steady"\nv0 = 0.01\n'
                                          't_total = 3e-3\ntheta = 0.5\n[[grid]]\nseed = [0, 1]\n')
    (tmp_path / "child.toml").write_text('extends = "parent.toml"\n[base]\ntheta = 1.0\n')
    (tmp_path / "grandchild.toml").write_text('name = "g"\nextends = "child.toml"\n[base]\nN = 41\n'
                                              '[[grid]]\nseed = [3]\ndelta = [0.2, 0.3]\n')
    flat = make_sweep({"base": {**FAST, "theta": 1.0, "delta": 0.5}, "grid": {"seed": [0, 1]}})
    child = load_sweep_definition(tmp_path / "child.toml")
    assert child.name == "sweep" and child.digest == flat.digest  # the parent's name is not inherited
    assert [m.config for m in child.members] == [m.config for m in flat.members]
    grand = load_sweep_definition(tmp_path / "grandchild.toml")
    assert grand.name == "g" and grand.dims == ("seed", "delta")
    assert [(m.config.N, m.config.theta, m.config.start, m.config.seed, m.config.delta) for m in grand.members] == \
        [(41, 1.0, "steady", 3, 0.2), (41, 1.0, "steady", 3, 0.3)]
    assert make_sweep(tomllib.loads(grand.to_toml())).digest == grand.digest  # written out flat, the same sweep
    # a shipped name when no file of that name lies beside it
    (tmp_path / "by-name.toml").write_text('extends = "tester-32-slower"\n[base]\nN = 64\nLy = 64\n'
                                           'krylov_preconditioner = "additive"\n')
    stores = Path(__file__).resolve().parents[2] / "stores"
    for n in (64, 128):
        recorded = load_sweep_definition(stores / f"tester-{n}-slower" / "sweep.toml", legacy=True)
        assert load_sweep_definition(preset_files()[f"tester-{n}-slower"]).digest == recorded.digest
    assert load_sweep_definition(tmp_path / "by-name.toml").digest == load_sweep_definition(
        stores / "tester-64-slower" / "sweep.toml", legacy=True).digest
    # a plan: [bisection] merged key by key too
    plan, parent = load_plan(preset_files()["mu-max-rubber-400ms"]), load_plan(preset_files()["mu-max-rubber"])
    assert plan.name == "mu-max-rubber-400ms" and plan.theta == (0.5,) and plan.seeds == parent.seeds == 2
    assert (plan.base.t_ramp, plan.base.t_decide) == (0.4, 0.6) and plan.base.material == parent.base.material
    assert plan.base.with_updates(t_ramp=0.2, t_decide=0.4) == parent.base
    assert "extends" not in read_study(tmp_path / "grandchild.toml")


@pytest.mark.parametrize("extends, words", [
    ('"nonesuch"', ["key 'extends' has value 'nonesuch'", "expected a study file beside it or a shipped preset",
                    "tester-32-slower"]),
    ("3", ["key 'extends' has value 3", "expected the name of a shipped preset or the path of a study file"]),
    ('"loop.toml"', ["loop.toml': key 'extends' has value 'bad.toml'", "leads back to itself",
                     "bad.toml -> loop.toml -> bad.toml",
                     "expected a chain that ends in a study without 'extends'"]),
])
def test_a_bad_extends_is_refused_naming_key_value_and_what_was_expected(tmp_path, slipchain_cli, extends, words):
    (tmp_path / "loop.toml").write_text('extends = "bad.toml"\n[[grid]]\nseed = [0]\n')
    (tmp_path / "bad.toml").write_text(f'extends = {extends}\n[base]\nN = 31\n[[grid]]\nseed = [0]\n')
    with pytest.raises(SweepError) as err:
        load_sweep_definition(tmp_path / "bad.toml")
    assert all(w in str(err.value) for w in words), str(err.value)
    r = slipchain_cli("sweep", str(tmp_path / "bad.toml"), "--store", str(tmp_path / "store"))
    assert r.returncode == 2 and "extends" in r.stderr and not (tmp_path / "store").exists()

"""Fig. 6 in 3-D and the slip maps through the CLI (issue 13): a small real sweep on a Dask local
cluster, its figure, report and tables; the maps of a 2-D run; bad input exits 2.

The sweep drives fast (v_d = 0.1 and 0.05 m/s, eta_c = omega0) so that its tiny systems slide
steadily in 0.3 ms and pass the run's physics checks (near v0 a 16-block system stick-slips as a
whole with a period of milliseconds)."""

import json
import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

SWEEP = """
name = "geometry-small"
[base]
t_total = 3e-4
dt = 3e-8
eta_c = 1e6
start = "steady"
output_interval = 1e-5
[[grid]]
geometry = ["chain", "chain2d", "slab"]
N = [16]
Ly = [1]
theta = [0.25, 1.0]
v_d = [0.1, 0.05]
seed = [0]
[[grid]]
geometry = ["slab", "halfspace"]
N = [8]
Ly = [8]
theta = [0.25, 1.0]
v_d = [0.05]
seed = [0]
"""


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "slipchain", *args], capture_output=True, text=True)


def test_fig6_3d_from_a_sweep(tmp_path, slipchain_cli, store_of_runs):
    (tmp_path / "s.toml").write_text(SWEEP)
    store, out = tmp_path / "store", tmp_path / "fig"
    # one worker: each worker process compiles the kernels anew, and the members are tiny (the
    # sweep on several workers is tests/workflows/test_runner.py's)
    r = _cli("sweep", str(tmp_path / "s.toml"), "--store", str(store), "--workers", "1", "--no-progress")
    assert r.returncode == 0, r.stderr
    r = slipchain_cli("figure", "fig6-3d", "--store", store, "--out", out)
    assert r.returncode == 0, r.stderr
    table = pd.read_csv(out / "table.csv")
    drops = pd.read_csv(out / "drops.csv")
    assert set(table["geometry"]) == {"chain", "chain2d", "slab", "halfspace"}
    assert len(table) == 16 and (table["n"] == 1).all()
    # each drop is the ratio of the table's mu at the largest and smallest theta
    for _, d in drops.iterrows():
        rows = table[(table["geometry"] == d["geometry"]) & (table["N"] == d["N"]) & (table["Ly"] == d["Ly"])
                     & np.isclose(table["v_d"], d["v_d"])].sort_values("theta")
        assert d["ratio"] == pytest.approx(rows["mu"].iloc[-1] / rows["mu"].iloc[0], rel=1e-5)
    assert np.isinf(drops[drops["geometry"] == "halfspace"]["H_over_L"]).all()
    report = (out / "report.md").read_text()
    assert "| 1 |" in report and "halfspace" in report and (out / "fig6-3d.png").stat().st_size > 10_000
    # f_d's sawtooth per point at each geometry's main size: one row per (geometry, theta, v_d) of one seed
    saw = pd.read_csv(out / "sawtooth.csv")
    assert set(saw["geometry"]) == set(table["geometry"]) and (saw["n"] == 1).all()
    keys = ["geometry", "theta", "v_d"]
    assert len(saw.merge(table[keys].drop_duplicates(), on=keys)) == len(saw) >= 10
    assert "## The sawtooth per point" in report and saw["swing"].notna().all()
    assert "Partial" not in report
    # the explicit levels follow each geometry's stability bound: the report names the step of every point
    steps = [line for line in report.splitlines() if line.startswith("| integrator = adaptive from dt = 3e-08 s")]
    assert "the step differs per point" in report and len(steps) == 2
    assert all(sum(f"| {g}, " in line or f"; {g}, " in line for line in steps) == 1 for g in set(table["geometry"]))
    # a store still running (one member's file not there yet): the report says how much of it the figure holds
    partial = tmp_path / "partial"
    shutil.copytree(store, partial)
    sorted((partial / "members").glob("*.nc"))[0].unlink()
    r = slipchain_cli("figure", "fig6-3d", "--store", partial, "--out", tmp_path / "fig-partial")
    assert r.returncode == 0, r.stderr
    assert "**Partial**: 15 of the sweep's 16 members completed" in (tmp_path / "fig-partial" / "report.md").read_text()
    assert len(pd.read_csv(tmp_path / "fig-partial" / "table.csv")) == 15
    # a store of one geometry (in its base config, as presets/fig6-3d-eps1.toml) is read as that geometry;
    # a store without v_d is refused, nothing written (these two stores' runs made here, without Dask)
    (tmp_path / "t.toml").write_text(SWEEP.split("[[grid]]")[0]
                                     + 'geometry = "slab"\nLy = 8\n[[grid]]\ntheta = [0.5, 1.0]\nv_d = [0.05]\nN = [8]\n')
    store_of_runs(tmp_path / "s2", tmp_path / "t.toml")
    r = slipchain_cli("figure", "fig6-3d", "--store", tmp_path / "s2", "--out", tmp_path / "one")
    assert r.returncode == 0, r.stderr
    one = pd.read_csv(tmp_path / "one" / "table.csv")
    assert set(one["geometry"]) == {"slab"} and len(one) == 2 and (one["Ly"] == 8).all()
    mu = one.set_index("theta")["mu"]
    slab = table[(table["geometry"] == "slab") & (table["N"] == 8) & np.isclose(table["v_d"], 0.05)].set_index("theta")["mu"]
    assert mu[1.0] == pytest.approx(slab[1.0], rel=1e-12)  # the same member as in the first store
    (tmp_path / "u.toml").write_text(SWEEP.split("[[grid]]")[0] + "[[grid]]\ntheta = [0.5, 1.0]\nN = [8]\n")
    store_of_runs(tmp_path / "s3", tmp_path / "u.toml")
    r = slipchain_cli("figure", "fig6-3d", "--store", tmp_path / "s3", "--out", tmp_path / "nothing")
    assert r.returncode == 2 and "v_d" in r.stderr and not (tmp_path / "nothing").exists()


def test_slip_maps_of_a_slab_run(tmp_path, slipchain_cli):
    run = tmp_path / "run.nc"
    r = slipchain_cli("run", "--set", 'geometry="slab"', "--set", "N=12", "--set", "Ly=10", "--set", "theta=1.0",
                      "--set", 'start="steady"', "--set", "t_total=2e-3", "--out", str(run), "--json")
    assert run.exists(), r.stderr
    r = slipchain_cli("figure", "slip-maps", "--run", str(run), "--out", str(tmp_path / "maps"), "--duration", "4e-3")
    assert r.returncode == 0, r.stderr
    ev = pd.read_csv(tmp_path / "maps" / "events.csv")
    assert len(ev) >= 1 and (ev["event_size"] <= 120).all() and (ev["event_moment"] > 0).all()
    assert (tmp_path / "maps" / "slip-maps.png").stat().st_size > 10_000
    # a chain run has no map: exit 2, one message, nothing written
    chain = tmp_path / "chain.nc"
    r = slipchain_cli("run", "--set", "N=12", "--set", "t_total=2e-4", "--out", str(chain), "--json")
    assert json.loads(r.stdout)["N"] == 12  # its report on stdout is JSON, nothing else
    r = slipchain_cli("figure", "slip-maps", "--run", str(chain), "--out", str(tmp_path / "none"))
    assert r.returncode == 2 and "Ly = 1" in r.stderr and not (tmp_path / "none").exists()

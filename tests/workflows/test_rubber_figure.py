"""Fig. 6 with the viscoelastic slider through the CLI (issue 28): two small real sweeps on a Dask
local cluster (material = 'prony' at two temperatures, and its elastic twin), the figure, report
and tables; mismatched stores exit 2. Fast drive (as tests/workflows/test_geometry_figures.py) so
that the tiny chains slide steadily in 0.3 ms and pass the run's physics checks."""

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

BASE = """
[base]
t_total = 3e-4
dt = 2e-8
integrator = "fold"
eta_c = 1e6
start = "steady"
output_interval = 1e-5
N = 16
{material}
[[grid]]
{temperature}theta = [0.25, 1.0]
v_d = [0.1, 0.05]
seed = [0, 1]
"""


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "slipchain", *args], capture_output=True, text=True)


def _definition(tmp_path, name, material, temperature, v_d="[0.1, 0.05]"):
    text = BASE.format(material=material, temperature=temperature).replace("[0.1, 0.05]", v_d)
    (tmp_path / f"{name}.toml").write_text(f'name = "{name}"\n' + text)
    return tmp_path / f"{name}.toml"


def _sweep(tmp_path, name, material, temperature, v_d="[0.1, 0.05]"):
    """The sweep through the CLI on a Dask local cluster of one worker (each worker process compiles the
    kernels anew, and the members are tiny; the sweep on several workers is tests/workflows/test_runner.py's)."""
    toml = _definition(tmp_path, name, material, temperature, v_d)
    r = _cli("sweep", str(toml), "--store", str(tmp_path / name), "--workers", "1", "--no-progress")
    assert r.returncode == 0, r.stderr
    return tmp_path / name


def test_rubber_figure_from_two_sweeps(tmp_path, slipchain_cli, store_of_runs):
    rubber = _sweep(tmp_path, "rubber", 'material = "prony"', "temperature = [20.0, 11.0]\n")
    # a twin that swept one velocity more (its runs made here, without Dask)
    elastic = store_of_runs(tmp_path / "elastic", _definition(tmp_path, "elastic", "", "", v_d="[0.1, 0.05, 0.2]")).path
    out = tmp_path / "fig"
    r = slipchain_cli("figure", "rubber", "--store", rubber, "--elastic", elastic, "--out", out)
    assert r.returncode == 0, r.stderr
    assert {p.name for p in out.iterdir()} == {"fig6-rubber.png", "fig6-rubber.pdf", "table.csv", "drops.csv", "report.md"}
    table = pd.read_csv(out / "table.csv")
    drops = pd.read_csv(out / "drops.csv")
    assert set(table["variant"]) == {"elastic", "prony 20 °C", "prony 11 °C"}
    assert len(table) == 12 and (table["n"] == 2).all()  # the twin where the rubber has data: not at v_d = 0.2
    assert not np.isclose(table["v_d"], 0.2).any() and not np.isclose(drops["v_d"], 0.2).any()
    # each drop is the ratio of the table's seed means at the largest and smallest theta
    for _, d in drops.iterrows():
        rows = table[(table["variant"] == d["variant"]) & np.isclose(table["v_d"], d["v_d"])].sort_values("theta")
        assert d["ratio"] == pytest.approx(rows["mu"].iloc[-1] / rows["mu"].iloc[0], rel=1e-5)
    # the three variants are three sets of runs (where all contacts slide steadily the bulk plays no
    # role and mu_star is the contact law's at v_d for any material: seen here at theta = 1, v_d = 0.1)
    t = table.set_index(["variant", "v_d", "theta"])["mu"]
    assert any(t["prony 20 °C"] != t["prony 11 °C"]) and any(t["elastic"] != t["prony 20 °C"])
    report = (out / "report.md").read_text()
    assert "| v_d | eta_c / omega0 | theta | elastic | prony 20 °C | prony 11 °C |" in report
    # stores swapped: the viscoelastic store must hold material = 'prony'
    r = slipchain_cli("figure", "rubber", "--store", elastic, "--elastic", rubber, "--out", tmp_path / "bad")
    assert r.returncode == 2 and "material = 'elastic'; expected 'prony'" in r.stderr
    assert not (tmp_path / "bad").exists()


def test_rubber_figure_with_one_drive_velocity_has_no_second_velocity_panel(tmp_path):
    """A store with one drive velocity (presets/fig6-rubber-slab.toml) gives panels (a) and the load effect
    only, not (a) twice: the figure is two panels wide, not three."""
    import matplotlib.image as mpimg

    from slipchain.analysis.rubber import rubber_drops
    from slipchain.plots.rubber import plot_rubber

    rows = [(var, T, 1e5, v, th, mu, 0.005, 2) for var, T, shift in (("elastic", np.nan, 0.0), ("prony 20 °C", 20.0, 0.05))
            for v in (1e-3, 3e-4) for th, mu in ((0.05, 0.9 + shift), (1.0, 0.8 + shift))]
    both = pd.DataFrame(rows, columns=["variant", "temperature", "eta_c", "v_d", "theta", "mu", "err", "n"])
    one = both[np.isclose(both["v_d"], 1e-3)].reset_index(drop=True)
    widths = []
    for table, v_d2 in ((both, 3e-4), (one, 1e-3)):
        attrs = {"v_d1": 1e-3, "v_d2": v_d2, "omega0": 1e6}
        out = tmp_path / f"{len(table)}"
        paths = plot_rubber(table, rubber_drops(table), attrs, out)
        png = next(p for p in paths if p.suffix == ".png")
        widths.append(mpimg.imread(png).shape[1])
    assert widths[1] < 0.75 * widths[0]  # 9.3 in against 14 in

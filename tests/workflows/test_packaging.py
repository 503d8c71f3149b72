"""Packaging (issue 15): the sdist and the wheel that ``python -m build`` makes hold the package and
its presets, and the wheel installed into a fresh venv runs.

The build runs without network (``--no-isolation``: setuptools and build come from the test
environment, both pinned in requirements.lock) on a copy of the source tree; the wheel is built
from the sdist, so a file missing from the sdist breaks the wheel too. The fresh venv gets the
wheel and only its declared dependencies (links to the test environment's copies, in a folder on
a .pth path: no download), and runs from an empty folder.
"""

import json
import os
import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TOP_LEVEL_OUTPUT = {".git", ".numba_cache", "results", "out", "dist", "build", ".pytest_cache", ".hypothesis"}
ANYWHERE = shutil.ignore_patterns(".venv*", "*.egg-info", "__pycache__", "_build")


def _ignore(folder: str, names: list[str]) -> set[str]:
    """What a clean checkout would not hold: build output at the top, caches anywhere."""
    top = set(names) & TOP_LEVEL_OUTPUT if Path(folder) == ROOT else set()
    return top | ANYWHERE(folder, names)


@pytest.fixture(scope="module")
def dist(tmp_path_factory) -> Path:
    src = tmp_path_factory.mktemp("src") / "slipchain"
    shutil.copytree(ROOT, src, ignore=_ignore)
    out = tmp_path_factory.mktemp("dist")
    r = subprocess.run([sys.executable, "-m", "build", "--no-isolation", "--outdir", str(out), str(src)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return out


def test_sdist_and_wheel_hold_the_package_its_presets_and_docs(dist):
    from slipchain._version import __version__

    (sdist,) = dist.glob("slipchain-*.tar.gz")
    (wheel,) = dist.glob("slipchain-*-py3-none-any.whl")
    assert wheel.name.startswith(f"slipchain-{__version__}-")
    presets = sorted(p.name for p in (ROOT / "src" / "slipchain" / "presets").glob("*.toml"))
    with tarfile.open(sdist) as t:
        names = {n.split("/", 1)[1] for n in t.getnames() if "/" in n}
    assert {"pyproject.toml", "README.md", "requirements.lock", "requirements-nodeps.txt", "CHANGELOG.md", "src/slipchain/cli/__init__.py"} <= names
    assert {f"src/slipchain/presets/{p}" for p in presets} <= names
    with zipfile.ZipFile(wheel) as z:
        wnames = set(z.namelist())
        meta = z.read(next(n for n in wnames if n.endswith(".dist-info/METADATA"))).decode()
    assert {f"slipchain/presets/{p}" for p in presets} <= wnames
    assert "slipchain/engine/scheme.py" in wnames and not any(n.startswith("tests/") for n in wnames)
    # Ranges, not pins: the wheel installs beside a user's own numpy, xarray and dask.
    requires = [line.split(": ", 1)[1] for line in meta.splitlines() if line.startswith("Requires-Dist: ")]
    core = [r for r in requires if "extra ==" not in r]
    assert any(r.startswith("numpy") and ">=" in r for r in core) and not any("==" in r for r in core), core


def _declared_dependencies(farm: Path) -> Path:
    """A folder holding only what the wheel declares (its core Requires-Dist and theirs, markers
    evaluated), as links into the test environment: no download, and nothing else of the test
    environment (pytest, sphinx, our editable install) is importable beside the wheel, so an
    undeclared import fails here (issue 30)."""
    from importlib.metadata import distribution

    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name

    todo = [r for r in distribution("slipchain").requires or [] if "extra ==" not in r]
    seen: dict[str, object] = {}
    while todo:
        req = Requirement(todo.pop())
        if req.marker is not None and not req.marker.evaluate({"extra": ""}):
            continue
        name = canonicalize_name(req.name)
        if name in seen:
            continue
        seen[name] = dist = distribution(req.name)
        todo += dist.requires or []
    farm.mkdir()
    for dist in seen.values():
        root = Path(dist.locate_file(""))
        for top in {f.parts[0] for f in dist.files or [] if f.parts[0] not in ("..", "__pycache__")}:
            if (root / top).exists() and not (farm / top).exists() and not top.endswith(".pth"):
                (farm / top).symlink_to(root / top)
    return farm


def test_the_wheel_in_a_fresh_venv_runs_a_model_and_finds_its_presets(dist, tmp_path):
    (wheel,) = dist.glob("slipchain-*-py3-none-any.whl")
    venv = tmp_path / "fresh"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    py = venv / "bin" / "python"
    r = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "-q", "--no-deps", "--no-index",
                        str(wheel)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    purelib = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    (Path(purelib) / "_declared_dependencies.pth").write_text(str(_declared_dependencies(tmp_path / "deps")) + "\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "PYTHONPATH": ""}
    exe = venv / "bin" / "slipchain"

    version = subprocess.run([str(exe), "--version"], capture_output=True, text=True, env=env, timeout=120)
    from slipchain._version import __version__

    assert version.returncode == 0 and version.stdout.strip() == f"slipchain {__version__}", version.stderr
    where = subprocess.run([str(py), "-c", "import slipchain, slipchain.sweeps as s; print(slipchain.__file__); "
                            "print(len(s.load_preset('quick').members), len(s.load_preset('paper').members))"],
                           capture_output=True, text=True, env=env, timeout=120)
    assert where.returncode == 0, where.stderr
    module, counts = where.stdout.split("\n")[:2]
    assert Path(module).is_relative_to(venv) and counts == "60 368"  # the installed copy, with its presets
    # Issue 30: every study by name, from an empty folder outside the repository (tester-128-slower extends
    # tester-32-slower by name: resolved inside the installed package)
    empty = tmp_path / "empty"
    empty.mkdir()
    for args, words in ((["presets"], "validation campaign"),
                        (["sweep", "fig6-3d", "--store", "x", "--dry-run"], "100 would run"),
                        (["sweep", "quick", "--store", "q", "--dry-run"], "60 would run"),
                        (["sweep", "tester-128-slower", "--store", "t", "--dry-run"], "8 would run"),  # extends
                        (["mu-max", "mu-max", "--out", "m", "--dry-run"], "Nothing run or written")):
        r = subprocess.run([str(exe), *args], capture_output=True, text=True, env={**env, "COLUMNS": "200"}, cwd=empty,
                           timeout=300)
        assert r.returncode == 0 and words in r.stdout, (args, r.stdout, r.stderr)
    assert not list(empty.iterdir())  # dry runs write nothing
    run = subprocess.run([str(exe), "run", "--set", "N=31", "--set", "theta=0.5", "--set", "start=steady",
                          "--set", "v0=0.01", "--set", "delta=0.2", "--set", "t_total=3e-3", "--json"],
                         capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stderr
    info = json.loads(run.stdout)
    assert info["status"] == "completed" and info["n_contacts"] == 16 and 0 < info["mu_star"] < 2

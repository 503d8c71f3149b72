"""Issue 30: a full disk. A sweep whose store fills its file system used to print 33 h5py tracebacks
and crash (exit 139), leaving a stale temporary file. Now it stops with one error line that says
what could not be written, that nothing is lost and how to resume; it leaves no temporary file; and
after space is freed the same command resumes and loses nothing.

A real small file system: a tmpfs mounted for the test (root only; CI runs as root).
"""

import errno
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from slipchain.results.io import read_dataset, write_dataset


@pytest.fixture
def small_fs(tmp_path):
    mnt = tmp_path / "small"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here ({r.stderr.strip()}): needs root")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def _resize(mnt: Path, size: str) -> None:
    subprocess.run(["mount", "-o", f"remount,size={size}", str(mnt)], check=True, capture_output=True)


def test_a_dataset_that_does_not_fit_is_one_oserror_and_leaves_nothing(small_fs):
    small = xr.Dataset({"a": ("x", np.arange(10.0))})
    write_dataset(small, small_fs / "small.nc")
    big = xr.Dataset({"a": ("x", np.random.default_rng(0).random(100_000))})  # 800 kB
    with pytest.raises(OSError) as err:
        write_dataset(big, small_fs / "big.nc")
    assert err.value.errno == errno.ENOSPC and err.value.filename == str(small_fs / "big.nc")
    assert sorted(p.name for p in small_fs.iterdir()) == ["small.nc"]  # no temporary file, nothing half-written
    assert read_dataset(small_fs / "small.nc")["a"].values.tolist() == list(range(10))


def test_a_sweep_on_a_full_disk_stops_with_one_line_and_resumes_after(small_fs, tmp_path):
    definition = tmp_path / "sweep.toml"
    definition.write_text('name = "full"\n[base]\nN = 31\nstart = "steady"\nv0 = 0.01\ndelta = 0.2\ntheta = 0.5\n'
                          't_total = 3e-3\nintegrator = "fixed"\n[grid]\nseed = [0, 1, 2, 3, 4, 5, 6, 7]\n')
    store = small_fs / "s"
    cmd = [sys.executable, "-m", "slipchain", "sweep", str(definition), "--store", str(store), "--workers", "1",
           "--no-progress"]
    _resize(small_fs, "160k")  # room for the store's own files and a few members
    full = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert full.returncode == 1, full.stdout + full.stderr
    errors = [line for line in full.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in full.stderr, full.stderr
    assert f"could not write to the store '{store}'" in errors[0] and "run the same command again" in errors[0]
    assert not list(store.rglob("*.tmp"))
    kept = sorted([*store.glob("members/*.nc"), *store.glob("failed/*.nc")])  # completed; a physics check failed
    assert 1 <= len(kept) < 8
    for p in kept:
        assert read_dataset(p).attrs["member_id"] == p.stem
    _resize(small_fs, "8m")  # space freed: the same command resumes
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert "error:" not in again.stderr and again.returncode in (0, 1), again.stdout + again.stderr  # 1: a member's check
    completed = {p.stem for p in (store / "members").glob("*.nc")}
    assert len(completed | {p.stem for p in (store / "failed").glob("*.nc")}) == 8
    assert {p.stem for p in kept if p.parent.name == "members"} <= completed  # nothing stored before is lost

"""The memory check (issue 11, item 5): a run too large for the machine is refused before it allocates."""

import json
import os
import subprocess
import sys

import pytest

from slipchain import make_config
from slipchain.engine.memory import GiB, MemoryEstimateError, available_bytes, check_memory, estimate_bytes
from slipchain.model.config import ConfigError


def test_cli_refuses_a_run_too_large_for_memory_naming_N_and_writes_nothing(tmp_path, slipchain_cli):
    # Before: killed by the kernel's OOM killer (exit 137, no message) after minutes of swapping.
    out = tmp_path / "big.nc"
    r = slipchain_cli("run", "--set", "N=1000000000", "--out", out)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr and r.stderr.startswith("error: N = 1000000000")
    assert "GiB of memory" in r.stderr and "available" in r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_the_estimate_grows_as_the_arrays_do_and_a_batch_counts_every_row():
    c = make_config(N=10_000, theta=1.0, t_total=1e-2)
    assert estimate_bytes(make_config(N=20_000, theta=1.0, t_total=1e-2)) == pytest.approx(2 * estimate_bytes(c), rel=0.01)
    longer = estimate_bytes(make_config(N=10_000, theta=1.0, t_total=2e-2)) - estimate_bytes(c)
    assert longer == pytest.approx(10_000 * 4 * 8 * 20, rel=0.05)  # per-chunk contact sums: 20 more chunks of 0.5 ms
    # A dead-weight run keeps one per-contact record however long it runs (the recorder's running sum):
    # only its output samples grow with its length.
    dw, dw2 = (make_config(N=10_000, theta=1.0, dead_weight=0.8, t_max=t, start="rest") for t in (1.0, 2.0))
    assert estimate_bytes(dw2) - estimate_bytes(dw) == pytest.approx(1.0 / dw.output_interval * 128, rel=0.01)
    # A spring-driven run's records stop growing at twice their budget (observers.CONTACT_SUMS_BYTES, merged
    # pairwise past it): 10 000 contacts at 320 kB a record hold at most 2 x 104 records, whatever the length
    sd, sd2 = (make_config(N=10_000, theta=1.0, t_total=t) for t in (1.0, 2.0))
    assert estimate_bytes(sd2) - estimate_bytes(sd) == pytest.approx(1.0 / sd.output_interval * 128, rel=0.01)
    assert estimate_bytes(sd) - estimate_bytes(dw) == pytest.approx(2 * 104 * 10_000 * 32 - 10_000 * 32, rel=0.01)
    one = check_memory([c], available=10 * GiB)
    with pytest.raises(MemoryEstimateError, match="3 realisations run together") as e:
        check_memory([c] * 3, available=int(2.5 * one) + 300 * 2**20)
    assert isinstance(e.value, ConfigError) and "N = 10000" in str(e.value)
    have = available_bytes()
    assert have is None or 0 < have < 2**50


CHILD = """
import json, sys
from pathlib import Path
from slipchain import make_config, run
from slipchain.engine.memory import estimate_bytes

def status(key):
    line = next(l for l in Path("/proc/self/status").read_text().splitlines() if l.startswith(key + ":"))
    return int(line.split()[1]) * 1024

run(make_config(N=101, theta=0.5, t_total=2e-6, output_interval=1e-6, start="steady"))  # compiled, warm
try:
    Path("/proc/self/clear_refs").write_text("5")  # reset the peak (VmHWM) to the current resident set
except OSError as e:
    print(json.dumps({"skip": str(e)}))
    sys.exit(0)
before = status("VmRSS")
c = make_config(N=400_000, theta=1.0, t_total=2e-6, output_interval=1e-6, start="steady")
run(c)
print(json.dumps({"measured": status("VmHWM") - before, "estimate": estimate_bytes(c)}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self (Linux)")
def test_the_estimate_covers_the_measured_peak_memory_without_refusing_what_fits():
    # Independent measurement: the peak resident set of a fresh process during a large run, above
    # what it held before (the peak is reset first, so compiling the engine, which can take more
    # than the run, does not hide it). Large arrays are mapped fresh (MALLOC_MMAP_THRESHOLD_), not
    # taken from heap that the compiler freed. The estimate must cover it, and not by more than 1.6x.
    env = {**os.environ, "MALLOC_MMAP_THRESHOLD_": "131072"}
    r = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout.strip().splitlines()[-1])
    if "skip" in got:
        pytest.skip(f"cannot reset the peak resident set here: {got['skip']}")
    measured, estimate = got["measured"], got["estimate"]
    assert measured <= estimate <= 1.6 * measured, (measured, estimate)

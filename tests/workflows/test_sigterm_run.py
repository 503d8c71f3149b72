"""Issue 30: SIGTERM (a batch scheduler's time limit) stops `slipchain run` as Ctrl-C does: the
run's rows stop with status interrupted, what was simulated is written, the checkpoint is kept for
the resume, and the exit code is 143. (The sweep's case: tests/workflows/test_runner.py.)"""

import signal
import subprocess
import sys
import time

from slipchain.results.io import read_dataset


def test_sigterm_stops_a_run_with_its_checkpoint_and_exit_143(tmp_path):
    ckpt, out = tmp_path / "run.ckpt.nc", tmp_path / "run.nc"
    # 10 s of simulated time: minutes of wall time, so the signal lands long before the end
    cmd = [sys.executable, "-m", "slipchain", "run", "--set", "N=31", "--set", "t_total=10.0", "--set",
           'start="steady"', "--checkpoint", str(ckpt), "--checkpoint-every", "0", "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        t_end = time.time() + 300
        while not ckpt.exists():  # the first chunk is done and checkpointed: the loop is running
            assert proc.poll() is None, proc.communicate()
            assert time.time() < t_end, "no checkpoint within 300 s"
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, stdout + stderr
    assert "interrupted by SIGTERM" in stderr and f"the checkpoint {ckpt} is kept" in stderr
    ds = read_dataset(out)
    assert ds.attrs["status"] == "interrupted" and 0 < ds.attrs["t_total"] < 10.0
    assert ckpt.exists()

"""Issue 30: SIGTERM (a batch scheduler's time limit) stops `slipchain run` as Ctrl-C does: the
run's rows stop with status interrupted, what was simulated is written, the checkpoint is kept for
the resume, and the exit code is 143. (The sweep's case: tests/workflows/test_runner.py.)"""

import os
import signal
import subprocess

from slipchain.results.io import read_dataset


def test_sigterm_stops_a_run_with_its_checkpoint_and_exit_143(tmp_path, cli_stopping_at_first_checkpoint):
    ckpt, out = tmp_path / "run.ckpt.nc", tmp_path / "run.nc"
    args = ["run", "--set", "N=31", "--set", "t_total=0.1", "--set", 'start="steady"', "--checkpoint", str(ckpt),
            "--checkpoint-every", "0", "--out", str(out)]
    proc = subprocess.Popen([*cli_stopping_at_first_checkpoint, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        _, status = os.waitpid(proc.pid, os.WUNTRACED)  # stopped after its first chunk and checkpoint
        assert os.WIFSTOPPED(status), proc.communicate()
        proc.send_signal(signal.SIGTERM)
        proc.send_signal(signal.SIGCONT)  # handled as it resumes: before its second chunk ends
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, stdout + stderr
    assert "interrupted by SIGTERM" in stderr and f"the checkpoint {ckpt} is kept" in stderr
    ds = read_dataset(out)
    assert ds.attrs["status"] == "interrupted" and 0 < ds.attrs["t_total"] < 0.1
    assert ckpt.exists()

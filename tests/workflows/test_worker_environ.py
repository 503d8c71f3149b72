"""The local cluster's workers start with glibc's own allocator settings, not Dask's MALLOC_TRIM_THRESHOLD_.

Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in every worker it spawns, which also fixes glibc's mmap
threshold: the slab's compiled steps, which allocate their FFTs' results every step, then ran 2x slower
in a sweep than in `slipchain run` (``executor.LOCAL_WORKER_ENVIRON``; docs/performance.md). Checked in a
fresh interpreter whose environment lacks the variable, since a nanny started earlier in this process
(another test's cluster) writes it into os.environ, which later workers inherit.
"""

import json
import os
import subprocess
import sys

SCRIPT = r"""
import json, logging, os
from distributed import Client, LocalCluster
from slipchain.sweeps.executor import dask_client

def env():
    return os.environ.get("MALLOC_TRIM_THRESHOLD_")

with dask_client(n_workers=1) as client:
    ours = list(client.run(env).values())
with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0",
                  silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
    plain = list(client.run(env).values())
print(json.dumps({"ours": ours, "plain": plain}))
"""


def _workers_environ(extra: dict[str, str]) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "MALLOC_TRIM_THRESHOLD_"}
    env.update(extra)
    out = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_local_cluster_workers_keep_glibc_allocator_defaults():
    seen = _workers_environ({})
    assert seen["ours"] == [None]  # dask_client's workers: the variable unset
    assert seen["plain"] == ["65536"]  # Dask's default cluster sets it (what LOCAL_WORKER_ENVIRON undoes)


def test_a_trim_threshold_the_user_set_is_kept():
    seen = _workers_environ({"MALLOC_TRIM_THRESHOLD_": "1048576"})
    assert seen["ours"] == ["1048576"]

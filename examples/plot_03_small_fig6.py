"""
A small Fig. 6 sweep on Dask
============================

The paper's central result at a small size: mu_star against the load theta at the two drive
velocities, two seeds each, N = 101. The sweep runs on a local Dask cluster and writes one file
per member into a store (a temporary directory here); ``open_sweep`` gathers them into one
Dataset with a dimension per swept parameter. At v_d = v0 friction falls with load; at
v_d2 = 3e-4 m/s it barely moves.
"""

import tempfile

import matplotlib.pyplot as plt

from slipchain import open_sweep, run_sweep
from slipchain.sweeps import make_sweep

sweep = make_sweep({
    "name": "gallery-fig6",
    "base": {"N": 101, "start": "steady", "sem_target": 0.02},
    "grid": {"theta": [0.1, 0.4, 1.0], "v_d": [3e-4, 1e-3], "seed": [0, 1]},
})
store = tempfile.mkdtemp(prefix="slipchain-gallery-")
report = run_sweep(sweep, store, n_workers=2, progress=False)
print(f"{len(report.ran)} members ran, {len(report.failed)} failed")
ds = open_sweep(store)
mean, err = ds["mu_star"].mean("seed"), ds["mu_star"].std("seed") / 2**0.5

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
for vd in ds["v_d"].values:
    ax.errorbar(ds["theta"], mean.sel(v_d=vd), err.sel(v_d=vd), marker="o", capsize=3, label=f"v_d = {vd:g} m/s")
ax.set(xlabel="theta (fraction of blocks with a contact, ~ load)", ylabel="mu_star", title="Fig. 6 in small: N = 101, 2 seeds")
ax.legend()

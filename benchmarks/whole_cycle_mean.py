"""mu_star against the mean of f_d over whole slip cycles, for runs that stick-slip as a whole (issue 27).

For each member of the given stores at the given geometry, theta and v_d: the slip events (drops of f_d below 0.3
of the largest drop, merged within 5 samples), the mean of f_d from the first event after ``--after`` seconds to the
last (whole cycles), scaled as mu_star is (mu_star over the mean of f_d in its steady window), beside mu_star and the
mean period. Two stores of one study with different output samples (fig6-3d-eps1-128-fast2 and -fast3) give the
same whole-cycle means and different mu_star: the steady window's phase (docs/performance.md, "Samples of 5 ms").

    .venv/bin/python benchmarks/whole_cycle_mean.py results/fig6-3d-eps1-128-fast2 results/fig6-3d-eps1-128-fast3 \
        --geometry chain2d --theta 1 --v-d 1e-3
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import xarray as xr

from slipchain.results.observables import steady_estimate


def whole_cycles(ds: xr.Dataset, after: float) -> tuple[int, float, float, float]:
    """(events, whole-cycle mean in mu_star's units, mu_star, mean period) of one member."""
    t, f = ds.time.values, ds.f_d.values
    d = np.diff(f)
    idx = np.flatnonzero(d < 0.3 * d.min())
    events = [i for k, i in enumerate(idx) if k == 0 or i - idx[k - 1] > 5]
    late = [e for e in events if t[e] > after]
    a, b = late[0] + 1, late[-1] + 1
    mu = float(ds.attrs["mu_star"])
    scale = mu / f[steady_estimate(f).start:].mean()
    return len(events), float(f[a:b].mean() * scale), mu, float(np.diff(t[events]).mean())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("stores", nargs="+", type=Path)
    ap.add_argument("--geometry", default="chain2d")
    ap.add_argument("--theta", type=float, default=1.0)
    ap.add_argument("--v-d", type=float, default=1e-3)
    ap.add_argument("--after", type=float, default=2.0, help="the first event counted after this time (s)")
    args = ap.parse_args()
    for store in args.stores:
        for path in sorted((store / "members").glob("*.nc")):
            with xr.open_dataset(path) as ds:
                a = ds.attrs
                if (a["geometry"] != args.geometry or abs(float(a["theta"]) - args.theta) > 1e-3
                        or float(a["v_d"]) != args.v_d):
                    continue
                n, whole, mu, period = whole_cycles(ds, args.after)
                print(f"{store.name} seed {int(a['seed'])}: {n} events, whole-cycle mean {whole:.5f}, mu_star {mu:.5f}, "
                      f"period {period:.4f} s")


if __name__ == "__main__":
    main()

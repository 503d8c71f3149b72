"""mu_star against the mean of f_d over whole slip cycles, for runs that stick-slip as a whole (issue 27).

For each member of the given stores at the given geometry, theta and v_d: in mu_star's steady window (MSER), the
mean of f_d over whole cycles (:func:`slipchain.results.observables.whole_cycle_mean`, from the first slip event, a
fall counted by ``count_cycles``, to the last), scaled as mu_star is (mu_star over the mean of f_d in its steady
window), beside mu_star and the mean period between the falls. Two stores of one study with different output samples (fig6-3d-eps1-128-fast2 and -fast3) give the
same whole-cycle means and different mu_star: the steady window's phase (docs/performance.md, "Samples of 5 ms").

    .venv/bin/python benchmarks/whole_cycle_mean.py results/fig6-3d-eps1-128-fast2 results/fig6-3d-eps1-128-fast3 \
        --geometry chain2d --theta 1 --v-d 1e-3
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import xarray as xr

from slipchain.results.observables import cycle_falls, steady_estimate, whole_cycle_mean


def whole_cycles(ds: xr.Dataset) -> tuple[int, float, float, float]:
    """(slip events, whole-cycle mean in mu_star's units, mu_star, mean period) of one member."""
    t, f = ds.time.values, ds.f_d.values
    start = steady_estimate(f).start
    window, tw = f[start:], t[start:]
    falls = cycle_falls(window)
    mu = float(ds.attrs["mu_star"])
    scale = mu / window.mean()
    return int(falls.size), whole_cycle_mean(window) * scale, mu, float(np.diff(tw[falls]).mean())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("stores", nargs="+", type=Path)
    ap.add_argument("--geometry", default="chain2d")
    ap.add_argument("--theta", type=float, default=1.0)
    ap.add_argument("--v-d", type=float, default=1e-3)
    args = ap.parse_args()
    for store in args.stores:
        for path in sorted((store / "members").glob("*.nc")):
            with xr.open_dataset(path) as ds:
                a = ds.attrs
                if (a["geometry"] != args.geometry or abs(float(a["theta"]) - args.theta) > 1e-3
                        or float(a["v_d"]) != args.v_d):
                    continue
                n, whole, mu, period = whole_cycles(ds)
                print(f"{store.name} seed {int(a['seed'])}: {n} events, whole-cycle mean {whole:.5f}, mu_star {mu:.5f}, "
                      f"period {period:.4f} s")


if __name__ == "__main__":
    main()

"""Issue 29: how far each stored release run is from the released runaway rule's thresholds, and whether today's
classification reads every stored dead-weight run as it was stored.

1. ``--margins OUT.csv``: every stored release on the slab (a dead weight with ``t_decide``, not slowly loaded), read
   at each compiled chunk's end from three ringing periods after the release (where ``stop_at_runaway`` reads it,
   :func:`slipchain.results.schema._released_runaway`): the top's mean velocities v1, v2 over its last two ringing
   periods. Per run: its outcome, the first chunk at which v1 is beyond the bound RUNAWAY_FACTOR v0 10**delta and
   v2 > v1 (``t_first``, ``ratio_first`` = v2/v1 there, ``over_bound`` = v1/bound), the first at which v2 >
   RUNAWAY_RISE v1 (``t_rule``: where the rule stops it now), and the largest v2/v1 anywhere beyond the bound
   (``max_ratio``). A margin that separates the runaways (ratio_first) from the rest (max_ratio) is what RUNAWAY_RISE
   rests on.
2. ``--reclassify``: :func:`slipchain.results.schema.dead_weight_status` on every stored dead-weight record against
   the status stored with it; prints each that differs.

    .venv/bin/python benchmarks/stop_rule_margins.py --margins docs/tester-3d/redecide-stop/margins.csv --reclassify
"""

from __future__ import annotations

import argparse
import glob

import pandas as pd

from slipchain.analysis.traces import _runs, run_outcome
from slipchain.engine.control import chunk_samples
from slipchain.results.schema import RUNAWAY_RISE, _beyond_branch, _period_velocities, dead_weight_status, slowly_loaded


def dead_weight_stores(root: str = "stores") -> list[str]:
    """The stores under ``root`` whose sweep has a dead weight and at least one completed run."""
    out = []
    for toml in sorted(glob.glob(f"{root}/*/sweep.toml")):
        store = toml[: -len("/sweep.toml")]
        if "dead_weight" in open(toml).read() and glob.glob(f"{store}/members/*.nc"):
            out.append(store)
    return out


def runs(stores: list[str]):
    for store in stores:
        try:
            yield from _runs([store])
        except Exception as e:  # a store of runs of another drive
            print(f"skipped {store}: {str(e)[:120]}")


def margins(stores: list[str]) -> pd.DataFrame:
    rows = []
    for store, mid, cfg, ds in runs(stores):
        if cfg.dead_weight is None or cfg.t_decide is None or cfg.geometry != "slab" or slowly_loaded(cfg):
            continue
        time, x = ds["time"].values, ds["X_mean"].values
        out, v_end = run_outcome(cfg, ds.attrs.get("velocity_status", ""), time, x)
        k = chunk_samples(cfg, cfg.output_interval)
        bound = _beyond_branch(cfg)
        first = rule = None
        ratios = []
        for n in range(k, time.size + 1, k):
            got = _period_velocities(cfg, time[:n], x[:n])
            if got is None or not got[0] > bound:
                continue
            v1, v2, _ = got
            ratios.append(v2 / v1)
            if first is None and v2 > v1:
                first = (time[n - 1], v2 / v1, v1 / bound)
            if rule is None and v2 > RUNAWAY_RISE * v1:
                rule = time[n - 1]
        rows.append(dict(store=store.split("/")[-1], member_id=mid, N=cfg.N, temperature=cfg.temperature,
                         eta_c=cfg.eta_c, theta=cfg.theta, seed=cfg.seed, mu_a=cfg.dead_weight, t_decide=cfg.t_decide,
                         t_end=float(time[-1]), outcome=out, v_end=v_end,
                         t_first=None if first is None else first[0], ratio_first=None if first is None else first[1],
                         over_bound=None if first is None else first[2], t_rule=rule,
                         max_ratio=max(ratios, default=float("nan"))))
    return pd.DataFrame(rows)


def reclassify(stores: list[str]) -> tuple[int, int]:
    n = same = 0
    for store, mid, cfg, ds in runs(stores):
        if cfg.dead_weight is None:
            continue
        time, x = ds["time"].values, ds["X_mean"].values
        stored = ds.attrs.get("velocity_status", "")
        status, reason, _ = dead_weight_status(cfg, time, x)
        n += 1
        if status == stored:
            same += 1
        else:
            print(f"{store} {mid} theta={cfg.theta:g} mu_a={cfg.dead_weight:g}: stored {stored}, now {status}: {reason}")
    return same, n


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--margins", help="write the release runs' margins to this CSV")
    p.add_argument("--reclassify", action="store_true", help="check today's classification of every stored run")
    p.add_argument("--root", default="stores")
    a = p.parse_args()
    stores = dead_weight_stores(a.root)
    if a.margins:
        df = margins(stores)
        df.to_csv(a.margins, index=False)
        run_away = df[df.outcome == "runaway"]
        rest = df[df.outcome != "runaway"]
        print(f"{len(df)} release runs: {len(run_away)} runaways, first beyond the bound and faster at v2/v1 >= "
              f"{run_away.ratio_first.min():.4f} ({run_away.ratio_first.isna().sum()} never); the others' largest v2/v1 "
              f"beyond the bound {rest.max_ratio.max():.4f}; RUNAWAY_RISE = {RUNAWAY_RISE}")
    if a.reclassify:
        same, n = reclassify(stores)
        print(f"{same} of {n} stored dead-weight runs classified as stored")


if __name__ == "__main__":
    main()

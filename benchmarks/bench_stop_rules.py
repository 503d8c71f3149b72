"""Issue 29: what the stop rules of a released slab save (configs ``stop_at_runaway``, ``stop_when_held``;
docs/tester-3d "Stopping a released run early"), measured side by side in one process.

Runs of the tester's 16 x 16 block released at once (preset ``tester-16-long``: the weight at once, decided from
t_decide = 2 s, t_max = 3 s), each made three times: as stored; decided from t_decide = 0.8 s (the 128 x 128
presets'); and from 0.8 s with both rules on; everything else the same: wall time, where each stopped and what it
said. A run's record is the stored run's own up to where it stops (bit for bit on one machine,
tests/physics/test_dead_weight.py), so all three must say the same side of mu_max; the ratios of the walls are what
the earlier decision and the rules save on this interface. The first run in the process pays the compilation, so
a warm-up run of 5 ms goes first.

    python benchmarks/bench_stop_rules.py                        # theta = 0.5 at 0.7 (runaway), theta = 1 at 0.75 (held)
    python benchmarks/bench_stop_rules.py --pick 0.5:0.6         # another member (theta:mu_a)
"""

from __future__ import annotations

import argparse
import platform
import time
from importlib import resources

from slipchain import run
from slipchain.analysis.traces import SIDES, run_outcome
from slipchain.sweeps.definition import load_sweep_definition

PRESET = "tester-16-long"
DEFAULT = ("0.5:0.7", "1:0.75")
VARIANTS = ((None, False), (0.8, False), (0.8, True))  # (t_decide, both rules): None keeps the preset's


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--pick", nargs="+", default=list(DEFAULT), help="theta:mu_a of tester-16-long's members")
    args = ap.parse_args()
    sweep = load_sweep_definition(str(resources.files("slipchain.presets") / f"{PRESET}.toml"))
    picks = [tuple(float(v) for v in p.split(":")) for p in args.pick]
    members = [m for p in picks for m in sweep.members if (m.config.theta, m.config.dead_weight) == p]
    run(members[0].config.model_copy(update={"t_decide": None, "t_max": 0.005, "t_total": 0.005, "t_ramp": 1e-3}))
    print(f"# {platform.processor() or platform.machine()}: {PRESET}, each member as stored, decided from 0.8 s, and "
          "with the stop rules too; one process, side by side", flush=True)
    print("| theta | mu_a | t_decide (s) | rules | wall (s) | t_end (s) | status | outcome |")
    print("|---|---|---|---|---|---|---|---|")
    totals = [0.0] * len(VARIANTS)
    for m in members:
        sides = []
        for k, (t_decide, rules) in enumerate(VARIANTS):
            cfg = m.config.model_copy(update={"t_decide": t_decide or m.config.t_decide, "stop_at_runaway": rules,
                                              "stop_when_held": rules})
            t0 = time.perf_counter()
            ds = run(cfg)
            wall = time.perf_counter() - t0
            totals[k] += wall
            status = ds.attrs["velocity_status"]
            out, _ = run_outcome(cfg, status, ds["time"].values, ds["X_mean"].values)
            sides.append(SIDES[out])
            print(f"| {cfg.theta:g} | {cfg.dead_weight:g} | {cfg.t_decide:g} | {'on' if rules else 'off'} | {wall:.1f} | "
                  f"{float(ds['time'].values[-1]):.3f} | {status} | {out} |", flush=True)
        print(f"# theta = {m.config.theta:g}, mu_a = {m.config.dead_weight:g}: the same side of mu_max: {len(set(sides)) == 1}")
    print(f"# all: {totals[0]:.1f} s as stored, {totals[1]:.1f} s decided from 0.8 s ({totals[0] / totals[1]:.2f}x), "
          f"{totals[2]:.1f} s with the rules too ({totals[0] / totals[2]:.2f}x)")


if __name__ == "__main__":
    main()

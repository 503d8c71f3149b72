# The held lower ends of rung 3s's brackets (docs/ladder/index.md, "Rung 3s by bisection to the end") rerun with runs
# of up to 10 s: do they still hold? From the repository root, after `slipchain mu-max ladder-eps1-slow-held --out
# results/ladder-eps1-slow-held`:  python docs/ladder/eps1-slow-held/check_t_max.py   (4.5 min on 2 cores)
import pandas as pd
from slipchain.workflows.dead_weight import evaluate_many, load_plan
from slipchain.sweeps.catalogue import find_study

def main():
    plan = load_plan(find_study("ladder-eps1-slow-held"), ["t_max=10"])
    table = pd.read_csv("results/ladder-eps1-slow-held/mu_max.csv")
    ev = pd.read_csv("results/ladder-eps1-slow-held/evaluations.csv")
    held = ev[ev["velocity_status"] == "held"].merge(table[["theta", "seed", "lo"]], on=["theta", "seed"])
    held = held[held["mu_a"] == held["lo"]]
    jobs = [(plan.base.with_updates(theta=float(r.theta), seed=int(r.seed)), float(r.mu_a)) for r in held.itertuples()]
    for (c, m), e in zip(jobs, evaluate_many(jobs, store="results/ladder-eps1-slow-held-10", n_workers=2, progress=False)):
        print(c.theta, c.seed, m, e.velocity_status, f"{e.velocity:.3g}", e.message[-120:])

if __name__ == "__main__":
    main()

"""Issue 26: two stores of the same sweep made with different integrators, member by member.

Members are matched by their coordinates other than the integrator's own keys (integrator,
step_tol) and dt, which is matched by its ratio to the store's largest dt (so that a time-step
grid at half the step pairs with the other's half step); for each pair z = (mu_a - mu_b)/sqrt(SE_a**2 + SE_b**2). Prints the number of pairs,
the largest |z| and the rms z, how many pairs lie beyond 2 and 3 combined SE, and each store's
sweep wall time (its invocations.jsonl) and summed member run time; ``--csv`` writes every pair.

    .venv/bin/python benchmarks/compare_stores.py results/quick-fixed results/quick-default [--csv pairs.csv]

A store may be named ``STORE@INTEGRATOR`` to take only its members with that integrator, so that one
sweep over integrators compares with itself (issue 27), with the pairs broken down by epsilon:

    .venv/bin/python benchmarks/compare_stores.py results/implicit-corners@implicit results/implicit-corners@adaptive

``--by geometry v_d`` groups the table by other coordinates (text ones too), e.g. a study rerun beside its old store:

    .venv/bin/python benchmarks/compare_stores.py OLD NEW --by geometry v_d --csv pairs.csv

``--ignore output_interval`` leaves coordinates out of the matching (a variant that swept one beside a store that did not):

    .venv/bin/python benchmarks/compare_stores.py results/fig6-3d-eps1-128-remeasure results/fig6-3d-eps1-128-fast3 \
        --by geometry v_d --ignore output_interval
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

OWN = {"dt", "integrator", "step_tol", "member_id", "status", "mu_star", "mu_star_sem", "t_total", "wall_time_s",
       "message"}


def _split(arg: str) -> tuple[Path, str | None]:
    path, _, integrator = arg.partition("@")
    return Path(path), integrator or None


def _rows(store: Path, integrator: str | None = None, ignore: frozenset = frozenset()) -> dict[tuple, dict]:
    with (store / "index.csv").open() as fh:
        rows = [r for r in csv.DictReader(fh) if integrator is None or r.get("integrator") == integrator]
    keys = [k for k in rows[0] if k not in OWN and k not in ignore]
    top = max(float(r["dt"]) for r in rows) if "dt" in rows[0] else None

    def key(r):
        role = (("dt_ratio", round(float(r["dt"]) / top, 6)),) if top else ()
        return tuple((k, _value(r[k])) for k in keys) + role

    return {key(r): r for r in rows if r["status"] == "completed"}


def _value(text: str) -> float | str:
    """A coordinate's value: a number where it reads as one (theta, v_d, ...), else its text (geometry, ...)."""
    try:
        return float(text)
    except ValueError:
        return text


def _sweep_wall(store: Path) -> float:
    total = 0.0
    if not (store / "invocations.jsonl").exists():  # a committed store carries no log of its invocations
        return float("nan")
    for line in (store / "invocations.jsonl").read_text().splitlines():
        rec = json.loads(line)
        total += float(rec.get("wall_time_s", rec.get("wall_s", 0.0)) or 0.0)
    return total


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("a", help="STORE or STORE@INTEGRATOR")
    ap.add_argument("b", help="STORE or STORE@INTEGRATOR")
    ap.add_argument("--csv", type=Path)
    ap.add_argument("--by", nargs="+", default=["epsilon"], help="coordinates whose values group the summary table")
    ap.add_argument("--ignore", nargs="+", default=[], help="coordinates left out of the matching (a store that swept "
                    "output_interval beside one that did not)")
    args = ap.parse_args()
    (pa, ia), (pb, ib) = _split(args.a), _split(args.b)
    ra, rb = _rows(pa, ia, frozenset(args.ignore)), _rows(pb, ib, frozenset(args.ignore))
    common = sorted(set(ra) & set(rb))
    z = np.array([(float(ra[k]["mu_star"]) - float(rb[k]["mu_star"]))
                  / np.hypot(float(ra[k]["mu_star_sem"]), float(rb[k]["mu_star_sem"])) for k in common])
    print(f"pairs: {len(common)} (completed in {args.a}: {len(ra)}, in {args.b}: {len(rb)})")
    print(f"largest |z| {np.abs(z).max():.2f}, rms z {np.sqrt(np.mean(z**2)):.2f}, mean z {z.mean():+.2f}; "
          f"|z| > 2: {int((np.abs(z) > 2).sum())}, |z| > 3: {int((np.abs(z) > 3).sum())}")
    def group(k):
        d = dict(k)
        return tuple(d.get(b) for b in args.by)

    groups = sorted({group(k) for k in common} - {tuple(None for _ in args.by)}, key=str)
    if groups:
        print(f"| {' | '.join(args.by)} | pairs | mu_star bit-equal | largest abs z | rms z | members' run time a (s) | "
              "b (s) | ratio b/a |")
        print("|---" * (len(args.by) + 7) + "|")
    for g in groups:
        sel = [i for i, k in enumerate(common) if group(k) == g]
        ta = sum(float(ra[common[i]]["wall_time_s"]) for i in sel)
        tb = sum(float(rb[common[i]]["wall_time_s"]) for i in sel)
        same = sum(ra[common[i]]["mu_star"] == rb[common[i]]["mu_star"] for i in sel)
        print(f"| {' | '.join(f'{v:g}' if isinstance(v, float) else str(v) for v in g)} | {len(sel)} | {same} | "
              f"{np.abs(z[sel]).max():.2f} | {np.sqrt(np.mean(z[sel] ** 2)):.2f} | {ta:.1f} | {tb:.1f} | {tb / ta:.2f} |")
    for arg, store, rows in ((args.a, pa, ra), (args.b, pb, rb)):
        run = sum(float(r["wall_time_s"]) for r in rows.values())
        print(f"{arg}: sweep wall {_sweep_wall(store):.1f} s, members' run time {run:.1f} s")
    if args.csv:
        with args.csv.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow([k for k, _ in common[0]] + ["mu_a", "se_a", "mu_b", "se_b", "z", "wall_a", "wall_b"])
            for k, zz in zip(common, z):
                w.writerow([v for _, v in k] + [ra[k]["mu_star"], ra[k]["mu_star_sem"], rb[k]["mu_star"],
                                                rb[k]["mu_star_sem"], f"{zz:.3f}", ra[k]["wall_time_s"], rb[k]["wall_time_s"]])


if __name__ == "__main__":
    main()

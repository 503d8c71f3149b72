"""The studies that ship with slipchain, found by name (issue 30).

Every TOML file in the package's ``presets/`` folder is a study: a sweep (``[base]`` and
``[[grid]]``, run by ``slipchain sweep NAME``, or by ``slipchain reproduce --preset SHORT`` for the
Fig. 6 family) or a mu-max plan (``[bisection]``, run by ``slipchain mu-max NAME``). A name is the
file's stem (``fig6-3d``, ``mu-max``); the Fig. 6 family also answers to the short names of
``reproduce --preset`` (``quick`` for ``fig6-quick``). :data:`CATALOGUE` says what each is for: a
study of the model, the paper's figure, or a validation campaign (a numerical check of the
integrators, not a result about friction), with its run count and the wall time it took on 2 cores
(the page that records it is named). ``slipchain presets`` prints the table; a test keeps it equal
to the files.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from ..model.config import ConfigError, read_toml


@dataclass(frozen=True)
class Study:
    """One shipped preset: its kind ('study', 'validation' or 'plan'), its run count, the wall time it
    took on 2 cores (as recorded on the page ``source``) and its purpose in a line."""

    kind: str
    runs: int
    wall_2_cores: str
    source: str
    purpose: str


CATALOGUE: dict[str, Study] = {
    "fig6-quick": Study("study", 60, "1 min", "docs/performance.md",
                        "Fig. 6 at a glance: the main job (`make run`)"),
    "fig6-paper": Study("study", 368, "4 min", "docs/performance.md", "Fig. 6 in full, with time-step and length checks"),
    "fig6-eps1": Study("study", 56, "23 min", "docs/fig6-eps1/index.md",
                       "Fig. 6 at the physical contact stiffness, epsilon = 1"),
    "fig6-3d": Study("study", 100, "29 min", "docs/fig6-3d/index.md",
                     "Fig. 6 on a 2-D interface: the 2-D chains and an elastic slab"),
    "fig6-3d-eps1": Study("study", 48, "56 min", "docs/fig6-3d-eps1/index.md",
                          "Fig. 6 on a 64 x 64 slab and 2-D chains at the physical contact stiffness, epsilon = 1 "
                          "(implicit)"),
    "fig6-3d-eps1-128": Study("study", 48, "over 10 h (est.: theta = 1 ~8x fig6-3d-eps1 per run, theta = 0.05 more)", "docs/fig6-3d-eps1/index.md",
                              "fig6-3d-eps1 on the 128 x 128 interface of issue 27 (run in parts: it resumes)"),
    "fig6-3d-eps1-128-fast": Study("study", 48, "78 min on 2 cores (re-measured 2026-12-07 in one sweep: 9 305 CPU-s, 11-401 s a run, Xeon; first run 42 873 CPU-s at Dask's allocator setting)", "docs/fig6-3d-eps1/index.md",
                                   "fig6-3d-eps1-128 with each point's fastest stepper (TR-BDF2 on the slab, adaptive "
                                   "on chain2d at low load)"),
    "fig6-3d-eps1-128-fast2": Study("study", 48, "8 516 CPU-s, about 71 min on 2 cores (44 members reused from the re-measured fast preset, 4 run anew; Xeon)", "docs/fig6-3d-eps1/index.md",
                                    "fig6-3d-eps1-128-fast with chain2d at theta = 0.2 on backward Euler (2.3-2.9x faster "
                                    "there than the adaptive step at 128 x 128)"),
    "fig6-3d-eps1-128-fast3": Study("study", 48, "60.3 min on 2 cores (3 616 s in one sweep 2026-12-07, 7 201 CPU-s, 11-424 s a run; Xeon)", "docs/fig6-3d-eps1/index.md",
                                    "fig6-3d-eps1-128-fast2 with 5-ms samples at theta >= 0.5 (the implicit stepper's "
                                    "step ends within its sample: 1.15-3.7x faster there)"),
    "fig6-3d-eps1-128-fast4": Study("study", 48, "59.2 min on 2 cores (3 554 s in one sweep 2026-12-07, 6 913 CPU-s, 10-418 s a run; Xeon)", "docs/fig6-3d-eps1/index.md",
                                    "fig6-3d-eps1-128-fast3 with chain2d at theta = 0.1, v_d2 on backward Euler "
                                    "(additive; 1.60x) and the slab at theta = 1 and 0.7, v_d1 with 10-ms samples "
                                    "(1.11-1.22x)"),
    "fig6-3d-eps1-rubber": Study("study", 8, "30 min", "docs/fig6-3d-eps1-rubber/index.md",
                                 "fig6-3d-eps1 in rubber at v_d1: the 64 x 64 rubber slab at epsilon = 1 (implicit)"),
    "fig6-rubber": Study("study", 144, "10 min", "docs/fig6-rubber/index.md",
                         "Fig. 6 with a viscoelastic slider (Prony bulk) at 20 and 11 °C"),
    "fig6-rubber-elastic": Study("study", 72, "25 s", "docs/fig6-rubber/index.md",
                                 "the elastic twin of fig6-rubber: the paper's model on its grid and step"),
    "fig6-rubber-slab": Study("study", 144, "3 h (v_d1: 31 min; a v_d2 run 4-8 min)", "docs/fig6-rubber-slab/index.md",
                              "Fig. 6 in rubber on a 64 x 64 slab under the drive springs, 20 and 11 °C"),
    "fig6-rubber-slab-elastic": Study("study", 72, "15 min (v_d1: 5 min; a v_d2 run 34 s)", "docs/fig6-rubber-slab/index.md",
                                      "the elastic twin of fig6-rubber-slab: the elastic slab on its grid and step"),
    "epsilon": Study("study", 24, "23 min", "docs/mechanism/epsilon-index.csv",
                     "the load effect against the contact stiffness epsilon"),
    "velocity": Study("study", 66, "4 min", "docs/mechanism/velocity-index.csv", "mu_star(v_d) at several loads"),
    "dead-weight": Study("study", 14, "2 min", "docs/mechanism/dead-weight-index.csv",
                         "the slider under a hanging weight: velocity or runaway"),
    "mu-max": Study("plan", 130, "42 min", "docs/mu-max/index.md",
                    "mu_max(theta) under a dead weight by bisection, the tester's observable"),
    "mu-max-rubber": Study("plan", 42, "17 min", "docs/mu-max-rubber/index.md",
                           "mu_max(theta) under a dead weight with a viscoelastic slider"),
    "mu-max-rubber-400ms": Study("plan", 14, "about 15 min", "docs/mu-max-rubber/index.md",
                                 "the rubber's mu_max at theta = 0.5 loaded twice as slowly (400-ms ramp)"),
    "ladder-eps1": Study("plan", 63, "9 min", "docs/ladder/index.md",
                         "the ladder's epsilon = 1 rung: mu_max on the chain under a dead weight (200-ms ramp)"),
    "ladder-eps1-held": Study("plan", 96, "9 min (3-29 s a run)", "docs/ladder/index.md",
                              "the epsilon = 1 rung to the end: runs of 3 s, runaways stopped, held runs below"),
    "ladder-eps1-slow-held": Study("plan", 56, "30 min (22-93 s a run)", "docs/ladder/index.md",
                                   "rung 3s to the end: the 2-s ramp, runaways stopped, held runs below, four loads"),
    "ladder-eps1-slow20-held": Study("plan", 56, "about 6 h (10.7 core-hours, 470-1 080 s a run, Xeon; resumes)", "docs/ladder/index.md",
                                     "rung 3s-20b: the 20-s ramp by bisection (runs of 24 s, two seeds): the chain's slow-loading limit"),
    "ladder-eps1-slow6-held": Study("plan", 56, "98 min (90-240 s a run)", "docs/ladder/index.md",
                                    "rung 3s-6b: the 6-s ramp by bisection, runs of 10 s, held runs below, four loads"),
    "ladder-eps1-slow": Study("plan", 27, "47 min", "docs/ladder/index.md",
                              "the epsilon = 1 rung loaded ten times more slowly (2-s ramp, runs of 5 s)"),
    "ladder-eps1-slow-grid": Study("study", 122, "2- and 6-s ramps 35 min; 20-s ramps ~5 h (510-880 s per run decided at 20.5 s)", "docs/ladder/index.md",
                                   "the epsilon = 1 rung's weights held or run away with 2-, 6- and 20-s ramps"),
    "ladder-slab": Study("plan", 40, "40 min", "docs/ladder/index.md",
                         "the ladder's slab rung: mu_max on a 16 x 16 elastic slab, epsilon = 1"),
    "ladder-rubber": Study("plan", 8, "16 min", "docs/ladder/index.md",
                           "the ladder's rubber rung by bisection (stopped at its bracket: needs longer runs)"),
    "ladder-rubber-long": Study("plan", 84, "12 min (8-22 s a run)", "docs/ladder/index.md",
                                "the ladder's rubber rung by bisection: runs of 5 s, runaways stopped, held runs below"),
    "ladder-rubber-slow": Study("plan", 84, "61 min (80-200 s a run)",
                                "docs/ladder/index.md", "rung 5 with the weight raised over 2 s: does the rubber's dip shrink?"),
    "ladder-rubber-grid": Study("study", 16, "283 s on 16 CPUs", "docs/ladder/index.md",
                                "the ladder's rubber rung as a grid of weights on a 16 x 16 slab"),
    "tester-16": Study("study", 16, "405 s on 16 CPUs", "docs/tester-3d/index.md",
                       "the tester's protocol on a 16 x 16 interface: rubber, H = 50 a, its top, the weight at once"),
    "tester-16-12s": Study("study", 2, "12 min (216 and 491 s; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                           "the runaway at theta 0.05 and 1 with the weight raised half as fast: is 6 s the slow limit?"),
    "tester-16-long": Study("study", 8, "35 core-minutes (70-906 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                            "tester-16's release at once, decided from 2 s (runs of 3 s): each load's undecided gap"),
    "tester-16-long-11c": Study("study", 8, "40 core-minutes (52-878 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                "tester-16-long's release at once at Fig. 3's 11 °C (seed 0)"),
    "tester-16-long-11c-2": Study("study", 6, "19 core-minutes (55-352 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                  "tester-16-long-11c's open brackets closed (theta 0.05, 0.2 and 1 at two more weights each)"),
    "tester-16-release": Study("study", 4, "17 core-minutes (67-427 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                               "tester-16-long at theta = 0.5 with the weight released over 0.1 and 0.3 s"),
    "tester-16-release-2": Study("study", 6, "4 of 6 run (theta = 0.05 at 0.95: 935-997 s, runaways; theta = 0.5: 61-120 s; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                 "tester-16-release's brackets closed: theta = 0.05 at 0.95, 1.0 and theta = 0.5 at 0.6, 0.75"),
    "tester-16-release-seeds": Study("study", 16, "13 of 16 run (43-937 s each; theta = 0.05 at 0.95 for seeds 1 over 0.3 s and 2 not yet)", "docs/tester-3d/index.md",
                                     "tester-16-release's brackets for seeds 1 and 2 (over 0.1 and 0.3 s)"),
    "tester-16-release-seeds-2": Study("study", 5, "17 core-minutes (58-312 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                       "tester-16-release-seeds' open brackets at theta = 0.5 closed (seeds 1 and 2)"),
    "tester-16-release-low": Study("study", 4, "4 core-minutes (43-65 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                   "tester-16-release at theta = 0.05 (0.85 and 0.9 over 0.1 and 0.3 s)"),
    "tester-16-long-seeds": Study("study", 16, "81 core-minutes (82-956 s a run; a Zen 5 EPYC)",
                                  "docs/tester-3d/index.md", "tester-16-long's brackets for seeds 1 and 2"),
    "tester-16-low": Study("study", 4, "22 min", "docs/tester-3d/index.md",
                           "tester-16's lowest load at dt = 5e-8 s"),
    "tester-16-slow": Study("study", 25, "1 h 44 min", "docs/tester-3d/index.md",
                            "tester-16 in the slow-loading limit: the weight raised over 1 s and 3 s (the implicit step)"),
    "tester-16-slower": Study("study", 24, "19 of 24 run (700-7 300 s each, 2 at a time; part on 16 CPUs)", "docs/tester-3d/index.md",
                              "tester-16-slow at heavier weights and a 6-s ramp: where the slowly loaded block runs away"),
    "tester-16-finer": Study("study", 5, "all 5 run (1 400-4 700 s each, 1-2 at a time)", "docs/tester-3d/index.md",
                             "tester-16-slower's 6-s ramp at mu_a = 1.00, the midpoint of its bracket"),
    "tester-16-seeds": Study("study", 16, "all 16 run (830-3 000 s each, 7.4 core-hours; partly on 16 CPUs, partly before the compiled steps)", "docs/tester-3d/index.md",
                             "tester-16-slower's 6-s bracket, 0.95 and 1.05, for seeds 1 and 2"),
    "tester-16-11c-slow": Study("study", 8, "all 8 run (570-2 900 s each, 3.5 core-hours; partly on 16 CPUs, partly before the compiled steps)", "docs/tester-3d/index.md",
                                "tester-16-seeds' 6-s bracket, 0.95 and 1.05, at Fig. 3's 11 °C (seed 0)"),
    "tester-32-long": Study("study", 4, "39 core-minutes (328-866 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                            "tester-16-long's release at once on 32 x 32 at the weights that decide the dip (seed 0)"),
    "tester-32-long-seeds": Study("study", 8, "69 core-minutes (188-754 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                  "tester-32-long for seeds 1 and 2"),
    "tester-32-seeds": Study("study", 16, "not yet measured (the steady side: 150-450 s a run on one core)",
                             "docs/tester-3d/index.md", "tester-32-slower for seeds 1 and 2"),
    "tester-32-slower": Study("study", 8, "all 8 run (154-2 601 s each, 2.0 core-hours; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                              "tester-16-slower's 6-s bracket, 0.95 and 1.05, on a 32 x 32 interface (seed 0)"),
    "tester-64-long": Study("study", 4, "all 4 run (theta = 0.5 at 0.6 held, 0.7 ran away; theta = 0.05 at 0.85 ran away: 1 391, 5 381 and 15 117 s on one Zen 5 core beside another run; theta = 1 at 0.85 ran away, 5 782 s on one EPYC core beside another run)", "docs/tester-3d/index.md",
                            "tester-32-long's release at once on 64 x 64 (seed 0)"),
    "tester-64-long-2": Study("study", 1, "1 of 1 run: held at 0.8 (793 s on one Zen 5 core beside another run)",
                              "docs/tester-3d/index.md", "tester-64-long's theta = 0.05 at 0.8, after it ran away at 0.85 (seed 0)"),
    "tester-64-long-3": Study("study", 1, "1 of 1 run: held at 0.75 (3 020 s on one EPYC core beside another run)", "docs/tester-3d/index.md",
                              "tester-64-long's theta = 1 at 0.75, beside its 0.85 (seed 0)"),
    "tester-64-long-4": Study("study", 1, "1 of 1 run: ran away at 0.65 (4 026 s on one EPYC core, partly beside another run)", "docs/tester-3d/index.md",
                              "tester-64-long's theta = 0.5 at 0.65, inside its bracket [0.60, 0.70) (seed 0)"),
    "tester-64-long-5": Study("study", 2, "1 of 2 run: ran away at 0.7 (2 428 s on one core of a 2-core AMD EPYC with AVX-512); 0.75 not run (above a runaway)", "docs/tester-3d/index.md",
                              "tester-64-long's fourth load, theta = 0.2 at 16 x 16's bracket, 0.7 and 0.75 (seed 0)"),
    "tester-64-long-6": Study("study", 2, "all 2 run: held at 0.6 and 0.65 (534 and 537 s, one core each of a 2-core AMD EPYC with AVX-512)", "docs/tester-3d/index.md",
                              "tester-64-long-5's theta = 0.2 at 0.6 and 0.65, after it ran away at 0.7 (seed 0)"),
    "tester-64-long-seeds": Study("study", 4, "all 4 run (seed 1: theta = 0.05 held at 0.8, 4 900 s; theta = 0.5 ran away at 0.7, 9 398 s; one core each of a 2-core AMD EPYC without AVX-512; seed 2: held, 707 s; ran away, 4 527 s; one core each of a 2-core AMD EPYC with AVX-512)", "docs/tester-3d/index.md",
                                  "tester-64-long for seeds 1 and 2 at seed 0's bounding weights: theta = 0.05 at 0.8, theta = 0.5 at 0.7"),
    "tester-64-long-seeds-2": Study("study", 4, "4 of 4 run: held at 0.65 (1 121, 1 122 s), ran away at 0.7 (2 754, 2 666 s; one core each of a 2-core AMD EPYC with AVX-512)", "docs/tester-3d/index.md",
                                    "tester-64-long-seeds at theta = 0.2, seed 0's bracket 0.65 and 0.7 (seeds 1, 2)"),
    "tester-64-long-seeds-3": Study("study", 4, "4 of 4 run: held at 0.75 (2 741, 2 489 s), ran away at 0.85 (5 589, 5 628 s; one core each of a 2-core AMD EPYC with AVX-512)", "docs/tester-3d/index.md",
                                    "tester-64-long-seeds at theta = 1, seed 0's bracket 0.75 and 0.85 (seeds 1, 2)"),
    "tester-64-slower": Study("study", 8, "5 of 8 run: the steady side, 502-645 s each, and theta = 1 at 1.05, 2 395 s (a Zen 5 EPYC)", "docs/tester-3d/index.md",
                              "tester-32-slower on a 64 x 64 interface (seed 0)"),
    "tester-128-long": Study("study", 2, "2 of 2 run: theta = 0.05 held at 0.8 (10 462 s), theta = 0.5 ran away at 0.65 (11 864 s; one core each of a 2-core AMD EPYC with AVX-512)", "docs/tester-3d/index.md",
                             "the release on 128 x 128 at 64 x 64's tightest bounds: theta = 0.05 at 0.8, theta = 0.5 at 0.65 (seed 0; decided from 0.8 s)"),
    "tester-128-long-2": Study("study", 2, "1 of 2 run (theta = 0.2 at 0.7 ran away: 13 054 s on one core); theta = 1 at 0.75 held by the stop rules at 0.995 s, stopped and checkpointed at 1.035 s after 16 419 s", "docs/tester-3d/index.md",
                               "tester-128-long at theta = 1, 0.75 and theta = 0.2, 0.7 (64 x 64's held and runaway sides for all three seeds; seed 0)"),
    "tester-128-long-3": Study("study", 4, "4 of 4 run (seed 1 theta = 0.5 at 0.65 ran away, stopped at 0.541 s: 16 416 s; seed 0 theta = 0.05 at 0.85 ran away, stopped at 0.182 s: 23 291 s; seed 1 theta = 0.05 at 0.8 held, read at 0.8 s: 17 098 s; seed 0 theta = 0.5 at 0.6 held, read at 0.816 s: 12 234 s; one Intel Xeon core each beside other runs, the last two partly at glibc's allocator defaults)", "docs/tester-3d/index.md",
                               "tester-128-long stopped when decided (stop_at_runaway, stop_when_held): seed 1 at its weights, seed 0 at the other side of its brackets"),
    "tester-128-long-4": Study("study", 5, "5 of 5 run (seed 0's theta = 0.2 held at 0.65, read held at 0.8 s: 3 908 s; seed 0's theta = 1 ran away at 0.85, decided at 0.8 s: 11 629 s; seed 1's theta = 0.5 held at 0.6, read held at 0.8 s: 11 794 s; seed 2's theta = 0.5 ran away at 0.65, stopped at 0.541 s: 9 738 s; seed 2's theta = 0.05 held at 0.8, read held at 0.8 s: 7 460 s; wall seconds on one Intel Xeon core each, beside other runs)", "docs/tester-3d/index.md",
                               "tester-128-long-3's next runs: seed 1 theta = 0.5 at 0.6, seed 2 at the tightest pair (0.05 at 0.8, 0.5 at 0.65), seed 0 theta = 0.2 at 0.65 and theta = 1 at 0.85"),
    "tester-128-long-5": Study("study", 10, "done, 10 of 10 (seed 1's theta = 0.05 ran away at 0.85, 7 240 s of wall on one core; seeds 1's and 2's theta = 1 held at 0.75, 7 952 and 7 283 s, and ran away at 0.85, 3 111 and 3 128 s; seed 2's theta = 0.5 held at 0.6, 2 218 s; seeds 1's and 2's theta = 0.2 held at 0.65, 1 248 and 1 103 s, and ran away at 0.7, 982 and 911 s; 2026-12-07): the 128 x 128 release's 24 runs complete", "docs/tester-3d/index.md",
                               "tester-128-long-4's next runs, whatever it says: seed 2 theta = 0.5 at 0.6, seed 1 theta = 0.05 at 0.85, seeds 1 and 2 at theta = 0.2 (0.65, 0.7) and theta = 1 (0.75, 0.85)"),
    "tester-128-long-6": Study("study", 1, "done: seed 2's theta = 0.05 ran away at 0.85 (6 589 s of wall on one core, 2026-12-06)", "docs/tester-3d/index.md",
                               "seed 2's theta = 0.05 at 0.85, the other side of its held run at 0.8 (tester-128-long-4)"),
    "tester-128-slower": Study("study", 8, "1 of 8 run (theta = 1 at 0.95: 5 423 s on one Zen 5 core; theta = 0.05 at 0.95 checkpointed at 1.45 s after 4 124 s)", "docs/tester-3d/index.md",
                               "tester-32-slower on the issue's 128 x 128 interface (seed 0)"),
    "tester-onset-32-seeds": Study("study", 8, "45 core-minutes (231-596 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                   "mu_max at the runaway's onset on 32 x 32, seeds 1 and 2, every load"),
    "tester-onset-128": Study("study", 4, "1 of 4 run (theta = 1: 9 818 s on one Zen 5 core, partly beside 2 sweeps); the others ran as tester-onset-128-etol",
                              "docs/tester-3d/index.md", "mu_max at the runaway's onset on 128 x 128, every load (seed 0)"),
    "tester-onset-32-etol": Study("study", 4, "15 core-minutes (160-376 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                  "tester-onset-32-seeds' seed 1 with energy_tol = 1e-3: the onset where the default puts it?"),
    "tester-16-long-etac": Study("study", 8, "7 of 8 run (theta = 0.05 at 0.85: 1 684 s; the others 89-349 s; beside other runs); theta = 0.05 at 0.9 checkpointed", "docs/tester-3d/index.md",
                                 "tester-16-long's release at once at the paper's largest contact damping, eta_c = omega0"),
    "tester-16-long-etac-2": Study("study", 1, "run (231 s beside other runs): held, so [0.80, 0.85) at eta_c = omega0", "docs/tester-3d/index.md",
                                   "tester-16-long-etac's theta = 0.05 at 0.8, below the 0.85 that ran away at eta_c = omega0"),
    "tester-16-long-etac-3": Study("study", 7, "22 core-minutes (145-293 s a run; an Intel Xeon beside two sweeps); theta = 0.05 at 0.85 rerun with the rule's margin", "docs/tester-3d/index.md",
                                   "tester-16-long's release at once at the paper's middle contact damping, eta_c = 0.3 omega0, stopped when decided"),
    "tester-16-long-etac-3-check": Study("study", 3, "694 s (theta = 0.05 to 0.8 s), 1 030 s (theta = 1 to 3 s), about 1 840 s (theta = 0.05 to 3 s); an Intel Xeon beside two sweeps", "docs/tester-3d/index.md",
                                         "tester-16-long-etac-3's marginal runs (theta = 0.05 at 0.85, theta = 1 at 0.8) without the stop rules, decided from 0.8 and 2 s"),
    "tester-16-long-etac-seeds": Study("study", 16, "all 16 run (144-285 s a run, 3 528 s on one Intel Xeon core beside a niced 128 x 128 sweep); R(0.5) as seed 0's but seed 1 at omega0, (0.82, 0.94)", "docs/tester-3d/index.md",
                                       "the release's dip R(0.5) at eta_c = 0.3 omega0 and omega0, seeds 1 and 2, on seed 0's brackets"),
    "tester-16-long-etac-seeds-2": Study("study", 2, "both run (161 and 177 s beside two sweeps): both ran away, so [0.70, 0.75)", "docs/tester-3d/index.md",
                                         "tester-16-long-etac-seeds' seed 1 at omega0, theta = 0.5 at 0.75 and 0.8 (0.7 held)"),
    "tester-16-long-etac-seeds-check": Study("study", 2, "both run (1 952 and 496 s beside two sweeps): both ran away, decided at 2 s", "docs/tester-3d/index.md",
                                             "tester-16-long-etac-seeds' two narrowest runaways (+5.0 % a period) without the stop rules, decided from 2 s"),
    "tester-onset-32-etac": Study("study", 8, "all 8 run (146-645 s a run, 2 438 s on one Zen 5 core beside two sweeps)", "docs/tester-3d/index.md",
                                  "tester-onset-32-etol at the paper's other contact dampings, eta_c = 0.3 omega0 and omega0"),
    "tester-onset-32-short": Study("study", 4, "11 core-minutes (84-305 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                   "tester-onset-32-etol with the ramp cut short (to 0.98 over 5.6 s, decided from 5.65 s): the same onset, less runaway?"),
    "tester-onset-128-etol": Study("study", 3, "all 3 run (theta = 0.2 from rest 3 704 s; 0.05 and 0.5, restarted to take the savings, 6 049 and 5 624 s; one Zen 5 core each)",
                                   "docs/tester-3d/index.md", "tester-onset-128's lighter loads with energy_tol = 1e-3 and the ramp cut short (seed 0)"),
    "tester-onset-128-seeds": Study("study", 8, "all 8 run: theta = 0.05 (4 829-4 865 s each), 1 (1 420-2 067 s), 0.5 (6 372 and 5 695 s) and 0.2 (6 504 and 5 981 s) on one Zen 5 core beside other runs", "docs/tester-3d/index.md",
                                    "tester-onset-128-etol for seeds 1 and 2 at every load"),
    "tester-onset-32-11c": Study("study", 4, "27 core-minutes (235-716 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                 "mu_max at the runaway's onset on 32 x 32 at Fig. 3's 11 °C, every load (seed 0)"),
    "tester-onset-64-low": Study("study", 2, "58 core-minutes (1 476 and 1 992 s; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                                 "mu_max at the runaway's onset on 64 x 64 at the tester's pressures, theta 0.02 and 0.01 (seed 0)"),
    "tester-onset-64": Study("study", 4, "76 core-minutes (727-2 049 s a run; a Zen 5 EPYC)", "docs/tester-3d/index.md",
                             "mu_max at the runaway's onset on 64 x 64, every load (seed 0)"),
    "tester-16-11c": Study("study", 15, "about 420 s on 16 CPUs", "docs/tester-3d/index.md",
                           "tester-16 at Fig. 3's 11 °C (theta 0.2, 0.5, 1; five weights)"),
    "tester-128": Study("plan", 72, "not run (est. ~700 core-hours: a cluster's job)", "docs/tester-3d/index.md",
                        "issue 29's plan: mu_max by bisection in the tester's protocol, 128 x 128, 4 loads, 3 seeds"),
    "tester-128-slow": Study("plan", 72, "not run (est. ~100 core-hours, unmeasured at 128 x 128)", "docs/tester-3d/index.md",
                             "tester-128 in the slow-loading limit (the weight raised over 3 s, the implicit step)"),
    "fig6-fold": Study("validation", 48, "1.4 min", "docs/fold-convergence/report.md",
                       "the fold-aware step at three dt against dt = 1e-8 s"),
    "implicit-corners": Study("validation", 48, "11 min", "docs/numerics.md",
                              "the implicit stepper against the adaptive one at the Fig. 6 corners, epsilon 1e-2, 0.1, 1"),
    "fig6-adaptive": Study("validation", 32, "1.3 min", "docs/numerics.md",
                           "the adaptive step against the fixed step at epsilon = 1e-2"),
    "fig6-eps01": Study("validation", 32, "15 min", "docs/numerics.md",
                        "the adaptive step against the fixed step at epsilon = 0.1"),
    "fig6-eps1-check": Study("validation", 36, "12 min", "docs/numerics.md",
                             "epsilon = 1: a tolerance ten times tighter; rest against steady start"),
}


def preset_files() -> dict[str, Path]:
    """Every shipped preset file by name (its stem)."""
    folder = resources.files("slipchain") / "presets"
    return {Path(str(p)).stem: Path(str(p)) for p in folder.iterdir() if str(p).endswith(".toml")}


def find_study(name_or_path: str | Path) -> Path | None:
    """The file a command was given: an existing path as it is, else the shipped preset of that name
    (its stem, with or without '.toml'; the Fig. 6 family also by ``reproduce``'s short name);
    None if neither exists."""
    path = Path(name_or_path)
    if path.exists():
        return path
    name = path.name[:-5] if path.name.endswith(".toml") else path.name
    files = preset_files()
    return files.get(name) or files.get(f"fig6-{name}")


def read_study(path: str | Path) -> dict[str, Any]:
    """A study file (sweep or mu-max plan) as plain data, with its ``extends`` resolved.

    ``extends = "NAME"`` at the top of a study makes it a variant of another: NAME is a study file
    beside it (a path relative to the extending file's folder) or, failing that, a shipped preset's name.
    The parent is read first (itself possibly extending another) and the child's keys laid over it:
    a table (``[base]``, ``[bisection]``) key by key, anything else (``[[grid]]``, ``name``) whole; the
    parent's ``name`` is never inherited. What results is the flat study the child would have been
    written out as, so members, ids and the sweep's digest are the same as for that flat file (a
    store records the flat definition). ConfigError names the file, the key and the value for a parent
    that is neither a file nor a shipped preset, a value that is not a string, and a cycle.
    """
    return _read_study(Path(path), ())


def _read_study(path: Path, chain: tuple[Path, ...]) -> dict[str, Any]:
    data = dict(read_toml(path))
    if "extends" not in data:
        return data
    parent = data.pop("extends")
    where = f"study file {str(path)!r}: key 'extends' has value {parent!r}"
    if not isinstance(parent, str) or not parent.strip():
        raise ConfigError(f"{where}; expected the name of a shipped preset or the path of a study file")
    beside = path.parent / parent
    found = beside if beside.is_file() else preset_files().get(parent.removesuffix(".toml"))
    if found is None:
        raise ConfigError(f"{where}; expected a study file beside it or a shipped preset: "
                          f"{', '.join(sorted(preset_files()))}")
    here = chain + (path.resolve(),)
    if found.resolve() in here:
        cycle = " -> ".join(str(p.name) for p in here + (found.resolve(),))
        raise ConfigError(f"{where}, which leads back to itself ({cycle}); expected a chain that ends in a "
                          "study without 'extends'")
    merged = _read_study(found, here)
    merged.pop("name", None)
    for key, value in data.items():
        old = merged.get(key)
        merged[key] = {**old, **value} if isinstance(old, dict) and isinstance(value, dict) else value
    return merged


def missing_message(what: str, given: str | Path) -> str:
    """The error for a study that is neither a file nor a shipped name."""
    return (f"{what} {str(given)!r} is neither a file nor the name of a shipped preset; shipped: "
            f"{', '.join(sorted(preset_files()))} (`slipchain presets` lists them)")


__all__ = ["CATALOGUE", "Study", "find_study", "missing_message", "preset_files", "read_study"]

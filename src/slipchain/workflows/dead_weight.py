"""The experiment's own observable (issue 14, first part): the largest dead weight at which the
slider still reaches steady sliding, mu_max, found by bisection over the applied mu_a.

The tester of the paper (Figs. 1-3) hangs a weight on the slider and measures the steady velocity;
above the first maximum of mu(v) no steady state exists and the slider runs away. For the model,
one evaluation is a dead-weight run (config key ``dead_weight = mu_a``: a constant force
``mu_a * epsilon * f0 * theta`` on every upper block) whose velocity is classified exactly as the
tester's traces are (:func:`slipchain.results.velocity.steady_velocity`): ``ok`` (steady sliding),
``runaway`` (still accelerating, or faster than the rising branch allows) or ``no-steady``.

Bisection keeps ``lo`` steady and ``hi`` runaway and halves the bracket until it is narrower than
``2*tol``; mu_max is its middle (so within ``tol`` of the true edge, for this realisation and run
length), v_max the steady velocity measured at ``lo``. A ``no-steady`` evaluation stops the
bisection with that status: the run was too short to decide (a longer ``t_total`` decides it).
With ``held`` (plan key, :func:`mu_max_many`'s argument) an undecided run whose record ends on the rising
branch counts as below the maximum, as the tester's grids read it (rung 6l of docs/ladder): a ``no-steady``
run that is **held** by :func:`slipchain.analysis.traces.run_outcome` (its mean velocity over the record's
last HELD_WINDOW s below ONSET_FACTOR v0 10**delta, so the weight did not pull it away within the run) is
evaluated ``held`` and moves ``lo`` up as a steady one does; ``v_max`` is then that end velocity. This is for
sliders that creep under a constant weight for longer than any affordable run (the viscoelastic slab, whose
arms relax over up to a second at 20 °C: docs/ladder, rung 5); it bounds mu_max for runs of that length,
as a tester's own runs do. Off (the default) the bisection is the tester's alone, as before.
Just below the maximum the steady state is hard to reach and to recognise (its restoring slope,
the slope of f(v), vanishes at the peak): with identical contacts (N = 11, delta = 0) mu_a = 1.0,
1.5e-4 below the analytic peak 1.00015, is classified runaway in runs of 5, 20 and 50 ms alike,
so the bisection from [0.5, 1.5] gives 0.996 (bracket 0.992-1.000), 0.004 below the peak: within
the issue's resolution of 0.005, and biased low (tests/physics/test_mu_max.py).

:func:`mu_max_many` runs the bisections of many realisations (theta, seeds) in lock-step: each
round evaluates every open bracket's middle at once, as one sweep (:class:`Rounds`): its runs are
the members of a store in ``OUT/rounds/<digest>``, run on Dask (a real local cluster by default)
by the same executor as ``slipchain sweep``, so a kill, a second driver, a failed run or a
corrupt file behaves as it does in any sweep, and an interrupted call resumes without
recomputing what it had finished (issue 30).

A :class:`Plan` (``[base]`` and ``[bisection]`` of a TOML file, e.g. ``presets/mu-max.toml``)
says what ``slipchain mu-max`` runs; :func:`run_plan` runs it and writes its tables. Use the
automatic dead-weight length (config ``t_decide``, :class:`slipchain.engine.control.UntilDecided`)
so that slow corners (theta = 0.1) are decided rather than left ``no-steady``.
"""

from __future__ import annotations

import json
import os
import tempfile
from contextlib import ExitStack
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np

from ..analysis.statistics import ratios_to_first
from ..analysis.traces import HELD  # an evaluation's status with ``held`` on: undecided, but ended on the rising branch (run_outcome)
from ..engine.backends import BackendName
from ..engine.simulate import run
from ..model.config import Config, ConfigError, make_config
from ..results.io import write_bytes, write_csv, write_text_atomic
from ..results.schema import Status
from ..results.velocity import VelocityStatus
from ..sweeps.definition import SweepDefinition, make_sweep, member_id

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

TOL = 0.005  # the resolution of mu_max
BRACKET = "bracket"  # status of a realisation whose runs at lo or hi did not bracket mu_max


class BracketError(ValueError):
    """The runs at ``lo`` or ``hi`` did not bracket mu_max (found by running them; they are kept in OUT/rounds)."""


@dataclass
class Evaluation:
    """One dead-weight run of the bisection."""

    mu_a: float
    velocity_status: str
    velocity: float
    message: str


@dataclass
class MuMax:
    """mu_max of one realisation: the bracket [lo, hi] (lo steady, hi runaway) and its middle."""

    status: str  # 'ok' (bracket narrower than 2*tol), 'no-steady' (an undecided run stopped it), 'bracket' (lo/hi refuted)
    mu_max: float
    v_max: float  # steady velocity at lo, m/s
    lo: float
    hi: float
    evaluations: list[Evaluation] = field(default_factory=list)
    message: str = ""  # why it is not 'ok'


def evaluate(config: Config, mu_a: float, backend: str | BackendName = BackendName.CPU, held: bool = False) -> Evaluation:
    """One dead-weight run at applied ``mu_a`` and the tester's classification of its velocity
    (``held``: an undecided run that ends on the rising branch is ``held``, module docstring)."""
    cfg = config.with_updates(dead_weight=float(mu_a))
    ds = run(cfg, backend=backend, progress=False)
    e = _evaluation(mu_a, ds.attrs)
    return _held(cfg, e, lambda: ds) if held else e


def mu_max(config: Config | Mapping[str, Any], *, lo: float = 0.3, hi: float = 1.5, tol: float = TOL,
           backend: str | BackendName = BackendName.CPU, held: bool = False) -> MuMax:
    """The largest applied mu_a with steady sliding, by bisection to within ``tol`` (module docstring).

    ``config``: the realisation (its ``dead_weight`` is set by the bisection; give ``t_total``
    long enough for the velocity to settle). ``lo`` must give steady sliding (or, with ``held``, a
    held run) and ``hi`` a runaway; BracketError (naming them and what the runs gave) if they do not;
    ConfigError if ``lo >= hi``.
    """
    cfg = config if isinstance(config, Config) else make_config(dict(config))
    return _bisect([cfg], lo, hi, tol, lambda jobs: [evaluate(c, m, backend, held) for c, m in jobs])[0]


def mu_max_many(configs: list[Config], *, lo: float = 0.3, hi: float = 1.5, tol: float = TOL,
                store: str | os.PathLike | None = None, client: Any = None, scheduler: str | None = None,
                n_workers: int | None = None, backend: str | BackendName = BackendName.CPU, strict: bool = True,
                progress: bool | None = None, held: bool = False) -> list[MuMax]:
    """:func:`mu_max` for many realisations at once, each round's runs a sweep of their own in a
    store (:class:`Rounds`); the same results as one :func:`mu_max` per config.

    ``store``: the output directory that keeps every round (OUT/rounds; a second call resumes),
    else a temporary one; ``client``: an existing ``distributed.Client``, else ``scheduler`` (an
    address) or a local cluster of ``n_workers`` processes, started only if something is to run.
    ``strict=False``: a refuted bracket marks that realisation ``bracket`` instead of raising
    BracketError. ``held``: held runs count below the maximum (module docstring). KeyboardInterrupt
    if interrupted (Ctrl-C, SIGTERM): every finished run is kept."""
    configs = [c if isinstance(c, Config) else make_config(dict(c)) for c in configs]
    with Rounds(store, client=client, scheduler=scheduler, n_workers=n_workers, backend=backend,
                progress=progress, held=held) as rounds:
        return _bisect(configs, lo, hi, tol, rounds.evaluate, strict)


def evaluate_many(jobs: list[tuple[Config, float]], *, store: str | os.PathLike | None = None, client: Any = None,
                  scheduler: str | None = None, n_workers: int | None = None,
                  backend: str | BackendName = BackendName.CPU, progress: bool | None = None) -> list[Evaluation]:
    """:func:`evaluate` for many (config, mu_a) pairs, run as one sweep (:meth:`Rounds.evaluate`)."""
    with Rounds(store, client=client, scheduler=scheduler, n_workers=n_workers, backend=backend,
                progress=progress) as rounds:
        return rounds.evaluate(jobs)


ROUNDS = "rounds"  # OUT/rounds/<digest>: one sweep store per round of dead-weight runs
LEGACY_CACHE = "cache"  # OUT/cache/<member id>.json: the evaluations of slipchain 0.2.0 and before (read, never written)


class Rounds:
    """The dead-weight runs of a bisection, one round at a time, each round a sweep in a store.

    A round's runs (one per open bracket, or the lo/hi ends, or the curve points) are the members
    of a sweep over the keys in which they differ (theta, seed, dead_weight, ...), stored in
    ``OUT/rounds/<digest>`` and run by :func:`slipchain.sweeps.executor.run_sweep`: the same
    resume, quarantine of unreadable files, failure records, checkpoints of long members,
    progress bar and scheduler as any ``slipchain sweep``. The rounds follow from the results
    before them, so a second call meets the same rounds and finds their members done; a kill
    loses only the runs in flight. ``OUT`` itself carries a driver lock for the whole bisection
    (a second driver is refused, naming the first).

    An evaluation is read from its member file's attributes (``velocity_status``, ``velocity``,
    ``message``, ``velocity_reason``); a failed member (``error``, ``diverged``) gives that status,
    which stops its realisation's bisection with the reason while the others go on (it is rerun by
    the next call). A run that another round already holds (a plan given more seeds, a curve point
    that the bisection visited) is copied from there, not rerun; so is nothing else. The JSON files
    that slipchain 0.2.0 kept in ``OUT/cache`` are still read: a run found there is not run again.
    """

    def __init__(self, out: str | os.PathLike | None, *, client: Any = None, scheduler: str | None = None,
                 n_workers: int | None = None, backend: str | BackendName = BackendName.CPU,
                 progress: bool | None = None, announce: Callable[[str], None] | None = None,
                 batch_size: int | None = None, held: bool = False):
        self.out, self.client, self.scheduler, self.n_workers = out, client, scheduler, n_workers
        self.held = held  # an undecided member that ends on the rising branch is evaluated 'held' (_held)
        self.batch_size = batch_size  # runs per task, advanced together (run_sweep's batch_size)
        self.announce = announce  # called with the dashboard's address when a cluster is started
        self.backend, self.progress = str(backend), progress
        self._stack = ExitStack()

    def __enter__(self) -> "Rounds":
        from ..sweeps.store import driver_lock

        if self.out is None:
            self.out = self._stack.enter_context(tempfile.TemporaryDirectory(prefix="slipchain-mu-max-"))
        self.out = Path(self.out)
        (self.out / ROUNDS).mkdir(parents=True, exist_ok=True)
        self._stack.enter_context(driver_lock(self.out, "mu-max output"))
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stack.close()

    def _client(self) -> Any:
        """The Dask client: the given one, else one started now and kept for the later rounds."""
        if self.client is None:
            from ..sweeps.executor import GPU_THREADS, dask_client

            gpu = self.backend == BackendName.GPU
            self.client = self._stack.enter_context(
                dask_client(self.scheduler, self.n_workers or (1 if gpu else None), GPU_THREADS if gpu else 1,
                            self.announce))
        return self.client

    def evaluate(self, jobs: list[tuple[Config, float]]) -> list[Evaluation]:
        """One round: every (config, mu_a) evaluated, from its store if done, else run."""
        from ..engine import interrupts
        from ..sweeps.executor import run_sweep
        from ..sweeps.store import Store

        interrupts.check()  # a Ctrl-C or SIGTERM between rounds whose KeyboardInterrupt was lost
        configs = [c.with_updates(dead_weight=float(m)) for c, m in jobs]
        ids = [member_id(c) for c in configs]
        found = {i: e for i, c in zip(ids, configs) if (e := self._legacy(i, c.dead_weight)) is not None}
        todo = list({i: c for i, c in zip(ids, configs) if i not in found}.values())
        if todo:
            sweep = round_sweep(todo)
            st = Store.open(self.out / ROUNDS / sweep.digest, sweep)
            self._reuse(st)
            report = run_sweep(sweep, st, client=self._client() if st.pending() else None, scheduler=self.scheduler,
                               n_workers=self.n_workers, progress=self.progress, backend=self.backend,
                               announce=self.announce, batch_size=self.batch_size)
            if report.interrupted:
                raise KeyboardInterrupt
            for m in sweep.members:
                e = _evaluation(m.config.dead_weight, st.member_attrs(m))
                found[m.id] = _held(m.config, e, lambda m=m: st.read_member(m)) if self.held else e
        return [found[i] for i in ids]

    def _legacy(self, mid: str, mu_a: float) -> Evaluation | None:
        """The evaluation that slipchain 0.2.0 cached in OUT/cache/<id>.json, if there is a whole one."""
        try:
            e = Evaluation(**json.loads((self.out / LEGACY_CACHE / f"{mid}.json").read_text()))
        except (OSError, ValueError, TypeError):  # absent, or cut by a kill: run it
            return None
        return e if e.mu_a == mu_a else None

    def _reuse(self, st: Any) -> None:
        """Copy into ``st`` the finished members that another round's store holds (atomically)."""
        for m in st.pending():
            for other in sorted((self.out / ROUNDS).glob(f"*/members/{m.id}.nc")):
                if other.parent.parent != st.path:
                    write_bytes(st.member_path(m.id), other.read_bytes())
                    break


def round_sweep(configs: list[Config], name: str = "mu-max-round") -> SweepDefinition:
    """The sweep whose members are exactly ``configs``: the first is the base, and each config is
    one single-valued grid over the keys in which any of them differs from it (always theta, seed
    and dead_weight), so its member ids are the configs' own ids."""
    dumps = [c.model_dump() for c in configs]
    first = dumps[0]
    keys = ["theta", "seed", "dead_weight"]
    keys += sorted({k for d in dumps for k in d if d[k] != first[k] and k not in keys})
    sweep = make_sweep({"name": name, "base": {k: v for k, v in first.items() if v is not None},
                        "grid": [{k: [d[k]] for k in keys} for d in dumps]})
    assert [m.id for m in sweep.members] == [member_id(c) for c in configs]
    return sweep


NOT_RUN = "not run"  # the message of an evaluation whose member the store does not hold yet


def outcome(ev: "pd.DataFrame") -> "pd.Series":
    """Each evaluation row's status, NOT_RUN for a member the store does not hold yet (its status is
    'error'); a table without a ``message`` column: the status as it is."""
    if "message" not in ev.columns:
        return ev["velocity_status"]
    return ev["velocity_status"].where(ev["message"] != NOT_RUN, NOT_RUN)


def _evaluation(mu_a: float, attrs: Mapping[str, Any] | None) -> Evaluation:
    """An evaluation from a run's attributes (the Dataset of :func:`run`, or a stored member's)."""
    a = attrs or {"status": "error", "message": NOT_RUN}
    status = str(a.get("status", Status.ERROR))
    if status != Status.COMPLETED:  # failed or interrupted: its own status stops the bisection
        return Evaluation(float(mu_a), status, float("nan"), str(a.get("message", "")))
    vstatus = str(a.get("velocity_status", VelocityStatus.NO_STEADY))
    message = str(a.get("message", ""))
    if vstatus == VelocityStatus.NO_STEADY and a.get("velocity_reason"):  # say why it is undecided
        message = "; ".join(m for m in (message, str(a["velocity_reason"])) if m)
    return Evaluation(float(mu_a), vstatus, float(a.get("velocity", np.nan)), message)


def _held(cfg: Config, e: Evaluation, dataset: Callable[[], Any]) -> Evaluation:
    """``e`` evaluated ``held`` where it is an undecided (``no-steady``) run that
    :func:`slipchain.analysis.traces.run_outcome` calls held (module docstring; ``dataset`` gives the run's
    record, read only then), with its end velocity; otherwise ``e`` as it is."""
    if e.velocity_status != VelocityStatus.NO_STEADY or e.message == NOT_RUN:
        return e
    from ..analysis.traces import HELD_WINDOW, ONSET_FACTOR, run_outcome

    ds = dataset()
    outcome, v_end = run_outcome(cfg, str(e.velocity_status), ds["time"].values, ds["X_mean"].values)
    if outcome != HELD:
        return e
    why = (f"held: {v_end:.3g} m/s over the last {HELD_WINDOW:g} s, below {ONSET_FACTOR:g} v0 10**delta "
           "(not pulled away within the run)")
    return Evaluation(e.mu_a, HELD, v_end, "; ".join(m for m in (e.message, why) if m))


LOWER = (str(VelocityStatus.OK), HELD)  # the statuses that move a bracket's lo up


def _bisect(configs: list[Config], lo: float, hi: float, tol: float,
            evaluate_all: Callable[[list[tuple[Config, float]]], list[Evaluation]], strict: bool = True) -> list[MuMax]:
    """Bisection of every config in lock-step: ``evaluate_all`` gets one round's (config, mu_a) pairs.
    ``strict``: a realisation whose lo/hi runs refute the bracket raises BracketError; else it gets
    status ``bracket`` (its reason in ``message``) and the others go on."""
    if not (tol > 0 and 0 < lo < hi):
        raise ConfigError(f"mu_max needs 0 < lo < hi and tol > 0; got lo = {lo}, hi = {hi}, tol = {tol}")
    n = len(configs)
    ends = evaluate_all([(c, lo) for c in configs] + [(c, hi) for c in configs])
    evals = [[ends[i], ends[n + i]] for i in range(n)]
    refuted: dict[int, str] = {}  # realisations whose runs at lo or hi did not bracket mu_max, and why
    for i in range(n):
        e_lo, e_hi = evals[i]
        if e_lo.velocity_status not in LOWER:
            refuted[i] = (f"mu_max: lo = {lo} must give steady sliding; the run gave {e_lo.velocity_status} "
                          f"({e_lo.message or 'no message'}) for seed {configs[i].seed}, theta {configs[i].theta}; "
                          "expected a smaller lo or a longer run (t_total, or t_max with t_decide)")
        elif e_hi.velocity_status != VelocityStatus.RUNAWAY:
            refuted[i] = (f"mu_max: hi = {hi} must run away; the run gave {e_hi.velocity_status} for seed "
                          f"{configs[i].seed}, theta {configs[i].theta}; expected a larger hi")
    if refuted and strict:
        raise BracketError(refuted[min(refuted)])
    brackets = [[lo, hi, evals[i][0].velocity] for i in range(n)]
    stopped = dict(refuted)  # realisations whose bisection ended undecided (refuted, or a no-steady run), and why
    while True:
        open_ = [i for i in range(n) if i not in stopped and brackets[i][1] - brackets[i][0] > 2 * tol]
        if not open_:
            break
        mids = [0.5 * (brackets[i][0] + brackets[i][1]) for i in open_]
        for i, mid, e in zip(open_, mids, evaluate_all([(configs[i], m) for i, m in zip(open_, mids)])):
            evals[i].append(e)
            if e.velocity_status in LOWER:
                brackets[i][0], brackets[i][2] = mid, e.velocity
            elif e.velocity_status == VelocityStatus.RUNAWAY:
                brackets[i][1] = mid
            else:
                stopped[i] = (f"undecided at mu_a = {mid:.6g} ({e.velocity_status}: {e.message or 'no message'}); "
                              f"bracket {brackets[i][0]:.6g}-{brackets[i][1]:.6g}")
    return [MuMax(BRACKET if i in refuted else str(VelocityStatus.NO_STEADY if i in stopped else VelocityStatus.OK),
                  float("nan") if i in stopped else 0.5 * (brackets[i][0] + brackets[i][1]),
                  float("nan") if i in refuted else brackets[i][2], brackets[i][0], brackets[i][1], evals[i],
                  stopped.get(i, "")) for i in range(n)]


def mu_max_table(base: Config, thetas: list[float], seeds: list[int], *, lo: float = 0.3, hi: float = 1.5,
                 tol: float = TOL, store: str | os.PathLike | None = None, client: Any = None,
                 n_workers: int | None = None, backend: str | BackendName = BackendName.CPU) -> "pd.DataFrame":
    """mu_max and v_max for every (theta, seed) from ``base`` (:func:`mu_max_many`), one row each."""
    configs = [base.with_updates(theta=float(t), seed=int(s)) for t in thetas for s in seeds]
    results = mu_max_many(configs, lo=lo, hi=hi, tol=tol, store=store, client=client, n_workers=n_workers,
                          backend=backend)
    return _table(configs, results)


def _table(configs: list[Config], results: list[MuMax]) -> "pd.DataFrame":
    import pandas as pd

    return pd.DataFrame([{"theta": c.theta, "seed": c.seed, "status": r.status, "mu_max": r.mu_max, "lo": r.lo,
                          "hi": r.hi, "v_max_m_s": r.v_max, "runs": len(r.evaluations), "message": r.message}
                         for c, r in zip(configs, results)])


def mu_max_summary(table: "pd.DataFrame") -> "pd.DataFrame":
    """Seed mean of mu_max per theta with its standard error (seed scatter; at least the bisection's
    half-width tol/sqrt(3) per seed when all seeds agree) and mu_max/mu_max(theta_min)."""
    import pandas as pd

    rows = []
    for theta, g in table[table["status"] == str(VelocityStatus.OK)].groupby("theta"):
        n = len(g)
        half = float(((g["hi"] - g["lo"]) / 2).mean())
        se = max(float(g["mu_max"].std(ddof=1)) / np.sqrt(n) if n > 1 else 0.0, half / np.sqrt(3 * n))
        rows.append({"theta": theta, "mu_max": float(g["mu_max"].mean()), "mu_max_se": se, "seeds": n,
                     "v_max_m_s": float(g["v_max_m_s"].mean())})
    out = pd.DataFrame(rows)
    return ratios_to_first(out) if len(out) else out


def evaluations_table(configs: list[Config], results: list[MuMax]) -> "pd.DataFrame":
    """Every dead-weight run of the bisections: theta, seed, applied mu_a, status, velocity (m/s)."""
    return _evaluation_rows([(c, e) for c, r in zip(configs, results) for e in r.evaluations], "bisection")


def store_evaluations(store: str | os.PathLike, columns: tuple[str, ...] = ()) -> "pd.DataFrame":
    """Every member of a sweep store over ``dead_weight`` as the rows of :func:`evaluations_table`
    (source 'sweep'): the tester's classification of each run, or its failure status (a member not
    run yet: 'error', 'not run'), with a column for each other parameter the sweep varies (e.g. the
    ramp ``t_ramp`` of presets/ladder-eps1-slow-grid.toml) and for each config key in ``columns``
    (e.g. ``t_ramp`` of a store that does not vary it, to be read beside one that does)."""
    from ..sweeps.store import Store

    unknown = [c for c in columns if c not in Config.model_fields]
    if unknown:
        raise ConfigError(f"column {unknown[0]!r} is not a config key; expected one of the config's keys (e.g. t_ramp)")
    st = Store.open(store)  # member_attrs: None for a member not run yet, never an exception
    extra = [d for d in dict.fromkeys([*st.sweep.dims, *columns]) if d not in ("theta", "seed", "dead_weight")]
    return _evaluation_rows([(m.config, _evaluation(m.config.dead_weight, st.member_attrs(m))) for m in st.sweep.members],
                            "sweep", extra)


def _evaluation_rows(pairs: list[tuple[Config, Evaluation]], source: str, extra: list[str] = ()) -> "pd.DataFrame":
    """One row per evaluation: theta, seed, the ``extra`` config keys, mu_a, the tester's status, the
    velocity, the source, and the message (for an undecided run, why: its velocity's drift)."""
    import pandas as pd

    columns = ["theta", "seed", *extra, "mu_a", "velocity_status", "velocity_m_s", "source", "message"]
    return pd.DataFrame([{"theta": c.theta, "seed": c.seed, **{k: getattr(c, k) for k in extra}, "mu_a": e.mu_a,
                          "velocity_status": e.velocity_status, "velocity_m_s": e.velocity, "source": source,
                          "message": e.message} for c, e in pairs], columns=columns)


# --- a mu-max plan: the base config and the bisection's settings in one TOML file ------------------

PLAN_KEYS = {"theta": "a list of numbers in (0, 1]", "seeds": "an integer >= 1 (seeds 0..seeds-1)",
             "lo": "a number > 0 that gives steady sliding", "hi": "a number > lo that runs away",
             "tol": "a number > 0 (resolution of mu_max)",
             "curve": "a list of numbers > 0: extra applied mu_a below lo, run at seed 0, for the mu(v) figure",
             "held": "true or false: an undecided run that ends on the rising branch counts below mu_max"}


@dataclass(frozen=True)
class Plan:
    """What ``slipchain mu-max`` runs: ``[base]`` (a config; its dead_weight is set by the
    bisection) and ``[bisection]`` (:data:`PLAN_KEYS`) of a TOML file, e.g. presets/mu-max.toml."""

    base: Config
    theta: tuple[float, ...] = (0.1, 1.0)
    seeds: int = 4
    lo: float = 0.3
    hi: float = 1.5
    tol: float = TOL
    curve: tuple[float, ...] = ()
    name: str = "mu-max"
    held: bool = False  # held runs count below the maximum (module docstring)

    def check(self) -> "Plan":
        """Every setting valid and every config of the plan valid, before anything runs (ConfigError)."""
        def bad(key: str, value: Any) -> ConfigError:
            return ConfigError(f"mu-max key '{key}' has value {value!r}; expected {PLAN_KEYS[key]}")

        if not self.theta:
            raise bad("theta", list(self.theta))
        if self.seeds < 1:
            raise bad("seeds", self.seeds)
        if not (self.tol > 0 and np.isfinite(self.tol)):
            raise bad("tol", self.tol)
        if not (0 < self.lo < self.hi and np.isfinite(self.hi)):
            raise ConfigError(f"mu-max keys 'lo' and 'hi' have values {self.lo!r} and {self.hi!r}; expected "
                              "0 < lo < hi (lo steady, hi runaway)")
        if any(not (0 < m and np.isfinite(m)) for m in self.curve):
            raise bad("curve", list(self.curve))
        if self.base.t_total is None and self.base.t_decide is None:
            raise ConfigError("config keys 't_total' and 't_decide' are both absent; expected the length of each "
                              "dead-weight run: t_total (fixed, s) or t_decide (automatic, at most t_max), "
                              "e.g. --set t_decide=0.05")
        for t in self.theta:
            self.base.with_updates(theta=float(t))  # ConfigError naming theta
        return self

    def configs(self) -> list[Config]:
        return [self.base.with_updates(theta=float(t), seed=int(s)) for t in self.theta for s in range(self.seeds)]


def load_plan(path: str | os.PathLike | None, overrides: list[str] = (), **settings: Any) -> Plan:
    """A :class:`Plan` from a TOML file (``[base]`` and ``[bisection]``; a flat file is a base config
    alone; ``extends``: :func:`~slipchain.sweeps.catalogue.read_study`), ``name=value`` overrides of the
    base, then explicit ``settings`` (None: not given)."""
    from ..model.config import parse_override
    from ..sweeps.catalogue import read_study

    data = read_study(path) if path is not None else {}
    is_plan = "base" in data or "bisection" in data
    base = dict(data.get("base", {})) if is_plan else dict(data)
    if is_plan:
        extra = sorted(set(data) - {"base", "bisection", "name"})
        if extra:
            raise ConfigError(f"mu-max plan {str(path)!r} has unknown table(s)/key(s) {extra}; expected [base], "
                              "[bisection] and name")
    bisection = dict(data.get("bisection", {}))
    unknown = sorted(set(bisection) - set(PLAN_KEYS))
    if unknown:
        raise ConfigError(f"mu-max key(s) {unknown} in [bisection] unknown; expected some of {sorted(PLAN_KEYS)}")
    for item in overrides:
        key, value = parse_override(item)
        base[key] = value
    base.setdefault("dead_weight", 1.0)  # a placeholder: the bisection sets it (t_decide needs a dead weight)
    for key, value in settings.items():
        if value is not None:
            bisection[key] = value
    bad = next((k for k in bisection if not _convertible(k, bisection[k])), None)
    if bad is not None:
        raise ConfigError(f"mu-max key '{bad}' has value {bisection[bad]!r}; expected {PLAN_KEYS[bad]}")
    kw = {k: (tuple(float(x) for x in v) if k in ("theta", "curve") else int(v) if k == "seeds"
              else bool(v) if k == "held" else float(v))
          for k, v in bisection.items()}
    return Plan(make_config(base), name=str(data.get("name", "mu-max")), **kw).check()


def _convertible(key: str, value: Any) -> bool:
    """Whether a [bisection] value has the type PLAN_KEYS says (TOML or CLI; no strings; booleans for
    ``held`` alone)."""
    def number(x: Any) -> bool:
        return isinstance(x, (int, float)) and not isinstance(x, bool)

    if key == "held":
        return isinstance(value, bool)
    if key in ("theta", "curve"):
        return isinstance(value, (list, tuple)) and all(number(x) for x in value)
    if key == "seeds":
        return number(value) and float(value).is_integer()
    return number(value)


@dataclass
class PlanResult:
    table: "pd.DataFrame"  # one row per (theta, seed): mu_max.csv
    summary: "pd.DataFrame"  # seed means: mu_max_summary.csv
    evaluations: "pd.DataFrame"  # every dead-weight run: evaluations.csv


def run_plan(plan: Plan, out: str | os.PathLike, *, client: Any = None, scheduler: str | None = None,
             n_workers: int | None = None, backend: str | BackendName = BackendName.CPU,
             progress: bool | None = None, announce: Callable[[str], None] | None = None,
             batch_size: int | None = None) -> PlanResult:
    """Run a plan: the bisections (:func:`mu_max_many`) and the ``curve`` points, every run a member
    of a round's store in OUT/rounds (:class:`Rounds`; a second call resumes), then write mu_max.csv,
    mu_max_summary.csv, evaluations.csv and plan.toml into ``out`` (each file atomically). A
    realisation whose lo/hi runs refute the bracket has status ``bracket`` (with the reason) and
    the others go on; BracketError only when every realisation's bracket is refuted (nothing to
    report). KeyboardInterrupt if interrupted (the finished runs are kept); SweepError if another
    driver runs ``out``; StoreWriteError on a full disk. ``announce``: called with the Dask
    dashboard's address when the cluster starts. ``batch_size``: runs per task, advanced together
    (one FFT per step for a batch of slab rows: far cheaper per run on small interfaces; results
    are those of single runs, as in any sweep)."""
    import pandas as pd

    out = Path(out)
    configs = plan.configs()
    with Rounds(out, client=client, scheduler=scheduler, n_workers=n_workers, backend=backend,
                progress=progress, announce=announce, batch_size=batch_size, held=plan.held) as rounds:
        results = _bisect(configs, plan.lo, plan.hi, plan.tol, rounds.evaluate, strict=False)
        curve_jobs = [(plan.base.with_updates(theta=float(t), seed=0), float(m)) for t in plan.theta for m in plan.curve]
        curve = rounds.evaluate(curve_jobs) if curve_jobs else []
    table = _table(configs, results)
    if all(r.status == BRACKET for r in results):
        raise BracketError(results[0].message)
    evals = pd.concat([evaluations_table(configs, results),
                       _evaluation_rows([(cfg, e) for (cfg, _), e in zip(curve_jobs, curve)], "curve")],
                      ignore_index=True)
    result = PlanResult(table, mu_max_summary(table), evals)
    write_csv(result.table, out / "mu_max.csv")
    write_csv(result.summary, out / "mu_max_summary.csv")
    write_csv(result.evaluations, out / "evaluations.csv")
    write_text_atomic(out / "plan.toml", plan_toml(plan))
    return result


def plan_toml(plan: Plan) -> str:
    """The plan as the TOML file :func:`load_plan` reads (the base config in full)."""
    lists = lambda xs: "[" + ", ".join(repr(float(x)) for x in xs) + "]"  # noqa: E731
    base = plan.base.to_toml()
    return (f'name = "{plan.name}"\n\n[base]\n{base}\n[bisection]\ntheta = {lists(plan.theta)}\nseeds = {plan.seeds}\n'
            f"lo = {plan.lo!r}\nhi = {plan.hi!r}\ntol = {plan.tol!r}\ncurve = {lists(plan.curve)}\n"
            + ("held = true\n" if plan.held else ""))  # absent when off: the plan.toml of every result before it


def single_contact_maximum(config: Config, points: int = 400_001) -> tuple[float, float]:
    """The first maximum of eq. (1) for one contact with v* = v0, in units of epsilon*f0, and the
    velocity where it lies: the analytic mu_max of identical contacts (delta = 0, theta = 1),
    where every block slides steadily at the u that solves f(u, v0) = mu_a*epsilon*f0."""
    u = config.v0 * np.logspace(-3, 3, points)
    f = config.contact_law.force(u, config.v0) / (config.epsilon * config.f0)
    i = int(np.argmax(np.diff(f) < 0))  # the first point after which f falls
    return float(f[i]), float(u[i])


__all__ = ["BRACKET", "HELD", "NOT_RUN", "PLAN_KEYS", "TOL", "BracketError", "Evaluation", "MuMax", "Plan", "PlanResult", "Rounds",
           "evaluate", "evaluate_many", "round_sweep",
           "evaluations_table", "load_plan", "outcome", "mu_max", "mu_max_many", "mu_max_summary", "mu_max_table", "plan_toml",
           "run_plan", "single_contact_maximum"]


# --- the figure and report of a mu-max result ------------------------------------------------------

def mu_max_figure(result: str | os.PathLike, out: str | os.PathLike,
                  spring_index: str | os.PathLike | None = None) -> list[Path]:
    """Figs. 2-3 from the model (:func:`slipchain.plots.dead_weight.plot_mu_max`) and report.md, from
    a ``slipchain mu-max`` output directory; ``spring_index`` a velocity sweep's index CSV for the
    spring-drive maximum beside it. ConfigError naming what is missing."""
    import pandas as pd

    from ..analysis.fit import g
    from ..model.config import read_toml
    from ..plots.dead_weight import plot_mu_max, spring_drive_maxima

    folder = Path(result)
    files = {n: folder / n for n in ("mu_max_summary.csv", "evaluations.csv", "plan.toml", "mu_max.csv")}
    for name, f in files.items():
        if not f.is_file():
            raise ConfigError(f"mu-max result {str(folder)!r} has no {name}; expected the --out directory of "
                              "`slipchain mu-max`")
    summary, evals, table = (pd.read_csv(files[n]) for n in ("mu_max_summary.csv", "evaluations.csv", "mu_max.csv"))
    if summary.empty:
        raise ConfigError(f"{str(files['mu_max_summary.csv'])!r} has no theta with a decided mu_max; nothing to draw")
    plan_data = read_toml(files["plan.toml"])
    base = make_config(dict(plan_data.get("base", {})))
    held = bool(plan_data.get("bisection", {}).get("held", False))
    v = np.geomspace(base.v0 * 1e-4, base.v0 * 10, 600)
    branch = (v, g(v, base.v0, base.delta, base.c))
    try:
        spring = spring_drive_maxima(spring_index) if spring_index is not None else None
    except (OSError, ValueError) as e:
        raise ConfigError(f"--spring {str(spring_index)!r}: {e}") from None
    paths = plot_mu_max(summary, evals, branch, spring, out)
    text = mu_max_report(summary, table, spring, base, folder, spring_index, held)
    paths.append(write_text_atomic(Path(out) / "report.md", text))
    return paths


def mu_max_report(summary: "pd.DataFrame", table: "pd.DataFrame", spring: "pd.DataFrame | None", base: Config,
                  folder: Path, spring_index, held: bool = False) -> str:
    """report.md: the numbers behind the figure and what they say (``held``: the plan counted held runs
    below the maximum)."""
    from ..analysis.fit import g_max
    from ..analysis.traces import HELD_WINDOW

    slider = ("elastic springs" if base.material == "elastic"
              else f"{base.material} rubber at {base.temperature:g} °C")
    if base.geometry != "chain":  # the chain's reports keep their title; a 2-D interface says which
        slider += f", {base.geometry} geometry, {base.N} x {base.Ly} interface"
    if base.epsilon != Config.model_fields["epsilon"].default:  # and a contact stiffness other than the paper's
        slider += f", epsilon = {base.epsilon:g}"
    if base.t_ramp is not None and base.t_ramp != 0.2:  # and a ramp other than the 200 ms of docs/mu-max
        slider += f", the weight raised over {base.t_ramp:g} s"
    # the title names the slider: each report of the site has its own (issue 30)
    lines = [f"# mu_max(theta) under a dead weight, {slider}: the model measured as the tester measures", "",
             f"From `{folder}` (`slipchain mu-max`; N = {base.N}, eta_c = {base.eta_c:g} 1/s, epsilon = {base.epsilon:g}, "
             f"t_decide = {base.t_decide}, t_max = {base.t_max:g} s). Every contact sliding steadily would give at most "
             f"g_max = {g_max(base.delta, base.c):.4f} (eq. 1 averaged over v*)."
             + (" Held runs (undecided at t_max but ending on the rising branch, `slipchain.analysis.traces.run_outcome`) "
                "count below the maximum (plan key `held`); where the bracket's lower end is held, v_max is its "
                f"velocity over the run's last {HELD_WINDOW:g} s, still creeping." if held else ""), "",
             "| theta | seeds decided | mu_max (± SE) | ratio to smallest theta | v_max (m/s) |", "|---|---|---|---|---|"]
    for r in summary.itertuples():
        n_all = int((table["theta"] == r.theta).sum())
        lines.append(f"| {r.theta:g} | {r.seeds}/{n_all} | {r.mu_max:.4f} ± {r.mu_max_se:.4f} | "
                     f"{r.ratio_to_theta_min:.4f} ± {r.ratio_se:.4f} | {r.v_max_m_s:.3g} |")
    undecided = table[table["status"] != "ok"]
    if len(undecided):
        lines += ["", "Not decided (left out of the means):", ""]
        lines += [f"- theta {r.theta:g}, seed {r.seed}: {r.status} (bracket {r.lo:.4g}-{r.hi:.4g})"
                  + (f": {r.message}" if isinstance(getattr(r, "message", ""), str) and r.message else "")
                  for r in undecided.itertuples()]
    lo, hi = summary.iloc[0], summary.iloc[-1]
    fall = 1 - hi["ratio_to_theta_min"]
    lines += ["", f"From theta = {lo['theta']:g} to {hi['theta']:g} the dead-weight maximum changes by "
              f"{-fall:+.1%} ± {hi['ratio_se']:.1%} (ratio {hi['ratio_to_theta_min']:.4f} ± {hi['ratio_se']:.4f})."]
    if spring is not None:
        lines += ["", f"Spring drive (`{spring_index}`: the largest seed-mean mu_star over v_d):", "",
                  "| theta | max mu_star (± SE) | at v_d (m/s) | ratio to smallest theta |", "|---|---|---|---|"]
        for r in spring.itertuples():
            lines.append(f"| {r.theta:g} | {r.mu_max:.4f} ± {r.mu_max_se:.4f} | {r.v_d:.3g} | "
                         f"{r.ratio_to_theta_min:.4f} ± {r.ratio_se:.4f} |")
    return "\n".join(lines) + "\n"


__all__ += ["mu_max_figure", "mu_max_report"]

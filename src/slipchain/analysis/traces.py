"""The slider's velocity against time, as a tester's distance record shows it (issue 29), and the
friction maximum read from where a slowly loaded slider runs away.

A dead-weight run stores the upper layer's mean position <X>(t) (the top's position on the slab,
``X_mean``) at every output sample. :func:`window_velocity` turns it into the mean velocity over
windows of a given length, exactly from the positions (no differentiation of noise): the distance
travelled across the window over its length, which is what a tester's distance record gives read at
that resolution. :func:`velocity_traces` does it for every run of dead-weight stores.

**The maximum from the runaway's onset** (:func:`runaway_onset`). While the hanging weight rises slowly
(the ramp ``t_ramp``: F(t) = mu_a t/t_ramp in units of epsilon f0 theta), the slider follows the rising
branch of mu(v); when the weight passes the branch's maximum mu_max there is no steady velocity left and
the slider accelerates away. So the weight at the moment it runs away measures mu_max, to the weight's
rise over one output sample, where a grid of weights (a bisection's bracket) resolves it only to its
step. The moment is where the velocity over one sample passes ``k v0 10**delta`` (above the largest
contact velocity scale v* of eq. (1), so above every velocity of the rising branch) for the last time:
after it the velocity stays above. With k = 3 (:data:`ONSET_FACTOR`) the estimate converges to the
analytic maximum of identical contacts as the ramp slows (tests/unit/test_traces.py: within 2e-4 at a
ramp of 40 ms); ``mu_onset_10`` (k = 10) beside it says how much the choice of k matters. The weight
keeps rising while the slider accelerates, and a faster ramp lets the slider lag behind the branch,
so the estimate depends on the ramp's rate: compare loads at one ramp, and ramps with each other, to
find the slow-loading limit.

**Held, under the tester's release** (:func:`run_outcome`, :func:`seed_brackets`). With the weight at once
the heavy top overshoots onto fast sliding and then either runs away or comes back onto the rising
branch, where it creeps ever more slowly and rings: the tester's velocity algorithm calls such a run
"no steady sliding" for seconds. A run is **held** when it did not run away (its recorded status is not
``runaway``) and its mean velocity over the last :data:`HELD_WINDOW` s of the record is below
``ONSET_FACTOR v0 10**delta`` (the rising branch's velocities, as for the onset): the weight did not pull
the block away within the run, which is what a tester reads as "below the maximum". A run that is neither
steady, runaway nor held (still sliding fast when the record ends, e.g. decelerating from the overshoot)
is ``undecided``. So every load's mu_max under a protocol lies in [the largest steady or held weight,
the smallest runaway one) per seed: a bound for runs of that length, as a tester's own runs give.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from ..results.schema import branch_scale  # v0 10**delta, the scale of every threshold here
from ..results.velocity import VelocityStatus

ONSET_FACTOR = 3.0  # the runaway's onset: the velocity passes ONSET_FACTOR v0 10**delta for the last time
ONSET_CHECK = 10.0  # ...and, for comparison, this multiple
ELASTIC_WEIGHTS = (0.1, 0.2)  # mu_a: where ramp_branch reads the interface's elastic loading rate (eq. (1) slips < 1e-7 m/s there)
HELD_WINDOW = 0.2  # s: the last stretch of a record whose mean velocity says held (about one ring of the tester's top)
BRANCH_VELOCITIES = (3e-5, 1e-4, 2e-4)  # m/s: where branch_summary reads mu(v), below every load's maximum
BRANCH_COLUMNS = ("t", "mu", "v", "v_slip")  # ramp_branch's columns (velocity_traces adds the run's identity)
STEADY, HELD, UNDECIDED = "steady", "held", "undecided"  # run_outcome's values (one spelling each) ...
RUNAWAY = str(VelocityStatus.RUNAWAY)  # ... and the tester's status for a runaway, which it keeps
OUTCOMES = (STEADY, HELD, RUNAWAY, UNDECIDED)  # the first two bound mu_max from below (BELOW)
BELOW = (STEADY, HELD)  # the outcomes that bound mu_max from below: the largest such weight is a bracket's lower end


def window_velocity(time: np.ndarray, x: np.ndarray, window: float) -> tuple[np.ndarray, np.ndarray]:
    """The mean velocity over consecutive windows of length ``window`` (s): ``(x(t_j + window) - x(t_j)) /
    window`` at the windows' midpoints, the windows starting at the first sample and stepping by
    ``window / 2`` (so they overlap by half). Positions are taken at the samples nearest to each window's
    ends (``window`` is rounded to a whole number of samples, at least one). Empty for a record shorter
    than one window."""
    time, x = np.asarray(time, float), np.asarray(x, float)
    if time.size < 2:
        return np.zeros(0), np.zeros(0)
    n = max(int(round(window / _interval(time))), 1)
    step = max(n // 2, 1)
    start = np.arange(0, time.size - n, step)
    w = time[start + n] - time[start]
    return 0.5 * (time[start] + time[start + n]), (x[start + n] - x[start]) / w


def _sample_velocity(time: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The mean velocity over each sample interval, ``diff(x) / diff(time)`` (m/s; one shorter than the
    record)."""
    return np.diff(np.asarray(x, float)) / np.diff(np.asarray(time, float))


def _interval(time: np.ndarray) -> float:
    """The record's sample interval (s): the median of its time differences; NaN for fewer than two samples."""
    return float(np.median(np.diff(np.asarray(time, float)))) if len(time) > 1 else float("nan")


def _earliest(*times: float) -> float:
    """The earliest of ``times`` that is finite; NaN if none is."""
    finite = [t for t in times if np.isfinite(t)]
    return min(finite) if finite else float("nan")


def last_crossing(time: np.ndarray, x: np.ndarray, threshold: float) -> float:
    """The end of the first sample interval after which the velocity over every sample stays above
    ``threshold`` (m/s): the last upward crossing, so early transients (a release's overshoot, the
    top's ringing) do not count. NaN if the record ends at or below it."""
    v = _sample_velocity(time, x)
    if v.size == 0 or v[-1] <= threshold:
        return float("nan")
    below = np.nonzero(v <= threshold)[0]
    j = below[-1] + 1 if below.size else 0
    return float(time[j + 1])


def first_crossing(time: np.ndarray, x: np.ndarray, threshold: float) -> float:
    """The end of the first sample interval over which the velocity exceeds ``threshold`` (m/s); NaN if
    none does."""
    up = np.nonzero(_sample_velocity(time, x) > threshold)[0]
    return float(time[up[0] + 1]) if up.size else float("nan")


def is_release(cfg, time: np.ndarray, x: np.ndarray) -> bool:
    """Whether a dead-weight run's weight came on too fast to read the rising branch or the runaway's onset
    from its ramp: the weight at once (no ramp longer than two samples), or raised so fast that the top's
    velocity from the slab's growing elastic shear alone (its median over 10-50 % of the ramp, ``x`` the
    top's record ``X_mean``) exceeds half the onset threshold ONSET_FACTOR v0 10**delta (a release over
    0.1-0.3 s: the threshold would be crossed by loading, not by sliding)."""
    from ..model.system import dead_weight_ramp_time

    ramp = dead_weight_ramp_time(cfg)
    if ramp is None or not ramp > 2 * _interval(time):
        return True
    mid = (time > 0.1 * ramp) & (time <= 0.5 * ramp)
    v = _sample_velocity(time, x)
    return bool(mid[1:].any() and np.median(v[mid[1:]]) > 0.5 * ONSET_FACTOR * branch_scale(cfg))


def runaway_onset(cfg, time: np.ndarray, x: np.ndarray, x_interface: np.ndarray | None = None) -> dict:
    """The applied weight mu_a(t) = mu_a min(t / t_ramp, 1) at the runaway's onset (module docstring)
    for one dead-weight run (its config and its ``X_mean`` record): ``mu_onset`` (ONSET_FACTOR),
    ``mu_onset_10`` (ONSET_CHECK), ``t_onset`` (s), ``during_ramp`` (the onset came while the weight still
    rose: otherwise mu_onset is the full weight, an upper bound of mu_max only) and ``resolution`` (the
    weight's rise over one sample). NaN where the run does not run away or has no ramp to read
    (:func:`is_release`). With the interface's record ``x_interface`` (``x_mean``) also ``mu_slip`` and
    ``t_slip``: where the interface first slips faster than ONSET_FACTOR v0 10**delta (from rest under a
    ramp there is no overshoot to skip): the end of the creep on the rising branch, a few samples before
    the top's reading (the heavy top answers the interface's first slip by ringing; under the heaviest
    loads the interface re-sticks and slips again before it slides on, so its *last* crossing would come
    late)."""
    from ..model.system import dead_weight_ramp_time

    ramp = dead_weight_ramp_time(cfg)
    interval = _interval(time)
    nan = float("nan")
    out = {"mu_onset": nan, "mu_onset_10": nan, "t_onset": nan, "during_ramp": False, "resolution": nan,
           "mu_slip": nan, "t_slip": nan}
    if is_release(cfg, time, x):  # no ramp to read, or the top's elastic loading alone near the threshold
        return out
    scale = branch_scale(cfg)
    t_on, t_10 = (last_crossing(time, x, k * scale) for k in (ONSET_FACTOR, ONSET_CHECK))
    t_slip = first_crossing(time, x_interface, ONSET_FACTOR * scale) if x_interface is not None else nan

    def weight(t: float) -> float:
        return cfg.dead_weight * min(t / ramp, 1.0) if np.isfinite(t) else nan

    return {"mu_onset": weight(t_on), "mu_onset_10": weight(t_10),
            "t_onset": t_on, "during_ramp": bool(np.isfinite(t_on) and t_on <= ramp),
            "resolution": cfg.dead_weight * interval / ramp,
            "mu_slip": weight(t_slip) if np.isfinite(t_slip) and t_slip <= ramp else nan, "t_slip": t_slip}


def run_outcome(cfg, status: str, time: np.ndarray, x: np.ndarray) -> tuple[str, float]:
    """What one dead-weight run says about mu_max (module docstring): ``"steady"`` (the tester's status
    ``ok``), ``"runaway"``, ``"held"`` (neither, and its mean velocity over the last :data:`HELD_WINDOW` s,
    or the whole record if shorter, below ``ONSET_FACTOR v0 10**delta``) or ``"undecided"``; and that
    end velocity (m/s)."""
    time, x = np.asarray(time, float), np.asarray(x, float)
    if time.size < 2:
        return (STEADY if status == VelocityStatus.OK else RUNAWAY if status == RUNAWAY else UNDECIDED), float("nan")
    n = max(int(round(HELD_WINDOW / _interval(time))), 1)  # the window in whole samples
    j = max(time.size - 1 - n, 0)
    v_end = float((x[-1] - x[j]) / (time[-1] - time[j]))
    if status == VelocityStatus.OK:
        return STEADY, v_end
    if status == RUNAWAY:
        return RUNAWAY, v_end
    return (HELD if v_end < ONSET_FACTOR * branch_scale(cfg) else UNDECIDED), v_end


def seed_brackets(runs: pd.DataFrame, by: list[str] | tuple[str, ...] = (), status: str = "outcome",
                  lower: tuple[str, ...] = BELOW, upper: tuple[str, ...] = (RUNAWAY,)) -> pd.DataFrame:
    """The bracket on mu_max that each seed's runs give, per group ``by`` (e.g. interface, temperature,
    ramp, load): ``lo`` the largest weight ``mu_a`` whose ``status`` is in ``lower`` (0 if none), ``hi``
    the smallest in ``upper`` (inf if none), ``runs`` how many runs, and ``consistent`` (lo < hi: a held
    or steady weight above a runaway one refutes the bracket)."""
    keys = [*by, "seed"] if "seed" in runs.columns else list(by)
    rows = []
    for key, g in (runs.groupby(keys, dropna=False) if keys else [((), runs)]):
        key = key if isinstance(key, tuple) else (key,)
        lo = g[g[status].isin(lower)]["mu_a"]
        hi = g[g[status].isin(upper)]["mu_a"]
        lo, hi = (float(lo.max()) if len(lo) else 0.0), (float(hi.min()) if len(hi) else np.inf)
        rows.append({**dict(zip(keys, key)), "lo": lo, "hi": hi, "runs": len(g), "consistent": lo < hi})
    return pd.DataFrame(rows, columns=[*keys, "lo", "hi", "runs", "consistent"])


# What distinguishes a protocol's group in the brackets: the run's length of decision (config t_decide) among them,
# since a release read at 0.8 s and one read at 2 s are two protocols whose answers may differ (a top hovering just
# beyond the branch at 0.8 s came back by 2 s: docs/tester-3d, "The rule's margin"), not one bracket refuted
BRACKET_KEYS = ("N", "temperature", "eta_c", "t_ramp", "t_decide", "theta")
KEYS = ("N", "temperature", "eta_c", "rate", "theta")  # what distinguishes a group of runs in onset_summary


def loading_rate(cfg) -> float:
    """The weight's rise per second during the ramp, mu_a / t_ramp, to 4 significant digits (so that
    1.05 over 6 s and 1.015 over 5.8 s are one rate: the onset depends on the rate, not on where the
    ramp ends); NaN without a ramp."""
    from ..model.system import dead_weight_ramp_time

    ramp = dead_weight_ramp_time(cfg)
    return float(f"{cfg.dead_weight / ramp:.4g}") if ramp and cfg.dead_weight else float("nan")


def _runs(stores: list[str | os.PathLike], checkpoints: bool = False):
    """(store name, member id, config, dataset) of every completed run of the stores, and with ``checkpoints``
    of every run not stored yet whose checkpointed record the stop rules decide (:func:`_decided_checkpoints`);
    SweepError for a store that is not one, holds no such run, or a run without a dead weight."""
    from ..model.config import config_from_toml
    from ..sweeps.definition import SweepError
    from ..sweeps.store import Store

    for store in stores:
        st = Store.open(store)
        done = st.completed_ids()
        decided = list(_decided_checkpoints(st, done)) if checkpoints else []
        if not done and not decided:
            raise SweepError(f"store {os.fspath(store)!r} holds no completed run"
                             + (" nor a checkpointed one that the stop rules decide" if checkpoints else "")
                             + "; expected a dead-weight sweep's store")
        for m in st.sweep.members:
            if m.id not in done:
                continue
            ds = st.read_member(m)
            cfg = config_from_toml(ds.attrs["config"])
            if cfg.dead_weight is None or "X_mean" not in ds:
                raise SweepError(f"store {os.fspath(store)!r}: member {m.id} is not a dead-weight run (dead_weight = "
                                 f"{cfg.dead_weight!r}); expected a sweep of dead-weight runs (e.g. presets/tester-16.toml)")
            yield Path(store).name, m.id, cfg, ds
        for mid, cfg, ds in decided:
            yield Path(store).name, mid, cfg, ds


def _decided_checkpoints(st, done: set[str]):
    """(member id, config, dataset) of each run of store ``st`` not in ``done`` whose checkpoint holds a record
    that the stop rules (``stop_at_runaway`` and ``stop_when_held`` on, the run's own ``t_decide``) decide, as
    ``slipchain status`` reads it (:func:`slipchain.sweeps.status.checkpointed`,
    :func:`slipchain.engine.control.rules_decision`): the record up to that decision, which is the record of the
    same run made with the rules on (they do not change the dynamics before they stop it), with the status they
    give it (attribute ``velocity_status``) and ``source = "checkpoint"``. A released slab only (the runs the
    rules are for); an unreadable checkpoint is left out, as status reports it."""
    from ..engine.control import rules_decision
    from ..results.velocity import VelocityStatus
    from ..sweeps.status import checkpointed

    flying, _, _ = checkpointed(st)
    for m in st.sweep.members:
        if m.id in done or m.id not in flying:
            continue
        row, _ = flying[m.id]
        decision = rules_decision(m.config, row.X_mean)
        if decision is None or decision.verdict is None:  # not the released slab, or not decided on the record so far
            continue
        n, (status, reason, fit) = decision.n, decision.verdict
        ok = status == VelocityStatus.OK  # the tester's velocity and SE where it slid steadily (results.schema.dead_weight_attrs)
        ds = xr.Dataset({"X_mean": ("time", row.X_mean[:n]), "x_mean": ("time", row.x_mean[:n])},
                        coords={"time": decision.time[:n]},
                        attrs={"velocity_status": status, "velocity_reason": reason, "source": "checkpoint",
                               "velocity": fit.velocity if ok else np.nan, "velocity_sem": fit.sem if ok else np.nan})
        yield m.id, m.config, ds


def velocity_traces(stores: list[str | os.PathLike], window: float,
                    checkpoints: bool = False) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Every completed run of dead-weight sweep stores (with ``checkpoints`` also every run not stored yet that the
    stop rules decide on its checkpointed record, :func:`_decided_checkpoints`): its windowed velocities (:func:`window_velocity`;
    columns store, member_id, N, temperature, eta_c, theta, seed, mu_a, t_ramp, rate (:func:`loading_rate`),
    t_decide, status (the tester's classification the run recorded), source ("member", or "checkpoint"), t (s),
    v (m/s)) and, one row per run
    with the same identifying columns, its outcome and end velocity (:func:`run_outcome`: ``outcome``,
    ``v_end``), the tester's steady velocity and its SE where it slid steadily, and its runaway onset
    (:func:`runaway_onset`); and the rising branch its ramp traced (:func:`ramp_branch`: t, mu, v, with the
    identifying columns). SweepError naming the store for one that is not a store,
    holds no completed run, or holds runs without a dead weight; ValueError for a window that is not a
    positive number of seconds."""
    if not (isinstance(window, (int, float)) and np.isfinite(window) and window > 0):
        raise ValueError(f"window has value {window!r}; expected a positive number of seconds (e.g. 0.02)")
    traces, onsets, branches = [], [], []
    for store, mid, cfg, ds in _runs(stores, checkpoints):
        who = {"store": store, "member_id": mid, "N": cfg.N, "temperature": cfg.temperature, "eta_c": cfg.eta_c, "theta": cfg.theta,
               "seed": cfg.seed, "mu_a": cfg.dead_weight, "t_ramp": cfg.t_ramp, "rate": loading_rate(cfg),
               "t_decide": cfg.t_decide, "status": ds.attrs.get("velocity_status", ""),
               "source": ds.attrs.get("source", "member")}
        time, x = ds["time"].values, ds["X_mean"].values
        t, v = window_velocity(time, x, window)
        traces.append(pd.DataFrame({**who, "t": t, "v": v}))
        outcome, v_end = run_outcome(cfg, who["status"], time, x)
        xi = ds["x_mean"].values
        onset = runaway_onset(cfg, time, x, xi)
        onsets.append({**who, "outcome": outcome, "v_end": v_end, "velocity": float(ds.attrs.get("velocity", np.nan)),
                       "velocity_sem": float(ds.attrs.get("velocity_sem", np.nan)), **onset})
        if not is_release(cfg, time, x):  # a release's ramp traces the top's loading, not the branch
            branches.append(ramp_branch(cfg, time, xi, window, _earliest(onset["t_onset"], onset["t_slip"])).assign(**who))
    branch = (pd.concat(branches, ignore_index=True) if branches
              else pd.DataFrame(columns=[*who, *BRANCH_COLUMNS]))  # every run a release
    return pd.concat(traces, ignore_index=True), pd.DataFrame(onsets), branch


SIDES = {STEADY: "below", HELD: "below", RUNAWAY: "above", UNDECIDED: "undecided"}  # a run's side of mu_max


def redecide(stores: list[str | os.PathLike], t_decides: list[float] | tuple[float, ...],
             stop_at_runaway: bool = False, stop_when_held: bool = False) -> tuple[pd.DataFrame, dict[float, int]]:
    """Every completed run of dead-weight stores that had the automatic length (config ``t_decide``),
    replayed as if its ``t_decide`` had been each of ``t_decides`` (the stores read once): its stored record <X>(t) fed in the run's compiled
    chunks (:func:`~slipchain.engine.control.chunk_samples`, a sample at a time while the weight rises) to the
    automatic length the run used
    (:class:`slipchain.engine.control.UntilDecided`), up to where that would have stopped it, and classified
    there as a run classifies its record (:func:`~slipchain.results.schema.dead_weight_status`,
    :func:`run_outcome`). The physics is the stored run's: its force ramp is kept (``t_ramp`` set to the
    ramp it had), so only where the run stops and what it is called can change. A replay still undecided at
    the record's end is the record's own classification there. Returns one row per run (the identifying
    columns of :func:`velocity_traces`; the stored ``status``, ``outcome`` and record length ``t_end``; the
    replay's ``t_stop``, ``status_replay``, ``outcome_replay``; ``agree``: both on the same side of mu_max,
    :data:`SIDES`; ``t_decide_replay``), and per replayed t_decide how many runs were skipped because their ramp
    does not end before it (a slowly loaded run: nothing to replay). Where every run of a protocol agrees, its sweeps with
    ``t_decide`` would have bracketed mu_max alike and stopped the runaways earlier. ``stop_at_runaway``,
    ``stop_when_held``: replay with that config on (a released run on the slab read over its top's ringing
    periods, :func:`~slipchain.results.schema.certain_runaway`, :func:`~slipchain.results.schema.certain_held`),
    where the runs may not have had it; columns of those names say which.
    ValueError for a ``t_decide`` that is not a positive number of seconds."""
    from ..model.system import dead_weight_ramp_time

    for t_decide in t_decides:
        if not (isinstance(t_decide, (int, float)) and np.isfinite(t_decide) and t_decide > 0):
            raise ValueError(f"t_decide has value {t_decide!r}; expected a positive number of seconds (e.g. 0.8)")
    rows, skipped = [], {float(t): 0 for t in t_decides}
    for store, mid, cfg, ds in _runs(stores):
        if cfg.t_decide is None:
            continue
        ramp = dead_weight_ramp_time(cfg)
        time, x = ds["time"].values, ds["X_mean"].values
        status = ds.attrs.get("velocity_status", "")
        out, _ = run_outcome(cfg, status, time, x)
        for t_decide in t_decides:
            if not ramp < t_decide:
                skipped[float(t_decide)] += 1
                continue
            row = _replay(cfg, time, x, float(t_decide), ramp, stop_at_runaway or cfg.stop_at_runaway,
                          stop_when_held or cfg.stop_when_held)
            rows.append({"store": store, "member_id": mid, **row, "status": status, "outcome": out, "t_end": float(time[-1]),
                         "agree": SIDES[out] == SIDES[row["outcome_replay"]]})
    return pd.DataFrame(rows), skipped


def _replay(cfg, time: np.ndarray, x: np.ndarray, t_decide: float, ramp: float, stop: bool = False,
            held: bool = False) -> dict:
    """:func:`redecide` for one stored record at one ``t_decide`` (``stop``, ``held``: configs ``stop_at_runaway``,
    ``stop_when_held``): the identifying columns and the replay's
    (:func:`~slipchain.engine.control.replay_decision`)."""
    from ..engine.control import replay_decision
    from ..results.schema import dead_weight_status

    c = cfg.model_copy(update={"t_decide": t_decide, "t_ramp": ramp, "stop_at_runaway": stop, "stop_when_held": held})
    n = replay_decision(c, x)
    status_r, _, _ = dead_weight_status(c, time[:n], x[:n])
    out_r, _ = run_outcome(c, status_r, time[:n], x[:n])
    return {"N": cfg.N, "temperature": cfg.temperature, "eta_c": cfg.eta_c, "theta": cfg.theta, "seed": cfg.seed,
            "mu_a": cfg.dead_weight, "t_ramp": ramp, "t_decide": cfg.t_decide, "t_decide_replay": t_decide,
            "stop_at_runaway": stop, "stop_when_held": held, "t_stop": float(time[n - 1]), "status_replay": status_r, "outcome_replay": out_r}


def onset_summary(onsets: pd.DataFrame) -> pd.DataFrame:
    """mu_max per group of runs (:data:`KEYS`: interface, temperature, contact damping, loading rate, load) from the onsets
    read during the ramp: the mean over runs (seeds; a seed with several weights counts once, its mean), its
    standard error (the seeds' scatter; NaN for one), the mean read at the check threshold
    (``mu_max_10``) and from the interface's first slip (``mu_max_slip``), and R = the group's mean over the
    smallest load's at the same interface, temperature, damping and rate, with its standard error (independent errors),
    ``R_10`` the same at the check threshold and ``R_slip`` from the interface's first slip (how much R depends
    on where and how the onset is read)."""
    ok = onsets[onsets["during_ramp"].astype(bool)]
    if "mu_slip" not in ok.columns:
        ok = ok.assign(mu_slip=np.nan)
    per_seed = ok.groupby([*KEYS, "seed"], dropna=False).agg(mu=("mu_onset", "mean"), mu_10=("mu_onset_10", "mean"),
                                                            mu_slip=("mu_slip", "mean"),
                                                            resolution=("resolution", "max")).reset_index()
    rows = []
    for key, g in per_seed.groupby(list(KEYS), dropna=False):
        n = len(g)
        rows.append({**dict(zip(KEYS, key)), "runs": n, "mu_max": g["mu"].mean(),
                     "mu_max_se": g["mu"].std(ddof=1) / np.sqrt(n) if n > 1 else np.nan,
                     "mu_max_10": g["mu_10"].mean(), "mu_max_slip": g["mu_slip"].mean(), "resolution": g["resolution"].max()})
    table = pd.DataFrame(rows, columns=[*KEYS, "runs", "mu_max", "mu_max_se", "mu_max_10", "mu_max_slip", "resolution"])
    # R compares the loads of one group: every key but theta (elastic runs: temperature NaN, hence dropna=False)
    groups = [k for k in KEYS if k != "theta"]
    ratio, ratio_se = _to_smallest_load(table, "mu_max", "mu_max_se", groups)
    return table.assign(R=ratio, R_se=ratio_se, R_10=_to_smallest_load(table, "mu_max_10", None, groups)[0],
                        R_slip=_to_smallest_load(table, "mu_max_slip", None, groups)[0])


def _to_smallest_load(table: pd.DataFrame, value: str, se: str | None, groups: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Each row's ``value`` over the smallest theta's in its group (the rows equal in ``groups``), and with
    a standard-error column ``se`` the ratio's error (:func:`slipchain.analysis.statistics.ratio`: independent
    errors; 0 at the smallest load itself); NaN errors without one."""
    from .statistics import ratio

    r = pd.Series(np.nan, index=table.index)
    r_se = r.copy()
    for _, same in table.groupby(groups, dropna=False):
        low = same.loc[same["theta"].idxmin()]
        if se is None:
            r[same.index] = same[value] / low[value]
            continue
        q, e = ratio(same[value], same[se], low[value], low[se])
        r[same.index], r_se[same.index] = q, e
        r_se[low.name] = 0.0
    return r.to_numpy(), r_se.to_numpy()


def ramp_branch(cfg, time: np.ndarray, x: np.ndarray, window: float, t_end: float) -> pd.DataFrame:
    """mu(v) on the rising branch read from a slowly loaded run (Figs. 2-3's axes from one run): at each
    window (:func:`window_velocity`) that ends by ``t_end`` (the runaway's onset, or the ramp's end if it
    does not run away) and within the ramp, the window's mean applied weight (the ramp is linear: mu_a
    t/t_ramp half a sample after the window's midpoint, the engine holding each sample's weight at its
    value at the sample's end), against the window's mean velocity of ``x``, the
    **interface's** mean position ``x_mean``: the slip. (Not the top's: while the weight rises the top also
    moves by the slider's growing elastic shear, H tau/G on the slab, at a rate that at theta = 1 on the
    tester's 0.5-cm block, mu_a rising at 0.175 per second, is about 1.7e-3 m/s, ten times the creep; in
    steady sliding the two move together.) Where the weight rises slowly against the block's response the
    block follows its steady branch, so each point is a steady run's (mu, v) read without waiting for it;
    the check is :func:`branch_check`. Empty without a ramp longer than two windows, and where the weight
    rose so fast that the interface's elastic loading rate (below) exceeds the slowest velocity
    branch_summary reads, BRANCH_VELOCITIES[0] (3e-5 m/s; the tester's 6-s ramps load at about 1e-5 m/s,
    theta = 0.05's 0.3-s release at about 2e-4).

    ``v_slip``: the velocity less the interface's elastic loading rate. Where only a fraction theta of the
    interface's sites carries a contact, the free sites move with the slab's growing shear, so the mean
    interface position advances even where nothing slips, at a rate proportional to the weight's (about
    1e-5 m/s at theta 0.05-0.5 on the tester's block at 0.175 per second; none at theta = 1, every site a
    contact). It is taken as the median window velocity while the weight is between
    :data:`ELASTIC_WEIGHTS` (where eq. (1) has the contacts creep at 1e-9 to 1e-7 m/s) and subtracted."""
    from ..model.system import dead_weight_ramp_time

    ramp = dead_weight_ramp_time(cfg)
    if ramp is None or not ramp > 2 * window:
        return pd.DataFrame(columns=list(BRANCH_COLUMNS), dtype=float)
    t, v = window_velocity(time, x, window)
    dt = _interval(time)
    half = 0.5 * max(int(round(window / dt)), 1) * dt  # the window's half length, as window_velocity rounds it
    end = min(t_end, ramp) if np.isfinite(t_end) else ramp
    keep = t + half <= end + 0.5 * dt
    # the engine raises the weight a sample at a time, holding over each sample its value at the sample's end
    # (control.DeadWeightRamp): over a window the mean weight is the one half a sample after its midpoint
    mu = cfg.dead_weight * (t + 0.5 * dt) / ramp
    low = (mu >= ELASTIC_WEIGHTS[0]) & (mu <= ELASTIC_WEIGHTS[1]) & (t + half <= ramp)
    v_el = float(np.median(v[low])) if low.any() else 0.0
    if abs(v_el) > BRANCH_VELOCITIES[0]:  # loaded so fast that the slip would be a difference of like numbers
        return pd.DataFrame(columns=list(BRANCH_COLUMNS), dtype=float)
    return pd.DataFrame({"t": t[keep], "mu": mu[keep], "v": v[keep], "v_slip": v[keep] - v_el})


def _last_passage(a: np.ndarray, b: np.ndarray, level: float) -> float:
    """``b`` where ``a`` passes ``level`` upwards for the last time, linear between the two samples around
    it (NaN if it never does)."""
    up = np.nonzero((a[1:] >= level) & (a[:-1] < level))[0]
    if not up.size:
        return float("nan")
    i = up[-1]
    return float(b[i] + (level - a[i]) / (a[i + 1] - a[i]) * (b[i + 1] - b[i]))


def rows_equal(column: pd.Series, value) -> np.ndarray:
    """Rows of a numeric ``column`` equal to ``value`` (np.isclose); NaN or None (an elastic run's
    temperature) equal to NaN or None."""
    col = pd.to_numeric(column, errors="coerce").to_numpy(dtype=float)
    return np.isnan(col) if value is None or pd.isna(value) else np.isclose(col, float(value))


def rows_matching(frame: pd.DataFrame, values: dict) -> np.ndarray:
    """Rows of ``frame`` equal in every column named in ``values`` to its value (:func:`rows_equal`): the rows
    of one group (e.g. interface, temperature and contact damping)."""
    return np.all([rows_equal(frame[k], v) for k, v in values.items()], axis=0)


def branch_check(branch: pd.DataFrame, steady: pd.DataFrame) -> pd.DataFrame:
    """The ramp's reading against the tester's: for every steady run (``steady``: rows with N, temperature,
    eta_c, theta, seed, mu_a, velocity, velocity_sem), the velocity at which the slowly loaded runs of the same
    interface, temperature, contact damping, load and seed (``branch``: :func:`ramp_branch` rows with those columns, a
    ``member_id`` and the ``rate``) passed that weight (their slip velocity ``v_slip``), interpolated in
    log v between their two windows around it (the last passage, so the start's transient does not
    count), and its ratio to the steady velocity. One row per (steady run, ramp run); none where no ramp run reached the weight."""
    rows = []
    keys = ["N", "temperature", "eta_c", "theta", "seed"]
    for _, s in steady.iterrows():
        same = branch[rows_matching(branch, {k: s[k] for k in keys}) & (branch["v_slip"] > 0)]
        for mid, g in same.groupby("member_id"):
            v_ramp = float(np.exp(_last_passage(g["mu"].to_numpy(), np.log(g["v_slip"].to_numpy()), s["mu_a"])))
            if np.isfinite(v_ramp):
                rows.append({**{k: s[k] for k in keys}, "mu_a": s["mu_a"], "v_steady": s["velocity"],
                             "v_steady_se": s["velocity_sem"], "ramp_member": mid, "rate": g["rate"].iloc[0],
                             "v_ramp": v_ramp, "ratio": v_ramp / s["velocity"]})
    return pd.DataFrame(rows, columns=[*keys, "mu_a", "v_steady", "v_steady_se", "ramp_member", "rate", "v_ramp", "ratio"])




def branch_summary(branch: pd.DataFrame, velocities: tuple[float, ...] = BRANCH_VELOCITIES) -> pd.DataFrame:
    """mu on the rising branch at fixed sliding velocities, Figs. 2-3's comparison at a given speed: per run
    of ``branch`` (:func:`ramp_branch`), the weight where its slip velocity ``v_slip`` passed each of
    ``velocities`` for the last time (interpolated in log v); then per interface, temperature, contact
    damping, loading rate and load (:data:`KEYS`) the mean over seeds (a seed's several runs: their mean), its standard error, and R = that mean over the
    smallest load's at the same interface, temperature, damping and rate (independent errors). One row per group and
    velocity."""
    per_run = []
    for (mid,), g in branch[branch["v_slip"] > 0].groupby(["member_id"]):
        logv, mu = np.log(g["v_slip"].to_numpy()), g["mu"].to_numpy()
        for v in velocities:
            per_run.append({**{k: g[k].iloc[0] for k in (*KEYS, "seed")}, "v": v, "mu": _last_passage(logv, mu, np.log(v))})
    runs = pd.DataFrame(per_run, columns=[*KEYS, "seed", "v", "mu"]).dropna(subset=["mu"])
    per_seed = runs.groupby([*KEYS, "v", "seed"], dropna=False)["mu"].mean().reset_index()
    table = per_seed.groupby([*KEYS, "v"], dropna=False)["mu"].agg(["mean", "std", "count"]).reset_index()
    table = table.rename(columns={"mean": "mu", "count": "seeds"})
    table["mu_se"] = np.where(table["seeds"] > 1, table["std"] / np.sqrt(table["seeds"]), np.nan)
    table = table.drop(columns="std")
    table["R"], table["R_se"] = _to_smallest_load(table, "mu", "mu_se", [k for k in KEYS if k != "theta"] + ["v"])
    return table[[*KEYS, "v", "seeds", "mu", "mu_se", "R", "R_se"]]


def protocol_brackets(onsets: pd.DataFrame) -> pd.DataFrame:
    """mu_max under each protocol from its runs' outcomes (:func:`run_outcome`): one row per interface,
    temperature, contact damping, ramp, length of decision and load (:data:`BRACKET_KEYS`) with every seed's bracket (:func:`seed_brackets`),
    their envelope [the smallest lo, the largest hi] (``lo``, ``hi``: where the seed mean of mu_max can
    lie), the seeds, the runs, and how many seeds' runs are inconsistent (a held or steady weight at or
    above a runaway one)."""
    per_seed = seed_brackets(onsets, BRACKET_KEYS)
    rows = []
    for key, g in per_seed.groupby(list(BRACKET_KEYS), dropna=False):
        rows.append({**dict(zip(BRACKET_KEYS, key)), "lo": g["lo"].min(), "hi": g["hi"].max(), "seeds": len(g),
                     "runs": int(g["runs"].sum()), "inconsistent": int((~g["consistent"]).sum()),
                     "per_seed": "; ".join(f"seed {int(r.seed)}: [{r.lo:g}, {r.hi:g})" for r in g.itertuples())})
    return pd.DataFrame(rows, columns=[*BRACKET_KEYS, "lo", "hi", "seeds", "runs", "inconsistent", "per_seed"])


__all__ = ["BELOW", "BRACKET_KEYS", "BRANCH_COLUMNS", "BRANCH_VELOCITIES", "ELASTIC_WEIGHTS", "HELD", "HELD_WINDOW", "KEYS",
           "ONSET_CHECK", "ONSET_FACTOR", "OUTCOMES", "RUNAWAY", "STEADY", "UNDECIDED", "branch_check", "branch_scale",
           "branch_summary", "first_crossing", "is_release", "last_crossing", "loading_rate", "onset_summary",
           "protocol_brackets", "ramp_branch", "rows_equal", "rows_matching", "run_outcome", "runaway_onset", "seed_brackets", "velocity_traces",
           "window_velocity"]

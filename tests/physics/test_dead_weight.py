"""Dead-weight drive: a constant force on the upper layer instead of the springs at v_d."""

import numpy as np
import pytest
from scipy.optimize import brentq

from slipchain import make_config, run
from slipchain.sweeps.definition import member_id


def _single_contact(dw, **kw):
    """N = 3, one contact (theta = 1/3), v* = v0 exactly (delta = 0): the total force N*F_b = dw*epsilon*f0."""
    return make_config(N=3, theta=1 / 3, delta=0.0, dead_weight=dw, t_total=4e-3, **kw)


@pytest.mark.parametrize("dw", [0.5, 0.9, 0.99])
def test_single_contact_reaches_the_analytic_steady_velocity(dw):
    cfg = _single_contact(dw)
    ds = run(cfg)
    a = ds.attrs
    assert a["status"] == "completed" and a["velocity_status"] == "ok", a["velocity_reason"]
    law, amp = cfg.contact_law, cfg.epsilon * cfg.f0
    # steady state: every block at v, so the one contact carries the whole load, f(v, v0) = dw*epsilon*f0
    v_exact = 10 ** brentq(lambda lv: law.force(np.array([10**lv]), cfg.v0)[0] / amp - dw, -12, np.log10(cfg.v0))
    assert abs(a["velocity"] - v_exact) <= 3 * a["velocity_sem"], (a["velocity"], v_exact, a["velocity_sem"])
    assert abs(a["velocity"] / v_exact - 1) < 0.05
    assert a["mu_star"] == dw and a["check_energy_balance_passed"] == 1


@pytest.mark.parametrize("eta_c", [1e5, 0.0])
def test_above_the_maximum_the_slider_runs_away(eta_c):
    a = run(_single_contact(1.02, eta_c=eta_c)).attrs
    assert a["velocity_status"] == "runaway" and np.isnan(a["velocity"])
    assert "runaway" in a["velocity_reason"]


def test_dead_weight_is_off_by_default_and_leaves_member_ids_unchanged():
    cfg = make_config()
    assert cfg.dead_weight is None
    # the id of a spring-drive config does not see the new option (stores written before it stay valid)
    assert member_id(cfg) == member_id(make_config(dead_weight=None))
    assert member_id(cfg) != member_id(make_config(dead_weight=0.9))
    with pytest.raises(Exception, match="config key 'dead_weight' has value -1.0"):
        make_config(dead_weight=-1.0)


# The slab's rigid top with a mass of its own (issue 29: the tester's plate, what sits on it and the hanging weight)

@pytest.mark.parametrize("top_mass", [1e-6, 4e-6])
def test_a_heavy_top_under_a_step_weight_accelerates_as_newton_says(top_mass):
    """A weight a hundred times the largest friction the contacts can give, applied at once to a slab
    whose top carries top_mass per block (a thousand blocks' mass and more): the plate and the blocks move
    together at F_b / (m + upper_mass) (momentum: the body's and the dampers' forces are internal, the
    contacts' at most 1 % of F_b), so X = F_b t**2 / (2 (m + upper_mass)); measured within 1.1 % in the
    first microsecond (the blocks catch up with the plate) and 0.3 % after."""
    from slipchain.model.system import build_system, dead_weight_force

    cfg = make_config(geometry="slab", N=8, Ly=8, N_L=5, theta=0.5, epsilon=1e-2, seed=0, integrator="fold", dt=1e-8,
                      output_interval=1e-6, t_total=2e-5, t_ramp=1e-6, dead_weight=100.0, start="rest",
                      top_mass=top_mass)
    assert cfg.upper_mass == pytest.approx(cfg.N_L * cfg.m + top_mass, rel=1e-15)
    ds = run(cfg, progress=False)
    t = ds.time.values
    want = dead_weight_force(build_system(cfg)) * t**2 / (2 * (cfg.m + cfg.upper_mass))
    rel = ds.X_mean.values / want - 1
    assert abs(rel[0]) < 0.015 and np.abs(rel[4:]).max() < 0.005, rel
    assert ds.attrs["check_energy_balance_passed"] == 1


def test_the_testers_top_is_the_load_and_the_hanging_weight():
    """top_mass = 'tester': (1 + mu_a) p0 a**2 / g per block with p0 = theta p_theta1 (absent: epsilon tau_f, so
    that p0 a**2 is the model's normal force per block epsilon f0 theta); its plate mode's
    stable step is the linear analysis' (heavier: not below the bare slab's); bad combinations are named."""
    from slipchain.model.config import ConfigError

    base = dict(geometry="slab", N=8, Ly=8, N_L=50, theta=0.4, dead_weight=0.8, epsilon=1.0, t_total=1e-3)
    cfg = make_config(**base, top_mass="tester", p_theta1=5e4)
    assert cfg.p_nominal == pytest.approx(2e4)
    assert cfg.upper_mass == pytest.approx(50 * cfg.m + 1.8 * 2e4 * 1e-8 / 9.80665, rel=1e-12)
    assert cfg.dt_stable >= make_config(**base).dt_stable
    # the default: the model's own normal stress epsilon tau_f at theta = 1 (p0 a**2 = epsilon f0 theta)
    assert make_config(**base, top_mass="tester").p_nominal * 1e-8 == pytest.approx(cfg.epsilon * cfg.f0 * 0.4)
    for bad, key in ((dict(top_mass="tester", dead_weight=None), "top_mass"), (dict(p_theta1=5e4), "p_theta1"),
                     (dict(top_mass="heavy"), "top_mass"), (dict(top_mass=-1.0), "top_mass"),
                     (dict(top_mass="tester", geometry="chain2d"), "top_mass")):
        with pytest.raises(ConfigError, match=f"config key '{key}'"):
            make_config(**{**base, **bad})


def test_certain_runaway_reads_both_halves_of_the_last_stretch():
    """certain_runaway on records of exact velocities (v0 10**delta = 1e-3 m/s: the branch's bound
    RUNAWAY_FACTOR v0 10**delta = 0.01 m/s): beyond it over both halves of the last RUNAWAY_WINDOW and
    faster over the second, a runaway; decelerating, or below the bound over the first half, or a record
    shorter than half the window, not."""
    from slipchain.results.schema import RUNAWAY_WINDOW, certain_runaway

    cfg = make_config(N=11, theta=1.0, delta=0.0, dead_weight=1.0, t_ramp=0.15, t_decide=0.2, t_max=0.3,
                      stop_at_runaway=True)
    t = np.arange(1, 4001) * 1e-5  # 40 ms: the window is the last 20 ms
    last = t > t[-1] - RUNAWAY_WINDOW

    def record(v_first, v_second):
        v = np.where(t <= t[-1] - 0.5 * RUNAWAY_WINDOW, v_first, v_second)
        return np.cumsum(v * 1e-5)

    assert "0.015 -> 0.03 m/s" in certain_runaway(cfg, t, record(0.015, 0.03))
    assert certain_runaway(cfg, t, record(0.03, 0.015)) is None  # slowing down
    assert certain_runaway(cfg, t, record(0.005, 0.05)) is None  # not yet beyond the branch over the first half
    assert certain_runaway(cfg, t[-500:], record(0.015, 0.03)[-500:]) is None  # 5 ms: too short to say
    assert last.sum() == 2000


def test_stop_at_runaway_ends_the_run_soon_after_the_onset_with_the_same_record():
    """Identical contacts loaded over 0.1 s to 1.2 times eq. (1)'s maximum: with stop_at_runaway the run
    stops at the certain runaway, within RUNAWAY_WINDOW of the onset (measured 10 ms here; on the tester's
    32 x 32 block 33 ms, against the 0.13 s the decision from t_decide took; docs/tester-3d), classified
    runaway; its record is
    the full run's up to there, bit for bit, so the onset read from it is the same."""
    from slipchain.analysis.traces import runaway_onset
    from slipchain.workflows.dead_weight import single_contact_maximum

    ident = dict(N=11, theta=1.0, delta=0.0, start="rest")
    f_max, _ = single_contact_maximum(make_config(**ident, t_total=5e-3))
    cfg = dict(ident, dead_weight=1.2 * f_max, t_ramp=0.1, t_decide=0.11, t_max=0.2, output_interval=1e-5)
    full, short = run(cfg), run(dict(cfg, stop_at_runaway=True))
    assert full.attrs["velocity_status"] == short.attrs["velocity_status"] == "runaway"
    assert "stop_at_runaway" in short.attrs["velocity_reason"] and full.time.values[-1] >= 0.11 - 1e-9
    n = short.time.size
    for v in ("X_mean", "x_mean", "f_d"):
        assert np.array_equal(full[v].values[:n], short[v].values), v
    ons = [runaway_onset(make_config(**c), ds.time.values, ds.X_mean.values, ds.x_mean.values)
           for c, ds in ((cfg, full), (dict(cfg, stop_at_runaway=True), short))]
    assert ons[0]["during_ramp"] and ons[0]["t_onset"] < short.time.values[-1] < ons[0]["t_onset"] + 0.02
    for key in ("mu_onset", "mu_onset_10", "mu_slip"):
        assert ons[0][key] == ons[1][key], key
    for bad in (dict(t_total=0.1), dict(t_decide=0.11, t_max=0.2), dict(t_ramp=1e-3, t_decide=0.11, t_max=0.2)):
        with pytest.raises(Exception, match="stop_at_runaway.*unless dead_weight and t_decide.*at least half"):
            make_config(**ident, dead_weight=0.5, **bad, stop_at_runaway=True)  # no decision, no ramp, a release
    assert member_id(make_config(**cfg)) == member_id(make_config(**cfg, stop_at_runaway=False))
    assert "stop_at_runaway" not in make_config(**cfg).to_toml()


# A released slab (issue 29's tester, shrunk): a light rigid top (T = 2.49 ms) on a 4 x 4 interface, identical
# contacts at the physical stiffness; the weight hangs at once (t_ramp 10 us)
RELEASE = dict(geometry="slab", N=4, Ly=4, N_L=50, theta=1.0, delta=0.0, epsilon=1.0, start="rest", top_mass=1e-6,
               eta_c=1e5, t_ramp=1e-5, t_decide=0.02, t_max=0.03, output_interval=2e-5)


def test_the_top_rings_with_the_period_of_its_mass_on_the_layers_shear():
    """model.system.top_ringing_period, T = 2 pi sqrt(M / (a**2 G/H)), against the released top's own ringing
    while the interface holds (a light weight: the top's velocity peaks, damped, come every T), within 2 %
    (the output interval is 0.8 % of T); and None where there is no rigid top."""
    from scipy.signal import find_peaks

    from slipchain.model.system import top_ringing_period

    cfg = make_config(**RELEASE, dead_weight=0.3)
    T = top_ringing_period(cfg)
    assert T == pytest.approx(2 * np.pi * np.sqrt((50 * cfg.m + 1e-6) / (cfg.a * cfg.G / 50)), rel=1e-12)
    ds = run(cfg)
    t, X = ds.time.values, ds.X_mean.values
    peaks, _ = find_peaks(np.gradient(X, t))
    assert len(peaks) >= 5
    assert np.diff(t[peaks][:5]) == pytest.approx(np.full(4, T), rel=0.02)
    assert top_ringing_period(make_config(N=11, dead_weight=0.5, t_total=0.01)) is None
    assert top_ringing_period(make_config(geometry="slab", N=4, Ly=4)) is None


def test_a_creep_that_speeds_up_on_the_rising_branch_is_no_runaway():
    """dead_weight_status on exact records after the weight (v0 10**delta = 1e-3 m/s): a velocity that rises by
    about 20 % over the tester's last window is a runaway beyond v0 10**delta, and no-steady (a held run: on the
    rising branch, below the maximum) below it, where a released top creeps and its ringing's residual or a creep
    that speeds up makes the fit "still rise" (tester-16-long-etac-3-check: back on the branch at 1.8 s, creeping
    at 5e-5 m/s, read "runaway: the velocity still rises by +10 %" at 3 s before this)."""
    from slipchain.analysis.traces import run_outcome
    from slipchain.results.schema import dead_weight_status

    cfg = make_config(N=11, theta=1.0, delta=0.0, dead_weight=1.0, t_ramp=1e-3, t_decide=2.0, t_max=3.0)
    t = np.arange(1, 3001) * 1e-3
    for v0, says, outcome in ((5e-5, "no-steady", "held"), (2e-4, "no-steady", "held"), (5e-3, "runaway", "runaway")):
        x = v0 * (t + 0.25 * t**2 / t[-1])  # the velocity rises steadily, by 20 % of v0 over the last window
        status, reason, _ = dead_weight_status(cfg, t, x)
        assert status == says, (v0, reason)
        assert run_outcome(cfg, status, t, x)[0] == outcome
        assert ("creeps on the rising branch" in reason) == (says == "no-steady"), reason
        assert "still rises" in reason  # the tester's fit, quoted either way


def test_a_released_runaway_is_read_over_the_tops_last_two_ringing_periods():
    """certain_runaway for a release on the slab's top (results.schema._released_runaway) on records of exact
    velocities: ringing far beyond the branch about a mean that falls, never; a mean velocity beyond the branch
    (0.01 m/s) rising from period to period, from RING_START = 3 periods after the ramp, not before; an
    overshoot from rest that peaks at 2 T and comes back, not (a check from 2 T would have called it a runaway:
    why the first period is left out)."""
    from slipchain.model.system import RING_START, top_ringing_period
    from slipchain.results.schema import RUNAWAY_RISE, certain_runaway, runaway_window

    cfg = make_config(**RELEASE, dead_weight=0.9, stop_at_runaway=True)
    T = top_ringing_period(cfg)
    assert runaway_window(cfg) == 2 * T and RING_START == 3
    dt = 1e-6
    t = np.arange(1, int(round(6 * T / dt)) + 1) * dt

    def verdict(v, upto):
        n = int(np.searchsorted(t, upto))
        return certain_runaway(cfg, t[:n], np.cumsum(v * dt)[:n])

    ring = 0.5 * np.sin(2 * np.pi * t / T)  # +-0.5 m/s, fifty times the branch's bound
    for upto in np.linspace(2 * T, 6 * T, 9):
        assert verdict(ring + 0.02 * np.exp(-t / T), upto) is None  # ringing about a falling mean
        assert verdict(ring + 0.002 * t / T, upto) is None  # a rising mean, below the bound over the period before
    rising = ring + 0.02 * t / T  # the mean beyond the branch, and rising
    assert verdict(rising, 2.9 * T) is None and "ringing periods" in verdict(rising, 3.05 * T)
    # beyond the branch (three times the bound) and barely faster: 1.4 % a period, as the top that slowed down and came
    # back (tester-16-long-etac-3-check), never; 6 % a period (the stored runaways: 5.8 % or more), from 3 periods on
    assert RUNAWAY_RISE == 1.05
    assert all(verdict(ring + 0.03 * 1.014 ** (t / T), upto) is None for upto in np.linspace(3 * T, 6 * T, 7))
    faster = ring + 0.03 * 1.06 ** (t / T)
    assert verdict(faster, 2.9 * T) is None and "5% faster or more" in verdict(faster, 3.05 * T)
    overshoot = np.where(t < 2 * T, 0.05 * t / T, 0.1 * np.exp(-(t - 2 * T) / (0.1 * T)))
    assert all(verdict(overshoot, upto) is None for upto in np.linspace(3 * T, 6 * T, 7))
    slow = make_config(N=11, theta=1.0, delta=0.0, dead_weight=1.0, t_ramp=0.15, t_decide=0.2, t_max=0.3,
                       stop_at_runaway=True)
    assert runaway_window(slow) == 0.02  # a slowly loaded run keeps the 20-ms halves


def test_a_held_top_is_read_over_its_last_two_ringing_periods():
    """certain_held (config stop_when_held) on records of exact velocities (v0 10**delta = 1e-3 m/s, the branch's
    top here): ringing at +-0.5 m/s about a mean below the top and falling, held from 3 T after the ramp on, not
    before; about a mean that rises, or that falls from above the top, not held."""
    from slipchain.model.system import top_ringing_period
    from slipchain.results.schema import certain_held

    cfg = make_config(**RELEASE, dead_weight=0.3, stop_when_held=True)
    T = top_ringing_period(cfg)
    dt = 1e-6
    t = np.arange(1, int(round(6 * T / dt)) + 1) * dt

    def verdict(v, upto):
        n = int(np.searchsorted(t, upto))
        return certain_held(cfg, t[:n], np.cumsum(v * dt)[:n])

    ring = 0.5 * np.sin(2 * np.pi * t / T)
    falling = ring + 5e-4 * np.exp(-t / T)
    assert verdict(falling, 2.9 * T) is None and "held" in verdict(falling, 3.05 * T)
    for upto in np.linspace(3.05 * T, 6 * T, 7):
        assert verdict(ring + 2e-4 * t / T, upto) is None  # a rising mean, below the top
        assert verdict(ring + 0.05 * np.exp(-t / (20 * T)), upto) is None  # falling, but far above the top


def test_a_released_slab_stops_at_its_runaway_or_once_held_as_its_replay_does(tmp_path, store_of_runs):
    """The released 4 x 4 slab (RELEASE) below and above the contacts' maximum, with stop_at_runaway and
    stop_when_held: the runaway stops at the first chunk end from 3 T on (7.52 ms here, where the decision at
    t_decide took 20 ms), classified runaway by its ringing periods; the held run (ringing through zero at
    several m/s first) stops at a decision from t_decide on, before t_max, once its top is back on the branch
    (certain_held), classified no-steady, its last period's mean velocity on the branch. Each record is the full run's up to there, bit for bit.
    The replay of the full runs' stored records with both configs on (analysis.traces.redecide) stops each
    where the run stopped and says what it said. Both keys stay refused off the slab."""
    from slipchain.analysis.traces import redecide
    from slipchain.model.system import top_ringing_period
    from slipchain.sweeps.definition import make_sweep

    sweep = make_sweep({"name": "release", "base": {**RELEASE, "dead_weight": 0.3}, "grid": {"dead_weight": [0.3, 0.9]}})
    store_of_runs(tmp_path / "s", sweep)
    replay, _ = redecide([tmp_path / "s"], [RELEASE["t_decide"]], stop_at_runaway=True, stop_when_held=True)
    T = top_ringing_period(make_config(**RELEASE, dead_weight=0.9))
    for m in sweep.members:
        full = run(m.config)
        short = run(m.config.model_copy(update={"stop_at_runaway": True, "stop_when_held": True}))
        n = short.time.size
        for v in ("X_mean", "x_mean", "f_d"):
            assert np.array_equal(full[v].values[:n], short[v].values), v
        row = replay[replay["member_id"] == m.id].iloc[0]
        assert row["stop_at_runaway"] and row["stop_when_held"] and row["status_replay"] == short.attrs["velocity_status"]
        assert row["t_stop"] == pytest.approx(float(short.time.values[-1]), abs=1e-9)
        t_end = short.time.values[-1]
        if m.config.dead_weight == 0.9:
            assert full.attrs["velocity_status"] == short.attrs["velocity_status"] == "runaway"
            assert "ringing periods" in short.attrs["velocity_reason"]
            assert 3 * T <= t_end < 3 * T + 0.001 and full.time.values[-1] >= RELEASE["t_decide"]
        else:
            assert full.attrs["velocity_status"] == short.attrs["velocity_status"] == "no-steady"
            assert "stop_when_held" in short.attrs["velocity_reason"] and full.time.values[-1] == pytest.approx(0.03)
            assert RELEASE["t_decide"] - 1e-9 <= t_end < RELEASE["t_max"] - 1e-3
            t, X = short.time.values, short.X_mean.values
            j = int(np.searchsorted(t, t_end - T))
            assert (X[-1] - X[j]) / (t_end - t[j]) < m.config.v0 * 10**m.config.delta  # the last period on the branch
    for key in ("stop_at_runaway", "stop_when_held"):
        with pytest.raises(Exception, match=f"{key}.*geometry = 'slab'"):
            make_config(N=11, dead_weight=0.5, t_ramp=1e-3, t_decide=0.11, t_max=0.2, **{key: True})
    cfg = make_config(**RELEASE, dead_weight=0.3)
    assert member_id(cfg) == member_id(cfg.model_copy(update={"stop_when_held": False}))
    assert "stop_when_held" not in cfg.to_toml()

"""implicit_scheme = 'trbdf2' (issue 27): TR-BDF2 above the explicit levels on the slab, half-space and
chain2d, in place of backward Euler.

Independent checks: a contact-free step against the scheme's own linear analysis
(:func:`slipchain.model.stability.trbdf2_amplification`), far beyond the explicit stable step
(tests/physics/test_implicit.py, beside backward Euler's); second
order in the step through creep (the error against a finer step falls fourfold per halving, where
backward Euler's halves); agreement with the explicit adaptive step at the physical contact stiffness
through the start event and creep under the spring drive (slab, chain2d) and the dead weight; its
numerical dissipation far below backward Euler's; the refusals and unchanged member ids. Checkpoints
resume bit for bit: tests/physics/test_checkpoint.py ("implicit chain2d, trbdf2").
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

import slipchain as sc
from slipchain.engine.backends import Batch
from slipchain.engine.backends.host import CPUBackend
from slipchain.model.config import ConfigError, make_config
from slipchain.model.stability import be_amplification, trbdf2_amplification
from slipchain.model.system import build_system, initial_state

EPS1 = dict(N=8, Ly=8, N_L=5, theta=1.0, eta_c=1e5, v_d=1e-3, epsilon=1.0, seed=3, start="steady", dt=1e-7)


def test_numerical_dissipation_of_a_resolved_mode_is_fourth_order():
    """An undamped mode at h omega = 0.1: TR-BDF2 keeps its energy to ~7e-3 (h omega)**4 per step, where
    backward Euler loses ~(h omega)**2 (the reason for the scheme: the energy residual that bounded
    backward Euler's steps through creep, docs/numerics.md)."""
    w = 1e4
    h = 0.1 / w
    B, D = np.array([[[w * w]]]), np.zeros((1, 1, 1))
    y = np.array([1.0 / w, 0.0])  # (x, v): energy 1/2 (w**2 x**2 + v**2) = 1/2
    A = trbdf2_amplification(B, D, h)[0]
    y1 = A @ y
    loss_tr = 1.0 - (w * w * y1[0] ** 2 + y1[1] ** 2)
    Abe = be_amplification(B, D, h)[0]  # in (x/h, v)
    z1 = Abe @ np.array([y[0] / h, y[1]])
    loss_be = 1.0 - (w * w * (z1[0] * h) ** 2 + z1[1] ** 2)
    assert 0.0 < loss_tr < 2e-2 * 0.1**4 and 0.5 * 0.1**2 < loss_be < 2.0 * 0.1**2, (loss_tr, loss_be)


def _creep_errors(geometry: str, scheme: str, levels=(11, 12, 13, 14, 15), ref: int = 9):
    """From one state in the creep after the start event (8 x 8, epsilon = 1), 0.2 s with the step capped
    at dt 2**L; the error against the same scheme with a finer cap (relative, largest over positions)."""
    cfg = make_config(geometry=geometry, **EPS1, output_interval=0.05, t_total=1.0, integrator="implicit",
                      step_tol=1.0, implicit_scheme=scheme)
    system = build_system(cfg)
    b0 = Batch.pack([system], [initial_state(system)])
    CPUBackend().advance(b0, 1, cfg.sample_steps)  # 0.05 s: past the start event

    def creep(level):
        b = copy.deepcopy(b0)
        b.step_control[:, 4] = level
        CPUBackend().advance(b, 1, 4 * cfg.sample_steps)
        return np.concatenate([b.x[0], b.X[0]])

    reference = creep(ref)
    return {L: float(np.abs(creep(L) - reference).max() / np.abs(reference).max()) for L in levels}


@pytest.mark.parametrize("geometry", ["slab", "chain2d"])
def test_second_order_in_the_step_through_creep(geometry):
    """TR-BDF2's error against a finer step falls fourfold per halving through creep (measured ratios
    4.00-4.2 on both geometries, 3.3-ms steps to 0.2-ms ones), where backward Euler's halves; and at
    the longest step it is hundreds of times smaller than backward Euler's (slab: 6.4e-8 against 4.2e-5)."""
    tr = _creep_errors(geometry, "trbdf2")
    ratios = [tr[L + 1] / tr[L] for L in (12, 13, 14)]
    assert all(3.5 < r < 4.6 for r in ratios), (tr, ratios)
    be = _creep_errors(geometry, "backward-euler", levels=(14, 15))
    assert 1.7 < be[15] / be[14] < 2.4, be
    assert tr[15] < 1e-2 * be[15], (tr, be)


CASES = {
    "slab": dict(geometry="slab", N=16, Ly=16, start="steady", t_total=0.05),
    "chain2d": dict(geometry="chain2d", N=16, Ly=16, start="steady", t_total=0.05),
    "slab, dead weight": dict(geometry="slab", N=8, Ly=8, dead_weight=0.3, start="rest", t_total=0.05),
    "slab, low load": dict(geometry="slab", N=16, Ly=16, theta=0.05, start="steady", t_total=0.05),
    "halfspace": dict(geometry="halfspace", N=16, Ly=16, start="steady", t_total=0.05),
    "chain2d, dead weight": dict(geometry="chain2d", N=8, Ly=8, dead_weight=0.3, start="rest", t_total=0.05),
}


@pytest.mark.parametrize("case", CASES)
def test_agrees_with_the_adaptive_step_at_the_physical_contact_stiffness(case):
    """epsilon = 1, through the start event and the creep after it (and at low load its frequent small
    events): the drive force (or the plate's path under the dead weight) agrees with the explicit adaptive
    step sample by sample, the works agree, and the energy balance holds, at least as well as backward
    Euler's (tests/physics/test_implicit.py)."""
    cfg = dict(dict(N_L=5, theta=1.0, eta_c=1e5, v_d=1e-3, dt=1e-7, epsilon=1.0, seed=0, output_interval=1e-3),
               **CASES[case])
    tr = sc.run(dict(cfg, integrator="implicit", implicit_scheme="trbdf2"))
    ada = sc.run(dict(cfg, integrator="adaptive"))
    assert tr.attrs["check_energy_balance_passed"] == 1
    if "dead_weight" in cfg:
        assert abs(tr.attrs["velocity"] / ada.attrs["velocity"] - 1) < 1e-3
        assert np.abs(tr.X_mean.values - ada.X_mean.values).max() < 1e-6 * np.abs(ada.X_mean.values).max()
        assert tr.attrs["check_energy_balance"] < 1e-4
        return
    ft, fa = tr.f_d.values, ada.f_d.values
    # the half-space drifts apart from the adaptive step over the window for either implicit step (measured:
    # TR-BDF2 4.7e-3 of the largest force at the end, backward Euler 6.6e-3; the others below 2e-3)
    tol = 6e-3 if cfg["geometry"] == "halfspace" else 3e-3
    assert np.abs(ft - fa).max() < tol * np.abs(fa).max(), np.abs(ft - fa).max() / np.abs(fa).max()
    for key in ("W_drive", "W_damping", "W_contacts"):
        assert abs(tr.attrs[key] / ada.attrs[key] - 1) < 3e-3, key
    # the energy balance over these short windows from the steady start: as the adaptive step's (measured
    # 1.1e-3 on the half-space and 1.9e-3 on the slab at low load for both)
    assert tr.attrs["check_energy_balance"] < 1.1 * ada.attrs["check_energy_balance"] + 1e-4


def test_refused_where_nothing_builds_it_and_keeps_member_ids():
    """TR-BDF2 is built for the Newton-Krylov step (slab, half-space, chain2d) with the elastic bulk; the
    chain's compiled step and the Prony arms refuse it with the reason. The default, 'backward-euler', was the
    only step before the key: absent from member ids and TOML text (config.OFF)."""
    from slipchain.sweeps.definition import member_id

    for cfg in (dict(N=16, integrator="implicit"), dict(geometry="slab", N=8, Ly=8, integrator="adaptive"),
                dict(geometry="slab", N=8, Ly=8, integrator="implicit", material="prony", N_L=50, epsilon=1.0)):
        with pytest.raises(ConfigError, match="implicit_scheme.*'trbdf2'.*absent \\(or 'backward-euler'\\) unless"):
            make_config(**cfg, dt=1e-7, implicit_scheme="trbdf2")
    with pytest.raises(ConfigError, match="implicit_scheme"):
        make_config(geometry="slab", N=8, Ly=8, integrator="implicit", dt=1e-7, implicit_scheme="bdf3")
    cfg = dict(geometry="slab", N=16, Ly=16, N_L=50, epsilon=1.0, material="prony", integrator="implicit", dt=1e-7,
               theta=0.5, dead_weight=0.85, top_mass="tester", start="rest", t_ramp=1.0, t_decide=1.5, t_max=2.5,
               output_interval=1e-3)
    default = make_config(**cfg)
    assert member_id(default) == member_id(make_config(**cfg, implicit_scheme="backward-euler")) == "6be15db5e8130c7c"
    slab = dict(geometry="slab", N=8, Ly=8, integrator="implicit", dt=1e-7, epsilon=1.0)
    assert "implicit_scheme" not in make_config(**slab).to_toml()
    tr = make_config(**slab, implicit_scheme="trbdf2")
    assert 'implicit_scheme = "trbdf2"' in tr.to_toml()
    assert member_id(tr) != member_id(make_config(**slab))

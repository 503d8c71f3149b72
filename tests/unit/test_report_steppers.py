"""The Fig. 6-in-3-D report states the step that made each point (a preset may pick each point's
fastest stepper, as fig6-3d-eps1-128-fast does)."""

import pandas as pd

from slipchain import make_config
from slipchain.analysis.geometry import report_markdown, steppers
from slipchain.analysis.reports import step_text


def _attrs(configs):
    return {"v_d1": 1e-3, "v_d2": 3e-4, "main": {"slab": (8, 8, 5), "chain2d": (8, 8, 5)}, "epsilon": 1.0,
            "integrator": configs[0].integrator, "steppers": steppers(configs)}


def _table():
    return pd.DataFrame({"geometry": ["slab"], "N": [8], "Ly": [8], "N_L": [5], "theta": [1.0], "v_d": [1e-3],
                         "mu": [0.6], "err": [0.01], "n": [2], "box": [8e-4], "H_over_L": [5 / 8]})


def test_one_step_for_every_point_keeps_the_one_line():
    cfgs = [make_config(geometry="slab", N=8, Ly=8, epsilon=1.0, integrator="implicit", theta=th, seed=s)
            for th in (0.5, 1.0) for s in (0, 1)]
    assert list(steppers(cfgs)) == [step_text(cfgs[0])]
    assert steppers(cfgs)[step_text(cfgs[0])] == [("slab", 0.5, 1e-3), ("slab", 1.0, 1e-3)]  # seeds collapse
    report = report_markdown(_table(), pd.DataFrame(), _attrs(cfgs))
    assert f"epsilon = 1, {step_text(cfgs[0])}." in report and "the step differs per point" not in report
    assert "backward Euler above" in report  # the members' step in full, not only the integrator's name


def test_one_step_is_the_members_not_the_base():
    """A grid that sets every member's integrator: the report names the members' step, not the base's."""
    cfgs = [make_config(geometry="slab", N=8, Ly=8, epsilon=1.0, integrator="adaptive", theta=th) for th in (0.5, 1.0)]
    attrs = _attrs(cfgs) | {"integrator": "implicit"}  # the store's base says implicit
    report = report_markdown(_table(), pd.DataFrame(), attrs)
    assert f"epsilon = 1, {step_text(cfgs[0])}." in report and "implicit" not in report
    without = report_markdown(_table(), pd.DataFrame(), attrs | {"steppers": {}})  # no completed member
    assert "epsilon = 1, integrator = 'implicit'." in without


def test_mixed_steps_are_listed_with_their_points():
    trbdf2 = dict(geometry="slab", N=8, Ly=8, epsilon=1.0, integrator="implicit", implicit_scheme="trbdf2",
                  krylov_preconditioner="additive")
    cfgs = [make_config(**trbdf2, theta=1.0), make_config(**trbdf2, theta=0.7, v_d=3e-4),
            make_config(**trbdf2, theta=0.1, dt=5e-8),
            make_config(geometry="chain2d", N=8, Ly=8, epsilon=1.0, integrator="adaptive", theta=0.1)]
    steps = steppers(cfgs)
    assert len(steps) == 3
    assert "TR-BDF2 preconditioned 'additive' above" in step_text(cfgs[0])
    assert "backward Euler above" in step_text(make_config(geometry="slab", N=8, Ly=8, integrator="implicit"))
    assert step_text(cfgs[3]).startswith("integrator = adaptive")
    report = report_markdown(_table(), pd.DataFrame(), _attrs(cfgs))
    assert "integrator = 'implicit'." not in report
    rows = [line for line in report.splitlines() if line.startswith("| integrator = ")]
    assert rows == [f"| {step_text(cfgs[0])} | slab, 0.001: 1; slab, 0.0003: 0.7 |",
                    f"| {step_text(cfgs[2])} | slab, 0.001: 0.1 |",
                    f"| {step_text(cfgs[3])} | chain2d, 0.001: 0.1 |"]

"""The automatic length follows slip cycles (issue 26, config ``t_max_cycles``).

At epsilon = 1 the whole chain stick-slips in cycles far longer than the default cap t_max: a run
that reaches t_max with fewer than FEW_CYCLES cycles in its steady window goes on, its cap following
its cycles, until the window holds DEFAULT_MIN_CYCLES of them and the standard error is reached (at
most t_max_cycles). Here v_d = 10 v0 makes the cycles ten times shorter than at the paper's v_d1, so
that twenty of them cost seconds. Each test counts the cycles again from the stored trace.
"""

import numpy as np
import pytest
import xarray as xr

import slipchain as sc
from slipchain.engine import checkpoint as ckpt
from slipchain.engine import memory
from slipchain.engine.control import DEFAULT_MIN_CYCLES, FEW_CYCLES
from slipchain.model.config import DEFAULT_T_MAX_CYCLES, make_config
from slipchain.results.observables import count_cycles, steady_estimate

CFG = dict(N=31, theta=1.0, epsilon=1.0, start="steady", v_d=1e-2, t_max=0.02, output_interval=1e-4, seed=1)


def _cycles(ds):
    fd = ds["f_d"].values
    return count_cycles(fd[steady_estimate(fd).start:])


@pytest.fixture(scope="module")
def extended():
    return sc.run(CFG, progress=False)


@pytest.fixture(scope="module")
def capped():
    return sc.run({**CFG, "t_max_cycles": 0.0}, progress=False)  # what the key's absence meant before


def test_a_run_that_stick_slips_as_a_whole_runs_until_its_window_holds_the_cycles(extended, capped):
    assert make_config(CFG).t_max_cycles == DEFAULT_T_MAX_CYCLES
    # without the extension: stopped at t_max with a few cycles (the condition that extends)
    assert capped.attrs["t_total"] == pytest.approx(CFG["t_max"]) and _cycles(capped) < FEW_CYCLES
    assert "t_max = 0.02 s reached" in capped.attrs["message"]
    # with it: converged past t_max, well before the ceiling, with the cycles in its steady window
    a = extended.attrs
    assert a["status"] == "completed" and a["sem_target_reached"] == 1
    assert CFG["t_max"] < a["t_total"] < DEFAULT_T_MAX_CYCLES
    assert _cycles(extended) >= DEFAULT_MIN_CYCLES
    assert "past t_max = 0.02 s" in a["message"]
    assert a["check_energy_balance_passed"] == 1
    # until t_max the extended run is the capped run, bit for bit
    n = capped.sizes["time"]
    np.testing.assert_array_equal(extended["f_d"].values[:n], capped["f_d"].values)


def test_the_cap_follows_the_cycles_up_to_t_max_cycles(extended):
    short = sc.run({**CFG, "t_max_cycles": 0.3}, progress=False)
    assert short.attrs["t_total"] == pytest.approx(0.3)
    assert short.attrs["sem_target_reached"] == 0 and _cycles(short) < DEFAULT_MIN_CYCLES
    msg = short.attrs["message"]
    assert "the cap 0.3 s (extended past t_max = 0.02 s" in msg and "raise t_max_cycles" in msg
    np.testing.assert_array_equal(short["f_d"].values, extended["f_d"].values[:short.sizes["time"]])


def test_an_extension_that_would_not_fit_in_memory_is_refused_with_its_reason(monkeypatch):
    cfg = make_config(CFG)
    assert memory.extension_refusal(cfg, 0.02, 30.0, available=10**12) is None
    why = memory.extension_refusal(cfg, 0.02, 30.0, available=memory.BASE_BYTES + 1000)
    assert "not extended to 30 s" in why and "GiB more memory" in why
    assert memory.estimate_bytes(cfg, 30.0) > memory.estimate_bytes(cfg, 0.02) == memory.estimate_bytes(cfg)
    # a machine with 1000 bytes beyond the margin: the run to t_max is let through (its start's check
    # off), the first extension is refused
    import sys

    monkeypatch.setattr(sys.modules["slipchain.engine.simulate"], "check_memory", lambda configs: 0)
    monkeypatch.setattr(memory, "available_bytes", lambda: memory.BASE_BYTES + 1000)
    ds = sc.run(CFG, progress=False)
    assert ds.attrs["t_total"] == pytest.approx(CFG["t_max"]) and "not extended to" in ds.attrs["message"]


class Crash(Exception):
    pass


def test_a_run_killed_after_its_extension_resumes_bit_for_bit(extended, tmp_path, monkeypatch):
    path = tmp_path / "run.ckpt.nc"
    original = ckpt.Checkpointer.save

    def save(self):
        original(self)
        controls = self._live[2]
        if controls[0].extended and controls[0].n * 1e-4 > 0.5:
            raise Crash("past t_max, extended")

    with monkeypatch.context() as m:
        m.setattr(ckpt.Checkpointer, "save", save)
        with pytest.raises(Crash):
            sc.run(CFG, checkpoint=path, checkpoint_every=0, progress=False)
    resumed = sc.run(CFG, checkpoint=path, progress=False)
    reference = extended.copy()
    for ds in (reference, resumed):
        for k in ("wall_time_s", "resumed_at"):
            ds.attrs.pop(k, None)
    xr.testing.assert_identical(reference, resumed)

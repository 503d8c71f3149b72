"""The combination matrix (issue 26): every geometry x integrator x drive runs on the CPU, or is refused
with the capability table's reason (:mod:`slipchain.model.capabilities`).

Each accepted cell, on a tiny system: the run closes its energy balance, a run crashed after a
checkpoint resumes bit for bit, and the adaptive step agrees with the fixed step to the order its
tolerance promises (the difference shrinks with step_tol).
"""

import numpy as np
import pytest
import xarray as xr

from slipchain.engine import checkpoint as ckpt
from slipchain.engine.simulate import run
from slipchain.model.capabilities import DRIVES, GEOMETRIES, INTEGRATORS, MATERIALS, refusal
from slipchain.model.config import ConfigError, make_config

GEOMETRY = {"chain": dict(N=8), "chain2d": dict(geometry="chain2d", N=4, Ly=4),
            "slab": dict(geometry="slab", N=4, Ly=4), "halfspace": dict(geometry="halfspace", N=4, Ly=4)}
DRIVE = {"spring": {}, "dead_weight": dict(dead_weight=0.7)}
STEP = {"fixed": dict(dt=2e-8), "fold": dict(dt=1e-7), "adaptive": dict(dt=2e-8), "implicit": dict(dt=2e-8)}
# The cells' runs (balance, checkpoint): base steps of 5e-8 s, within every cell's stable step (at least 1.6e-7 s:
# chain2d with the rubber) and at most the accurate one (1e-7 s); the fixed step at 3e-8 s, under its bound for
# these contacts (3.6e-8 s: one root per contact; make_config refuses more).
CELL_STEP = {"fixed": 3e-8, "fold": 1e-7, "adaptive": 5e-8, "implicit": 5e-8}
COMMON = dict(theta=0.5, start="steady", output_interval=1e-5, seed=1)
CELLS = [(g, i, d, m) for m in MATERIALS for g in GEOMETRIES for i in INTEGRATORS for d in DRIVES]


def _config(geometry, integrator, drive, material="elastic", **kw):
    step = STEP[integrator]
    extra = dict(material="prony") if material == "prony" else {}
    return make_config(**COMMON, **GEOMETRY[geometry], **DRIVE[drive], integrator=integrator, **extra,
                       **{**step, **kw})


class Crash(Exception):
    pass


@pytest.mark.parametrize("geometry, integrator, drive, material", CELLS)
def test_every_cell_runs_or_is_refused_by_the_table(geometry, integrator, drive, material, tmp_path, monkeypatch):
    why = refusal(geometry, integrator, drive, "cpu", material)
    if why is not None:
        with pytest.raises(ConfigError, match="a combination that runs: " + why.split("(")[0]):
            _config(geometry, integrator, drive, material, t_total=1.2e-3)
        return
    cfg = _config(geometry, integrator, drive, material, t_total=1.2e-3, dt=CELL_STEP[integrator])
    assert cfg.dt < cfg.dt_stable  # (three chunks of 0.5 ms)
    reference = run(cfg, progress=False)
    assert np.isfinite(reference["f_d"].values).all() and np.isfinite(reference["x"].values).all()
    assert reference.attrs["check_energy_balance_passed"] == 1, reference.attrs["check_energy_balance"]
    if material == "prony":  # the bulk dissipates, and its state is part of the checkpoint (resumed below)
        assert reference.attrs["W_bulk"] < 0 and np.abs(reference["xi"].values).max() > 0
    path = tmp_path / "run.ckpt.nc"
    original = ckpt.Checkpointer.save

    def save(self):
        original(self)
        if self.writes >= 1:
            raise Crash("after the first chunk")

    with monkeypatch.context() as m:
        m.setattr(ckpt.Checkpointer, "save", save)
        with pytest.raises(Crash):
            run(cfg, checkpoint=path, checkpoint_every=0, progress=False)
    resumed = run(cfg, checkpoint=path, progress=False)  # (its own checkpoints at the default interval: the last)
    for ds in (reference, resumed):
        for k in ("wall_time_s", "resumed_at"):
            ds.attrs.pop(k, None)
    xr.testing.assert_identical(reference, resumed)


def _trace(ds, drive):
    """What the run measures: f_d with the spring drive, the slider's position <X> under the dead weight."""
    return ds["f_d"].values if drive == "spring" else ds["X_mean"].values


@pytest.mark.parametrize("geometry, drive, material", [(g, d, m) for m in MATERIALS for g in GEOMETRIES for d in DRIVES
                                                       if refusal(g, "adaptive", d, "cpu", m) is None])
def test_adaptive_step_converges_to_the_fixed_step(geometry, drive, material):
    fixed = _trace(run(_config(geometry, "fixed", drive, material, t_total=1e-3), progress=False), drive)
    end = fixed.size
    if material == "prony" and drive == "spring":
        # With the rubber the comparison ends 50 us before the first slip event (after the start's dip, the
        # first sample 5 % below the running maximum of f_d): its onset, at the end of a slow creep along a flat
        # maximum of f_d, moves by tens of us with any step near 1e-7 s, the fold step's too
        # (docs/guide/viscoelastic.md), so there the steps are compared over many events, statistically
        # (test_viscoelastic.py).
        low = int(np.argmin(fixed[: fixed.size // 2]))
        rise = fixed[low:]
        drop = rise < 0.95 * np.maximum.accumulate(rise)
        end = (low + int(np.argmax(drop)) if drop.any() else fixed.size) - 5
        assert end >= 20  # at least 0.2 ms compared
    diff = []
    for tol in (1e-2, 1e-3):
        ds = run(_config(geometry, "adaptive", drive, material, t_total=1e-3, step_tol=tol), progress=False)
        diff.append(float(np.abs(_trace(ds, drive)[:end] - fixed[:end]).max() / np.abs(fixed[:end]).max()))
    assert diff[0] < 3e-2  # a relative error of the order of the tolerance (measured: up to 1.1e-2)
    if material == "prony":
        # With the rubber the top level is held at fold's accuracy bound, 0.1/omega0 (Config.dt_accurate), and
        # the arms' O(h) error there, which the velocity-error estimate does not see, is a floor the tolerance
        # cannot lower: the adaptive step is then as accurate as the fold step at its top level (the slab under
        # the drive springs: 3.6e-3 at either tolerance, fold 3.6e-3 against the fixed step at 1e-8 s).
        top = _config(geometry, "adaptive", drive, material, t_total=1e-3).dt_accurate
        floor = _trace(run(_config(geometry, "fold", drive, material, t_total=1e-3, dt=top), progress=False), drive)
        floor = float(np.abs(floor[:end] - fixed[:end]).max() / np.abs(fixed[:end]).max())
        assert diff[1] < diff[0] or max(diff) < 1.5 * floor
    else:
        assert diff[1] < diff[0]  # and smaller with a tighter tolerance


def test_auto_backend_chooses_per_config_and_says_so():
    """On a GPU host (numba's CUDA simulator stands in for one here) 'auto' gives the GPU the
    combinations the table lets it run and the CPU the others, with a BackendFallback warning;
    'gpu' refuses the others with the table's reason."""
    from slipchain.engine.backends import BackendFallback, CPUBackend, get_backend
    from slipchain.engine.backends.cuda import CUDABackend, cuda_available

    if not cuda_available():  # pragma: no cover - numba without its CUDA target
        pytest.skip("numba.cuda is not usable here (neither a GPU nor the simulator)")
    fixed = _config("chain", "fixed", "spring", t_total=1e-5)
    assert isinstance(get_backend("auto", [fixed]), CUDABackend)
    for geometry, integrator, drive, material in CELLS:
        why = refusal(geometry, integrator, drive, "gpu", material)
        if why is None or refusal(geometry, integrator, drive, "cpu", material) is not None:
            continue
        cfg = _config(geometry, integrator, drive, material, t_total=1e-5)
        with pytest.warns(BackendFallback, match="runs this batch on the CPU: " + why.split("(")[0]):
            assert isinstance(get_backend("auto", [fixed, cfg]), CPUBackend)
        with pytest.raises(RuntimeError, match="backend 'gpu' cannot run this config"):
            get_backend("gpu", [cfg])


def test_the_docs_show_the_table_of_the_code():
    from pathlib import Path

    from slipchain.model.capabilities import markdown_table

    docs = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"
    assert markdown_table() in docs.read_text()

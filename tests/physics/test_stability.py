"""The stable step (issue 26): Config's bound is the scheme's linear stability limit, per geometry and drive.

Three independent statements of it are compared: the bound Config uses
(:func:`slipchain.model.stability.stable_step`: eigenvalue bisection for the chains, Jury's closed
form at the stiffest mode for the slab), the eigenvalues of every Fourier mode's amplification
matrix, and the engine itself: a contact-free system started from a small random displacement
stays bounded for 1e5 steps at 0.98 of the bound and blows up at 1.02 of it (run past Config's
check, which refuses that step with a message naming dt and the bound).
"""

import numpy as np
import pytest

from slipchain.engine.simulate import simulate
from slipchain.model.config import Config, ConfigError, make_config
from slipchain.model.stability import chain_modes, largest_stable_step, plate_mode, slab_modes, spectral_radius
from slipchain.model.system import State, build_system

# Contact-free systems: one contact whose force is negligible (epsilon tiny) and no contact damping.
FREE = dict(theta=0.1, epsilon=1e-12, eta_c=0.0, integrator="fold", output_interval=1e-5)
CASES = {
    "chain": dict(N=10),
    "chain, dead weight": dict(N=10, dead_weight=0.5),
    "chain2d": dict(geometry="chain2d", N=6, Ly=4),
    "chain2d, dead weight": dict(geometry="chain2d", N=6, Ly=4, dead_weight=0.5),
    "slab": dict(geometry="slab", N=8, Ly=8),
    "slab, dead weight": dict(geometry="slab", N=8, Ly=8, dead_weight=0.5),
    "halfspace": dict(geometry="halfspace", N=8, Ly=8),
    "chain, stiff damping": dict(N=10, eta=1e6),  # damping-limited: h*6*eta alone would allow 3.3e-7 s
}


def _modes(cfg):
    if cfg.geometry in ("chain", "chain2d"):
        kd = 0.0 if cfg.dead_weight is not None else cfg.K_d
        return [chain_modes(cfg.N, cfg.Ly, cfg.m, cfg.N_L, cfg.K, cfg.K_L, cfg.K_T, kd, cfg.K_Y, cfg.K_LY, cfg.eta)]
    return [slab_modes(cfg)] + ([plate_mode(cfg)] if cfg.dead_weight is not None else [])


@pytest.mark.parametrize("case", CASES)
def test_config_bound_is_the_linear_limit_of_every_mode(case):
    cfg = make_config(**FREE, **CASES[case], dt=1e-9)
    bound = cfg.dt_stable
    groups = _modes(cfg)
    # every mode (the slab's whole rfft2 grid and its plate mode) by eigenvalue bisection
    assert bound == pytest.approx(min(largest_stable_step(B, D) for B, D in groups), rel=1e-6)
    assert max(spectral_radius(B, D, 0.98 * bound) for B, D in groups) <= 1.0 + 1e-7
    assert max(spectral_radius(B, D, 1.02 * bound) for B, D in groups) > 1.0 + 1e-4


def test_the_bound_couples_springs_and_damping():
    # Symplectic Euler with explicit damping, scalar mode: h**2 w**2 + 2 h g < 4 (Jury). The old check
    # bounded h*w and h*g separately; the chain at the paper's values is limited below both.
    cfg = make_config(dt=1e-8)
    assert cfg.dt_stable < min(1.8 / cfg.omega_max, 1.8 / (6 * cfg.eta))
    assert cfg.dt_stable == pytest.approx(6.8655e-7, rel=1e-4)  # the linearisation: about 6.9e-7 s


def _spread(cfg: Config) -> tuple[float, float]:
    """(initial, final) largest |x - <x>| of a contact-free run from a random displacement of 1e-9 m
    (final inf where the state went non-finite)."""
    n = cfg.n_blocks
    x = 1e-9 * np.random.default_rng(0).standard_normal(n)
    ds = simulate(build_system(cfg), State(x, np.zeros(n), np.zeros(n), np.zeros(n), 0), progress=False)
    xf = ds["x"].values
    final = float(np.abs(xf - xf.mean()).max()) if np.isfinite(xf).all() else np.inf
    return float(np.abs(x - x.mean()).max()), final


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning")  # the run outside the bound overflows, as it must
@pytest.mark.parametrize("case", ["chain", "chain2d", "slab", "slab, dead weight", "chain, stiff damping"])
def test_engine_stays_bounded_just_inside_and_blows_up_just_outside(case):
    bound = make_config(**FREE, **CASES[case], dt=1e-9).dt_stable
    steps = 100_000

    def data(f):
        return {**FREE, **CASES[case], "dt": f * bound, "output_interval": 1000 * f * bound, "t_total": steps * f * bound}

    with pytest.raises(ConfigError, match=f"config key 'dt'.*dt < {bound:.4g} s, the largest stable step"):
        make_config(data(1.02))
    inside = make_config(data(0.98))
    outside = Config.model_construct(**{**inside.model_dump(), **data(1.02)})  # past the check: show why it exists
    start, end = _spread(inside)
    assert end <= 3.0 * start  # bounded (the modes are damped; symplectic Euler's energy error is bounded)
    start, end = _spread(outside)
    assert end > 1e6 * start  # a mode grows by more than 1.0001 per step (or the state went non-finite)


def test_trbdf2_is_second_order_l_stable_and_dissipates_far_less_than_backward_euler():
    """stability.trbdf2_amplification (the analysis of a less dissipative implicit step, issue 27): on the
    chain's modes (springs and pair damping together) its error against the exact propagator expm(h J) is
    third order per step (halving h divides it by ~8); every mode decays for steps from 1e-9 s to 10 s
    (A-stable) and the radius falls like 1/h far above the modes' time scales (L-stable); on an undamped
    resolved mode it keeps the energy to ~7.35e-3 (h omega)^4 per step where backward Euler loses (h omega)^2."""
    from scipy.linalg import expm

    from slipchain.model.stability import be_amplification, chain_modes, trbdf2_amplification

    cfg = make_config(N=31)
    B, D = chain_modes(cfg.N, cfg.Ly, cfg.m, cfg.N_L, cfg.K, cfg.K_L, cfg.K_T, cfg.K_d, cfg.K_Y, cfg.K_LY, cfg.eta)
    k = 7
    d = B.shape[1]
    J = np.block([[np.zeros((d, d)), np.eye(d)], [-B[k], -D[k]]])
    omega = np.sqrt(np.abs(np.linalg.eigvals(B[k])).max())
    errors = [np.abs(trbdf2_amplification(B[k:k + 1], D[k:k + 1], h)[0] - expm(h * J)).max()
              for h in (0.02 / omega, 0.01 / omega)]
    assert 7.0 < errors[0] / errors[1] < 9.0
    radii = [np.abs(np.linalg.eigvals(trbdf2_amplification(B, D, h))).max() for h in np.logspace(-9, 1, 21)]
    assert max(radii) < 1.0
    assert radii[-1] < 1e-4 and 8.0 < radii[-3] / radii[-1] < 12.0  # ~ 1/h: ten times the step, a tenth
    w = np.array([[[1.0]]])
    for hw in (0.05, 0.1, 0.2):
        kept = np.abs(np.linalg.eigvals(trbdf2_amplification(w, 0.0 * w, hw)[0])).max() ** 2
        kept_be = np.abs(np.linalg.eigvals(be_amplification(w, 0.0 * w, hw)[0])).max() ** 2
        assert 1.0 - kept == pytest.approx(7.35e-3 * hw ** 4, rel=0.1)
        assert 1.0 - kept_be == pytest.approx(hw ** 2, rel=0.05)

"""The 2-D geometries of issue 13 (chain2d, slab, halfspace): reductions to the chain, the slab's
modes against their analytic dynamics, its uniform mode against an independent ODE solver, energy
balance, and the config's checks (member ids of chain runs unchanged)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import slipchain as sc
from slipchain.model.config import ConfigError, make_config
from slipchain.model.system import build_system, elastic_kernel, initial_state, uniform_stiffness
from slipchain.sweeps.definition import member_id


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.mean(np.abs(a))


def test_chain2d_with_one_row_is_the_chain_to_round_off():
    """Issue 13: chain2d at Ly = 1 (its own 2-D stencil, y-neighbours = the block itself) reproduces
    the chain: f_d(t) and mu_star to round-off before the dynamics amplify it (1 ms here)."""
    base = dict(N=101, t_total=1e-3, theta=0.5, start="steady", output_interval=1e-4)
    a = sc.run(base)
    b = sc.run(dict(base, geometry="chain2d"))
    assert a.attrs["geometry"] == "chain" and b.attrs["geometry"] == "chain2d"
    assert _rel(a.f_d.values, b.f_d.values) < 1e-12
    assert abs(a.attrs["mu_star"] / b.attrs["mu_star"] - 1) < 1e-12
    assert np.max(np.abs(a.x.values - b.x.values)) < 1e-12 * np.max(np.abs(a.x.values))


def test_chain2d_rows_repeated_across_y_are_the_chain():
    """Contacts repeated identically in every one of Ly = 4 rows: the motion is uniform in y, the y
    springs and dampers carry nothing, and every row moves as the chain (same f_d per block)."""
    cfg = make_config(N=61, theta=0.3, t_total=1e-3, start="steady", output_interval=1e-4)
    chain = build_system(cfg)
    ly = 4
    cfg2 = cfg.with_updates(geometry="chain2d", Ly=ly)
    sites = (chain.contact_sites[:, None] * ly + np.arange(ly)[None, :]).ravel()
    two_d = build_system(cfg2, sites, np.repeat(chain.vstar, ly))
    a = sc.simulate(chain)
    b = sc.simulate(two_d)
    assert _rel(a.f_d.values, b.f_d.values) < 1e-12
    assert np.max(np.abs(b.x.values.reshape(61, ly) - a.x.values[:, None])) < 1e-12 * np.max(np.abs(a.x.values))


@pytest.mark.parametrize("geometry", ["slab", "halfspace"])
def test_slab_rows_repeated_across_y_equal_one_row(geometry):
    """The slab's kernel at qy = 0 is k_PSV(qx): a y-uniform state of an (N, 4) slab moves as the
    (N, 1) slab (only FFT round-off differs)."""
    cfg = make_config(N=32, geometry=geometry, theta=0.3, t_total=5e-4, start="steady", output_interval=1e-4)
    one = build_system(cfg)
    ly = 4
    sites = (one.contact_sites[:, None] * ly + np.arange(ly)[None, :]).ravel()
    four = build_system(cfg.with_updates(Ly=ly), sites, np.repeat(one.vstar, ly))
    a, b = sc.simulate(one), sc.simulate(four)
    assert _rel(a.f_d.values, b.f_d.values) < 1e-9
    assert np.max(np.abs(b.x.values.reshape(32, ly) - a.x.values[:, None])) < 1e-9 * np.max(np.abs(a.x.values))


@pytest.mark.parametrize("geometry,mode", [("slab", (1, 0)), ("slab", (2, 3)), ("halfspace", (0, 1))])
def test_slab_fourier_mode_rings_at_its_frequency(geometry, mode):
    """No contacts, steady sliding plus one Fourier mode of amplitude A: the mode is a damped
    oscillator, A e^{-gamma t/2} (cos w_d t + gamma/(2 w_d) sin w_d t), w**2 = a**2 k(q)/m,
    gamma = c_s/a. Checked at the end against the scheme's first-order error (halved with dt)."""
    lx, ly = 16, 8
    errs = []
    for dt in (2e-9, 1e-9):
        cfg = make_config(N=lx, Ly=ly, geometry=geometry, dt=dt, t_total=4e-7, output_interval=1e-8, start="steady",
                          integrator="fixed")
        system = build_system(cfg, np.array([0]), np.array([cfg.v0]))
        system = type(system)(cfg, np.zeros(0, np.int64), np.zeros(0))
        st = initial_state(system)
        ix, iy = np.meshgrid(np.arange(lx), np.arange(ly), indexing="ij")
        amp = 1e-9
        st.x[:] = amp * np.cos(2 * np.pi * (mode[0] * ix / lx + mode[1] * iy / ly)).ravel()
        ds = sc.simulate(system, st)
        k = elastic_kernel(cfg)[mode[0], mode[1]]
        w0, g = math.sqrt(k / cfg.m), cfg.radiation_damping_rate
        wd = math.sqrt(w0**2 - g**2 / 4)
        t = ds.attrs["steps"] * dt
        expect = amp * math.exp(-g * t / 2) * (math.cos(wd * t) + g / (2 * wd) * math.sin(wd * t))
        got = (ds.x.values - cfg.v_d * t).reshape(lx, ly)
        shape = np.cos(2 * np.pi * (mode[0] * ix / lx + mode[1] * iy / ly))
        errs.append(np.max(np.abs(got - expect * shape)) / amp)
    assert errs[1] < 0.6 * errs[0] + 1e-9 and errs[1] < 0.05, errs


def test_slab_uniform_mode_from_rest_agrees_with_an_ode_solver():
    """Identical contacts on every block, from rest: the slab moves as one block,
    m x'' = a**2 k(0) (v_d t - x) - m gamma (x' - v_d) - f(x'), k(0) = (H/G + 1/kappa_d)**-1.
    f_d(t) = a**2 k(0) (v_d t - x) against scipy's Radau at 1e-10, within the scheme's O(dt)."""
    cfg = make_config(N=8, Ly=4, geometry="slab", theta=1.0, delta=0.0, t_total=2e-4, output_interval=1e-6,
                      dt=1e-8)
    ds = sc.run(cfg)
    law = cfg.contact_law
    k0 = cfg.a**2 * uniform_stiffness(cfg)
    g = cfg.radiation_damping_rate

    def rhs(t, y):
        x, u = y
        return [u, (k0 * (cfg.v_d * t - x) - cfg.m * g * (u - cfg.v_d) - float(law.force(u, cfg.v0))) / cfg.m]

    t = ds.time.values
    sol = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0], method="Radau", rtol=1e-10, atol=1e-20, dense_output=True)
    # f_d is the mean over each output interval: compare with the interval mean of the exact force
    tt = np.linspace(t - 1e-6, t, 21)
    exact = np.mean(k0 * (cfg.v_d * tt - sol.sol(tt.ravel())[0].reshape(tt.shape)), axis=0)
    assert np.max(np.abs(ds.f_d.values - exact)) < 2e-3 * np.max(np.abs(exact))
    assert ds.attrs["check_energy_balance_passed"] == 1


@pytest.mark.parametrize("geometry", ["chain2d", "slab", "halfspace"])
def test_energy_balance_with_random_contacts(geometry):
    """Stick-slip on a 16 x 8 interface: the stored energy changes by the drive's work minus what
    damping and contacts dissipate (results.checks) within the scheme's O(dt) (the fixed step at
    2e-8 s; the default adaptive step in tests/physics/test_matrix.py)."""
    ds = sc.run(dict(N=16, Ly=8, geometry=geometry, theta=0.3, t_total=1e-3, start="steady", integrator="fixed"))
    assert ds.attrs["check_energy_balance_passed"] == 1, ds.attrs["message"]
    assert ds.attrs["check_energy_balance"] < 1e-3
    assert np.isfinite(ds.attrs["mu_star"]) and ds.sizes["block"] == 128


def test_geometry_keys_keep_chain_member_ids_and_name_bad_values():
    """geometry = 'chain' and Ly = 1 are the defaults: left out of ids and TOML (stores stay valid);
    bad combinations name the key and what is allowed."""
    cfg = make_config()
    assert member_id(cfg) == member_id(make_config(geometry="chain", Ly=1))
    assert "geometry" not in cfg.to_toml() and "Ly" not in cfg.to_toml()
    two_d = make_config(geometry="slab", Ly=4, N=8)
    assert member_id(two_d) != member_id(two_d.with_updates(geometry="halfspace"))
    assert 'geometry = "slab"' in two_d.to_toml()
    for bad, words in [(dict(Ly=4), "'Ly' has value 4; expected 1 with geometry = 'chain'"),
                       (dict(geometry="halfspace", dead_weight=0.9), "'dead_weight' has value 0.9; expected a combination that runs: a half-space has no top"),
                       (dict(geometry="slab", N=8, E=1e11, dt=2e-8), "largest stable step"),
                       (dict(geometry="torus"), "'geometry'"),
                       (dict(geometry="chain2d", Ly=0), "'Ly'")]:
        with pytest.raises(ConfigError, match=words.replace("*", r"\*").replace("(", r"\(")):
            make_config(**bad)


def test_gpu_backend_refuses_chain2d_and_needs_cupy_for_the_slab():
    """The CUDA kernel is the chain's: chain2d on it is an error that says so; the slab goes to the
    array code on CuPy, which names the extra to install where CuPy is missing (numba's CUDA
    simulator stands in for the GPU here, as in tests/physics/test_backends.py)."""
    with pytest.raises(RuntimeError, match="geometry = 'chain2d' runs on the CPU only"):
        sc.run(dict(N=8, Ly=4, geometry="chain2d", t_total=1e-5, integrator="fixed"), backend="gpu")
    try:
        import cupy  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="gpu-fft"):
            sc.run(dict(N=8, Ly=4, geometry="slab", t_total=1e-5, integrator="fixed"), backend="gpu")


@pytest.mark.parametrize("geometry", ["slab", "halfspace"])
def test_array_code_agrees_with_the_numba_loop(geometry):
    """The slab written once in array operations (engine/backends/arrays.py: the code CuPy runs on a
    GPU), here on NumPy + scipy.fft, against the numba loop: two independent implementations, the
    same run to 1e-8 (their contact solvers stop at different tolerances, ~1e-9 per step), a batch
    of two rows with different theta and v_d at once."""
    from slipchain.engine.backends.arrays import ArrayBackend

    cfgs = [make_config(geometry=geometry, N=8, Ly=4, theta=th, v_d=v, t_total=1e-4, start="steady", integrator="fixed",
                        output_interval=1e-5, seed=s) for th, v, s in ((0.5, 1e-3, 1), (1.0, 3e-4, 2))]
    systems = [build_system(c) for c in cfgs]
    ref = sc.simulate_batch(systems)
    got = sc.simulate_batch(systems, backend=ArrayBackend())
    for a, b in zip(ref, got):
        assert _rel(a.f_d.values, b.f_d.values) < 1e-8
        assert np.max(np.abs(a.x.values - b.x.values)) < 1e-8 * np.max(np.abs(a.x.values))
        assert abs(a.attrs["mu_star"] / b.attrs["mu_star"] - 1) < 1e-8
        assert b.attrs["check_energy_balance_passed"] == 1


def _placed(layout, n, k):
    """``k`` read arrays and ``k`` written arrays of ``n`` doubles in one buffer: 'interleaved' puts each written
    array right after a read array (within the wrapped range numba's negative-index handling adds past a read
    array's end, where the vectorised loop's alias check once saw a conflict), 'written-first' puts every written
    array before every read array (no conflict in either check)."""
    buf = np.empty(2 * k * n)
    blocks = [buf[j * n:(j + 1) * n] for j in range(2 * k)]
    if layout == "interleaved":
        return blocks[0::2], blocks[1::2]
    return blocks[k:], blocks[:k]


@pytest.mark.parametrize("lx, ly", [(1, 1), (1, 5), (4, 1), (2, 2), (3, 7), (64, 64)])
def test_lattice_neighbours_are_the_periodic_lattice_neighbours(lx, ly):
    """The 2-D stencils' shared index helper against numpy's periodic shifts of the row-major (Lx, Ly) index grid
    (block ix*Ly + iy; ip/im along x, jp/jm along y), and unsigned (the reason it exists: docs/performance.md)."""
    from slipchain.engine.backends.cpu import lattice_neighbours

    grid = np.arange(lx * ly).reshape(lx, ly)
    want = [grid, np.roll(grid, -1, 0), np.roll(grid, 1, 0), np.roll(grid, -1, 1), np.roll(grid, 1, 1)]
    for ix in range(lx):
        for iy in range(ly):
            got = lattice_neighbours(ix, iy, lx, ly)
            assert [int(g) for g in got] == [int(w[ix, iy]) for w in want]
    # unsigned in the compiled code (Python sees ints): numba's return type for int64 arguments
    assert {str(sig.return_type) for sig in lattice_neighbours.nopython_signatures} == {"UniTuple(uint64 x 5)"}


@pytest.mark.parametrize("kernel", ["explicit_forces_2d", "bulk_forces"])
def test_chain2d_stencil_bits_do_not_follow_where_its_arrays_lie(kernel):
    """The 2-D chains' stencil gives the same bits whatever lies after its arrays: with signed neighbour indices
    the vectorised inner loop's runtime alias check also covered a wrapped range past each read array's end, so a
    written array there sent the row to the scalar loop, which associates the sums otherwise (a 64 x 64 chain2d
    run's last bits followed its worker's heap; docs/performance.md). Ly = 64: a row long enough to vectorise."""
    from slipchain.engine.backends import cpu
    from slipchain.engine.backends import viscoelastic as ve

    ly, n = 64, 64 * 64
    vals = np.random.default_rng(7).standard_normal((4, n)) * np.array([[1.0], [1e-3], [1.0], [1e-3]])
    outs = {}
    for layout in ("interleaved", "written-first"):
        if kernel == "explicit_forces_2d":
            rd, wr = _placed(layout, n, 4)
            for a, v in zip(rd, vals):
                a[:] = v
            s = cpu._explicit_forces_2d(ly, *rd, *wr, 1.3, 0.7, 0.9, 0.1, 1.1, 0.6, 0.37, 0.2, 0.05, 1e-3, 2e-4)
            outs[layout] = [w.copy() for w in wr] + [np.array([s])]
        else:
            rd, wr = _placed(layout, n, 2)
            for a, v in zip(rd, vals[::2]):
                a[:] = v
            ve.bulk_forces(ly, *rd, *wr, 1.3, 0.7, 0.9, 1.1, 0.6)
            outs[layout] = [w.copy() for w in wr]
    for a, b in zip(outs["interleaved"], outs["written-first"]):
        assert a.tobytes() == b.tobytes(), np.flatnonzero(a != b)[:8]


def test_chain2d_stencils_vectorise_without_wrapped_alias_bounds(monkeypatch):
    """The static side of the test above: in the IR of both stencils no vectorised loop's alias check takes a bound
    from a 1-D array's length (the wrapped range of a possibly negative index; benchmarks/alias_scan.py's rule, which
    flags the old ``_explicit_forces_2d`` by exactly its four read arrays)."""
    from pathlib import Path

    from slipchain.engine.backends import cpu
    from slipchain.engine.backends import viscoelastic as ve

    monkeypatch.syspath_prepend(str(Path(__file__).parents[2] / "benchmarks"))  # undone after the test
    from alias_scan import wrapped_bounds

    n = 64 * 64
    a = [np.zeros(n) for _ in range(8)]
    cpu._explicit_forces_2d(64, *a, 1.3, 0.7, 0.9, 0.1, 1.1, 0.6, 0.37, 0.2, 0.05, 1e-3, 2e-4)
    ve.bulk_forces(64, *a[:4], 1.3, 0.7, 0.9, 1.1, 0.6)
    for kernel in (cpu._explicit_forces_2d, ve.bulk_forces):
        irs = [kernel.inspect_llvm(sig) for sig in kernel.signatures]
        # (whether LLVM vectorises the row loop at all follows the CPU: no check, nothing to follow the heap)
        assert not any(wrapped_bounds(ir) for ir in irs), kernel

"""The slab's Fourier-space stiffness (issue 13, first part): closed forms against the layer's
boundary-value problem, and the limits the issue names."""

import numpy as np
import pytest
from scipy.linalg import expm

from slipchain.model.elastic import (QH_HALFSPACE, halfspace_kernel, k_halfspace, k_psv, k_psv_bvp, k_sh,
                                     slab_kernel)

G, H = 1e7 / 3, 5e-4  # the paper's rubber (E = 10 MPa, nu = 1/2) and N_L a = 0.5 mm
KAPPA = 333.0 / 1e-8  # K_d / a**2
QH = np.array([1e-3, 0.05, 0.3, 1.0, 2.0, 5.0, 10.0, 15.0, 19.0])


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.49, 0.5])
def test_psv_closed_form_equals_the_boundary_value_problem(nu):
    q = QH / H
    assert k_psv(q, H, G, nu) == pytest.approx(k_psv_bvp(q, H, G, nu), rel=1e-11)


def _k_sh_bvp(q, kappa=None):
    """Anti-plane layer, independently: U' = S/G, S' = G q^2 U; U(0) = 1; top U = 0 or S = -kappa U."""
    out = []
    for qi in np.atleast_1d(q):
        P = expm(np.array([[0.0, 1.0 / G], [G * qi * qi, 0.0]]) * H)
        row = P[0] if kappa is None else P[1] + kappa * P[0]
        out.append(-(-row[0] / row[1]))  # S0 from row . (1, S0) = 0; k = -S0
    return np.array(out)


@pytest.mark.parametrize("kappa", [None, KAPPA, 1e3 * KAPPA])
def test_sh_closed_forms_equal_the_boundary_value_problem(kappa):
    q = QH / H
    assert k_sh(q, H, G, kappa) == pytest.approx(_k_sh_bvp(q, kappa), rel=1e-11)


@pytest.mark.parametrize("nu", [0.3, 0.5])
def test_limits_uniform_shear_half_space_and_stiff_springs(nu):
    q_small = np.array([1e-9, 1e-6]) / H
    for f in (lambda q, kap: k_sh(q, H, G, kap), lambda q, kap: k_psv(q, H, G, nu, kap)):
        # q -> 0: the layer's shear G/H, in series with the springs when the top is on springs
        assert f(q_small, None) == pytest.approx(G / H, rel=1e-5)
        assert f(q_small, KAPPA) == pytest.approx(1 / (H / G + 1 / KAPPA), rel=1e-5)
        assert f(np.array([0.0]), KAPPA)[0] == pytest.approx(1 / (H / G + 1 / KAPPA), rel=1e-15)
        # springs much stiffer than the layer: the clamped top
        q = QH / H
        assert f(q, 1e30) == pytest.approx(f(q, None), rel=1e-10)
        # springs soften every mode, less the shorter its wavelength
        soft, hard = f(q, KAPPA), f(q, None)
        assert np.all(soft[QH <= 5] < hard[QH <= 5]) and np.all(soft <= hard * (1 + 1e-12))
        assert soft[-1] / hard[-1] == pytest.approx(1.0, abs=1e-12)
    # qH -> inf: the half-space, G q/(1-nu) and G q, continuous across the switch to it
    for kap in (None, KAPPA):
        for side in (1 - 1e-9, 1 + 1e-9):
            q = np.array([QH_HALFSPACE * side]) / H
            kp_h, ks_h = k_halfspace(q, G, nu)
            assert k_psv(q, H, G, nu, kap) == pytest.approx(kp_h, rel=1e-13)
            assert k_sh(q, H, G, kap) == pytest.approx(ks_h, rel=1e-13)
    # rubber: nu = 1/2 is the limit of nu -> 1/2
    if nu == 0.5:
        q = QH / H
        assert k_psv(q, H, G, 0.5) == pytest.approx(k_psv(q, H, G, 0.5 - 1e-9), rel=1e-7)


def _k_psv_displacement_form(q, nu, kappa):
    """The in-plane layer in another formulation: state (U, U', W, W') of the Navier equations with
    lambda (so nu < 1/2), top tangential springs and W(H) = 0, bottom U = 1 and sigma_zz = 0."""
    lam = 2 * G * nu / (1 - 2 * nu)
    out = []
    for qi in np.atleast_1d(q):
        M = np.zeros((4, 4))
        M[0, 1], M[2, 3] = 1.0, 1.0
        M[1, 0], M[1, 3] = qi * qi * (1 + (lam + G) / G), -(lam + G) / G * qi
        M[3, 2], M[3, 1] = G * qi * qi / (lam + 2 * G), (lam + G) * qi / (lam + 2 * G)
        P = expm(M * H)
        spring = G * P[1] + G * qi * P[2] + kappa * P[0]  # sigma_xz(H) + kappa U(H) = 0
        A = np.array([[0.0, 0.0, lam + 2 * G], P[2, 1:], spring[1:]])
        a = np.linalg.solve(A, np.array([lam * qi, -P[2, 0], -spring[0]]))
        out.append(-G * (a[0] + qi * a[1]))
    return np.array(out)


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.49])
def test_psv_on_springs_agrees_with_a_second_formulation(nu):
    q = QH[QH <= 10] / H
    for kap in (KAPPA, 30 * KAPPA):
        assert k_psv(q, H, G, nu, kap) == pytest.approx(_k_psv_displacement_form(q, nu, kap), rel=1e-9)


def test_kernel_combines_the_two_modes_by_direction():
    q = np.linspace(0, 40 / H, 9)
    assert slab_kernel(q, 0 * q, H, G, 0.5, KAPPA) == pytest.approx(k_psv(q, H, G, 0.5, KAPPA), rel=1e-14)
    assert slab_kernel(0 * q, q, H, G, 0.5, KAPPA) == pytest.approx(k_sh(q, H, G, KAPPA), rel=1e-14)
    qx, qy = np.meshgrid(np.fft.fftfreq(16, 1e-4) * 2 * np.pi, np.fft.rfftfreq(16, 1e-4) * 2 * np.pi, indexing="ij")
    k = slab_kernel(qx, qy, H, G, 0.5, KAPPA)
    assert k[0, 0] == pytest.approx(1 / (H / G + 1 / KAPPA))
    assert np.allclose(k, slab_kernel(-qx, qy, H, G, 0.5, KAPPA), rtol=1e-14)
    # at 45 degrees the mean of the two modes
    d = np.array([10.0 / H]) / np.sqrt(2)
    mean = 0.5 * (k_psv(np.hypot(d, d), H, G, 0.5) + k_sh(np.hypot(d, d), H, G))
    assert slab_kernel(d, d, H, G, 0.5) == pytest.approx(mean, rel=1e-14)
    # the half-space: k(0) from the drive springs, G q/(1-nu) along x and G q along y elsewhere
    kh = halfspace_kernel(qx, qy, G, 0.5, KAPPA)
    assert kh[0, 0] == KAPPA and kh[3, 0] == pytest.approx(G * abs(qx[3, 0]) / 0.5)
    assert kh[0, 3] == pytest.approx(G * qy[0, 3])


def test_elastic_force_of_single_modes_and_of_a_uniform_shift():
    from slipchain.model.elastic import elastic_force, wavenumbers

    a, Lx, Ly = 1e-4, 16, 8
    qx, qy = wavenumbers(Lx, Ly, a)
    k = slab_kernel(qx, qy, H, G, 0.5, KAPPA)
    i, j = np.meshgrid(np.arange(Lx), np.arange(Ly), indexing="ij")
    # a uniform displacement against the drive: every block feels -a^2 k(0) (u - X)
    f = elastic_force(np.full((Lx, Ly), 3e-9), 1e-9, k, a)
    assert np.allclose(f, -a * a * k[0, 0] * 2e-9, rtol=1e-12, atol=0)
    # a single Fourier mode cos(qx x + qy y) is an eigenfunction: the force is -a^2 k(q) times it
    for mx, my in ((1, 0), (0, 2), (3, 1), (Lx // 2, 0)):
        u = 1e-9 * np.cos(2 * np.pi * (mx * i / Lx + my * j / Ly))
        kq = float(slab_kernel(2 * np.pi * mx / (Lx * a), 2 * np.pi * my / (Ly * a), H, G, 0.5, KAPPA))
        f = elastic_force(u, 0.0, k, a)
        assert np.max(np.abs(f + a * a * kq * u)) <= 1e-12 * np.max(np.abs(f))
    # linear, and the net force is that of the mean displacement alone (k(0))
    rng = np.random.default_rng(0)
    u1, u2 = rng.normal(size=(2, Lx, Ly)) * 1e-9
    f1, f2 = elastic_force(u1, 0.0, k, a), elastic_force(u2, 0.0, k, a)
    assert np.max(np.abs(elastic_force(u1 + 2 * u2, 0.0, k, a) - (f1 + 2 * f2))) <= 1e-12 * np.max(np.abs(f1))
    assert f1.sum() == pytest.approx(-a * a * k[0, 0] * u1.sum(), rel=1e-10)


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.5])
def test_two_port_gives_back_the_clamped_and_the_sprung_kernels(nu):
    """The slab's two-port (issue 28): A is the clamped kernel; eliminating the top, held by springs kappa,
    channel by channel gives the series kernel of the boundary-value problem; the P-SV solve's two
    off-diagonal entries agree (reciprocity, not assumed by the solve); q -> 0 is the uniform shear."""
    from slipchain.model.elastic import _psv_twoport_full, slab_kernel, slab_twoport, wavenumbers

    H, G, kappa = 1e-3, 3e6, 2e9
    qx, qy = wavenumbers(16, 8, 1e-4)
    A, BP, BS, DP, DS = slab_twoport(qx, qy, H, G, nu)
    assert A == pytest.approx(slab_kernel(qx, qy, H, G, nu), rel=1e-11)
    q2 = qx * qx + qy * qy
    wp = np.where(q2 > 0, qx * qx / np.where(q2 > 0, q2, 1.0), 1.0)
    ws = 1.0 - wp
    k12p = np.divide(BP, wp, out=np.zeros_like(BP), where=wp > 0)
    k12s = np.divide(BS, ws, out=np.zeros_like(BS), where=ws > 0)
    series = A - wp * k12p**2 / (DP + kappa) - ws * k12s**2 / (DS + kappa)
    assert series == pytest.approx(slab_kernel(qx, qy, H, G, nu, kappa), rel=1e-10)
    assert (A[0, 0], BP[0, 0], DP[0, 0]) == pytest.approx((G / H, -G / H, G / H))
    q = np.array([3e2, 3e3, 1e4])  # qH = 0.3, 3, 10
    k11, k12, k21, k22 = _psv_twoport_full(q, H, G, nu)
    assert k12 == pytest.approx(k21, rel=1e-7)
    assert np.all(k11 * k22 > k12 * k21) and np.all(k11 > 0)  # positive definite (K12 changes sign with qH in P-SV)

"""The slab and half-space geometries on the CPU (issue 13): elastic force by FFT, contacts by numba.

The interface is an (Lx, Ly) periodic grid of blocks (mass m) on the bottom face of a quasi-static
elastic body; the body's force on the blocks is ``-IFFT[a**2 k(q) FFT(x - v_d t)]``
(:func:`slipchain.model.elastic.elastic_force`, k from :mod:`slipchain.model.elastic`), with the
radiation damping ``-m gamma (u - v_d)``, ``gamma = c_s/a`` (G/c_s per area, relative to the
slider's body moving with the drive). Equation of motion of block i::

    m du_i/dt = F_el,i - m gamma (u_i - v_d) - f(u_i, v*_i) [if i carries a contact]

Step n -> n+1 (the chain's scheme, :mod:`slipchain.engine.scheme`, with the elastic force in
place of the springs):

1. F_el from x^n: one batched ``rfft2``/``irfft2`` pair for all rows (scipy.fft), the drive's
   uniform displacement added to the q = 0 mode alone (a**2 k(0) v_d t on every block);
2. u^{n+1} = u^n + dt/m (F_el - m gamma (u^n - v_d)) for every block (numba, :func:`body_explicit`);
3. contact blocks: the chain's implicit contact solve (:func:`.cpu._contacts`);
4. x^{n+1} = x^n + dt u^{n+1}; the works: drive a**2 k(0) (N v_d t - sum x^n) v_d dt (the uniform
   mode of the elastic force is what the drive transmits), damping, contacts.

The drive force per block, f_d = a**2 k(0) (v_d t - <x>), is what mu_star averages. Explicit, so
``Config`` requires dt below the stable step of the modes, h**2 omega**2 + 2 h gamma < 4
(:mod:`slipchain.model.stability`).

**Dead weight** (issue 26): the top is a rigid plate, carried by the applied force F_b per block
instead of the drive springs, with the slab's mass N_L m per block (the chain's upper layer under
the dead weight; ``X``, ``U`` of every block hold the plate's displacement and velocity, so that
the slider's position <X> is read as in the chain). The body's force on the blocks is then
``-IFFT[a**2 k_c(q) FFT(x - X)]`` with k_c the kernel of the clamped top (the plate moves
uniformly: every q != 0 mode sees the top held), the radiation damping is relative to the plate,
``-m gamma (u_i - U)``, and the plate moves by the reactions::

    N_L m dU/dt = F_b - <F_el> + m gamma (<u> - U)

**Composition** (issue 26): this module is the slab's body (:func:`body_explicit`,
:func:`body_commit`); its FFT driver is :func:`.compose.fft_advance`; the steppers (fixed, fold, adaptive),
the contacts and the per-row loop are the chains' own, composed in :mod:`.compose`. With the
adaptive step the rows advance in lock-step, one accepted step per FFT, a rejected step retried at
once (the positions, hence the elastic force, have not moved).
"""

from __future__ import annotations

import math

import numba as nb

from ..scheme import A_WCONTACT, FASTMATH, O_FD, O_XMEAN, O_XUMEAN, P_FCONST, P_KD, P_M, P_META, P_ML, P_VD


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def body_explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, t):
    """The slab's body, explicit part (:mod:`.compose`; module docstring, step 2) for one row with
    parameters ``p``, a step h at drive time t, given -IFFT[a**2 k FFT(x)] in ``Fr`` (spring drive:
    the drive, uniform, enters through k(0) = ``k0`` alone) or -IFFT[a**2 k_c FFT(x - X)] (dead
    weight): the blocks' new velocities (contacts not yet applied) in ``un``, damping forces in
    ``dampx``, the plate's new velocity in every entry of ``Un`` (dead weight; the spring drive has
    no upper layer: ``Un`` = ``Ur`` = 0); returns the drive force sum (spring drive; 0 with the
    dead weight, whose work the run's energy balance takes from the plate's displacement)."""
    n = xr.size
    m = p[P_M]
    meta = p[P_META]
    dtm = h / m
    if p[P_KD] == 0.0:  # dead weight: the plate moves by the reactions
        up = Ur[0]
        sf = 0.0
        su = 0.0
        # The sums in a loop of their own, which writes nothing: in a loop that also writes un and dampx
        # LLVM guards the vectorised body by a run-time check of the arrays' distance in memory and
        # falls back to the scalar loop when two allocations happen to lie close, and with fastmath the
        # two sum in different orders (seen as a resumed run differing in the last bit; issue 30).
        for i in range(n):
            sf += Fr[i]
            su += ur[i]
        for i in range(n):
            d = -meta * (ur[i] - up)
            un[i] = ur[i] + dtm * (Fr[i] + d)
            dampx[i] = d
        unew = up + h / p[P_ML] * (p[P_FCONST] - sf / n + meta * (su / n - up))
        for i in range(n):
            Un[i] = unew
        return 0.0
    vd = p[P_VD]
    f_drive = k0 * vd * t  # the uniform mode's share of the drive, a**2 k(0) v_d t
    sx = 0.0
    for i in range(n):  # the sum on its own (see the dead weight's sums above)
        sx += xr[i]
    for i in range(n):
        d = -meta * (ur[i] - vd)
        un[i] = ur[i] + dtm * (Fr[i] + f_drive + d)
        dampx[i] = d
    for i in range(n):
        Un[i] = Ur[i]
    return k0 * (n * vd * t - sx)


@nb.njit(fastmath=FASTMATH, error_model="numpy")
def body_commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h):
    """The slab's body, commit (:mod:`.compose`; module docstring, step 4): positions from the
    accepted velocities (blocks, and the plate with the dead weight); returns the damping work over
    the step (the dampers act between block and plate, or block and drive) and 0 (no bulk
    viscosity: ``mt``, ``br`` are the material 'prony''s, unused here)."""
    wd = 0.0
    if p[P_KD] == 0.0:
        for i in range(xr.size):  # the work first, in a loop that writes nothing (see body_explicit)
            wd += dampx[i] * (un[i] - Un[i])
        for i in range(xr.size):
            xr[i] += h * un[i]
            ur[i] = un[i]
            Xr[i] += h * Un[i]
            Ur[i] = Un[i]
        return wd * h, 0.0
    for i in range(xr.size):
        wd += dampx[i] * un[i]
    for i in range(xr.size):
        xr[i] += h * un[i]
        ur[i] = un[i]
    return wd * h, 0.0


BODY = (body_explicit, body_commit, True)  # (explicit, commit, fastmath of its fixed loop): .compose


@nb.njit(cache=True)
def end_sample(x, X, status, step, fd, out, s, sample_steps, acc):
    """Record sample s (mean f_d, <x> and <X>: the plate with the dead weight, else 0, there being no
    upper layer) and flag rows that went non-finite."""
    nb_rows, n = x.shape
    for row in range(nb_rows):
        if status[row] >= 0:
            continue
        xs = 0.0
        Xs = 0.0
        for i in range(n):
            xs += x[row, i]
            Xs += X[row, i]
        out[row, s, O_FD] += fd[row] / sample_steps
        out[row, s, O_XMEAN] += xs / n
        out[row, s, O_XUMEAN] += Xs / n
        if not (math.isfinite(fd[row]) and math.isfinite(xs) and math.isfinite(acc[row, A_WCONTACT])):
            status[row] = step[row]
        fd[row] = 0.0


__all__ = ["BODY", "body_commit", "body_explicit", "end_sample"]

"""The CPU engine composed from pieces (issue 26): each piece written once, composed once per
combination into compiled loops.

The pieces, each a numba function with a fixed signature (so that any geometry goes with any
stepper, contact solver and drive):

* **Body** (geometry with today's material: the springs or the elastic kernel, the pair or
  radiation damping, and the drive acting on it): ``explicit(p, Fr, k0, xr, ur, Xr, Ur, un, Un,
  dampx, dampX, h, t) -> drive force sum`` writes every block's new velocity before the contacts
  (steps 1-2 of :mod:`slipchain.engine.scheme`) and the damping forces; ``commit(p, xr, ur, Xr, Ur,
  un, Un, dampx, dampX, h) -> damping work`` moves the positions by the accepted velocities (step 4).
  ``p`` is the row of the (B, P) parameter array, ``Fr`` the body's force from outside the kernel
  (the slab's FFT; empty for the chains), ``k0`` its uniform stiffness, ``t`` the drive's time.
  Two bodies: :data:`LATTICE` (chain, chain2d: :func:`.cpu.lattice_explicit`, :func:`.cpu.lattice_commit`)
  and :data:`SPECTRAL` (slab, half-space: :func:`.spectral.body_explicit`, :func:`.spectral.body_commit`).
  The drive (spring or dead weight) is part of the body's parameters: K_d and F_b on the chains'
  upper layer, the plate of the slab's clamped top (:mod:`.spectral`).
* **Contacts**: :func:`.cpu._contacts`, the implicit solve of every contact block, with the
  fixed-step or the fold-aware solver (the row's P_FOLD).
* **Stepper**: one accepted step of one row, ``step(p, Fr, k0, xr, ur, Xr, Ur, sites, vstar,
  n_contacts, ysolve, folds, control, ctl, aprev, cacc, j, step, sample_steps, rc, *scratch) ->
  (base steps taken, its f_d contribution, contact work, damping work, drive work)``, every array
  the row's, ``j`` the base steps done in the output sample, ``step`` those done in the run, ``rc``
  the row's constants (:func:`~slipchain.engine.scheme.row_parameters`):
  :func:`fixed_stepper` (``fixed``, ``fold``: the step dt) or :func:`adaptive_stepper`
  (``adaptive``: a trial step of length dt 2**k with its error estimate, then commit, or restore
  and retry finer; :mod:`.adaptive`). Each calls the body's explicit part, the contacts, and the
  body's commit; the driver adds up. ``ctl`` (4,) holds the adaptive step's place in its output
  sample (base steps done, level, level whose folds are loaded, whether an estimate exists),
  which every sample starts afresh, so that checkpoints resume bit for bit.
* **Driver**: the loop over rows, samples and steps. :func:`kernel_driver` runs a whole chunk of a
  row in one compiled call (the chains: the body needs nothing from outside); the slab's body needs
  one FFT of every row per step, so its driver (:func:`fft_advance`) alternates the FFT with
  :func:`rows_driver`, one step of every live row; with its explicit steppers (no top of its own) the whole chunk is
  one compiled call with its FFTs inside (:func:`fft_chunk_driver`, numpy.fft compiled by rocket-fft), and
  the implicit stepper's explicit steps between two tries are one compiled call per row
  (:func:`krylov_explicit_driver`).

:func:`loop` gives the compiled loop of a (geometry, integrator) combination, composed on first use
(numba caches each on disk: a closure over compiled pieces is cached like a function; the pieces it
calls are not cached on their own, :mod:`slipchain.engine.jitcache`). The
capability table (:mod:`slipchain.model.capabilities`) says which combinations run where; on the
CPU every one does. A new material (issue 28) is a new body, a new stepper (issue 27) a new
stepper: neither touches the loops.

Bit for bit: the chains' pieces are compiled as the loops they replace were (the stepper without
fastmath), the slab's explicit part and commit with fastmath as its fixed-step loop was.
"""

from __future__ import annotations

import functools

import numba as nb
import numpy as np

from ...model.geometries import GEOMETRIES
from ...model.elastic import parseval_weights
from ...model.viscoelastic import arm_kernel
from ..scheme import (A_WCONTACT, BODY_ROWS, A_WDAMP, A_WDRIVE, A_WVISC, FASTMATH, N_ACC, N_CACC, N_OUT, N_YS_STATE, P_AMP, P_C, P_DT,
                      P_ETAC, P_FOLD, P_KD, P_M, P_SLOW, P_VD)
from ..jitcache import stable_cache
from . import implicit, spectral, viscoelastic
from .pocketfft import fft_module, numba_fft
from .adaptive import (STEP_UP, _copy_solver_state, _error, _grid_level, _keep_acceleration, _load_folds,
                       _rejected_level, _weighted_contact_sums)
from .base import N_CARRY, N_CONTROL, Batch, ChunkOutput
from .cpu import _contact_sums, _contacts, _end_sample, _refresh_solver, lattice_commit, lattice_explicit, row_parameters

# ctl columns: the row's place in its output sample; the implicit stepper's back-off (explicit steps
# to wait before the next backward-Euler try, and the current wait after a failed one)
CT_J, CT_LEVEL, CT_LOADED, CT_HAVE, CT_WAIT, CT_BACKOFF = range(6)
N_CT = 6
MAX_BACKOFF = 1024
# an implicit step (a Newton solve, ~10 explicit steps' cost) pays only this many doublings above the explicit top
MIN_GAIN = 3
# The Krylov driver's cost rule (slab, half-space, chain2d): a backward-Euler try there costs a number of
# operator applications that varies by orders of magnitude (each conjugate-gradient iteration one FFT pair),
# so whether it pays is counted, not guessed from its level: in units of one explicit step (one FFT pair
# and the Python around it), a try costs KRYLOV_TRY_UNITS plus one per Newton and per conjugate-gradient
# iteration (two with krylov_preconditioner = 'additive', whose inverse is a second FFT pair; calibrated
# on a 16 x 16 slab, this project's 2-core machine: a try 2.4 ms, an explicit step 54 us, a
# conjugate-gradient iteration about as much). An accepted implicit step whose tries since the last
# one cost more units than the explicit steps at the explicit top that would cover its base steps (one per
# 2**top base steps), and that the controller does not step up from, hands back to the explicit steps,
# which then wait 1, 2, 4, ... MAX_BACKOFF explicit steps (doubling within a sample) before the next try.
# Counted, not timed: the choice, hence the result, is the same on every machine and after a resume.
KRYLOV_TRY_UNITS = 6.0
# control columns (Batch.step_control, N_CONTROL of them): tolerance (m/s), the adaptive step's top level, steps
# accepted, rejected, the implicit stepper's top level (:mod:`.implicit`), the last accepted step's error estimate,
# the implicit stepper's energy tolerance (Config.energy_tol: a step's energy residual at most this fraction of its works)
CTRL_TOP_IMPLICIT, CTRL_ERR, CTRL_ENERGY = 4, 5, 6


def fixed_stepper(explicit, commit, fastmath: bool):
    """The fixed step (integrators 'fixed', 'fold') of one row, composed with a body; compiled with
    the body's loop flags (``fastmath``: the slab's loop was)."""
    flags = dict(fastmath=FASTMATH, error_model="numpy") if fastmath else {}

    @nb.njit(cache=True, inline="always", **flags)
    def step(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, j, nstep, sample_steps, rc,
             scratch):
        un, Un, dampx, dampX, rk, ra, uk, fk, ok, ysave = scratch
        K, KL, KT, Kd, m, meta, vd, fconst, dt, dtm, dtmL, bc, c, m_eff, slow = rc
        fsum = explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, dt, nstep * dt)
        _contacts(nc, un, st, rk, ra, uk, fk, ok, vs, ys, m, m_eff, bc, c, 1.0 / dt, p[P_FOLD] > 0.0)
        w_contact = _contact_sums(nc, fk, uk, ca, slow) * dt
        w_damp, w_visc = commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, dt)
        return 1, fsum / xr.size, w_contact, w_damp, fsum * vd * dt, w_visc

    return step


def fixed_sample(explicit, commit, fastmath: bool):
    """One output sample of one row by the fixed step: :func:`fixed_stepper`'s step in a counted
    loop, the step written out (not called), so that the row's arrays are bound once per sample and
    not once per step (numba counts a reference for each array argument of an inlined call).
    ``wc, wd, wdr, wv``: the row's running contact, damping, drive and bulk works, returned with the
    sample's added step by step (the same sums, bit for bit, as a loop over steps in the driver).
    Returns (base steps, sum of f_d contributions, the four works)."""
    flags = dict(fastmath=FASTMATH, error_model="numpy") if fastmath else {}

    @nb.njit(**flags)
    def sample(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, nstep, sample_steps, rc,
               scratch, wc, wd, wdr, wv):
        un, Un, dampx, dampX, rk, ra, uk, fk, ok, ysave = scratch
        K, KL, KT, Kd, m, meta, vd, fconst, dt, dtm, dtmL, bc, c, m_eff, slow = rc
        fold = p[P_FOLD] > 0.0
        inv_dt = 1.0 / dt
        n = xr.size
        fds = 0.0
        for i in range(sample_steps):
            fsum = explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, dt, (nstep + i) * dt)
            _contacts(nc, un, st, rk, ra, uk, fk, ok, vs, ys, m, m_eff, bc, c, inv_dt, fold)
            wc -= _contact_sums(nc, fk, uk, ca, slow) * dt
            dwd, dwv = commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, dt)
            wd += dwd
            wv += dwv
            wdr += fsum * vd * dt
            fds += fsum / n
        return sample_steps, fds, wc, wd, wdr, wv

    return sample


def step_sample(stepper):
    """One output sample of one row by repeated steps of ``stepper`` (the adaptive and implicit
    steppers: each step takes one or more base steps), from the sample's start. Arguments and
    returns as :func:`fixed_sample`."""

    @nb.njit
    def sample(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, nstep, sample_steps, rc,
               scratch, wc, wd, wdr, wv):
        fds = 0.0
        j = 0
        for _ in range(sample_steps):  # every step takes at least one base step (a counted loop: faster)
            if j >= sample_steps:
                break
            w, dfd, dwc, dwd, dwdr, dwv = stepper(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap,
                                                  ca, j, nstep + j, sample_steps, rc, scratch)
            wc -= dwc
            wd += dwd
            wdr += dwdr
            wv += dwv
            fds += dfd
            j += w
        return j, fds, wc, wd, wdr, wv

    return sample


def adaptive_stepper(explicit, commit):
    """One accepted adaptive step of one row (:mod:`.adaptive`: levels h = dt 2**k on the fixed
    step's time grid, the error from consecutive accelerations, rejection and restore), composed
    with a body."""

    @nb.njit(cache=True, inline="always")
    def step(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, j, nstep, sample_steps, rc,
             scratch):
        un, Un, dampx, dampX, rk, ra, uk, fk, ok, ysave = scratch
        K, KL, KT, Kd, m, meta, vd, fconst, dt0, _, _, _, c, _, slow = rc
        amp = p[P_AMP]
        etac = p[P_ETAC]
        tol = ctrl[0]
        top = int(ctrl[1])
        n = xr.size
        while True:
            lv = _grid_level(cr[CT_LEVEL], j, sample_steps)
            if lv != cr[CT_LOADED]:
                _load_folds(nc, ys, fr[lv])
                cr[CT_LOADED] = lv
            w = 1 << lv
            h = dt0 * w
            fsum = explicit(p, Fr, k0, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h, nstep * dt0)
            if lv > 0:  # keep the contacts' solver state: the step may be rejected
                _copy_solver_state(nc, ys, ysave)
            _contacts(nc, un, st, rk, ra, uk, fk, ok, vs, ys, m, m * (1.0 + h * etac), h * amp, c, 1.0 / h, True)
            err = _error(n, ur, Ur, un, Un, ap, h) if cr[CT_HAVE] > 0 else 0.0
            if lv > 0 and err > tol:  # rejected (a slip event starts): again from the same state, finer
                _copy_solver_state(nc, ysave, ys)
                cr[CT_LEVEL] = _rejected_level(lv, err, tol)
                ctrl[3] += 1.0
                continue
            _keep_acceleration(n, ur, Ur, un, Un, ap, h)
            w_contact = _weighted_contact_sums(nc, fk, uk, ca, slow, w) * h
            w_damp, w_visc = commit(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h)
            ctrl[2] += 1.0
            ctrl[CTRL_ERR] = err
            if cr[CT_HAVE] > 0 and err < STEP_UP * tol and lv < top:
                lv += 1
            cr[CT_LEVEL] = lv
            cr[CT_HAVE] = 1
            return w, fsum / n * w, w_contact, w_damp, fsum * vd * h, w_visc

    return step


@nb.njit
def _back_off(cr):
    """Back from backward Euler to the explicit steps: wait twice as many explicit steps as last time
    (1, 2, 4, ... at most MAX_BACKOFF) before the next implicit try."""
    cr[CT_BACKOFF] = min(max(1, 2 * cr[CT_BACKOFF]), MAX_BACKOFF)
    cr[CT_WAIT] = cr[CT_BACKOFF]


# what :func:`implicit_plan` says the next step is: explicit at the top level (the sample's last few base steps),
# explicit (the adaptive step's levels), or a backward-Euler try
PLAN_TAIL, PLAN_EXPLICIT, PLAN_IMPLICIT = 0, 1, 2


@nb.njit
def implicit_plan(cr, ctrl, j, sample_steps):
    """The implicit stepper's next step (:mod:`.implicit`): (what, level, base steps). An implicit step
    needs no time grid (it has no folds per level): any whole number of base steps up to dt 2**level
    that ends within the sample; the sample's last few base steps are explicit (PLAN_TAIL)."""
    top_explicit = int(ctrl[1])
    want = min(cr[CT_LEVEL], int(ctrl[CTRL_TOP_IMPLICIT]))  # the controller's level
    w = min(1 << want, sample_steps - j)
    if want > top_explicit and w <= (1 << top_explicit):
        return PLAN_TAIL, want, w
    if want <= top_explicit:
        return PLAN_EXPLICIT, want, w
    return PLAN_IMPLICIT, want, w


@nb.njit
def after_explicit(cr, ctrl, was, nc, ys):
    """After an explicit step at the adaptive levels: count down the back-off, or, at the explicit top
    with a small error and every contact on the rising branch, let the next step be implicit."""
    top_explicit = int(ctrl[1])
    if cr[CT_WAIT] > 0:
        cr[CT_WAIT] -= 1
    elif (int(ctrl[CTRL_TOP_IMPLICIT]) > top_explicit and was >= top_explicit and cr[CT_LEVEL] == top_explicit
            and ctrl[CTRL_ERR] < STEP_UP * ctrl[0] and implicit.rising(nc, ys)):
        cr[CT_LEVEL] = top_explicit + 1


@nb.njit
def implicit_verdict(cr, ctrl, its, err, bal, scale, lv, cut):
    """A backward-Euler try of level ``lv`` (``its`` Newton iterations, -1: not takeable; error
    estimate ``err``; energy residual ``bal`` of works ``scale``): True where it is accepted, with the
    controller's next level set; False where rejected, the level lowered (to the explicit top at
    most, where a failed try backs off)."""
    tol = ctrl[0]
    top_explicit = int(ctrl[1])
    energy_tol = ctrl[CTRL_ENERGY]
    if its < 0 or err > tol or abs(bal) > energy_tol * scale:
        # rejected: finer (down to the explicit top, the adaptive step's levels); an energy residual
        # (numerical dissipation, ~ h) one level down
        ctrl[3] += 1.0
        if its < 0:
            cr[CT_LEVEL] = top_explicit
        elif err > tol:
            cr[CT_LEVEL] = max(min(_rejected_level(lv, err, tol), lv - 1), top_explicit)
        else:
            cr[CT_LEVEL] = lv - 1
        if cr[CT_LEVEL] == top_explicit:  # back to the explicit steps: wait longer before each new try
            _back_off(cr)
        return False
    if lv >= top_explicit + MIN_GAIN:
        cr[CT_BACKOFF] = 0
    ctrl[2] += 1.0
    ctrl[CTRL_ERR] = err
    # up while both the error and the energy residual (~ h) leave room for a doubling
    if cut:  # a step cut short says nothing about the next full one: the level is kept
        pass
    elif cr[CT_HAVE] > 0 and err < STEP_UP * tol and abs(bal) < 0.5 * energy_tol * scale \
            and lv < int(ctrl[CTRL_TOP_IMPLICIT]):
        lv += 1
    elif lv < top_explicit + MIN_GAIN:  # stuck within a few doublings of the explicit top: explicit is cheaper
        lv = top_explicit
        _back_off(cr)
    cr[CT_LEVEL] = lv
    cr[CT_HAVE] = 1
    return True


@nb.njit
def implicit_accept(p, ur, Ur, un, Un, ap, h, nc, st, vs, ys, yk, sk, uk, fk, ca, slow, w):
    """An accepted backward-Euler step, before the body's commit: its accelerations kept (the next
    error estimate), the contacts' velocities, forces and solver state from their (y, sign) in
    ``yk``, ``sk``, and the contacts' statistics at the step's end (w base steps)."""
    _keep_acceleration(ur.size, ur, Ur, un, Un, ap, h)
    implicit.be_contacts(nc, st, vs, ys, yk, sk, un, uk, fk, p[P_AMP], p[P_C], p[P_M] * p[P_ETAC])
    _weighted_contact_sums(nc, fk, uk, ca, slow, w)


def implicit_stepper(explicit, commit, prony: bool = False):
    """integrator = 'implicit' (issue 27, :mod:`.implicit`): the adaptive step up to its top level
    (``control[1]``, the explicit springs' stable step), backward Euler with everything implicit on
    the levels above it (up to ``control[4]``) while every contact is on the rising branch of eq. (1).
    Composed with the chain's body (its explicit part and commit serve the adaptive levels); the
    controller (:func:`implicit_plan`, :func:`after_explicit`, :func:`implicit_verdict`) is shared with
    the other geometries' (:func:`krylov_implicit_advance`). ``prony``: the body has Maxwell arms
    (material 'prony': they are in the backward-Euler system, :func:`.implicit.be_try_arms`; after a
    backward-Euler step they are updated by :func:`.viscoelastic.prony_be_commit`, their work being the
    step's balance's)."""
    astep = adaptive_stepper(explicit, commit)
    commit_be = viscoelastic.prony_be_commit if prony else commit
    be_try = implicit.be_try_arms if prony else implicit.be_try

    @nb.njit(cache=True, inline="always")
    def step(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, j, nstep, sample_steps, rc,
             scratch):
        un, Un, dampx, dampX, rk, ra, uk, fk, ok, ysave = scratch
        dt0 = rc[8]
        slow = rc[14]
        tol = ctrl[0]
        top_explicit = int(ctrl[1])
        n = xr.size
        while True:
            what, lv, w = implicit_plan(cr, ctrl, j, sample_steps)
            if what == PLAN_TAIL:
                cr[CT_LEVEL] = top_explicit
                res = astep(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, j, nstep,
                            sample_steps, rc, scratch)
                cr[CT_LEVEL] = lv  # (the controller's level kept for the next sample)
                return res
            if what == PLAN_EXPLICIT:
                was = cr[CT_LEVEL]
                res = astep(p, Fr, k0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, j, nstep,
                            sample_steps, rc, scratch)
                after_explicit(cr, ctrl, was, nc, ys)
                return res
            cut = w < (1 << lv)  # cut short by the sample's end
            h = dt0 * w
            t1 = (nstep + w) * dt0
            its = be_try(p, xr, ur, Xr, Ur, st, vs, nc, ys, un, Un, h, t1, tol, ra, rk, ap, cr[CT_HAVE] > 0, mt, br)
            err = 0.0
            if its > 0 and cr[CT_HAVE] > 0:
                err = _error(n, ur, Ur, un, Un, ap, h)
            bal = scale = fsum = w_drive = w_damp = w_contact = w_visc = 0.0
            if its > 0 and err <= tol:  # the works by the trapezoidal rule, and the step's energy residual
                bal, scale, fsum, w_drive, w_damp, w_contact = implicit.step_balance(p, xr, ur, Xr, Ur, un, Un, h, t1,
                                                                                     nc, st, vs, dampx, dampX)
                if prony:  # the arms' work
                    w_visc = implicit.chain_arm_work(p, mt, br, ur, Ur, un, Un, h)
                    bal -= w_visc
                    scale += abs(w_visc)
            if not implicit_verdict(cr, ctrl, its, err, bal, scale, lv, cut):
                continue
            implicit_accept(p, ur, Ur, un, Un, ap, h, nc, st, vs, ys, ra, rk, uk, fk, ca, slow, w)
            commit_be(p, mt, br, xr, ur, Xr, Ur, un, Un, dampx, dampX, h)
            return w, fsum / n * w, w_contact, w_damp, w_drive, w_visc

    return step


@nb.njit(cache=True)
def scratch_arrays(n, cmax):
    """The per-step work arrays of a stepper (one row at a time): new velocities and damping forces
    of both layers, the contacts' right-hand sides, velocities, forces, acceptance flags, and the
    solver state kept for a step that may be rejected."""
    return (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(cmax), np.empty(cmax), np.empty(cmax),
            np.empty(cmax), np.empty(cmax, dtype=np.bool_), np.empty((N_YS_STATE, cmax)))


@nb.njit
def start_sample(row, n_contacts, ysolve, params, ctl):
    """A row at the start of an output sample: exact 10**y, exp(-c y^2) for its contacts, level 0
    with no error estimate (so that a chunk boundary changes nothing)."""
    _refresh_solver(n_contacts[row], ysolve[row], params[row, P_C])
    ctl[row, CT_J] = 0
    ctl[row, CT_LEVEL] = 0
    ctl[row, CT_LOADED] = -1
    ctl[row, CT_HAVE] = 0
    ctl[row, CT_WAIT] = 0
    ctl[row, CT_BACKOFF] = 0


@nb.njit
def _restore_carry(cy, cr):
    """The implicit stepper's place at the start of a sample: where the last sample left it (Batch.carry)."""
    cr[CT_LEVEL] = int(cy[0])
    cr[CT_HAVE] = int(cy[1])
    cr[CT_WAIT] = int(cy[2])
    cr[CT_BACKOFF] = int(cy[3])


@nb.njit
def _save_carry(cy, cr):
    cy[0] = cr[CT_LEVEL]
    cy[1] = cr[CT_HAVE]
    cy[2] = cr[CT_WAIT]
    cy[3] = cr[CT_BACKOFF]


def kernel_driver(sample):
    """The whole chunk in one compiled call, row after row, one output sample of a row per call of
    ``sample`` (:func:`fixed_sample`, :func:`step_sample`) (a body that needs nothing from outside the
    kernel: the chains)."""

    @stable_cache
    @nb.njit(cache=True)
    def advance(x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control, bstate, material,
                carry, n_samples, sample_steps, out, acc, cacc, status):
        nb_rows, n = x.shape
        # :func:`scratch_arrays`' work arrays, allocated here (fresh allocations in view of the optimiser, likely why:
        # measured with benchmarks/bench_compose.py, through scratch_arrays the kernel is 4-5 % slower)
        cmax = sites.shape[1]
        un, Un, dampx, dampX = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        rk, ra, uk, fk = np.empty(cmax), np.empty(cmax), np.empty(cmax), np.empty(cmax)
        ok = np.empty(cmax, dtype=np.bool_)
        ysave = np.empty((N_YS_STATE, cmax))
        scratch = (un, Un, dampx, dampX, rk, ra, uk, fk, ok, ysave)  # (a tuple: a call of more than 30 arguments
        # compiles to CALL_FUNCTION_EX, which numba cannot inline)
        Fr = np.zeros(0)
        ctl = np.zeros((nb_rows, N_CT), dtype=np.int64)
        ap = np.zeros(2 * n)
        for row in range(nb_rows):
            if status[row] >= 0:
                continue
            p, xr, ur, Xr, Ur, st, vs = params[row], x[row], u[row], X[row], U[row], sites[row], vstar[row]
            nc = n_contacts[row]
            ys, fr, ctrl, cr, ca = ysolve[row], folds[row], control[row], ctl[row], cacc[row]
            mt, br = material[row], bstate[row]
            rc = row_parameters(p)
            w_drive = 0.0
            w_damp = 0.0
            w_contact = 0.0
            w_visc = 0.0
            keep = carry.shape[1] > 0  # the implicit stepper: its level and error memory go on across samples
            if keep:
                ap[:] = carry[row, N_CARRY:]
            for s in range(n_samples):
                start_sample(row, n_contacts, ysolve, params, ctl)
                if keep:
                    _restore_carry(carry[row], cr)
                j, fds, w_contact, w_damp, w_drive, w_visc = sample(
                    p, Fr, 0.0, mt, br, xr, ur, Xr, Ur, st, vs, nc, ys, fr, ctrl, cr, ap, ca, steps[row], sample_steps, rc,
                    scratch, w_contact, w_damp, w_drive, w_visc)
                steps[row] += j
                if keep:
                    _save_carry(carry[row], cr)
                if not _end_sample(xr, Xr, fds, sample_steps, w_contact, out[row, s]):
                    status[row] = steps[row]
                    break
            if keep:
                carry[row, N_CARRY:] = ap
            acc[row, A_WDRIVE] += w_drive
            acc[row, A_WDAMP] += w_damp
            acc[row, A_WCONTACT] += w_contact
            acc[row, A_WVISC] += w_visc

    return advance


def rows_driver(stepper, fastmath: bool, cached: bool = True):
    """One step of every live row whose sample is not complete, given the body's outside force ``F``
    of every row (the slab's FFT driver calls it once per FFT); compiled with the stepper's flags
    (it is inlined here). ``cached`` False: not cached on its own, for a compiled loop that calls it
    (:func:`fft_chunk_driver`; :mod:`slipchain.engine.jitcache`)."""
    flags = dict(fastmath=FASTMATH, error_model="numpy") if fastmath else {}

    def step_rows(F, k0, x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control, bstate, material,
                  ctl, aprev, cacc, acc, fd, sample_steps, status, scratch):
        for row in range(x.shape[0]):
            if status[row] >= 0 or ctl[row, CT_J] >= sample_steps:
                continue
            w, dfd, dwc, dwd, dwdr, dwv = stepper(params[row], F[row], k0[row], material[row], bstate[row], x[row],
                                                  u[row], X[row], U[row], sites[row], vstar[row], n_contacts[row],
                                                  ysolve[row], folds[row], control[row], ctl[row], aprev[row],
                                                  cacc[row], ctl[row, CT_J], steps[row], sample_steps,
                                                  row_parameters(params[row]), scratch)
            acc[row, A_WCONTACT] -= dwc
            acc[row, A_WDAMP] += dwd
            acc[row, A_WDRIVE] += dwdr
            acc[row, A_WVISC] += dwv
            fd[row] += dfd
            steps[row] += w
            ctl[row, CT_J] += w

    return stable_cache(nb.njit(cache=True, **flags)(step_rows)) if cached else nb.njit(**flags)(step_rows)


_end_sample_in_loop = nb.njit(spectral.end_sample.py_func)  # spectral.end_sample is cached (called from Python):
# a compiled loop compiles its own copy


@nb.njit
def _add_arm_sums(g, r, xi):
    """g += sum_j r_j xi_j of each row (the arms' field; rows, then arms, then sites: the order numpy's
    ``einsum("bj,bjn->bn")`` sums in). Not cached: :func:`fft_chunk_driver`'s chunk compiles its own copy, and
    :func:`_arm_sums` checks this very loop (:func:`numba_einsum`)."""
    b, J, n = xi.shape
    for row in range(b):
        for j in range(J):
            for i in range(n):
                g[row, i] += r[row, j] * xi[row, j, i]


def fft_chunk_driver(step_rows, adaptive: bool, prony: bool = False):
    """The slab's and half-space's explicit steppers (the fixed step, integrators 'fixed' and 'fold', or the
    adaptive step, ``adaptive``: the rows in lock-step, one accepted step per FFT) with the elastic body or
    (``prony``) the rubber's without a top of its own (the arms' field g = sum_j r_j xi_j by the loop numpy's
    einsum makes, checked once per process: :func:`numba_einsum`; its L_c g kept in work row 2J + 2), a
    whole chunk in one compiled call: :func:`fft_advance`'s loop over samples and steps with its FFTs inside numba
    (numpy.fft compiled by rocket-fft, the transforms scipy.fft runs, checked bit for bit once per process:
    :func:`.pocketfft.numba_fft`), then ``step_rows`` (:func:`rows_driver`, its uncached twin). The same
    arithmetic in the same order as :func:`fft_advance`, so the same bits (``benchmarks/slab_bits.py``),
    without the per-step Python layer: 2.4x faster per step on 16 x 16, 1.4x on 64 x 64
    (``benchmarks/bench_fft_chunk.py``, docs/performance.md)."""

    @stable_cache
    @nb.njit(cache=True)
    def advance(x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control, bstate, material, ctl,
                aprev, cacc, acc, fd, sample_steps, status, scratch, neg, k0, dead, out, n_samples, lx, ly):
        b, n = x.shape
        for s in range(n_samples):
            for row in range(b):
                if status[row] < 0:  # every sample starts afresh (checkpoints resume bit for bit)
                    start_sample(row, n_contacts, ysolve, params, ctl)
            for _ in range(sample_steps):
                if adaptive:  # every accepted step takes at least one base step: until every live row's sample is done
                    more = False
                    for row in range(b):
                        if status[row] < 0 and ctl[row, CT_J] < sample_steps:
                            more = True
                    if not more:
                        break
                if prony:  # fft_advance's viscoelastic force: L (x - X) and the arms' L_c g in one batched pair
                    J = material.shape[2]
                    pair = np.zeros((2 * b, n))
                    for row in range(b):
                        for i in range(n):
                            pair[row, i] = x[row, i] - X[row, i]
                    _add_arm_sums(pair[b:], material[:, 0, :], bstate[:, :J, :])
                    spec = np.fft.rfft2(pair.reshape((2 * b, lx, ly)), axes=(1, 2))
                    spec *= neg
                    both = np.fft.irfft2(spec, s=(lx, ly), axes=(1, 2)).reshape((2 * b, n))
                    force = np.empty((b, n))
                    for row in range(b):
                        for i in range(n):
                            bstate[row, 2 * J + 2, i] = both[b + row, i]
                            force[row, i] = both[row, i] + both[b + row, i]
                else:
                    src = x - X if dead else x  # dead-weight rows: the body acts on x - X
                    spec = np.fft.rfft2(src.reshape((b, lx, ly)), axes=(1, 2))
                    spec *= neg
                    force = np.fft.irfft2(spec, s=(lx, ly), axes=(1, 2)).reshape((b, n))
                step_rows(force, k0, x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control,
                          bstate, material, ctl, aprev, cacc, acc, fd, sample_steps, status, scratch)
            _end_sample_in_loop(x, X, status, steps, fd, out, s, sample_steps, acc)

    return advance


def fft_advance(batch: Batch, n_samples: int, sample_steps: int, fft=None) -> ChunkOutput:
    """Advance every live row of a slab/half-space batch by n_samples*sample_steps steps
    (module docstring): per step one batched FFT, then one step of every live row by the composed
    loop (:func:`loop`, the fixed or the adaptive stepper with this body); ``fft`` the FFT
    module (by default scipy.fft's transforms without its Python layer, :mod:`.pocketfft`). With the
    adaptive step the rows advance in lock-step, one accepted step per FFT (a rejected step is retried
    at once: the positions, hence the elastic force, have not moved)."""
    prony = batch.material_name == "prony"
    compiled = fft is None and batch.twoport is None and not batch.implicit and numba_fft() and (not prony or numba_einsum())
    if fft is None:
        fft = fft_module()
    b, n = batch.x.shape
    lx, ly = batch.shape
    kern = batch.kernel
    k0 = np.ascontiguousarray(kern[:, 0, 0])
    neg = -kern
    cmax = batch.sites.shape[1]
    out, acc, cacc = _chunk_outputs(batch, n_samples)
    fd = np.zeros(b)
    dead = bool(np.any(batch.params[:, P_KD] == 0.0))  # dead-weight rows: the body acts on x - X
    if compiled:  # the explicit steppers: the whole chunk in one compiled call, the same bits
        adaptive, folds, control = _stepper_inputs(batch)
        if prony:  # (the half-space's arms act through L less its uniform mode: arm_kernel)
            neg = np.concatenate([neg, arm_kernel(neg, batch.params[:, P_KD] == 0.0)])
        _fft_chunk(BODIES[batch.geometry] + ("-prony" if prony else ""), adaptive)(
            batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites, batch.vstar, batch.n_contacts,
            batch.ysolve, folds, control, batch.bstate, batch.material, np.zeros((b, N_CT), dtype=np.int64),
            np.zeros((b, 2 * n)), cacc, acc, fd, sample_steps, batch.status, scratch_arrays(n, cmax), neg, k0, dead,
            out, n_samples, lx, ly)
        return ChunkOutput(out, acc, cacc)
    grid = batch.x.reshape(b, lx, ly)  # a view: the FFT reads the state in place

    def force():
        spec = fft.rfft2(grid if not dead else (batch.x - batch.X).reshape(b, lx, ly), axes=(1, 2))
        spec *= neg
        return fft.irfft2(spec, s=(lx, ly), axes=(1, 2), overwrite_x=True).reshape(b, n)

    J = batch.material.shape[2] if batch.material is not None else 0
    top = _TopDriver(batch, fft, acc) if batch.twoport is not None else None
    if top is not None:  # the viscoelastic slab under the drive springs: its top solved between the steps
        force = top.force  # noqa: F811
    elif J:  # material 'prony': the arms' force too, kept in work row 2J + 2 (.viscoelastic)
        r = batch.material[:, 0, :]
        neg2 = np.concatenate([neg, arm_kernel(neg, batch.params[:, P_KD] == 0.0)])  # (the half-space: not k(0))

        def force():  # noqa: F811 - the viscoelastic slab's
            g = np.einsum("bj,bjn->bn", r, batch.bstate[:, :J])
            spec = fft.rfft2(np.concatenate([batch.x - batch.X, g]).reshape(2 * b, lx, ly), axes=(1, 2))
            spec *= neg2
            both = fft.irfft2(spec, s=(lx, ly), axes=(1, 2), overwrite_x=True).reshape(2 * b, n)
            batch.bstate[:, 2 * J + 2] = both[b:]
            return both[:b] + both[b:]

    adaptive, folds, control = _stepper_inputs(batch)
    step_rows = loop(batch.geometry, "implicit" if batch.implicit else adaptive, batch.material_name, top is not None)
    ctl = np.zeros((b, N_CT), dtype=np.int64)
    aprev = np.zeros((b, 2 * n))
    scratch = scratch_arrays(n, cmax)
    for s in range(n_samples):
        for row in np.flatnonzero(batch.status < 0):  # every sample starts afresh (checkpoints resume bit for bit)
            start_sample(row, batch.n_contacts, batch.ysolve, batch.params, ctl)
        # every accepted step takes at least one base step: sample_steps FFTs at most (the fixed step: exactly)
        for _ in range(sample_steps):
            if adaptive and not np.any((batch.status < 0) & (ctl[:, CT_J] < sample_steps)):
                break
            step_rows(force(), k0, batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites,
                      batch.vstar, batch.n_contacts, batch.ysolve, folds, control, batch.bstate, batch.material, ctl,
                      aprev, cacc, acc, fd, sample_steps, batch.status, scratch)
        spectral.end_sample(batch.x, batch.X, batch.status, batch.step, fd, out, s, sample_steps, acc)
    if top is not None:
        top.close()
    return ChunkOutput(out, acc, cacc)


class _TopDriver:
    """The top of the viscoelastic slab under the drive springs through one chunk (:mod:`.viscoelastic`,
    :func:`.viscoelastic.top_solve`): its fields and arms in Fourier space, loaded from the body state at
    the chunk's start and written back at its end, after a last solve at the chunk's final step (so that
    every chunk starts from a top in equilibrium, and a resumed run repeats the same arithmetic)."""

    def __init__(self, batch: Batch, fft, acc: np.ndarray):
        self.batch, self.fft, self.acc = batch, fft, acc
        b, n = batch.x.shape
        self.lx, self.ly = batch.shape
        J = batch.material.shape[2]
        self.J, self.t0 = J, 2 * J + BODY_ROWS
        self.r = batch.material[:, 0, :]
        grid = batch.bstate[:, self.t0:self.t0 + 2 + 2 * J].reshape(b, 2 + 2 * J, self.lx, self.ly)
        spec = fft.rfft2(grid, axes=(2, 3))
        self.Zh = np.ascontiguousarray(spec[:, :2])
        self.Th = np.ascontiguousarray(spec[:, 2:].reshape(b, 2, J, self.lx, -1))
        self.ft = np.zeros_like(self.Zh)
        self.fel = np.zeros_like(spec[:, 0])
        self.farm = np.zeros_like(self.fel)
        self.wtop = np.zeros(b)
        self.weights = parseval_weights(self.lx, self.ly)
        self.wgt = np.repeat(self.weights, 2, axis=-1)  # (float views: .viscoelastic.top_solve)
        self.tp = np.repeat(batch.twoport, 2, axis=-1)

    def solve(self):
        """Solve every row's top whose last solve is older than its step (:func:`.viscoelastic.top_solve`)."""
        bt, fft = self.batch, self.fft
        b, n = bt.x.shape
        g = np.einsum("bj,bjn->bn", self.r, bt.bstate[:, :self.J])
        spec = fft.rfft2(np.concatenate([bt.x, g]).reshape(2 * b, self.lx, self.ly), axes=(1, 2))
        f = np.float64
        viscoelastic.top_solve(spec[:b].view(f), spec[b:].view(f), self.Zh.view(f), self.Th.view(f), self.ft.view(f),
                               self.tp, bt.material, bt.bstate, bt.step, bt.params, self.wgt, self.fel.view(f),
                               self.farm.view(f), self.wtop)

    def force(self) -> np.ndarray:
        b, n = self.batch.x.shape
        self.solve()
        both = self.fft.irfft2(np.concatenate([self.fel, self.farm]), s=(self.lx, self.ly), axes=(1, 2),
                               overwrite_x=True).reshape(2 * b, n)
        self.batch.bstate[:, 2 * self.J + 2] = both[b:]
        return both[:b] + both[b:]

    def close(self) -> None:
        bt = self.batch
        b, n = bt.x.shape
        self.solve()
        spec = np.concatenate([self.Zh, self.Th.reshape(b, 2 * self.J, self.lx, -1)], axis=1)
        bt.bstate[:, self.t0:self.t0 + 2 + 2 * self.J] = self.fft.irfft2(
            spec, s=(self.lx, self.ly), axes=(2, 3)).reshape(b, 2 + 2 * self.J, n)
        self.acc[:, A_WVISC] += self.wtop


def krylov_explicit_driver(step_rows):
    """The implicit stepper's explicit steps on one row of a slab, half-space or chain2d batch between two
    backward-Euler tries, compiled: :func:`krylov_implicit_advance`'s loop while :func:`implicit_plan` says
    explicit, the body's force from outside its kernel computed as its ``explicit_force`` does (the slab's
    -L (x - d) by numpy.fft in numba, rocket-fft; with the rubber under the dead weight the arms' -L_c g too,
    g = r . xi by np.dot, kept in work row 2J + 2; chain2d none), then ``step_rows`` (:func:`rows_driver`'s
    uncached twin of the geometry's adaptive step). The same arithmetic in the same order, so the same bits
    (checked once per process: :func:`.pocketfft.numba_fft`, :func:`numba_dot`). Returns (True, level, base
    steps) of the plan's next backward-Euler try, or (False, 0, 0) at the sample's end. Not for the rubber
    under the drive springs (its arms act through L less its mean, numpy's pairwise mean) nor the top."""

    @stable_cache
    @nb.njit(cache=True)
    def explicit_steps(k0, x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control, bstate, material,
                       ctl, aprev, cacc, acc, fd, sample_steps, status, scratch, kern, lx, ly, spectral_body, prony, dead):
        cr, ctrl = ctl[0], control[0]
        n = x.shape[1]
        J = material.shape[2]
        nc, ys = n_contacts[0], ysolve[0]
        pair = np.empty((2, n))
        force = np.zeros((1, n if spectral_body else 0))
        while cr[CT_J] < sample_steps:
            what, lv, w = implicit_plan(cr, ctrl, cr[CT_J], sample_steps)
            if what == PLAN_IMPLICIT:
                return True, lv, w
            was = cr[CT_LEVEL]
            if what == PLAN_TAIL:
                cr[CT_LEVEL] = int(ctrl[1])
            if spectral_body and prony:  # SpectralOperator.apply_both of (x - X, g), SlabSystem.arm_part (dead: L_c g)
                pair[0] = x[0] - X[0]
                pair[1] = np.dot(material[0, 0], bstate[0, :J])
                both = np.fft.irfft2(kern * np.fft.rfft2(pair.reshape((2, lx, ly)), axes=(1, 2)), s=(lx, ly),
                                     axes=(1, 2)).reshape((2, n))
                for i in range(n):
                    bstate[0, 2 * J + 2, i] = -both[1, i]
                    force[0, i] = -(both[0, i] + both[1, i])
            elif spectral_body:  # SpectralOperator.apply
                v = x[0] - X[0] if dead else x[0].copy()
                lvec = np.fft.irfft2(kern * np.fft.rfft2(v.reshape((lx, ly))), s=(lx, ly)).reshape(n)
                for i in range(n):
                    force[0, i] = -lvec[i]
            step_rows(force, k0, x, u, X, U, steps, params, sites, vstar, n_contacts, ysolve, folds, control, bstate,
                      material, ctl, aprev, cacc, acc, fd, sample_steps, status, scratch)
            if what == PLAN_TAIL:
                cr[CT_LEVEL] = lv
            else:
                after_explicit(cr, ctrl, was, nc, ys)
        return False, 0, 0

    return explicit_steps


@nb.njit(cache=True)
def _dot(r, br):
    """np.dot of a row's Prony weights and its arms' fields, compiled (:func:`numba_dot`; called from Python only)."""
    return np.dot(r, br)


@functools.cache
def numba_dot() -> bool:
    """Whether np.dot compiled by numba gives numpy's bits for the arms' sums g = r . xi (both call a BLAS
    gemv; checked once per process on a few sizes): else the Krylov driver's explicit steps stay in Python."""
    rng = np.random.default_rng(2)
    for J in (1, 3, 7, 12, 20):
        for n in (16, 64, 256):
            r, br = rng.random(J), rng.standard_normal((J, n))
            if _dot(r, br).tobytes() != np.dot(r, br).tobytes():
                return False
    return True


@functools.cache
def _krylov_explicit(body: str):
    """The compiled explicit steps of the implicit stepper's Krylov driver with this body (:func:`krylov_explicit_driver`)."""
    return _recipe(krylov_explicit_driver(rows_driver(stepper(body, True), False, cached=False)), "_krylov_explicit",
                   (body,))


def krylov_implicit_advance(batch: Batch, n_samples: int, sample_steps: int, fft=None) -> ChunkOutput:
    """integrator = 'implicit' on the slab, half-space and chain2d (issue 27; either drive, material
    'elastic'): row after row, each step as the implicit stepper's controller says
    (:func:`implicit_plan`, shared with the chain's compiled stepper): explicit steps by the
    geometry's compiled adaptive step on this row alone (:func:`rows_driver`; the slab's with one FFT
    each), backward-Euler tries by :func:`.implicit.krylov_be_try` (Newton, each linear solve by
    preconditioned conjugate gradients; :class:`.implicit.SlabSystem`, :class:`.implicit.LatticeSystem`),
    judged by :func:`implicit_verdict`. The level, error memory and back-off go on across samples
    (``Batch.carry``, as the chain's)."""
    default_fft = fft is None
    if fft is None:
        fft = fft_module()
    b, n = batch.x.shape
    spectral_body = BODIES[batch.geometry] == "spectral"
    prony = batch.material_name == "prony"
    J = batch.material.shape[2] if prony else 0
    out, acc, cacc = _chunk_outputs(batch, n_samples)
    fd = np.zeros(b)
    _, folds, control = _stepper_inputs(batch)
    # the explicit levels: the geometry's adaptive step, one row at a time (with 'prony' its level 0 alone:
    # Config.step_levels)
    top = _TopDriver(batch, fft, acc) if batch.twoport is not None else None  # the slab's top a state of its own
    step_rows = _row_loop(BODIES[batch.geometry] + ("-prony" if prony else "") + ("-top" if top is not None else ""))
    ctl = np.zeros((b, N_CT), dtype=np.int64)
    aprev = np.zeros((b, 2 * n))
    scratch = scratch_arrays(n, batch.sites.shape[1])
    un, Un, dampx, dampX, rk, ra, uk, fk, _, _ = scratch
    k0 = np.ascontiguousarray(batch.kernel[:, 0, 0]) if spectral_body else np.zeros(b)
    if prony:  # the arms' update with the step's velocities, then the body's commit
        commit = viscoelastic.slab_prony_be_commit if spectral_body else viscoelastic.prony_be_commit
    else:
        commit = spectral.body_commit if spectral_body else lattice_commit
    no_force = np.zeros((1, 0))
    carry = batch.carry
    # the explicit steps compiled (the same bits; Python where numba's FFT or dot differ or the body needs the Python)
    compiled = default_fft and top is None and (not spectral_body or numba_fft()) and (not prony or numba_dot())
    explicit_steps = _krylov_explicit(BODIES[batch.geometry] + ("-prony" if prony else "")) if compiled else None
    lx, ly = batch.shape
    trbdf2 = batch.implicit_scheme == "trbdf2"  # Config.implicit_scheme: TR-BDF2 above the explicit levels
    for row in np.flatnonzero(batch.status < 0):
        r = slice(row, row + 1)
        p = batch.params[row]
        dead = p[P_KD] == 0.0  # the dead weight: the slab's body acts on x - X (the plate's displacement in every entry)
        fast = explicit_steps is not None and (dead or not (prony and spectral_body))
        kern_row = batch.kernel[row] if spectral_body else no_force
        arms = implicit.Arms(batch.material[row], batch.bstate[row]) if prony else None
        if top is not None:
            system = implicit.TopSlabSystem(p, arms, top, row, batch.preconditioner)
        elif spectral_body:
            op = implicit.SpectralOperator(batch.kernel[row], batch.shape, fft)
            system = implicit.SlabSystem(op, p, arms, batch.preconditioner)
        else:
            system = implicit.LatticeSystem(p, batch.shape, fft, arms, batch.preconditioner)
        xr, ur, Xr, Ur = batch.x[row], batch.u[row], batch.X[row], batch.U[row]
        st, vs, nc, ys = batch.sites[row], batch.vstar[row], int(batch.n_contacts[row]), batch.ysolve[row]
        ctrl, cr, ap, ca = control[row], ctl[row], aprev[row], cacc[row]
        dt0, slow = p[P_DT], p[P_SLOW]
        ap[:] = carry[row, N_CARRY:]
        rows = (k0[r], batch.x[r], batch.u[r], batch.X[r], batch.U[r], batch.step[r], batch.params[r], batch.sites[r],
                batch.vstar[r], batch.n_contacts[r], batch.ysolve[r], folds[r], control[r], batch.bstate[r],
                batch.material[r], ctl[r], aprev[r], cacc[r], acc[r], fd[r])

        def explicit_force():
            """The body's force from outside its kernel for an explicit step: the slab's -L (x - d), with
            the arms' -L_c g (kept in work row 2J + 2, as :func:`fft_advance` does); the chains' none."""
            if not spectral_body:
                return no_force
            if top is not None:  # the top solved at this step (none if it is current), its force on the blocks
                return top.force()[r]
            if not prony:
                return -op.apply(xr - Xr if dead else xr)[None, :]
            g = arms.now()[0]
            le, lg = op.apply_both(xr - Xr, g)
            la = system.arm_part(lg, g)
            batch.bstate[row, 2 * J + 2] = -la
            return -(le + la)[None, :]

        for s in range(n_samples):
            start_sample(row, batch.n_contacts, batch.ysolve, batch.params, ctl)
            _restore_carry(carry[row], cr)
            spent = 0.0  # the tries' cost since the last accepted implicit step (KRYLOV_TRY_UNITS), per sample
            waits = 0  # the cost rule's back-off within this sample (not reset by the climb's accepted steps)
            while cr[CT_J] < sample_steps:
                if fast:  # the explicit steps up to the next try, compiled
                    more, lv, w = explicit_steps(*rows, sample_steps, batch.status[r], scratch, kern_row, lx, ly,
                                                 spectral_body, prony, dead)
                    if not more:
                        break
                    what = PLAN_IMPLICIT
                else:
                    what, lv, w = implicit_plan(cr, ctrl, cr[CT_J], sample_steps)
                if what != PLAN_IMPLICIT:
                    was = cr[CT_LEVEL]
                    if what == PLAN_TAIL:
                        cr[CT_LEVEL] = ctrl[1]
                    step_rows(explicit_force(), *rows, sample_steps, batch.status[r], scratch)
                    if what == PLAN_TAIL:
                        cr[CT_LEVEL] = lv
                    else:
                        after_explicit(cr, ctrl, was, nc, ys)
                    continue
                h = dt0 * w
                t1 = (batch.step[row] + w) * dt0
                if top is not None and batch.bstate[row, -1, 1] != batch.step[row]:  # the top current at the step's
                    top.solve()  # start (after explicit steps; a solve at the step of the last one changes nothing)
                if trbdf2:
                    its, n_cg, stages = implicit.krylov_trbdf2_try(system, p, xr, ur, Xr, Ur, st, vs, nc, ys, un, Un, h, t1,
                                                                   ctrl[0], ra, rk, ap, cr[CT_HAVE] > 0)
                else:
                    its, n_cg = implicit.krylov_be_try(system, p, xr, ur, Xr, Ur, st, vs, nc, ys, un, Un, h, t1, ctrl[0],
                                                       ra, rk, ap, cr[CT_HAVE] > 0)
                spent += KRYLOV_TRY_UNITS + abs(its) + n_cg * system.cg_units
                err = _error(n, ur, Ur, un, Un, ap, h) if its > 0 and cr[CT_HAVE] > 0 else 0.0
                bal = scale = fsum = w_drive = w_damp = w_contact = w_visc = 0.0
                if its > 0 and err <= ctrl[0]:
                    if trbdf2:
                        bal, scale, fsum, w_drive, w_damp, w_contact, w_visc = implicit.trbdf2_balance(system, p, stages, un,
                                                                                                       Un, nc, st, vs)
                    else:
                        bal, scale, fsum, w_drive, w_damp, w_contact, w_visc = system.balance(xr, ur, Xr, Ur, un, Un, h, t1,
                                                                                              nc, st, vs)
                cut = w < (1 << lv)
                if not implicit_verdict(cr, ctrl, its, err, bal, scale, lv, cut):
                    continue
                # a full step, not climbing, and dearer than the explicit steps it replaced: hand back
                if not cut and cr[CT_LEVEL] <= lv and spent * (1 << int(ctrl[1])) > w and cr[CT_LEVEL] > ctrl[1]:
                    waits = min(max(1, 2 * waits), MAX_BACKOFF)
                    cr[CT_LEVEL] = int(ctrl[1])
                    cr[CT_BACKOFF] = cr[CT_WAIT] = waits
                spent = 0.0
                implicit_accept(p, ur, Ur, un, Un, ap, h, nc, st, vs, ys, ra, rk, uk, fk, ca, slow, w)
                if trbdf2:  # the positions from the BDF2 stage's base: x' = xB + h2 u'
                    xr[:] = stages.xB
                    Xr[:] = stages.XB
                    commit(p, batch.material[row], batch.bstate[row], xr, ur, Xr, Ur, un, Un, dampx, dampX, stages.h2)
                else:
                    commit(p, batch.material[row], batch.bstate[row], xr, ur, Xr, Ur, un, Un, dampx, dampX, h)
                if top is not None:
                    system.commit_top(batch.step[row] + w, batch.bstate[row])
                acc[row, A_WCONTACT] -= w_contact
                acc[row, A_WDAMP] += w_damp
                acc[row, A_WDRIVE] += w_drive
                acc[row, A_WVISC] += w_visc
                fd[row] += fsum / n * w
                batch.step[row] += w
                cr[CT_J] += w
            _save_carry(carry[row], cr)
            # the sample's end for this row (the others' samples are zero here and done in their turn)
            if spectral_body:
                spectral.end_sample(batch.x[r], batch.X[r], batch.status[r], batch.step[r], fd[r], out[r], s,
                                    sample_steps, acc[r])
            elif not _end_sample(xr, Xr, fd[row], sample_steps, acc[row, A_WCONTACT], out[row, s]):
                batch.status[row] = batch.step[row]
            fd[row] = 0.0
            if batch.status[row] >= 0:
                break
        carry[row, N_CARRY:] = ap
    if top is not None:
        top.close()
    return ChunkOutput(out, acc, cacc)


def kernel_advance(batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
    """Advance every live row of a chains' batch by n_samples*sample_steps steps: one call of the
    composed whole-chunk kernel (:func:`kernel_driver`)."""
    out, acc, cacc = _chunk_outputs(batch, n_samples)
    adaptive, folds, control = _stepper_inputs(batch)
    loop(batch.geometry, "implicit" if batch.implicit else adaptive, batch.material_name)(
        batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites, batch.vstar, batch.n_contacts,
        batch.ysolve, folds, control, batch.bstate, batch.material, _carry(batch), n_samples, sample_steps, out, acc,
        cacc, batch.status)
    return ChunkOutput(out, acc, cacc)


def advance(batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
    """Advance a batch on the CPU by the driver of its geometry's body: :func:`kernel_advance` (the
    chains) or :func:`fft_advance` (the slab and half-space: the elastic force by FFT)."""
    if batch.implicit and batch.geometry != "chain":
        return krylov_implicit_advance(batch, n_samples, sample_steps)
    if BODIES[batch.geometry] == "spectral":
        return fft_advance(batch, n_samples, sample_steps)
    return kernel_advance(batch, n_samples, sample_steps)


def _carry(batch: Batch) -> np.ndarray:
    """The implicit stepper's state carried across samples (Batch.carry), or an empty (B, 0) stand-in."""
    return batch.carry if batch.carry is not None else np.zeros((batch.x.shape[0], 0))


def _chunk_outputs(batch: Batch, n_samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Zeroed per-sample outputs, work sums and per-contact sums of one chunk (:class:`ChunkOutput`)."""
    b = batch.x.shape[0]
    return np.zeros((b, n_samples, N_OUT)), np.zeros((b, N_ACC)), np.zeros((b, N_CACC, batch.sites.shape[1]))


def _stepper_inputs(batch: Batch) -> tuple[bool, np.ndarray, np.ndarray]:
    """(adaptive, folds, step control) for the steppers' common signature: the batch's own with the
    adaptive step, else zeroed stand-ins of the same types (the fixed stepper reads neither)."""
    if batch.folds is not None:
        return True, batch.folds, batch.step_control
    b, cmax = batch.sites.shape
    return False, np.zeros((b, 1, 2, cmax)), np.zeros((b, N_CONTROL))



LATTICE = (lattice_explicit, lattice_commit, False)  # chain, chain2d: (explicit, commit, fastmath of its fixed loop)
LATTICE_PRONY = (viscoelastic.prony_explicit, viscoelastic.prony_commit, False)  # chain, chain2d, material 'prony'
BODIES = {name: g.body for name, g in GEOMETRIES.items()}  # model.geometries


SPECTRAL = spectral.BODY  # slab, halfspace
SPECTRAL_PRONY = (viscoelastic.slab_prony_explicit, viscoelastic.slab_prony_commit, True)  # slab, dead weight, prony
SPECTRAL_PRONY_TOP = (viscoelastic.slab_top_prony_explicit, viscoelastic.slab_prony_commit, True)  # slab, springs, prony


def _body(name: str):
    return {"lattice": LATTICE, "lattice-prony": LATTICE_PRONY, "spectral": SPECTRAL, "spectral-prony": SPECTRAL_PRONY,
            "spectral-prony-top": SPECTRAL_PRONY_TOP}[name]


@functools.cache
def stepper(body: str, adaptive: bool | str):
    """The stepper of :func:`fixed_stepper`, :func:`adaptive_stepper` (``adaptive`` True) or
    :func:`implicit_stepper` (``adaptive`` = 'implicit') composed with a body ('lattice',
    'lattice-prony', 'spectral' or 'spectral-prony')."""
    explicit, commit, fastmath = _body(body)
    if adaptive == "implicit":
        return implicit_stepper(explicit, commit, body == "lattice-prony")
    return adaptive_stepper(explicit, commit) if adaptive else fixed_stepper(explicit, commit, fastmath)


def loop(geometry: str, adaptive: bool | str, material: str = "elastic", top: bool = False):
    """The compiled loop of one combination: for the chains the whole-chunk kernel
    (:func:`kernel_driver`), for the slab and half-space the per-step function of its FFT driver
    (:func:`rows_driver`). One per body and stepper, shared by the geometries of a body; integrators
    'fixed' and 'fold' share the fixed stepper (the fold-aware contact solve is the row's P_FOLD);
    the drive is the body's; ``material`` 'prony' the viscoelastic body of the chains or of the slab
    under the dead weight (:mod:`.viscoelastic`); ``top``: the slab's top a state of its own (material 'prony'
    under the drive springs, Config.top_is_state: the body 'spectral-prony-top')."""
    body = BODIES[geometry] + ("-prony" if material == "prony" else "") + ("-top" if top else "")
    return _loop(body, adaptive)


@functools.cache
def _row_loop(body: str):
    """One adaptive step of each live row (:func:`rows_driver`) with this body: the slab's FFT loop, or the
    same driver over the chains' body (the implicit stepper's explicit levels on chain2d, one row at a time)."""
    if body == "spectral":
        return _loop(body, True)
    return _recipe(rows_driver(stepper(body, True), False), "_row_loop", (body,))


@functools.cache
def _loop(body: str, adaptive: bool | str):
    explicit, commit, fastmath = _body(body)
    if body.startswith("lattice"):
        loop = kernel_driver(step_sample(stepper(body, adaptive)) if adaptive else fixed_sample(explicit, commit, fastmath))
    else:
        loop = rows_driver(stepper(body, adaptive), fastmath and not adaptive)
    return _recipe(loop, "_loop", (body, adaptive))


@functools.cache
def _fft_chunk(body: str, adaptive: bool = False):
    """The whole-chunk loop of the spectral body's fixed or adaptive step, elastic or 'spectral-prony'
    (:func:`fft_chunk_driver`; the step's flags as :func:`_loop`'s)."""
    explicit, commit, fastmath = _body(body)
    step_rows = rows_driver(stepper(body, adaptive), fastmath and not adaptive, cached=False)
    return _recipe(fft_chunk_driver(step_rows, adaptive, body == "spectral-prony"), "_fft_chunk", (body, adaptive))


@nb.njit(cache=True)
def _arm_sums(r, xi):
    """g = sum_j r_j xi_j of each row by the loop :func:`fft_chunk_driver` runs (:func:`numba_einsum`; called
    from Python only)."""
    g = np.zeros((xi.shape[0], xi.shape[2]))
    _add_arm_sums(g, r, xi)
    return g


@functools.cache
def numba_einsum() -> bool:
    """Whether the compiled arms' sums give numpy's ``einsum("bj,bjn->bn")`` bits (:func:`fft_advance`'s; checked once
    per process on a few sizes): else the rubber's fold step keeps the Python driver."""
    rng = np.random.default_rng(3)
    for b, J in ((1, 1), (1, 7), (2, 12), (3, 20)):
        for n in (16, 64, 256):
            r, xi = rng.random((b, J)), rng.standard_normal((b, J, n))
            if _arm_sums(r, xi).tobytes() != np.einsum("bj,bjn->bn", r, xi).tobytes():
                return False
    return True


def _recipe(loop, factory: str, args: tuple):
    """How a fresh process builds ``loop`` again (:class:`~slipchain.engine.jitcache.StableFunctionCache`:
    a loop missing from the cache is compiled in a fresh process, so that its code does not depend on
    what this one compiled before)."""
    loop._cache.recipe = (__name__, factory, args)
    return loop


__all__ = ["BODIES", "adaptive_stepper", "advance", "fft_advance", "fixed_stepper", "kernel_advance", "kernel_driver",
           "loop", "rows_driver", "start_sample", "stepper"]

"""Pieces shared by the time-stepping loops (explicit, coupled explicit, implicit; numba):
status codes, work arrays, the active-tooth set, and the end of a step (guards, energy
bookkeeping, output records).

Status codes: `solver.mbs.kernels.status` (par[ABORT], set from another thread, is checked at
the end of every step: `solver.mbs.interrupt`).

Teeth away from the mesh are left out of the integration, rigid to their hub; a tooth joins
the set when the pre-search names it a candidate and leaves it once it is outside the
candidates and at rest (rotation below ``par[PHI_QUIET]`` [rad], rate below
``par[DPHI_QUIET]`` [rad/s]). ``tset`` rows (`layout` T_*): the active tooth indices (first
``nact`` valid), and per-tooth 0/1 flags "active" and "candidate of this step". The flags are
int64, not bool: numba then reuses the int64 allocation it compiles anyway instead of
compiling np.zeros once more for bool. ``q``: generalised forces (hubs first, then the teeth).

Running sums of a run sit in ``book`` (`layout` B_* columns); the loops pass the powers of
each step to `end_step`, which integrates them with the trapezoidal rule.
"""
import math

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels import njit
from solver.mbs.kernels.status import ENERGY, INTERRUPTED, NONFINITE, OK, PENETRATION
from solver.mbs.kernels.toothcoupling import coupled_set


def work_arrays(ntooth, ctooth=None):
    """The work arrays ``ws`` of a loop over ntooth teeth (`layout.StepWork`: contact records,
    candidate pairs, generalised forces, predicted tooth rates, active set, running sums, and
    the coupled set of the tooth compliance ctooth [rad/(N m)], `toothcoupling.coupled_set`;
    None or 0 x 0: none). Plain Python (the caller allocates them: fewer numba functions,
    and no np.zeros of integers, to compile)."""
    rec = np.zeros((L.MAX_CONTACTS, L.N_C_COLS))
    pairs = np.zeros((L.MAX_CONTACTS, 3), dtype=np.int64)
    q = np.zeros(ntooth + 2)
    vpred = np.zeros(ntooth)
    tset = np.zeros((L.N_TSET, ntooth), dtype=np.int64)
    book = np.zeros(L.N_BOOK)
    cset = coupled_set(np.zeros((0, 0)) if ctooth is None else np.ascontiguousarray(ctooth, dtype=float))
    return L.StepWork(rec, pairs, q, vpred, tset, book, cset)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def initial_set(tset, teeth, pairs, npair, tz2):
    """Active set at t = 0: the teeth already moving and those of the npair candidate pairs,
    in tooth order. Returns its size."""
    ntooth = teeth.shape[1]
    active = tset[L.T_ACTIVE]
    for i in range(ntooth):
        if teeth[L.POS, i] != 0.0 or teeth[L.RATE, i] != 0.0:
            active[i] = True
    for p in range(npair):
        active[int(pairs[p, 0])] = True
        active[tz2 + int(pairs[p, 1])] = True
    # counters start as np.int64(0), not a literal 0: numba would otherwise compile each callee
    # once more for the argument type Literal[int](0)
    nact = np.int64(0)
    for i in range(ntooth):
        if active[i]:
            tset[L.T_ACT, nact] = i
            nact += 1
    return nact


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def activate(tset, nact, pairs, npair, tz2):
    """Flag the teeth of the candidate pairs and append those not yet active to the set
    (gear-2 teeth offset by tz2). Returns the new size; the new ones are act[old size:]."""
    for p in range(npair):
        for g in range(2):
            i = int(pairs[p, g]) + (tz2 if g == 1 else 0)
            tset[L.T_INCAND, i] = True
            if not tset[L.T_ACTIVE, i]:
                tset[L.T_ACTIVE, i] = True
                tset[L.T_ACT, nact] = i
                nact += 1
    return nact


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def end_step(ws, teeth, nc, npair, nact, tz2, powers, par, status):
    """The end of a step: guards, energy bookkeeping, and the active set.

    Records the largest contact force of the contacts ws.rec[:nc] and checks the penetration
    bound (status PENETRATION); integrates the work [J] and the dissipated energy [J] by the
    trapezoidal rule from the last step's powers to these, powers = (p_in_left, p_in, p_d):
    input power p_in [W] (p_in_left its left limit at this instant, where the driver
    acceleration jumps) and dissipation power p_d [W]; sets the quiet teeth outside the
    candidates exactly to rest (rotation, rate, acceleration and generalised force zero: rigid
    to the hub, whose inertia already holds them) and drops them from the set; resets the
    candidate flags of the npair pre-search pairs (gear-2 teeth offset by tz2); status
    INTERRUPTED once par[ABORT] is set. Returns (status, new number of active teeth).
    """
    rec, pairs, q, tset, book = ws.rec, ws.pairs, ws.q, ws.tset, ws.book
    p_in_left, p_in, p_d = powers
    if par[L.ABORT] != 0.0:
        status = INTERRUPTED
    for c in range(nc):
        if rec[c, L.C_FORCE] > book[L.B_FMAX]:
            book[L.B_FMAX] = rec[c, L.C_FORCE]
        if rec[c, L.C_DELTA] > par[L.DELTA_MAX]:
            status = PENETRATION
    dt = par[L.DT]
    book[L.B_WORK] += 0.5 * dt * (p_in_left + book[L.B_P_IN])
    book[L.B_DISS] += 0.5 * dt * (p_d + book[L.B_P_D])
    book[L.B_P_IN] = p_in
    book[L.B_P_D] = p_d
    act = tset[L.T_ACT]
    a = 0
    while a < nact:
        i = act[a]
        if (not tset[L.T_INCAND, i] and abs(teeth[L.POS, i]) < par[L.PHI_QUIET]
                and abs(teeth[L.RATE, i]) < par[L.DPHI_QUIET]):
            teeth[L.POS, i] = 0.0
            teeth[L.RATE, i] = 0.0
            teeth[L.ACC, i] = 0.0
            q[2 + i] = 0.0
            tset[L.T_ACTIVE, i] = False
            nact -= 1
            act[a] = act[nact]
        else:
            a += 1
    for p in range(npair):
        tset[L.T_INCAND, int(pairs[p, 0])] = False
        tset[L.T_INCAND, tz2 + int(pairs[p, 1])] = False
    return status, nact


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def record_contacts(out, o, rec, nc):
    """The loaded contacts of rec[:nc] into the slots of record o beyond the N_OUT columns
    (`layout` OC_*; none when ``out`` has no more columns): teeth, force [N], and moment on
    the driven gear [N m]; the slots left over hold tooth -1 and force 0."""
    slots = (out.shape[1] - L.N_OUT) // L.O_CONTACT_COLS
    k = 0
    for c in range(nc):
        if rec[c, L.C_FORCE] > 0.0 and k < slots:
            base = L.N_OUT + k * L.O_CONTACT_COLS
            out[o, base + L.OC_TOOTH1] = rec[c, L.C_TOOTH1]
            out[o, base + L.OC_TOOTH2] = rec[c, L.C_TOOTH2]
            out[o, base + L.OC_FORCE] = rec[c, L.C_FORCE]
            out[o, base + L.OC_MOMENT] = rec[c, L.C_FORCE] * rec[c, L.C_G2]
            k += 1
    for s in range(k, slots):
        base = L.N_OUT + s * L.O_CONTACT_COLS
        out[o, base + L.OC_TOOTH1] = -1.0
        out[o, base + L.OC_TOOTH2] = -1.0
        out[o, base + L.OC_FORCE] = 0.0
        out[o, base + L.OC_MOMENT] = 0.0


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def record_output(out, o, row, book, rec, nc, finite, par, status):
    """Write output record o (`layout` O_* columns) and check the state; returns the status.

    row = (time [s], TE [m], driven hub angle [rad], driver torque [N m], kinetic and
    potential energy [J]); with the largest contact force since the last record [N] (then
    reset), the loaded contacts of rec[:nc] (their count, and each in a slot when ``out`` has
    them: `record_contacts`), the work and dissipated energy [J] of ``book``, and the energy the
    coupled set's switches took out [J]. Status NONFINITE when the state is not ``finite`` or the energies are not,
    ENERGY when the balance shows a growth kinetic + potential - initial + dissipated - work
    [J] above par[ENERGY_TOL] times the energy scale, else ``status`` unchanged.
    """
    t, te, theta2, react, ke, pe = row
    n = 0
    for c in range(nc):
        if rec[c, L.C_FORCE] > 0.0:
            n += 1
    out[o, L.O_TIME] = t
    out[o, L.O_TE] = te
    out[o, L.O_FMAX] = book[L.B_FMAX]
    out[o, L.O_NC] = n
    out[o, L.O_REACT] = react
    out[o, L.O_KE] = ke
    out[o, L.O_PE] = pe
    out[o, L.O_WORK] = book[L.B_WORK]
    out[o, L.O_DISS] = book[L.B_DISS]
    out[o, L.O_THETA2] = theta2
    out[o, L.O_SWITCH] = book[L.B_SWITCH]
    record_contacts(out, o, rec, nc)
    book[L.B_FMAX] = 0.0
    if not (finite and math.isfinite(ke + pe)):
        return NONFINITE
    work = book[L.B_WORK]
    diss = book[L.B_DISS] + book[L.B_SWITCH]
    if status == OK and ke + pe - book[L.B_E0] + diss - work > par[L.ENERGY_TOL] * max(abs(work), ke + pe, diss):
        return ENERGY
    return status

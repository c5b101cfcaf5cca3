"""Velocity Verlet for the body-torsion coupled pair (numba).

Degrees of freedom beyond the plain model (`explicit.py`): each gear's teeth sit on a rigid
rim joined to its hub by the body spring k_body (``gear_par[:, K_BODY]``).

* gear 1: hub prescribed (the speed ramp); rim angle r1 free;
* gear 2: rim angle theta2 (the angle the contact search sees) and hub angle h2 free; the
  resisting torque acts on the hub;
* tooth rotations phi relative to their rim.

The rim of gear g carries inertia I_TOT - I_HUB plus its teeth (the arrowhead mass matrix of
the plain model with the rim in the hub's place); the hub carries I_HUB. The driver's hub is
prescribed, so the teeth no longer see its acceleration: the driver torque is
I_HUB1*theta1'' + k_body1*(theta1 - r1) + c_body1*(theta1' - r1'). The body springs carry
linear damping c_body (``C_BODY``, from a damping ratio on the body mode). TE is read at the
hubs: rb1*theta1 + rb2*h2. Energy bookkeeping as in `explicit.py` plus the hub kinetic
energy and the body springs' potential energy. The three body angles r1, theta2, h2 are the
state columns H_R1, H_TH2, H_H2 (`layout`); they move alike, as one array.

Teeth coupled through the body (``ctooth``, the compliance model; 0 x 0 otherwise): the
teeth of the pre-search candidates form the set S whose springs act through
K_S = (C[S, S])^-1 (`toothcoupling`); the other active teeth keep their own spring
kphi = 1/C[a, a]. When S changes, a tooth that joins it takes on the rotation and rate its
neighbours' moments give it (phi_i += sum_b C[i, b] M_b), and a tooth that leaves gives them
back. A tooth that joins unloaded (from rest, as teeth come from the frozen set) so changes
no spring moment, and a tooth that leaves keeps its own; the remaining teeth's moments move
by the coupling of the leaving tooth's moment, small since it has just left the mesh. What a
switch changes in the kinetic and elastic energy (the leaving tooth's residual moment, the
joining tooth's rate) is booked (book[B_SWITCH], output column O_SWITCH), so that the
energy balance closes: it takes energy out, about 2 % of what the dampers dissipate (0.012 J against 0.66 J
over a 0.3 s run-up of the paper pair to 450 rad/s).

Linear tooth-root dampers (par[IMEX] = 1) are taken implicitly in the kicks exactly as in
`explicit.py` (the arrowhead with the tooth inertia I_P + dt/4 c_phi, the damper at the rates
each kick starts with, and the next first kick's accelerations again with the new rates):
the step is then bound by the stiffness alone. Body and contact dampers stay explicit
(predicted velocity).
"""
import math

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels import njit
from solver.mbs.kernels.gearmesh import generalized_forces, pair_contacts
from solver.mbs.kernels.mechanics import dissipation_power, drive, driver_acc_left, kick_gear_par, mesh_energies
from solver.mbs.kernels.status import OK
from solver.mbs.kernels.stepping import activate, end_step, initial_set, record_output
from solver.mbs.kernels.toothcoupling import set_differs, set_energy, set_springs, update_set


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True, inline="always")
def rim_accelerations(q, act, nact, gp, acc, ha):
    """Arrowhead solves of both rims: fills ha[H_R1] (r1''), ha[H_TH2] (theta2'') and the
    teeth's acc. q[0], q[1]: generalised forces on the rims (contacts + body springs)."""
    tz2 = int(gp[1, L.TOOTH0])
    s1 = gp[0, L.I_TOT] - gp[0, L.I_HUB]
    s2 = gp[1, L.I_TOT] - gp[1, L.I_HUB]
    rhs1 = q[0]
    rhs2 = q[1]
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        c = gp[g, L.I_CPL]
        if g == 1:
            s2 -= c * c / gp[1, L.I_P]
            rhs2 -= c * q[2 + i] / gp[1, L.I_P]
        else:
            s1 -= c * c / gp[0, L.I_P]
            rhs1 -= c * q[2 + i] / gp[0, L.I_P]
    ha[L.H_R1] = rhs1 / s1
    ha[L.H_TH2] = rhs2 / s2
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        ar = ha[L.H_TH2] if g == 1 else ha[L.H_R1]
        acc[i] = (q[2 + i] - gp[g, L.I_CPL] * ar) / gp[g, L.I_P]


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True, inline="always")
def body_moments(gp, th1, w1, x, v):
    """Moments [N m] of the body springs and dampers on the driver rim and the driven hub, at
    the body angles x and rates v (columns H_*), driver hub at th1 [rad], w1 [rad/s]."""
    mb1 = gp[0, L.K_BODY] * (th1 - x[L.H_R1]) + gp[0, L.C_BODY] * (w1 - v[L.H_R1])
    mb2 = gp[1, L.K_BODY] * (x[L.H_H2] - x[L.H_TH2]) + gp[1, L.C_BODY] * (v[L.H_H2] - v[L.H_TH2])
    return mb1, mb2


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def body_dissipation(p, gp, w1, v):
    """p plus the power [W] of the body dampers at the driver hub rate w1 and the body rates
    v [rad/s]."""
    d1 = w1 - v[L.H_R1]
    d2 = v[L.H_H2] - v[L.H_TH2]
    return p + gp[0, L.C_BODY] * d1 * d1 + gp[1, L.C_BODY] * d2 * d2


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def coupled_forces(mdl, ws, nc, nact, cset, ns, drv, hub, v, teeth, gpk):
    """Forces and accelerations for the contacts ws.rec[:nc], the tooth rotations teeth[0] and
    the rates teeth[1] of their root dampers, the body angles hub[POS] and rates v (columns
    H_*): fills q, the teeth's and the bodies' accelerations (row ACC of hub, and of the teeth
    teeth[2]); drv = (theta1 [rad], theta1' [rad/s], theta1'' [rad/s²], load torque [N m])
    (scalars: a tuple holding an array, built each step, would be reference-counted); gpk: gear_par of the arrowhead solve (with implicit tooth-root dampers the
    tooth inertia I_P + dt/4 c_phi, `explicit.py`). Returns (driver torque [N m], body-spring
    moment on the driver rim [N m])."""
    gp, kphi = mdl[0], mdl[3]
    q, act = ws.q, ws.tset[L.T_ACT]
    th1, w1, acc1, tl = drv
    phi, acc = teeth[0], teeth[2]
    q[:] = 0.0
    generalized_forces(ws.rec, nc, phi, teeth[1], act, nact, kphi, gp, 0.0, q)
    set_springs(cset, ns, kphi, phi, q)
    mb1, mb2 = body_moments(gp, th1, w1, hub[L.POS], v)
    q[0] += mb1
    q[1] += mb2
    rim_accelerations(q, act, nact, gpk, acc, hub[L.ACC])
    hub[L.ACC, L.H_H2] = (tl - mb2) / gp[1, L.I_HUB]
    return gp[0, L.I_HUB] * acc1 + mb1, mb1


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def coupled_energies(mdl, ws, nc, nact, cset, ns, drv, hub, teeth):
    """(kinetic, potential) energy [J]: hubs, rims, body springs, then `mesh_energies` with
    the teeth on the rims, and the coupled set's springs through K_S instead of their own.
    Arguments as `coupled_forces` but drv = (theta1 [rad], theta1' [rad/s]) (always this
    pair: another tuple type would compile the function once more)."""
    gp, kphi = mdl[0], mdl[3]
    th1, w1 = drv[0], drv[1]
    x = hub[L.POS]
    v = hub[L.RATE]
    ke = 0.5 * gp[0, L.I_HUB] * w1 * w1 + 0.5 * (gp[0, L.I_TOT] - gp[0, L.I_HUB]) * v[L.H_R1] * v[L.H_R1]
    ke += 0.5 * gp[1, L.I_HUB] * v[L.H_H2] * v[L.H_H2] + 0.5 * (gp[1, L.I_TOT] - gp[1, L.I_HUB]) * v[L.H_TH2] * v[L.H_TH2]
    pe = 0.5 * gp[0, L.K_BODY] * (th1 - x[L.H_R1]) ** 2 + 0.5 * gp[1, L.K_BODY] * (x[L.H_H2] - x[L.H_TH2]) ** 2
    ke, pe = mesh_energies(ke, pe, v[L.H_R1], v[L.H_TH2], teeth, ws.tset[L.T_ACT], nact, mdl, ws.rec, nc)
    if ns > 0:
        pe += set_energy(cset.ks, cset.lst, ns, teeth[L.POS])
        for a in range(ns):
            i = cset.lst[a]
            pe -= 0.5 * kphi[i] * teeth[L.POS, i] * teeth[L.POS, i]
    return ke, pe


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def new_candidates(newl, incand, pairs, npair, tz2):
    """Teeth of the candidate pairs not yet flagged in incand, in pair order, into newl (and
    flag them). Returns their number."""
    nn = np.int64(0)
    for p in range(npair):
        for g in range(2):
            i = int(pairs[p, g]) + (tz2 if g == 1 else 0)
            if not incand[i]:
                incand[i] = True
                newl[nn] = i
                nn += 1
    return nn


@njit(cache=True, nogil=True, no_cfunc_wrapper=True)
def verlet_coupled(mdl, ctl, hub, teeth, out, ws):
    """Integrate ipar[N_STEPS] steps of par[DT] [s] from t = 0 (see the module docstring);
    arguments, outputs and guards as `explicit.verlet`, with the body angles hub[:, H_*]
    (driver rim, driven rim, driven hub) and TE and theta2 at the hubs. mdl[4]: the tooth
    compliance [rad/(N m)] of teeth coupled through the body, or 0 x 0; mdl[5] the
    `layout.ContactParts`.
    Returns (status, step reached, max active teeth, 0).
    """
    gp, pp, lp, kphi, ctooth, parts = mdl
    geo = (gp, pp, lp, parts)
    par, ipar, table = ctl
    phi, dphi, acc = teeth[L.POS], teeth[L.RATE], teeth[L.ACC]
    rec, pairs, q, vpred, tset, book, cset = ws.rec, ws.pairs, ws.q, ws.vpred, ws.tset, ws.book, ws.cset
    act = tset[L.T_ACT]
    tz2 = int(gp[1, L.TOOTH0])
    dt, speed, ramp = par[L.DT], par[L.SPEED], par[L.SPEED_RAMP]
    x, v, ha = hub[L.POS], hub[L.RATE], hub[L.ACC]
    vh = np.zeros(L.N_HUB)
    vp = np.zeros(L.N_HUB)
    imex = par[L.IMEX] != 0.0
    gpk = kick_gear_par(gp, dt, imex)
    # the dissipation power integrated by the trapezoidal rule: without the implicit tooth-root
    # dampers, whose work each kick books exactly (below)
    gpd = gp.copy()
    if imex:
        for g in range(2):
            gpd[g, L.C_PHI] = 0.0
    mdl_d = (gpd, pp, lp, kphi, ctooth, parts)
    coupled = ctooth.shape[0] > 0
    newl, incand = cset.newl, tset[L.T_INCAND]
    th1, w1, acc1, tl = drive(0.0, par, table)
    # the contact search with the model's parts as arguments of their own (`gearmesh.pair_contacts`)
    buf = (rec, pairs)
    dev, ser, err, fric, edg = parts
    nc, npair = pair_contacts((x[L.H_R1], x[L.H_TH2], v[L.H_R1], v[L.H_TH2]), phi, dphi, geo, buf, dev, ser, err, fric, edg)
    ns = np.int64(0)
    if coupled:
        nn = new_candidates(newl, incand, pairs, npair, tz2)
        ns = update_set(cset, ns, nn, phi, dphi, dphi)
        tset[L.T_INCAND, :] = 0
    nact = initial_set(tset, teeth, pairs, npair, tz2)
    for i in range(dphi.shape[0]):     # (a loop: an array copied into a slice compiles numba's shape-error message)
        vpred[i] = dphi[i]
    react, mb1 = coupled_forces(mdl, ws, nc, nact, cset, ns, (th1, w1, acc1, tl), hub, v, (phi, dphi, acc), gpk)
    # the arrays the steps pass on, taken out once: a view, an attribute or a tuple of arrays made
    # in the loop is reference-counted each step (an atomic operation each), and a conditional
    # inside a call's arguments copies, and counts, every array before it. The forces' tooth
    # rates: with implicit dampers the rates the first kick ended with, where the second starts
    kicked = (phi, dphi if imex else vpred, acc)
    ke, pe = coupled_energies(mdl, ws, nc, nact, cset, ns, (th1, w1), hub, teeth)
    book[L.B_E0] = ke + pe
    book[L.B_P_IN] = react * w1 + tl * v[L.H_H2]
    book[L.B_P_D] = body_dissipation(dissipation_power(dphi, act, nact, mdl_d, rec, nc, ser), gp, w1, v)
    o = max_act = np.int64(0)
    row = (0.0, gp[0, L.RB] * th1 + gp[1, L.RB] * x[L.H_H2], x[L.H_H2], react, ke, pe)
    status = record_output(out, o, row, book, rec, nc, math.isfinite(row[1]), par, np.int64(OK))
    step = 0
    for step in range(1, ipar[L.N_STEPS] + 1):
        t = step * dt
        # half kick, drift
        for k in range(L.N_HUB):
            vh[k] = v[k] + 0.5 * dt * ha[k]
        e_damp = 0.0     # implicit tooth-root dampers: c * (mean rate of the kick)² summed over both kicks
        for a in range(nact):
            i = act[a]
            v0 = dphi[i]
            dphi[i] += 0.5 * dt * acc[i]
            phi[i] += dt * dphi[i]
            if imex:
                e_damp += gp[1 if i >= tz2 else 0, L.C_PHI] * (0.5 * (v0 + dphi[i])) ** 2
        for k in range(L.N_HUB):
            x[k] += dt * vh[k]
            vp[k] = vh[k] + 0.5 * dt * ha[k]    # predicted velocities for the damping terms
        th1, w1, acc1, tl = drive(t, par, table)
        for a in range(nact):
            i = act[a]
            vpred[i] = dphi[i] + 0.5 * dt * acc[i]
        nc, npair = pair_contacts((x[L.H_R1], x[L.H_TH2], vp[L.H_R1], vp[L.H_TH2]), phi, vpred, geo, buf, dev, ser, err, fric, edg)
        nn = new_candidates(newl, incand, pairs, npair, tz2) if coupled else 0
        n_old = nact
        nact = activate(tset, nact, pairs, npair, tz2)
        for a in range(n_old, nact):
            acc[act[a]] = 0.0
            vpred[act[a]] = 0.0
        if coupled and set_differs(cset, ns, nn):
            # the energy the switch moves (see the module docstring), booked
            ke, pe = coupled_energies(mdl, ws, nc, nact, cset, ns, (th1, w1), hub, teeth)
            ns = update_set(cset, ns, nn, phi, dphi, vpred)
            ke2, pe2 = coupled_energies(mdl, ws, nc, nact, cset, ns, (th1, w1), hub, teeth)
            book[L.B_SWITCH] += ke + pe - ke2 - pe2
        react, mb1 = coupled_forces(mdl, ws, nc, nact, cset, ns, (th1, w1, acc1, tl), hub, vp, kicked, gpk)
        # second half kick
        for k in range(L.N_HUB):
            v[k] = vh[k] + 0.5 * dt * ha[k]
        for a in range(nact):
            i = act[a]
            v0 = dphi[i]
            dphi[i] += 0.5 * dt * acc[i]
            if imex:    # the damper torque at the new rate, for the next first kick
                c = gp[1 if i >= tz2 else 0, L.C_PHI]
                q[2 + i] -= c * (dphi[i] - v0)
                e_damp += c * (0.5 * (v0 + dphi[i])) ** 2
        # the driver's hub inertia sees the one-sided acceleration where the ramp ends
        p_in_left = (gp[0, L.I_HUB] * driver_acc_left(t, speed, ramp) + mb1) * w1 + tl * v[L.H_H2]
        p_d = body_dissipation(dissipation_power(vpred, act, nact, mdl_d, rec, nc, ser), gp, w1, vp)
        # each kick of h = dt/2 takes the damper at its mean rate v: M dv = h (Q - C v) - so
        # the kinetic energy it removes is h c v² exactly (the trapezoidal rule on the end
        # rates' power misreads it where the joint is damped beyond critical and the
        # implicit rates alternate from kick to kick)
        book[L.B_DISS] += 0.5 * dt * e_damp
        status, nact = end_step(ws, teeth, nc, npair, nact, tz2, (p_in_left, react * w1 + tl * v[L.H_H2], p_d), par, status)
        if imex:    # the next first kick: its accelerations with the dampers at the new rates
            rim_accelerations(q, act, nact, gpk, acc, ha)
        max_act = max(max_act, nact)
        if step % ipar[L.OUT_EVERY] == 0:
            o += 1
            ke, pe = coupled_energies(mdl, ws, nc, nact, cset, ns, (th1, w1), hub, teeth)
            te = gp[0, L.RB] * th1 + gp[1, L.RB] * x[L.H_H2]
            finite = math.isfinite(x[L.H_TH2]) and math.isfinite(x[L.H_H2])
            status = record_output(out, o, (t, te, x[L.H_H2], react, ke, pe), book, rec, nc, finite, par, status)
        if status != OK:
            break
    return status, step, max_act, 0

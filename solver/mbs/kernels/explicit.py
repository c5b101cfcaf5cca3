"""Explicit, symplectic time integration of the pair (numba): velocity Verlet.

Degrees of freedom: the driven hub angle theta2 and the tooth rotations phi (relative to
their hubs). The driver hub follows the prescribed speed ramp, and the load torque ramps on
gear 2. The mass matrix of a gear is an arrowhead (hub row coupled to each tooth by
I_cpl = I_P + m*r_pv*l_g), solved in O(active teeth) by its Schur complement; teeth not in
the active set move rigidly with their hub (their inertia is in I_tot).

Active set: teeth of the pre-search candidates; a tooth outside it stays integrated until
|phi| < phi_quiet and |dphi| < dphi_quiet, then it is frozen at exactly zero.

Damping forces use the predicted velocity v_half + dt/2*a_old, which keeps second order.
With par[IMEX] = 1 (linear tooth-root dampers, n_c = 1 on both gears) the tooth-root damper
torque -c_phi*dphi is instead taken implicitly (IMEX), at the mean of the rates each half kick
starts and ends with: the kick over h = dt/2 solves (M + h/2*C) dv = h*(Q - C*v), an
arrowhead again, with the tooth inertia I_P + dt/4*c_phi in place of I_P
(`arrowhead_accelerations` on a copy of gear_par). The damper then acts by the trapezoidal
rule in each kick (A-stable, second order over the symmetric step; the same with the damper at
the kick's end rate alone would be first order): the step is limited by the stiffness alone,
not by the damping (`solver.mbs.stability`). The second kick ends the step; the generalised
forces at the new position are then taken with the new rates for the next step's first kick
(the damper is linear, so that is q - c_phi*dv, and a second arrowhead solve). Contact
dampers stay explicit (predicted velocity).
Energy bookkeeping (trapezoidal in time): work in (driver + load torque), kinetic and
potential energy, dissipated energy; the balance closes to O(dt^2).

Status codes: 0 ok, 1 non-finite state, 2 penetration beyond the bound, 3 energy balance.
"""
import math

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels import njit
from solver.mbs.kernels.gearmesh import generalized_forces, pair_contacts
from solver.mbs.kernels.mechanics import (
    arrowhead_accelerations,
    dissipation_power,
    drive,
    driver_acc_left,
    driver_speed,
    kick_gear_par,
    mesh_energies,
)
from solver.mbs.kernels.status import OK
from solver.mbs.kernels.stepping import activate, end_step, initial_set, record_output


@njit(cache=True, nogil=True, no_cfunc_wrapper=True)
def verlet(mdl, ctl, hub, teeth, out, ws):
    """Integrate ipar[N_STEPS] steps of par[DT] [s] from t = 0; write every
    ipar[OUT_EVERY]-th state to ``out`` (`layout` O_* columns).

    mdl: (gear_par, pair_par, law_par, k_phi, tooth_compliance, `layout.ContactParts`; the
    compliance unused here);
    ctl: (par, ipar, load_table) with the `layout` control columns and the load profile
    (n x 2; 0 rows: the torque ramp, see `load_torque`); hub[:, H_TH2] and teeth (rows
    angle, rate, acceleration) the initial state, advanced in place. The run stops on the
    guards of `stepping` (energy growth beyond par[ENERGY_TOL], checked at the output
    instants). ws: the work arrays (`layout.StepWork`, from `stepping.work_arrays`). Returns
    (status, step reached, max active teeth, 0).
    """
    gp, kphi = mdl[0], mdl[3]
    geo = (gp, mdl[1], mdl[2], mdl[5])
    par, ipar, table = ctl
    phi, dphi, acc = teeth[L.POS], teeth[L.RATE], teeth[L.ACC]
    rec, pairs, q, vpred, book = ws.rec, ws.pairs, ws.q, ws.vpred, ws.book
    act = ws.tset[L.T_ACT]
    tz2 = int(gp[1, L.TOOTH0])
    dt, speed, ramp = par[L.DT], par[L.SPEED], par[L.SPEED_RAMP]
    imex = par[L.IMEX] != 0.0
    gpk = kick_gear_par(gp, dt, imex)
    theta2, w2 = hub[L.POS, L.H_TH2], hub[L.RATE, L.H_TH2]
    th1, w1, acc1, tl = drive(0.0, par, table)
    # the contact search with the model's parts as arguments of their own (`gearmesh.pair_contacts`)
    buf = (rec, pairs)
    dev, ser, err, fric, edg = mdl[5]
    nc, npair = pair_contacts((th1, theta2, w1, w2), phi, dphi, geo, buf, dev, ser, err, fric, edg)
    nact = initial_set(ws.tset, teeth, pairs, npair, tz2)
    generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, tl, q)
    a2, s1, r1 = arrowhead_accelerations(q, act, nact, gpk, acc)
    react = s1 * acc1 + r1
    cr1 = gpk[0, L.I_CPL] / gpk[0, L.I_P]
    ke, pe = mesh_energies(0.5 * gp[0, L.I_TOT] * w1 * w1 + 0.5 * gp[1, L.I_TOT] * w2 * w2, 0.0, w1, w2,
                           teeth, act, nact, mdl, rec, nc)
    book[L.B_E0] = ke + pe
    book[L.B_P_IN] = react * w1 + tl * w2
    book[L.B_P_D] = dissipation_power(dphi, act, nact, mdl, rec, nc)
    te0 = gp[0, L.RB] * th1 + gp[1, L.RB] * theta2
    o = max_act = np.int64(0)
    status = record_output(out, o, (0.0, te0, theta2, react, ke, pe), book, rec, nc, math.isfinite(te0), par, np.int64(OK))
    step = 0
    for step in range(1, ipar[L.N_STEPS] + 1):
        # half kick (the driver coupling of gear-1 teeth as its exact speed increment), drift
        t_old = (step - 1) * dt
        t = step * dt
        dw_a = driver_speed(t_old + 0.5 * dt, speed, ramp) - driver_speed(t_old, speed, ramp)
        dw_b = driver_speed(t, speed, ramp) - driver_speed(t_old + 0.5 * dt, speed, ramp)
        w2h = w2 + 0.5 * dt * a2
        for a in range(nact):
            i = act[a]
            dphi[i] += 0.5 * dt * acc[i]
            if i < tz2:
                dphi[i] -= cr1 * dw_a
            phi[i] += dt * dphi[i]
        theta2 += dt * w2h
        th1, w1, acc1, tl = drive(t, par, table)
        # predicted velocities for the damping terms
        w2p = w2h + 0.5 * dt * a2
        for a in range(nact):
            i = act[a]
            vpred[i] = dphi[i] + 0.5 * dt * acc[i]
            if i < tz2:
                vpred[i] -= cr1 * dw_b
        # contacts; activate the teeth the pre-search finds
        nc, npair = pair_contacts((th1, theta2, w1, w2p), phi, vpred, geo, buf, dev, ser, err, fric, edg)
        n_old = nact
        nact = activate(ws.tset, nact, pairs, npair, tz2)
        for a in range(n_old, nact):
            acc[act[a]] = 0.0
            vpred[act[a]] = 0.0
        for i in range(q.shape[0]):
            q[i] = 0.0
        # (implicit dampers: at the rates the first kick ended with, where the second starts;
        # chosen apart from the calls: a conditional inside a call's arguments makes numba copy,
        # and so reference-count, every array argument before it, each step)
        rates = dphi if imex else vpred
        generalized_forces(rec, nc, phi, rates, act, nact, kphi, gp, tl, q)
        a2, s1, r1 = arrowhead_accelerations(q, act, nact, gpk, acc)
        react = s1 * acc1 + r1
        # second half kick
        w2 = w2h + 0.5 * dt * a2
        for a in range(nact):
            i = act[a]
            v0 = dphi[i]
            dphi[i] += 0.5 * dt * acc[i]
            if i < tz2:
                dphi[i] -= cr1 * dw_b
            if imex:    # the damper torque at the new rate, for the next first kick
                q[2 + i] -= gp[1 if i >= tz2 else 0, L.C_PHI] * (dphi[i] - v0)
        # one-sided driver torques where the speed ramp ends on this instant
        p_in_left = (s1 * driver_acc_left(t, speed, ramp) + r1) * w1 + tl * w2
        p_d = dissipation_power(rates, act, nact, mdl, rec, nc)
        status, nact = end_step(ws, teeth, nc, npair, nact, tz2, (p_in_left, react * w1 + tl * w2, p_d), par, status)
        if imex:    # the next first kick: its accelerations with the dampers at the new rates
            a2, _s, _r = arrowhead_accelerations(q, act, nact, gpk, acc)
        max_act = max(max_act, nact)
        if step % ipar[L.OUT_EVERY] == 0:
            o += 1
            ke, pe = mesh_energies(0.5 * gp[0, L.I_TOT] * w1 * w1 + 0.5 * gp[1, L.I_TOT] * w2 * w2, 0.0, w1, w2,
                                   teeth, act, nact, mdl, rec, nc)
            te = gp[0, L.RB] * th1 + gp[1, L.RB] * theta2
            finite = math.isfinite(theta2) and math.isfinite(w2)
            status = record_output(out, o, (t, te, theta2, react, ke, pe), book, rec, nc, finite, par, status)
        if status != OK:
            break
    hub[L.POS, L.H_TH2], hub[L.RATE, L.H_TH2], hub[L.ACC, L.H_TH2] = theta2, w2, a2
    return status, step, max_act, 0

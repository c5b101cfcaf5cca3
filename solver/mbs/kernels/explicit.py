"""Explicit, symplectic time integration of the pair (numba): velocity Verlet.

Degrees of freedom: the driven hub angle theta2 and the tooth rotations phi (relative to
their hubs). The driver hub follows the prescribed speed ramp, and the load torque ramps on
gear 2. The mass matrix of a gear is an arrowhead (hub row coupled to each tooth by
I_cpl = I_P + m*r_pv*l_g), solved in O(active teeth) by its Schur complement; teeth not in
the active set move rigidly with their hub (their inertia is in I_tot).

Active set: teeth of the pre-search candidates; a tooth outside it stays integrated until
|phi| < phi_quiet and |dphi| < dphi_quiet, then it is frozen at exactly zero.

Damping forces use the predicted velocity v_half + dt/2*a_old, which keeps second order.
Energy bookkeeping (trapezoidal in time): work in (driver + load torque), kinetic and
potential energy, dissipated energy; the balance closes to O(dt^2).

Status codes: 0 ok, 1 non-finite state, 2 penetration beyond the bound, 3 energy balance.
"""
import math

import numpy as np
from numba import njit

from solver.mbs.kernels.gearmesh import generalized_forces, mesh_contacts
from solver.mbs.kernels.laws import contact_energy, signed_pow, spring_energy
from solver.mbs.kernels.layout import (
    C_DDELTA,
    C_DELTA,
    C_FORCE,
    C_PHI,
    I_CPL,
    I_P,
    I_TOT,
    K_CON,
    M1,
    N_C,
    N_K,
    RB,
    TOOTH0,
)
from solver.mbs.kernels.stepping import (
    OK,
    PENETRATION,
    checked_status,
    clear_candidates,
    freeze_quiet_teeth,
    loaded_contacts,
    record_output,
)


@njit(cache=True)
def driver_motion(t, speed, ramp):
    """Driver angle [rad], speed [rad/s] and acceleration [rad/s²] of the speed ramp."""
    if t < ramp:
        acc = speed / ramp
        return 0.5 * acc * t * t, acc * t, acc
    return speed * (t - 0.5 * ramp), speed, 0.0


@njit(cache=True)
def driver_acc_left(t, speed, ramp):
    """Left limit of the driver acceleration at t [rad/s²]."""
    return speed / ramp if t <= ramp else 0.0


@njit(cache=True)
def load_torque(t, torque, ramp, table):
    """Resisting torque on gear 2 [N m] at time t [s]: ramped from zero to ``torque`` over
    ``ramp`` [s], or, when ``table`` (n x 2: time [s], torque [N m], times increasing) has
    rows, linear between its points and held at its ends."""
    n = table.shape[0]
    if n == 0:
        if t < ramp:
            return torque * t / ramp
        return torque
    if t <= table[0, 0]:
        return table[0, 1]
    for k in range(1, n):
        if t <= table[k, 0]:
            t0 = table[k - 1, 0]
            return table[k - 1, 1] + (table[k, 1] - table[k - 1, 1]) * (t - t0) / (table[k, 0] - t0)
    return table[n - 1, 1]


@njit(cache=True)
def driver_speed(t, speed, ramp):
    """Driver speed [rad/s] of the ramp (continuous, with a kink at the ramp end)."""
    return speed * t / ramp if t < ramp else speed


@njit(cache=True)
def _accelerations(q, act, nact, gp, acc, tz2):
    """Solve the arrowhead systems for the force part of the accelerations.

    Gear-1 teeth get (Q_phi)/I_P only: the prescribed driver's inertial coupling
    -I_cpl/I_P * theta1'' is applied by the caller as exact velocity increments, since
    theta1'' jumps at the end of the speed ramp. Returns (theta2'', S1, R1) with the driver
    torque T = S1*theta1'' + R1.
    """
    s = gp[1, I_TOT]
    rhs = q[1]
    for a in range(nact):
        i = act[a]
        if i >= tz2:
            c = gp[1, I_CPL]
            s -= c * c / gp[1, I_P]
            rhs -= c * q[2 + i] / gp[1, I_P]
    a2 = rhs / s
    s1 = gp[0, I_TOT]
    r1 = -q[0]
    for a in range(nact):
        i = act[a]
        if i >= tz2:
            acc[i] = (q[2 + i] - gp[1, I_CPL] * a2) / gp[1, I_P]
        else:
            acc[i] = q[2 + i] / gp[0, I_P]
            s1 -= gp[0, I_CPL] * gp[0, I_CPL] / gp[0, I_P]
            r1 += gp[0, I_CPL] * acc[i]
    return a2, s1, r1


@njit(cache=True)
def _energies(w1, w2, phi, dphi, act, nact, kphi, gp, rec, nc, lp, tz2):
    ke = 0.5 * gp[0, I_TOT] * w1 * w1 + 0.5 * gp[1, I_TOT] * w2 * w2
    pe = 0.0
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        w = w2 if g == 1 else w1
        ke += gp[g, I_CPL] * w * dphi[i] + 0.5 * gp[g, I_P] * dphi[i] * dphi[i]
        pe += spring_energy(phi[i], kphi[i], gp[g, N_K])
    for c in range(nc):
        pe += contact_energy(rec[c, C_DELTA], lp[K_CON], lp[M1])
    return ke, pe


@njit(cache=True)
def _dissipation_power(dphi, act, nact, gp, rec, nc, lp, tz2):
    p = 0.0
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        if gp[g, C_PHI] != 0.0:
            p += gp[g, C_PHI] * signed_pow(dphi[i], gp[g, N_C]) * dphi[i]
    for c in range(nc):
        d = rec[c, C_DELTA]
        if d > 0.0:
            fel = lp[K_CON] * d ** lp[M1]
            p += (rec[c, C_FORCE] - fel) * rec[c, C_DDELTA]
    return p


@njit(cache=True)
def verlet(gp, pp, lp, kphi, speed, speed_ramp, torque, torque_ramp, load_table, dt, n_steps, out_every,
           theta2, w2, phi, dphi, phi_quiet, dphi_quiet, delta_max, energy_tol,
           o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2):
    """Integrate n_steps of size dt [s] from t = 0; write every out_every-th state.

    theta2 [rad], w2 [rad/s], phi, dphi (Z1+Z2) are the initial state (phi, dphi updated in
    place). The resisting torque follows `load_torque` (ramp to ``torque`` over ``torque_ramp``
    [s], or the profile ``load_table``, n x 2, when it has rows). Outputs: time [s], TE [m], max contact force over the interval [N], loaded
    contacts, driver reaction torque [N m], kinetic, potential, input and dissipated energy
    [J], theta2 [rad]. The run stops (status 3) when the energy balance shows a growth
    work - (kinetic + potential - initial) - dissipated < -energy_tol * (energy scale), checked
    at the output instants. Returns (status, step reached, max active teeth).
    """
    ntooth = phi.shape[0]
    tz2 = int(gp[1, TOOTH0])
    rb1 = gp[0, RB]
    rb2 = gp[1, RB]
    rec = np.zeros((64, 15))
    pairs = np.zeros((64, 3), dtype=np.int64)
    q = np.zeros(ntooth + 2)
    acc = np.zeros(ntooth)
    vpred = np.zeros(ntooth)
    active = np.zeros(ntooth, dtype=np.int64)
    act = np.zeros(ntooth, dtype=np.int64)
    incand = np.zeros(ntooth, dtype=np.int64)
    for i in range(ntooth):
        if phi[i] != 0.0 or dphi[i] != 0.0:
            active[i] = True
    max_act = np.int64(0)

    t = 0.0
    th1, w1, acc1 = driver_motion(0.0, speed, speed_ramp)
    # initial forces
    nc, npair = mesh_contacts(th1, theta2, phi, w1, w2, dphi, gp, pp, lp, pairs, rec)
    for p in range(npair):
        active[int(pairs[p, 0])] = True
        active[tz2 + int(pairs[p, 1])] = True
    # counters start as np.int64(0), not a literal 0: numba would otherwise compile each callee
    # once more for the argument type Literal[int](0)
    nact = np.int64(0)
    for i in range(ntooth):
        if active[i]:
            act[nact] = i
            nact += 1
    for i in range(ntooth + 2):
        q[i] = 0.0
    generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, load_torque(0.0, torque, torque_ramp, load_table), q)
    a2, s1, r1 = _accelerations(q, act, nact, gp, acc, tz2)
    react = s1 * acc1 + r1
    cr1 = gp[0, I_CPL] / gp[0, I_P]
    ke, pe = _energies(w1, w2, phi, dphi, act, nact, kphi, gp, rec, nc, lp, tz2)
    e0 = ke + pe
    work = 0.0
    diss = 0.0
    p_in_old = react * w1 + load_torque(0.0, torque, torque_ramp, load_table) * w2
    p_d_old = _dissipation_power(dphi, act, nact, gp, rec, nc, lp, tz2)
    fmax = 0.0
    o = np.int64(0)
    record_output(o, 0.0, rb1 * th1 + rb2 * theta2, 0.0, nc, react, ke, pe, 0.0, 0.0, theta2,
                  o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2)
    status = np.int64(OK)
    step = 0
    for step in range(1, n_steps + 1):
        # half kick (the driver coupling of gear-1 teeth as its exact speed increment), drift
        t_old = (step - 1) * dt
        t = step * dt
        dw_a = driver_speed(t_old + 0.5 * dt, speed, speed_ramp) - driver_speed(t_old, speed, speed_ramp)
        dw_b = driver_speed(t, speed, speed_ramp) - driver_speed(t_old + 0.5 * dt, speed, speed_ramp)
        w2h = w2 + 0.5 * dt * a2
        for a in range(nact):
            i = act[a]
            dphi[i] += 0.5 * dt * acc[i]
            if i < tz2:
                dphi[i] -= cr1 * dw_a
            phi[i] += dt * dphi[i]
        theta2 += dt * w2h
        th1, w1, acc1 = driver_motion(t, speed, speed_ramp)
        tl = load_torque(t, torque, torque_ramp, load_table)
        # predicted velocities for the damping terms
        w2p = w2h + 0.5 * dt * a2
        for a in range(nact):
            i = act[a]
            vpred[i] = dphi[i] + 0.5 * dt * acc[i]
            if i < tz2:
                vpred[i] -= cr1 * dw_b
        # contacts; activate the teeth the pre-search finds
        nc, npair = mesh_contacts(th1, theta2, phi, w1, w2p, vpred, gp, pp, lp, pairs, rec)
        for p in range(npair):
            for g in range(2):
                i = int(pairs[p, g]) + (tz2 if g == 1 else 0)
                incand[i] = True
                if not active[i]:
                    active[i] = True
                    act[nact] = i
                    nact += 1
                    acc[i] = 0.0
                    vpred[i] = 0.0
        for i in range(ntooth + 2):
            q[i] = 0.0
        generalized_forces(rec, nc, phi, vpred, act, nact, kphi, gp, tl, q)
        a2, s1, r1 = _accelerations(q, act, nact, gp, acc, tz2)
        react = s1 * acc1 + r1
        # second half kick
        w2 = w2h + 0.5 * dt * a2
        for a in range(nact):
            i = act[a]
            dphi[i] += 0.5 * dt * acc[i]
            if i < tz2:
                dphi[i] -= cr1 * dw_b
        # guard and bookkeeping
        for c in range(nc):
            if rec[c, C_FORCE] > fmax:
                fmax = rec[c, C_FORCE]
            if rec[c, C_DELTA] > delta_max:
                status = PENETRATION
        # one-sided driver torques where the speed ramp ends on this instant
        p_in_left = (s1 * driver_acc_left(t, speed, speed_ramp) + r1) * w1 + tl * w2
        p_in = react * w1 + tl * w2
        p_d = _dissipation_power(vpred, act, nact, gp, rec, nc, lp, tz2)
        work += 0.5 * dt * (p_in_left + p_in_old)
        diss += 0.5 * dt * (p_d + p_d_old)
        p_in_old = p_in
        p_d_old = p_d
        # freeze quiet teeth outside the candidates
        nact = freeze_quiet_teeth(act, nact, active, incand, phi, dphi, acc, q, phi_quiet, dphi_quiet)
        clear_candidates(incand, pairs, npair, tz2)
        if nact > max_act:
            max_act = nact
        if step % out_every == 0:
            o += 1
            ke, pe = _energies(w1, w2, phi, dphi, act, nact, kphi, gp, rec, nc, lp, tz2)
            record_output(o, t, rb1 * th1 + rb2 * theta2, fmax, loaded_contacts(rec, nc), react, ke, pe, work, diss, theta2,
                          o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2)
            fmax = 0.0
            status = checked_status(status, math.isfinite(theta2) and math.isfinite(w2) and math.isfinite(ke + pe), ke, pe, e0, work, diss, energy_tol)
        if status != OK:
            break
    return status, step, max_act

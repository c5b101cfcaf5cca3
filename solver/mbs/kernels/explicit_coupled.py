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
energy and the body springs' potential energy.

Teeth coupled through the body (``ctooth``, the compliance model; 0 x 0 otherwise): the
teeth of the pre-search candidates form the set S whose springs act through
K_S = (C[S, S])^-1 (`toothcoupling`); the other active teeth keep their own spring
kphi = 1/C[a, a]. When S changes, a tooth that joins it takes on the rotation and rate its
neighbours' moments give it (phi_i += sum_b C[i, b] M_b), and a tooth that leaves gives them
back. A tooth that joins unloaded (from rest, as teeth come from the frozen set) so changes
no spring moment, and a tooth that leaves keeps its own; the remaining teeth's moments move
by the coupling of the leaving tooth's moment, small since it has just left the mesh.
"""
import math

import numpy as np
from numba import njit

from solver.mbs.kernels.explicit import _dissipation_power, driver_acc_left, driver_motion, load_torque
from solver.mbs.kernels.gearmesh import generalized_forces, mesh_contacts
from solver.mbs.kernels.laws import contact_energy, spring_energy
from solver.mbs.kernels.layout import C_BODY, C_DELTA, C_FORCE, I_CPL, I_HUB, I_P, I_TOT, K_BODY, K_CON, M1, N_K, RB, TOOTH0
from solver.mbs.kernels.stepping import (
    OK,
    PENETRATION,
    checked_status,
    clear_candidates,
    freeze_quiet_teeth,
    loaded_contacts,
    record_output,
)
from solver.mbs.kernels.toothcoupling import set_energy, set_moment, set_stiffness


@njit(cache=True)
def _rim_accelerations(q, act, nact, gp, acc, tz2, m1, m2):
    """Arrowhead solves of both rims: returns (r1'', theta2''); fills the teeth's acc.

    q[0], q[1]: generalised forces on the rims (contacts + body springs); m1, m2 the rim inertias.
    """
    s1 = m1
    s2 = m2
    rhs1 = q[0]
    rhs2 = q[1]
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        c = gp[g, I_CPL]
        if g == 1:
            s2 -= c * c / gp[1, I_P]
            rhs2 -= c * q[2 + i] / gp[1, I_P]
        else:
            s1 -= c * c / gp[0, I_P]
            rhs1 -= c * q[2 + i] / gp[0, I_P]
    a1 = rhs1 / s1
    a2 = rhs2 / s2
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        ar = a2 if g == 1 else a1
        acc[i] = (q[2 + i] - gp[g, I_CPL] * ar) / gp[g, I_P]
    return a1, a2


@njit(cache=True)
def _energies_coupled(w1, v1, w2, wh2, th1, r1, th2, h2, phi, dphi, act, nact, kphi, gp, rec, nc, lp, tz2,
                      ks, slst, ns):
    ke = 0.5 * gp[0, I_HUB] * w1 * w1 + 0.5 * (gp[0, I_TOT] - gp[0, I_HUB]) * v1 * v1
    ke += 0.5 * gp[1, I_HUB] * wh2 * wh2 + 0.5 * (gp[1, I_TOT] - gp[1, I_HUB]) * w2 * w2
    pe = 0.5 * gp[0, K_BODY] * (th1 - r1) ** 2 + 0.5 * gp[1, K_BODY] * (h2 - th2) ** 2
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        w = w2 if g == 1 else v1
        ke += gp[g, I_CPL] * w * dphi[i] + 0.5 * gp[g, I_P] * dphi[i] * dphi[i]
        pe += spring_energy(phi[i], kphi[i], gp[g, N_K])
    for c in range(nc):
        pe += contact_energy(rec[c, C_DELTA], lp[K_CON], lp[M1])
    if ns > 0:      # the set's springs through K_S instead of their own (linear) springs
        pe += set_energy(ks, slst, ns, phi)
        for a in range(ns):
            i = slst[a]
            pe -= 0.5 * kphi[i] * phi[i] * phi[i]
    return ke, pe


@njit(cache=True)
def _update_set(ctooth, ks, slst, ns, newl, nn, inset, innew, phi, dphi, vpred, mo, dmo):
    """Make newl[:nn] the coupled set (``inset`` flags the old members): teeth that join take
    their neighbours' share of rotation and rate, teeth that leave give it back (see the
    module docstring for what stays continuous). Returns the new size."""
    for a in range(nn):
        innew[newl[a]] = True
    same = nn == ns
    if same:
        for a in range(ns):
            if not innew[slst[a]]:
                same = False
                break
    if not same:
        for a in range(ns):
            mo[a] = set_moment(ks, slst, ns, phi, a)
            dmo[a] = set_moment(ks, slst, ns, vpred, a)
        for a in range(ns):                     # leaving
            i = slst[a]
            if not innew[i]:
                for b in range(ns):
                    j = slst[b]
                    if j != i:
                        phi[i] -= ctooth[i, j] * mo[b]
                        dphi[i] -= ctooth[i, j] * dmo[b]
                        vpred[i] -= ctooth[i, j] * dmo[b]
                inset[i] = False
        for a in range(nn):                     # joining
            i = newl[a]
            if not inset[i]:
                for b in range(ns):
                    j = slst[b]
                    phi[i] += ctooth[i, j] * mo[b]
                    dphi[i] += ctooth[i, j] * dmo[b]
                    vpred[i] += ctooth[i, j] * dmo[b]
        for a in range(nn):
            slst[a] = newl[a]
            inset[newl[a]] = True
        set_stiffness(ctooth, slst, nn, ks)
        ns = nn
    for a in range(nn):
        innew[newl[a]] = False
    return ns


@njit(cache=True)
def _set_springs(ks, slst, ns, kphi, phi, q):
    """Replace the own elastic spring torque of the set's teeth by the coupled one."""
    for a in range(ns):
        i = slst[a]
        q[2 + i] += kphi[i] * phi[i] - set_moment(ks, slst, ns, phi, a)


@njit(cache=True)
def verlet_coupled(gp, pp, lp, kphi, ctooth, speed, speed_ramp, torque, torque_ramp, load_table, dt, n_steps, out_every,
                   r1, v1, theta2, w2, h2, wh2, phi, dphi, phi_quiet, dphi_quiet, delta_max, energy_tol,
                   o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2):
    """Integrate n_steps of size dt [s] from t = 0 (see the module docstring).

    Initial state: driver rim r1 [rad] and speed v1, driven rim theta2 and w2, driven hub h2
    and wh2, phi and dphi (updated in place). Outputs as `explicit.verlet`, with TE and
    theta2 at the hubs; the same guards (energy growth beyond ``energy_tol`` as in `verlet`).
    ``ctooth``: the tooth compliance [rad/(N m)] of teeth coupled through the body, or 0 x 0.
    Returns (status, step reached, max active teeth).
    """
    ntooth = phi.shape[0]
    tz2 = int(gp[1, TOOTH0])
    rb1 = gp[0, RB]
    rb2 = gp[1, RB]
    kb1 = gp[0, K_BODY]
    kb2 = gp[1, K_BODY]
    cb1 = gp[0, C_BODY]
    cb2 = gp[1, C_BODY]
    mr1 = gp[0, I_TOT] - gp[0, I_HUB]
    mr2 = gp[1, I_TOT] - gp[1, I_HUB]
    ih1 = gp[0, I_HUB]
    ih2 = gp[1, I_HUB]
    rec = np.zeros((64, 15))
    pairs = np.zeros((64, 3), dtype=np.int64)
    q = np.zeros(ntooth + 2)
    acc = np.zeros(ntooth)
    vpred = np.zeros(ntooth)
    active = np.zeros(ntooth, dtype=np.int64)
    act = np.zeros(ntooth, dtype=np.int64)
    incand = np.zeros(ntooth, dtype=np.int64)
    coupled = ctooth.shape[0] > 0
    ms = 2 * pairs.shape[0] if coupled else 0   # the coupled set: at most both teeth of every candidate pair
    ks = np.zeros((ms, 2 * ms))
    slst = np.zeros(ms, dtype=np.int64)
    newl = np.zeros(ms, dtype=np.int64)
    mo = np.zeros(ms)
    dmo = np.zeros(ms)
    inset = np.zeros(ntooth, dtype=np.int64)
    innew = np.zeros(ntooth, dtype=np.int64)
    ns = np.int64(0)
    for i in range(ntooth):
        if phi[i] != 0.0 or dphi[i] != 0.0:
            active[i] = True
    max_act = np.int64(0)

    t = 0.0
    th1, w1, acc1 = driver_motion(0.0, speed, speed_ramp)
    tl = load_torque(0.0, torque, torque_ramp, load_table)
    nc, npair = mesh_contacts(r1, theta2, phi, v1, w2, dphi, gp, pp, lp, pairs, rec)
    nn = np.int64(0)
    for p in range(npair):
        for g in range(2):
            i = int(pairs[p, g]) + (tz2 if g == 1 else 0)
            active[i] = True
            if coupled and not incand[i]:
                incand[i] = True
                newl[nn] = i
                nn += 1
    if coupled:
        ns = _update_set(ctooth, ks, slst, ns, newl, nn, inset, innew, phi, dphi, dphi, mo, dmo)
        clear_candidates(incand, pairs, npair, tz2)
    nact = np.int64(0)     # not a literal 0: numba would compile the callees once more for it
    for i in range(ntooth):
        if active[i]:
            act[nact] = i
            nact += 1
    for i in range(ntooth + 2):
        q[i] = 0.0
    generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, 0.0, q)
    _set_springs(ks, slst, ns, kphi, phi, q)
    mb1 = kb1 * (th1 - r1) + cb1 * (w1 - v1)
    mb2 = kb2 * (h2 - theta2) + cb2 * (wh2 - w2)
    q[0] += mb1
    q[1] += mb2
    a1, a2 = _rim_accelerations(q, act, nact, gp, acc, tz2, mr1, mr2)
    ah2 = (tl - mb2) / ih2
    react = ih1 * acc1 + mb1
    ke, pe = _energies_coupled(w1, v1, w2, wh2, th1, r1, theta2, h2, phi, dphi, act, nact, kphi, gp, rec, nc, lp, tz2, ks, slst, ns)
    e0 = ke + pe
    work = 0.0
    diss = 0.0
    p_in_old = react * w1 + tl * wh2
    p_d_old = _dissipation_power(dphi, act, nact, gp, rec, nc, lp, tz2) + cb1 * (w1 - v1) ** 2 + cb2 * (wh2 - w2) ** 2
    fmax = 0.0
    o = np.int64(0)
    record_output(o, 0.0, rb1 * th1 + rb2 * h2, 0.0, nc, react, ke, pe, 0.0, 0.0, h2,
                  o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2)
    status = np.int64(OK)
    step = 0
    for step in range(1, n_steps + 1):
        t = step * dt
        # half kick, drift
        v1h = v1 + 0.5 * dt * a1
        w2h = w2 + 0.5 * dt * a2
        wh2h = wh2 + 0.5 * dt * ah2
        for a in range(nact):
            i = act[a]
            dphi[i] += 0.5 * dt * acc[i]
            phi[i] += dt * dphi[i]
        r1 += dt * v1h
        theta2 += dt * w2h
        h2 += dt * wh2h
        th1, w1, acc1 = driver_motion(t, speed, speed_ramp)
        tl = load_torque(t, torque, torque_ramp, load_table)
        # predicted velocities for the damping terms
        v1p = v1h + 0.5 * dt * a1
        w2p = w2h + 0.5 * dt * a2
        wh2p = wh2h + 0.5 * dt * ah2
        for a in range(nact):
            i = act[a]
            vpred[i] = dphi[i] + 0.5 * dt * acc[i]
        nc, npair = mesh_contacts(r1, theta2, phi, v1p, w2p, vpred, gp, pp, lp, pairs, rec)
        nn = np.int64(0)
        for p in range(npair):
            for g in range(2):
                i = int(pairs[p, g]) + (tz2 if g == 1 else 0)
                if coupled and not incand[i]:
                    newl[nn] = i
                    nn += 1
                incand[i] = True
                if not active[i]:
                    active[i] = True
                    act[nact] = i
                    nact += 1
                    acc[i] = 0.0
                    vpred[i] = 0.0
        if coupled:
            ns = _update_set(ctooth, ks, slst, ns, newl, nn, inset, innew, phi, dphi, vpred, mo, dmo)
        for i in range(ntooth + 2):
            q[i] = 0.0
        generalized_forces(rec, nc, phi, vpred, act, nact, kphi, gp, 0.0, q)
        _set_springs(ks, slst, ns, kphi, phi, q)
        mb1 = kb1 * (th1 - r1) + cb1 * (w1 - v1p)
        mb2 = kb2 * (h2 - theta2) + cb2 * (wh2p - w2p)
        q[0] += mb1
        q[1] += mb2
        a1, a2 = _rim_accelerations(q, act, nact, gp, acc, tz2, mr1, mr2)
        ah2 = (tl - mb2) / ih2
        react = ih1 * acc1 + mb1
        # second half kick
        v1 = v1h + 0.5 * dt * a1
        w2 = w2h + 0.5 * dt * a2
        wh2 = wh2h + 0.5 * dt * ah2
        for a in range(nact):
            i = act[a]
            dphi[i] += 0.5 * dt * acc[i]
        for c in range(nc):
            if rec[c, C_FORCE] > fmax:
                fmax = rec[c, C_FORCE]
            if rec[c, C_DELTA] > delta_max:
                status = PENETRATION
        # the driver's hub inertia sees the one-sided acceleration where the ramp ends
        p_in_left = (ih1 * driver_acc_left(t, speed, speed_ramp) + mb1) * w1 + tl * wh2
        p_in = react * w1 + tl * wh2
        p_d = (_dissipation_power(vpred, act, nact, gp, rec, nc, lp, tz2)
               + cb1 * (w1 - v1p) * (w1 - v1p) + cb2 * (wh2p - w2p) * (wh2p - w2p))
        work += 0.5 * dt * (p_in_left + p_in_old)
        diss += 0.5 * dt * (p_d + p_d_old)
        p_in_old = p_in
        p_d_old = p_d
        nact = freeze_quiet_teeth(act, nact, active, incand, phi, dphi, acc, q, phi_quiet, dphi_quiet)
        clear_candidates(incand, pairs, npair, tz2)
        if nact > max_act:
            max_act = nact
        if step % out_every == 0:
            o += 1
            ke, pe = _energies_coupled(w1, v1, w2, wh2, th1, r1, theta2, h2, phi, dphi, act, nact, kphi, gp, rec, nc, lp, tz2, ks, slst, ns)
            record_output(o, t, rb1 * th1 + rb2 * h2, fmax, loaded_contacts(rec, nc), react, ke, pe, work, diss, h2,
                          o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2)
            fmax = 0.0
            status = checked_status(status, math.isfinite(theta2) and math.isfinite(h2) and math.isfinite(ke + pe), ke, pe, e0, work, diss, energy_tol)
        if status != OK:
            break
    return status, step, max_act

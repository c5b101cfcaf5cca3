"""Implicit time integration of the pair (numba): HHT-alpha with Newton on the analytic tangent.

Same degrees of freedom, loads, active-tooth set and outputs as the explicit kernel
(`explicit.py`): the driven hub angle theta2 and the rotations phi of the active teeth; the
driver hub follows the prescribed speed ramp; idle quiet teeth are frozen rigid to their hub.

HHT-alpha (Hilber, Hughes, Taylor 1977), alpha in [-1/3, 0]:
    M a_{n+1} = (1 + alpha) Q(x_{n+1}, v_{n+1}, t_{n+1}) - alpha Q(x_n, v_n, t_n)
    x_{n+1} = x_n + dt v_n + dt^2 ((1/2 - beta) a_n + beta a_{n+1})
    v_{n+1} = v_n + dt ((1 - gamma) a_n + gamma a_{n+1})
with beta = (1 - alpha)^2/4, gamma = 1/2 - alpha. alpha = 0 is the trapezoidal rule (average
acceleration): unconditionally stable, second order, no numerical damping. alpha < 0 damps
the high frequencies and stays second order. The driver's inertial coupling -I_cpl*theta1''
on the gear-1 teeth is inertia, taken at the mid-step driver acceleration (exact when the end
of the speed ramp falls on a step boundary).

Newton on x_{n+1} with the tangent M/(beta dt^2) + (1+alpha)(K + gamma/(beta dt) C), where
K = sum_c k_t G G^T + spring tangents and C = sum_c dF/d(ddelta) G G^T + spring damping
tangents (the geometric term F dG/dx is left out: it changes only the convergence rate).
Teeth without a loaded contact are condensed out of each Newton system, so its cost stays
that of the few teeth in the mesh even when every tooth is integrated.
Converged when the last correction moves no flank point by more than newton_tol [m]; the
forces are then re-evaluated at the converged state (they start the next step).

Status codes: those of the explicit kernel, plus 4 Newton failure.
"""
import math

import numpy as np
from numba import njit

from solver.mbs.kernels.explicit import _dissipation_power, _energies, driver_motion, driver_speed, load_torque
from solver.mbs.kernels.gearmesh import generalized_forces, mesh_contacts, tooth_spring_tangent
from solver.mbs.kernels.laws import contact_damping_tangents, spring_damping_tangent
from solver.mbs.kernels.layout import (
    C_CON,
    C_DDELTA,
    C_DELTA,
    C_FORCE,
    C_G2,
    C_GA,
    C_GB,
    C_KT,
    C_PHI,
    C_TOOTH1,
    C_TOOTH2,
    I_CPL,
    I_P,
    I_TOT,
    M2,
    M3,
    MAX_CONTACTS,
    N_C,
    R_BND,
    RB,
    TOOTH0,
)
from solver.mbs.kernels.statics import solve_dense
from solver.mbs.kernels.stepping import (
    NONFINITE,
    OK,
    PENETRATION,
    checked_status,
    clear_candidates,
    freeze_quiet_teeth,
    loaded_contacts,
    record_output,
)

NEWTON = 4


@njit(cache=True)
def _activate(pairs, npair, tz2, active, act, nact, incand):
    """Add the teeth of the candidate pairs to the active set; returns the new count."""
    for p in range(npair):
        for g in range(2):
            i = int(pairs[p, g]) + (tz2 if g == 1 else 0)
            incand[i] = True
            if not active[i]:
                active[i] = True
                act[nact] = i
                nact += 1
    return nact


@njit(cache=True)
def _newton_step(rec, nc, phi, dphi, act, nact, kphi, gp, lp, tz2, cm, ck, cc, r, loc, cl, A, dx):
    """Solve J dx = r for J = cm*M + ck*K + cc*C over (theta2, active teeth); r indexed as dx
    (0: theta2, a + 1: tooth act[a]).

    A tooth without a loaded contact couples to theta2 only (through the hub inertia of gear 2)
    and is condensed out first; the dense solve runs over theta2 and the teeth in contact.
    """
    m = 0
    for c in range(nc):
        if rec[c, C_FORCE] <= 0.0:
            continue
        for g in range(2):
            i = int(rec[c, C_TOOTH1]) if g == 0 else tz2 + int(rec[c, C_TOOTH2])
            if loc[i] == 0:
                m += 1
                loc[i] = m
                cl[m - 1] = i
    n = m + 1
    for u in range(n):
        for v in range(n):
            A[u, v] = 0.0
    A[0, 0] = cm * gp[1, I_TOT]
    b = np.empty(n)
    b[0] = r[0]
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        d = (cm * gp[g, I_P] + ck * tooth_spring_tangent(i, phi, kphi, gp)
             + cc * spring_damping_tangent(dphi[i], gp[g, C_PHI], gp[g, N_C]))
        c0 = cm * gp[1, I_CPL] if g == 1 else 0.0
        k = loc[i]
        if k > 0:
            A[k, k] += d
            A[0, k] += c0
            A[k, 0] += c0
            b[k] = r[a + 1]
        else:
            A[0, 0] -= c0 * c0 / d
            b[0] -= c0 * r[a + 1] / d
    for c in range(nc):
        if rec[c, C_FORCE] <= 0.0:
            continue
        kd, cd = contact_damping_tangents(rec[c, C_DELTA], rec[c, C_DDELTA], rec[c, C_FORCE],
                                          lp[C_CON], lp[M2], lp[M3])
        w = ck * (rec[c, C_KT] + kd) + cc * cd
        i1 = loc[int(rec[c, C_TOOTH1])]
        i2 = loc[tz2 + int(rec[c, C_TOOTH2])]
        g0 = rec[c, C_G2]
        g1 = rec[c, C_GA]
        g2 = rec[c, C_GB]
        A[0, 0] += w * g0 * g0
        A[0, i1] += w * g0 * g1
        A[0, i2] += w * g0 * g2
        A[i1, 0] += w * g1 * g0
        A[i1, i1] += w * g1 * g1
        A[i1, i2] += w * g1 * g2
        A[i2, 0] += w * g2 * g0
        A[i2, i1] += w * g2 * g1
        A[i2, i2] += w * g2 * g2
    y = solve_dense(A[:n, :n], b)
    dx[0] = y[0]
    for a in range(nact):
        i = act[a]
        k = loc[i]
        if k > 0:
            dx[a + 1] = y[k]
        else:
            g = 1 if i >= tz2 else 0
            d = (cm * gp[g, I_P] + ck * tooth_spring_tangent(i, phi, kphi, gp)
                 + cc * spring_damping_tangent(dphi[i], gp[g, C_PHI], gp[g, N_C]))
            c0 = cm * gp[1, I_CPL] if g == 1 else 0.0
            dx[a + 1] = (r[a + 1] - c0 * y[0]) / d
    for u in range(m):
        loc[cl[u]] = 0


@njit(cache=True)
def hht(gp, pp, lp, kphi, speed, speed_ramp, torque, torque_ramp, load_table, dt, n_steps, out_every, alpha,
        theta2, w2, phi, dphi, phi_quiet, dphi_quiet, delta_max, energy_tol, newton_tol, max_iter,
        o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2, o_newton):
    """Integrate n_steps of size dt [s] from t = 0 with HHT-alpha; write every out_every-th state.

    Arguments as `explicit.verlet`, plus alpha [-] (in [-1/3, 0]), energy_tol [-] (relative
    energy growth that stops the run), newton_tol [m] and max_iter (Newton per step), and
    o_newton (most Newton iterations in a step of each output interval). Returns
    (status, step reached, max active teeth, total Newton iterations).
    """
    ntooth = phi.shape[0]
    tz2 = int(gp[1, TOOTH0])
    rb1 = gp[0, RB]
    rb2 = gp[1, RB]
    beta = 0.25 * (1.0 - alpha) ** 2
    gamma = 0.5 - alpha
    cm = 1.0 / (beta * dt * dt)
    ck = 1.0 + alpha
    cc = (1.0 + alpha) * gamma / (beta * dt)
    rec = np.zeros((64, 15))
    pairs = np.zeros((64, 3), dtype=np.int64)
    q = np.zeros(ntooth + 2)
    q_old = np.zeros(ntooth + 2)
    acc = np.zeros(ntooth)
    xt = np.zeros(ntooth)        # Newmark predictors of phi and dphi
    vt = np.zeros(ntooth)
    active = np.zeros(ntooth, dtype=np.int64)
    act = np.zeros(ntooth, dtype=np.int64)
    incand = np.zeros(ntooth, dtype=np.int64)
    A = np.zeros((2 * MAX_CONTACTS + 1, 2 * MAX_CONTACTS + 1))
    r = np.zeros(ntooth + 1)
    dx = np.zeros(ntooth + 1)
    loc = np.zeros(ntooth, dtype=np.int64)
    cl = np.zeros(2 * MAX_CONTACTS, dtype=np.int64)
    nact = np.int64(0)     # not a literal 0: numba would compile the callees once more for it
    for i in range(ntooth):
        if phi[i] != 0.0 or dphi[i] != 0.0:
            active[i] = True
            act[nact] = i
            nact += 1
    th1, w1, acc1 = driver_motion(0.0, speed, speed_ramp)
    nc, npair = mesh_contacts(th1, theta2, phi, w1, w2, dphi, gp, pp, lp, pairs, rec)
    nact = _activate(pairs, npair, tz2, active, act, nact, incand)
    tl = load_torque(0.0, torque, torque_ramp, load_table)
    generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, tl, q)
    # initial accelerations: the explicit arrowhead solve, plus the driver coupling
    s = gp[1, I_TOT]
    rhs = q[1]
    for a in range(nact):
        i = act[a]
        if i >= tz2:
            s -= gp[1, I_CPL] ** 2 / gp[1, I_P]
            rhs -= gp[1, I_CPL] * q[2 + i] / gp[1, I_P]
    a2 = rhs / s
    for a in range(nact):
        i = act[a]
        if i >= tz2:
            acc[i] = (q[2 + i] - gp[1, I_CPL] * a2) / gp[1, I_P]
        else:
            acc[i] = (q[2 + i] - gp[0, I_CPL] * acc1) / gp[0, I_P]
    react = gp[0, I_TOT] * acc1 - q[0]
    for a in range(nact):
        if act[a] < tz2:
            react += gp[0, I_CPL] * acc[act[a]]
    ke, pe = _energies(w1, w2, phi, dphi, act, nact, kphi, gp, rec, nc, lp, tz2)
    e0 = ke + pe
    work = 0.0
    diss = 0.0
    p_in_old = react * w1 + tl * w2
    p_d_old = _dissipation_power(dphi, act, nact, gp, rec, nc, lp, tz2)
    o = np.int64(0)
    record_output(o, 0.0, rb1 * th1 + rb2 * theta2, 0.0, nc, react, ke, pe, 0.0, 0.0, theta2,
                  o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2)
    o_newton[0] = 0
    fmax = 0.0
    itmax = 0
    total_it = 0
    a1_prev = acc1
    max_act = nact
    status = np.int64(OK)
    step = 0
    for step in range(1, n_steps + 1):
        t_old = (step - 1) * dt
        t = step * dt
        for i in range(ntooth + 2):
            q_old[i] = q[i]
        # driver acceleration over the step (constant when the ramp end lies on the grid)
        a1m = (driver_speed(t, speed, speed_ramp) - driver_speed(t_old, speed, speed_ramp)) / dt
        if a1m != a1_prev:
            # the driver acceleration jumps at t_old (end of the ramp): right limits of the
            # gear-1 tooth accelerations and of the driver power start this step
            react += gp[0, I_TOT] * (a1m - a1_prev)
            for a in range(nact):
                i = act[a]
                if i < tz2:
                    acc[i] -= gp[0, I_CPL] / gp[0, I_P] * (a1m - a1_prev)
                    react -= gp[0, I_CPL] ** 2 / gp[0, I_P] * (a1m - a1_prev)
            p_in_old = react * driver_speed(t_old, speed, speed_ramp) + load_torque(t_old, torque, torque_ramp, load_table) * w2
            a1_prev = a1m
        th1, w1, _a1 = driver_motion(t, speed, speed_ramp)
        tl = load_torque(t, torque, torque_ramp, load_table)
        # Newmark predictors; start Newton from a_{n+1} = a_n
        th2t = theta2 + dt * w2 + dt * dt * (0.5 - beta) * a2
        w2t = w2 + dt * (1.0 - gamma) * a2
        for a in range(nact):
            i = act[a]
            xt[i] = phi[i] + dt * dphi[i] + dt * dt * (0.5 - beta) * acc[i]
            vt[i] = dphi[i] + dt * (1.0 - gamma) * acc[i]
        theta2 = th2t + beta * dt * dt * a2
        for a in range(nact):
            i = act[a]
            phi[i] = xt[i] + beta * dt * dt * acc[i]
        it = 0
        last = 1e300
        while True:
            # velocities and accelerations of the iterate
            a2 = (theta2 - th2t) * cm
            w2 = w2t + gamma * dt * a2
            for a in range(nact):
                i = act[a]
                acc[i] = (phi[i] - xt[i]) * cm
                dphi[i] = vt[i] + gamma * dt * acc[i]
            nc, npair = mesh_contacts(th1, theta2, phi, w1, w2, dphi, gp, pp, lp, pairs, rec)
            n_before = nact
            nact = _activate(pairs, npair, tz2, active, act, nact, incand)
            for a in range(n_before, nact):
                # a tooth entering the active set: at rest on its hub, zero force history
                i = act[a]
                xt[i] = 0.0
                vt[i] = 0.0
                acc[i] = 0.0
                dphi[i] = 0.0
                q_old[2 + i] = 0.0
            for i in range(ntooth + 2):
                q[i] = 0.0
            generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, tl, q)
            if last < newton_tol and nact == n_before:
                break
            if it >= max_iter:
                status = NEWTON
                break
            it += 1
            # residual M a - (1+alpha) Q_{n+1} + alpha Q_n  (as r = -residual)
            r[0] = (1.0 + alpha) * q[1] - alpha * q_old[1] - gp[1, I_TOT] * a2
            for a in range(nact):
                i = act[a]
                g = 1 if i >= tz2 else 0
                ri = (1.0 + alpha) * q[2 + i] - alpha * q_old[2 + i] - gp[g, I_P] * acc[i]
                if g == 1:
                    ri -= gp[1, I_CPL] * a2
                    r[0] -= gp[1, I_CPL] * acc[i]
                else:
                    ri -= gp[0, I_CPL] * a1m
                r[a + 1] = ri
            _newton_step(rec, nc, phi, dphi, act, nact, kphi, gp, lp, tz2, cm, ck, cc, r, loc, cl, A, dx)
            last = abs(dx[0]) * rb2
            theta2 += dx[0]
            for a in range(nact):
                i = act[a]
                g = 1 if i >= tz2 else 0
                phi[i] += dx[a + 1]
                d = abs(dx[a + 1]) * gp[g, R_BND]
                if d > last:
                    last = d
            if not math.isfinite(last):
                status = NONFINITE
                break
        total_it += it
        if it > itmax:
            itmax = it
        react = gp[0, I_TOT] * a1m - q[0]
        for a in range(nact):
            if act[a] < tz2:
                react += gp[0, I_CPL] * acc[act[a]]
        for c in range(nc):
            if rec[c, C_FORCE] > fmax:
                fmax = rec[c, C_FORCE]
            if rec[c, C_DELTA] > delta_max:
                status = PENETRATION
        p_in = react * w1 + tl * w2
        p_d = _dissipation_power(dphi, act, nact, gp, rec, nc, lp, tz2)
        work += 0.5 * dt * (p_in + p_in_old)
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
            o_newton[o] = itmax
            fmax = 0.0
            itmax = 0
            status = checked_status(status, math.isfinite(theta2) and math.isfinite(w2) and math.isfinite(ke + pe), ke, pe, e0, work, diss, energy_tol)
        if status != OK:
            break
    return status, step, max_act, total_it

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
tangents (the geometric term F dG/dx is left out: it changes only the convergence rate). Flank
friction (a recorded friction force F_t = mu*tanh(v_s/v_reg)*F along the lever arms H) adds
H (F_t/F) dF/dx and H dF_t/dv_s H^T, nonsymmetric: the friction is implicit like the rest.
Teeth without a loaded contact are condensed out of each Newton system, so its cost stays
that of the few teeth in the mesh even when every tooth is integrated.
Converged when the last correction moves no flank point by more than newton_tol [m]; the
forces are then re-evaluated at the converged state (they start the next step).

Status codes: those of the explicit kernel, plus 4 Newton failure.

Newton work arrays ``nw`` (`layout.NewtonWork`, from `newton_arrays`): the scheme's
coefficients (K_* columns below), the forces of the last step, the Newmark predictors of the
teeth and of theta2 (rows POS, RATE), the system, residual, correction, and the
condensation's index maps.
"""
import math

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels import njit
from solver.mbs.kernels.gearmesh import generalized_forces, mesh_contacts, tooth_spring_tangent
from solver.mbs.kernels.laws import contact_damping_tangents, spring_damping_tangent
from solver.mbs.kernels.mechanics import (
    arrowhead_accelerations,
    dissipation_power,
    drive,
    driver_speed,
    load_torque,
    mesh_energies,
)
from solver.mbs.kernels.statics import solve_dense
from solver.mbs.kernels.status import NEWTON, NONFINITE, OK
from solver.mbs.kernels.stepping import activate, end_step, initial_set, record_output

# coefficients of the scheme: nw.coef
K_BETA = 0          # Newmark beta [-]
K_GAMMA = 1         # Newmark gamma [-]
K_CM = 2            # mass factor of the tangent 1/(beta dt^2) [1/s^2]
K_CK = 3            # stiffness factor 1 + alpha [-]
K_CC = 4            # damping factor (1 + alpha) gamma/(beta dt) [1/s]
K_ALPHA = 5         # alpha [-]


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def newton_arrays(ntooth, alpha, dt):
    """Work arrays ``nw`` of the HHT-alpha Newton for ntooth teeth, alpha [-], step dt [s]."""
    beta = 0.25 * (1.0 - alpha) ** 2
    gamma = 0.5 - alpha
    coef = np.array([beta, gamma, 1.0 / (beta * dt * dt), 1.0 + alpha, (1.0 + alpha) * gamma / (beta * dt), alpha])
    m = 2 * L.MAX_CONTACTS
    return L.NewtonWork(coef, np.zeros(ntooth + 2), np.zeros((2, ntooth)), np.zeros(2), np.zeros((m + 1, m + 1)),
                        np.zeros(ntooth + 1), np.zeros(ntooth + 1), np.zeros(ntooth, dtype=np.int64),
                        np.zeros(m, dtype=np.int64))


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _tooth_tangent(i, mdl, teeth, coef):
    """(diagonal entry, coupling to theta2) of tooth i in the Newton matrix."""
    gp, kphi = mdl[0], mdl[3]
    g = 1 if i >= int(gp[1, L.TOOTH0]) else 0
    d = (coef[K_CM] * gp[g, L.I_P] + coef[K_CK] * tooth_spring_tangent(i, teeth[L.POS], kphi, gp)
         + coef[K_CC] * spring_damping_tangent(teeth[L.RATE, i], gp[g, L.C_PHI], gp[g, L.N_C]))
    return d, (coef[K_CM] * gp[1, L.I_CPL] if g == 1 else 0.0)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _contact_rows(mdl, rec, nc, loc, A, coef):
    """Add the loaded contacts' tangents w G G^T (over theta2 and the teeth at loc) to A."""
    lp = mdl[2]
    tz2 = int(mdl[0][1, L.TOOTH0])
    for c in range(nc):
        if rec[c, L.C_FORCE] <= 0.0:
            continue
        kd, cd = contact_damping_tangents(rec[c, L.C_DELTA], rec[c, L.C_DDELTA], rec[c, L.C_FORCE],
                                          lp[L.C_CON], lp[L.M2], lp[L.M3])
        w = coef[K_CK] * (rec[c, L.C_KT] + kd) + coef[K_CC] * cd
        i1 = loc[int(rec[c, L.C_TOOTH1])]
        i2 = loc[tz2 + int(rec[c, L.C_TOOTH2])]
        g0 = rec[c, L.C_G2]
        g1 = rec[c, L.C_GA]
        g2 = rec[c, L.C_GB]
        A[0, 0] += w * g0 * g0
        A[0, i1] += w * g0 * g1
        A[0, i2] += w * g0 * g2
        A[i1, 0] += w * g1 * g0
        A[i1, i1] += w * g1 * g1
        A[i1, i2] += w * g1 * g2
        A[i2, 0] += w * g2 * g0
        A[i2, i1] += w * g2 * g1
        A[i2, i2] += w * g2 * g2
        if lp[L.MU] > 0.0:
            # friction: d(F_t H)/dx through F (the ratio F_t/F) and through v_s
            rf = rec[c, L.C_FT] / rec[c, L.C_FORCE] * w
            cf = coef[K_CC] * rec[c, L.C_DFT]
            idx = (0, i1, i2)
            gv = (g0, g1, g2)
            hv = (rec[c, L.C_H2], rec[c, L.C_HA], rec[c, L.C_HB])
            for x in range(3):
                for y in range(3):
                    A[idx[x], idx[y]] += hv[x] * (rf * gv[y] + cf * hv[y])


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def newton_correction(mdl, rec, nc, teeth, act, nact, nw):
    """Solve J dx = r for J = cm*M + ck*K + cc*C over (theta2, active teeth); r and dx of nw
    indexed 0: theta2, a + 1: tooth act[a].

    A tooth without a loaded contact couples to theta2 only (through the hub inertia of gear 2)
    and is condensed out first; the dense solve runs over theta2 and the teeth in contact.
    """
    gp = mdl[0]
    coef, A, r, dx, loc, cl = nw.coef, nw.A, nw.r, nw.dx, nw.loc, nw.cl
    tz2 = int(gp[1, L.TOOTH0])
    m = 0
    for c in range(nc):
        if rec[c, L.C_FORCE] <= 0.0:
            continue
        for g in range(2):
            i = int(rec[c, L.C_TOOTH1]) if g == 0 else tz2 + int(rec[c, L.C_TOOTH2])
            if loc[i] == 0:
                m += 1
                loc[i] = m
                cl[m - 1] = i
    n = m + 1
    A[:n, :n] = 0.0
    A[0, 0] = coef[K_CM] * gp[1, L.I_TOT]
    b = np.empty(n)
    b[0] = r[0]
    for a in range(nact):
        d, c0 = _tooth_tangent(act[a], mdl, teeth, coef)
        k = loc[act[a]]
        if k > 0:
            A[k, k] += d
            A[0, k] += c0
            A[k, 0] += c0
            b[k] = r[a + 1]
        else:
            A[0, 0] -= c0 * c0 / d
            b[0] -= c0 * r[a + 1] / d
    _contact_rows(mdl, rec, nc, loc, A, coef)
    y = solve_dense(A[:n, :n], b)
    dx[0] = y[0]
    for a in range(nact):
        k = loc[act[a]]
        if k > 0:
            dx[a + 1] = y[k]
        else:
            d, c0 = _tooth_tangent(act[a], mdl, teeth, coef)
            dx[a + 1] = (r[a + 1] - c0 * y[0]) / d
    for u in range(m):
        loc[cl[u]] = 0


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def driver_torque(q, act, nact, gp, acc, a1):
    """Torque the driver applies [N m] at driver acceleration a1 [rad/s²]:
    I_tot1*a1 - Q_theta1 + I_cpl1 * (sum of the gear-1 tooth accelerations)."""
    tz2 = int(gp[1, L.TOOTH0])
    react = gp[0, L.I_TOT] * a1 - q[0]
    for a in range(nact):
        if act[a] < tz2:
            react += gp[0, L.I_CPL] * acc[act[a]]
    return react


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def driver_jump(react, act, nact, gp, acc, da):
    """Right limits where the driver acceleration jumps by da [rad/s²] (end of the speed ramp):
    the gear-1 tooth accelerations (their inertial coupling) and the driver torque [N m]."""
    tz2 = int(gp[1, L.TOOTH0])
    react += gp[0, L.I_TOT] * da
    for a in range(nact):
        i = act[a]
        if i < tz2:
            acc[i] -= gp[0, L.I_CPL] / gp[0, L.I_P] * da
            react -= gp[0, L.I_CPL] ** 2 / gp[0, L.I_P] * da
    return react


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def hht_residual(mdl, q, nw, hub, acc, act, nact, a1m):
    """r = -(M a - (1+alpha) Q_{n+1} + alpha Q_n) into nw's r, over (theta2, active teeth);
    a1m [rad/s²]: the driver acceleration over the step (inertia on the gear-1 teeth)."""
    gp = mdl[0]
    coef, q_old, r = nw.coef, nw.q_old, nw.r
    tz2 = int(gp[1, L.TOOTH0])
    alpha = coef[K_ALPHA]
    a2 = hub[L.ACC, L.H_TH2]
    r[0] = (1.0 + alpha) * q[1] - alpha * q_old[1] - gp[1, L.I_TOT] * a2
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        ri = (1.0 + alpha) * q[2 + i] - alpha * q_old[2 + i] - gp[g, L.I_P] * acc[i]
        if g == 1:
            ri -= gp[1, L.I_CPL] * a2
            r[0] -= gp[1, L.I_CPL] * acc[i]
        else:
            ri -= gp[0, L.I_CPL] * a1m
        r[a + 1] = ri


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def newton_iterations(mdl, ctl, ws, nw, hub, teeth, nact, drv):
    """One HHT-alpha step: Newmark predictors, then Newton from a_{n+1} = a_n until the last
    correction moves no flank point by more than par[NEWTON_TOL] [m] and the active set stays;
    the forces q and contacts end at the converged state. drv = (theta1 [rad], theta1'
    [rad/s], load torque [N m], driver acceleration over the step [rad/s²]).
    Returns (status, iterations, contacts, candidate pairs, active teeth)."""
    gp, pp, lp, kphi = mdl[0], mdl[1], mdl[2], mdl[3]
    par, ipar, _table = ctl
    rec, pairs, q, tset = ws.rec, ws.pairs, ws.q, ws.tset
    coef, q_old, pred, hpred, dx = nw.coef, nw.q_old, nw.pred, nw.hpred, nw.dx
    th1, w1, tl, a1m = drv
    act = tset[L.T_ACT]
    phi, dphi, acc = teeth[L.POS], teeth[L.RATE], teeth[L.ACC]
    tz2 = int(gp[1, L.TOOTH0])
    dt, beta, gamma, cm = par[L.DT], coef[K_BETA], coef[K_GAMMA], coef[K_CM]
    a2 = hub[L.ACC, L.H_TH2]
    hpred[L.POS] = hub[L.POS, L.H_TH2] + dt * hub[L.RATE, L.H_TH2] + dt * dt * (0.5 - beta) * a2
    hpred[L.RATE] = hub[L.RATE, L.H_TH2] + dt * (1.0 - gamma) * a2
    for a in range(nact):
        i = act[a]
        pred[L.POS, i] = phi[i] + dt * dphi[i] + dt * dt * (0.5 - beta) * acc[i]
        pred[L.RATE, i] = dphi[i] + dt * (1.0 - gamma) * acc[i]
    hub[L.POS, L.H_TH2] = hpred[L.POS] + beta * dt * dt * a2
    for a in range(nact):
        i = act[a]
        phi[i] = pred[L.POS, i] + beta * dt * dt * acc[i]
    it = 0
    last = 1e300
    status = OK
    while True:
        # velocities and accelerations of the iterate
        hub[L.ACC, L.H_TH2] = (hub[L.POS, L.H_TH2] - hpred[L.POS]) * cm
        hub[L.RATE, L.H_TH2] = hpred[L.RATE] + gamma * dt * hub[L.ACC, L.H_TH2]
        for a in range(nact):
            i = act[a]
            acc[i] = (phi[i] - pred[L.POS, i]) * cm
            dphi[i] = pred[L.RATE, i] + gamma * dt * acc[i]
        nc, npair = mesh_contacts((th1, hub[L.POS, L.H_TH2], w1, hub[L.RATE, L.H_TH2]), phi, dphi, (gp, pp, lp, mdl[5]), (rec, pairs))
        n_before = nact
        nact = activate(tset, nact, pairs, npair, tz2)
        for a in range(n_before, nact):
            # a tooth entering the active set: at rest on its hub, zero force history
            i = act[a]
            pred[L.POS, i] = pred[L.RATE, i] = acc[i] = dphi[i] = q_old[2 + i] = 0.0
        q[:] = 0.0
        generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, tl, q)
        if last < par[L.NEWTON_TOL] and nact == n_before:
            break
        if it >= ipar[L.MAX_ITER]:
            status = NEWTON
            break
        it += 1
        hht_residual(mdl, q, nw, hub, acc, act, nact, a1m)
        newton_correction(mdl, rec, nc, teeth, act, nact, nw)
        last = abs(dx[0]) * gp[1, L.RB]
        hub[L.POS, L.H_TH2] += dx[0]
        for a in range(nact):
            i = act[a]
            phi[i] += dx[a + 1]
            d = abs(dx[a + 1]) * gp[1 if i >= tz2 else 0, L.R_BND]
            if d > last:
                last = d
        if not math.isfinite(last):
            status = NONFINITE
            break
    return status, it, nc, npair, nact


@njit(cache=True, nogil=True, no_cfunc_wrapper=True)
def hht(mdl, ctl, hub, teeth, out, ws):
    """Integrate ipar[N_STEPS] steps of par[DT] [s] from t = 0 with HHT-alpha (par[HHT_ALPHA]
    in [-1/3, 0]); arguments, outputs and guards as `explicit.verlet`, plus Newton's
    par[NEWTON_TOL] [m] and ipar[MAX_ITER] per step, and out[:, O_NEWTON] (most Newton
    iterations in a step of each output interval). Returns (status, step reached, max active
    teeth, total Newton iterations).
    """
    gp, pp, lp, kphi = mdl[0], mdl[1], mdl[2], mdl[3]
    par, ipar, table = ctl
    phi, dphi, acc = teeth[L.POS], teeth[L.RATE], teeth[L.ACC]
    tz2 = int(gp[1, L.TOOTH0])
    dt, speed, ramp = par[L.DT], par[L.SPEED], par[L.SPEED_RAMP]
    rec, pairs, q, tset, book = ws.rec, ws.pairs, ws.q, ws.tset, ws.book
    nw = newton_arrays(phi.shape[0], par[L.HHT_ALPHA], dt)
    act = tset[L.T_ACT]
    nact = initial_set(tset, teeth, pairs, np.int64(0), tz2)     # the teeth already moving
    th1, w1, acc1, tl = drive(0.0, par, table)
    nc, npair = mesh_contacts((th1, hub[L.POS, L.H_TH2], w1, hub[L.RATE, L.H_TH2]), phi, dphi, (gp, pp, lp, mdl[5]), (rec, pairs))
    nact = activate(tset, nact, pairs, npair, tz2)
    generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, tl, q)
    # initial accelerations: the explicit arrowhead solve, plus the driver coupling
    hub[L.ACC, L.H_TH2], _s1, _r1 = arrowhead_accelerations(q, act, nact, gp, acc)
    for a in range(nact):
        if act[a] < tz2:
            acc[act[a]] = (q[2 + act[a]] - gp[0, L.I_CPL] * acc1) / gp[0, L.I_P]
    react = driver_torque(q, act, nact, gp, acc, acc1)
    w2 = hub[L.RATE, L.H_TH2]
    ke, pe = mesh_energies(0.5 * gp[0, L.I_TOT] * w1 * w1 + 0.5 * gp[1, L.I_TOT] * w2 * w2, 0.0, w1, w2,
                           teeth, act, nact, mdl, rec, nc)
    book[L.B_E0] = ke + pe
    book[L.B_P_IN] = react * w1 + tl * w2
    book[L.B_P_D] = dissipation_power(dphi, act, nact, mdl, rec, nc)
    o = itmax = total_it = np.int64(0)
    row = (0.0, gp[0, L.RB] * th1 + gp[1, L.RB] * hub[L.POS, L.H_TH2], hub[L.POS, L.H_TH2], react, ke, pe)
    status = record_output(out, o, row, book, rec, nc, math.isfinite(row[1]), par, np.int64(OK))
    a1_prev = acc1
    max_act = nact
    step = 0
    for step in range(1, ipar[L.N_STEPS] + 1):
        t_old = (step - 1) * dt
        t = step * dt
        for i in range(q.shape[0]):     # (a loop: see `explicit_coupled`)
            nw.q_old[i] = q[i]
        # driver acceleration over the step (constant when the ramp end lies on the grid)
        a1m = (driver_speed(t, speed, ramp) - driver_speed(t_old, speed, ramp)) / dt
        if a1m != a1_prev:
            # the driver acceleration jumps at t_old (end of the ramp): right limits of the
            # gear-1 tooth accelerations and of the driver power start this step
            react = driver_jump(react, act, nact, gp, acc, a1m - a1_prev)
            tl_old = load_torque(t_old, par[L.TORQUE], par[L.TORQUE_RAMP], table)
            book[L.B_P_IN] = react * driver_speed(t_old, speed, ramp) + tl_old * hub[L.RATE, L.H_TH2]
            a1_prev = a1m
        th1, w1, _a1, tl = drive(t, par, table)
        status, it, nc, npair, nact = newton_iterations(mdl, ctl, ws, nw, hub, teeth, nact, (th1, w1, tl, a1m))
        total_it += it
        itmax = max(itmax, it)
        react = driver_torque(q, act, nact, gp, acc, a1m)
        w2 = hub[L.RATE, L.H_TH2]
        p_in = react * w1 + tl * w2
        p_d = dissipation_power(dphi, act, nact, mdl, rec, nc)
        status, nact = end_step(ws, teeth, nc, npair, nact, tz2, (p_in, p_in, p_d), par, status)
        max_act = max(max_act, nact)
        if step % ipar[L.OUT_EVERY] == 0:
            o += 1
            theta2 = hub[L.POS, L.H_TH2]
            ke, pe = mesh_energies(0.5 * gp[0, L.I_TOT] * w1 * w1 + 0.5 * gp[1, L.I_TOT] * w2 * w2, 0.0, w1, w2,
                                   teeth, act, nact, mdl, rec, nc)
            row = (t, gp[0, L.RB] * th1 + gp[1, L.RB] * theta2, theta2, react, ke, pe)
            status = record_output(out, o, row, book, rec, nc, math.isfinite(theta2) and math.isfinite(w2), par, status)
            out[o, L.O_NEWTON] = itmax
            itmax = 0
        if status != OK:
            break
    return status, step, max_act, total_it

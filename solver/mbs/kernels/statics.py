"""Static equilibrium of the pair at a sequence of driver angles (numba).

Unknowns at each angle: the driven hub angle theta2 and the rotations of the teeth that the
pre-search finds near the mesh (the others are unloaded: phi = 0). Newton on the tangent
K = sum_c k_t G G^T + diag(spring tangents) (plus, for a modified tip corner, the curvature of
its blend into the flank: `gearmesh.TIP_BLEND`), with continuation from the previous angle and
a backtracking line search on the residual. The spring tangent n*k*|phi|^(n-1) vanishes at
phi = 0 for n > 1, so a tiny diagonal term (1e-9 of the tooth's k_phi) regularises teeth
that carry no load; the residual, and so the solution, is exact.

Flank friction (law_par MU > 0): statics has no velocity, so the contact search sees the
rigid rolling kinematics at the driver speed par[S_W1] [rad/s] (theta2' = -rb1/rb2*theta1',
teeth at rest on their hubs): the sliding direction of a pair whose driver turns in its
positive sense, regularised as in dynamics at that speed. The caller zeroes the contact
damping (it would see the kinematic penetration rate). The tangent carries the friction's
change through the normal force (H (F_t/F) k_t G^T, nonsymmetric).
"""

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels import njit
from solver.mbs.kernels.gearmesh import generalized_forces, mesh_contacts, tooth_spring_tangent
from solver.mbs.kernels.layout import StaticWork
from solver.mbs.kernels.toothcoupling import set_moment, set_stiffness


@njit(cache=True, no_cfunc_wrapper=True)
def solve_dense(a, b):
    """Solve a x = b by Gaussian elimination with partial pivoting (a, b overwritten).

    The systems here are small (theta2 + the teeth near the mesh); a plain loop compiles in a
    fraction of the time np.linalg.solve takes.
    """
    n = b.shape[0]
    for k in range(n):
        p = k
        for i in range(k + 1, n):
            if abs(a[i, k]) > abs(a[p, k]):
                p = i
        if p != k:
            for j in range(n):
                a[k, j], a[p, j] = a[p, j], a[k, j]
            b[k], b[p] = b[p], b[k]
        piv = a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] / piv
            if f != 0.0:
                for j in range(k, n):
                    a[i, j] -= f * a[k, j]
                b[i] -= f * b[k]
    x = np.zeros(n)
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= a[i, j] * x[j]
        x[i] = s / a[i, i]
    return x


def static_work(ntooth, coupled=False):
    """Work arrays ``sw`` of the Newton for ntooth teeth (`layout.StaticWork`); ``ks``, the set
    stiffness of teeth coupled through the body (ntooth x 2 ntooth, `toothcoupling`), only when
    ``coupled`` (else None, which prunes the coupled code from the compiled kernel). Plain
    Python (the caller allocates them: np.zeros of integers is then not compiled)."""
    return StaticWork(np.zeros((L.MAX_CONTACTS, L.N_C_COLS)), np.zeros((L.MAX_CONTACTS, 3), dtype=np.int64),
                      np.zeros(ntooth + 2), np.zeros(ntooth), np.zeros(ntooth, dtype=np.int64),
                      np.zeros(ntooth, dtype=np.int64), np.zeros(ntooth + 1),
                      np.zeros((ntooth, 2 * ntooth)) if coupled else None)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _unknown_set(sw, npair, gp, phi):
    """Number the teeth of the npair candidate pairs 1.. in sw.pos (0 is theta2; -1: not an
    unknown) and list them in sw.lst; the other teeth are unloaded (phi = 0). Returns their
    number."""
    pairs, pos, lst = sw.pairs, sw.pos, sw.lst
    for i in range(pos.shape[0]):
        pos[i] = -1
    nt = np.int64(0)
    for i in range(npair):
        for g in range(2):
            t = int(pairs[i, g]) + int(gp[g, L.TOOTH0])
            if pos[t] < 0:
                nt += 1
                pos[t] = nt
                lst[nt - 1] = t
    for i in range(pos.shape[0]):
        if pos[i] < 0:
            phi[i] = 0.0
    return nt


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _unknown_forces(mdl, ks, sw, nc, nt, phi, torque):
    """Residual sw.r [N m] on theta2 and the nt unknown teeth from the contacts sw.rec[:nc]
    under the resisting torque [N m]; returns its max-norm. A coupled model's tooth springs
    act through the set stiffness ks (its per-tooth kphi are zero; ks is None otherwise)."""
    gp, kphi = mdl[0], mdl[3]
    q, lst, r = sw.q, sw.lst, sw.r
    generalized_forces(sw.rec, nc, phi, sw.zero_rates, lst, nt, kphi, gp, torque, q)
    r[0] = q[1]
    for a in range(nt):
        r[1 + a] = q[2 + lst[a]]
        if ks is not None:
            r[1 + a] -= set_moment(ks, lst, nt, phi, a)
    rn = 0.0
    for i in range(nt + 1):
        rn = max(rn, abs(r[i]))
    return rn


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _tangent(mdl, ks, sw, nc, nt, phi):
    """Newton tangent [N m/rad] over theta2 and the nt unknown teeth: the contacts sw.rec[:nc]
    plus the tooth springs (the set stiffness ks of a coupled model, else each tooth's own
    tangent, regularised where it vanishes at phi = 0)."""
    gp, lp, kphi = mdl[0], mdl[2], mdl[3]
    rec, pos, lst = sw.rec, sw.pos, sw.lst
    friction = lp[L.MU] > 0.0
    n = nt + 1
    K = np.zeros((n, n))
    for c in range(nc):
        kt = rec[c, L.C_KT]
        if kt <= 0.0:
            continue
        ia = int(rec[c, L.C_TOOTH1]) + int(gp[0, L.TOOTH0])
        ib = int(rec[c, L.C_TOOTH2]) + int(gp[1, L.TOOTH0])
        idx = (0, pos[ia], pos[ib])
        gv = (rec[c, L.C_G2], rec[c, L.C_GA], rec[c, L.C_GB])
        for x in range(3):
            for y in range(3):
                K[idx[x], idx[y]] += kt * gv[x] * gv[y]
        kg = rec[c, L.C_KGEO]
        if kg != 0.0:
            # the sharp blend of a modified tip corner into its flank: its curvature matters
            dv = (rec[c, L.C_DG2], rec[c, L.C_DGA], rec[c, L.C_DGB])
            for x in range(3):
                for y in range(3):
                    K[idx[x], idx[y]] += kg * dv[x] * dv[y]
        if friction and rec[c, L.C_FORCE] > 0.0:
            # the friction force F_t = (F_t/F)*F along H changes with the normal force
            rf = rec[c, L.C_FT] / rec[c, L.C_FORCE] * kt
            hv = (rec[c, L.C_H2], rec[c, L.C_HA], rec[c, L.C_HB])
            for x in range(3):
                for y in range(3):
                    K[idx[x], idx[y]] += rf * hv[x] * gv[y]
    if ks is not None:
        for m in range(nt):
            for m2 in range(nt):
                K[m + 1, m2 + 1] += ks[m, m2]
    else:
        for m in range(nt):
            i = lst[m]
            K[m + 1, m + 1] += tooth_spring_tangent(i, phi, kphi, gp) + 1e-9 * kphi[i]
    if K[0, 0] <= 0.0:
        K[0, 0] = 1e-9
    return K


@njit(cache=True, no_cfunc_wrapper=True)
def newton_system(mdl, theta1, theta2, phi, torque, sw):
    """The plain model's Newton system at driver angle theta1 and driven angle theta2 [rad] with
    the tooth rotations phi [rad] under the resisting torque [N m]: (tangent [N m/rad],
    residual [N m], the unknown teeth), the unknowns being theta2 and those teeth, as the
    sweep below builds them (for checks against finite differences); sw: `static_work`."""
    gp = mdl[0]
    ph = phi.copy()
    nc, npair = mesh_contacts((theta1, theta2, 0.0, 0.0), ph, sw.zero_rates, (gp, mdl[1], mdl[2], mdl[4]), (sw.rec, sw.pairs))
    nt = _unknown_set(sw, npair, gp, ph)
    _unknown_forces(mdl, None, sw, nc, nt, ph, torque)
    return _tangent(mdl, None, sw, nc, nt, ph), sw.r[:nt + 1].copy(), sw.lst[:nt].copy()


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _open_gap(gp, pp):
    """How far an open mesh may be from its first touch beyond the rigid gap [m]: both flanks'
    largest deviations, the pitch errors and eccentricities (a loop, not .max(): numpy's max
    and take would compile too)."""
    open_gap = 0.0
    for g in range(2):
        dev_max = 0.0
        if gp[g, L.DEV_ON] > 0.0:
            for k in range(L.DEV0, L.DEV0 + L.N_DEV):
                dev_max = max(dev_max, gp[g, k])
        open_gap += dev_max
    if pp.shape[0] > L.N_PAIR_PAR:
        open_gap += pp[L.E_BOUND]
    return open_gap


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _loaded(rec, nc):
    """Number of the contacts rec[:nc] that carry a force."""
    n = 0
    for c in range(nc):
        if rec[c, L.C_FORCE] > 0.0:
            n += 1
    return n


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _closing_angle(theta1, torque, open_steps, open_gap, gp, pp, lp):
    """Driven angle [rad] at driver angle theta1 [rad] of a mesh not yet in contact: the rigid
    gap closed plus the contact-only penetration under the torque [N m], and, as modified
    flanks or errors may leave the gap up to open_gap [m] more, open_steps 16ths of that (one
    more at each iteration without contact, near the first touch)."""
    rb1 = gp[0, L.RB]
    rb2 = gp[1, L.RB]
    dpen = (abs(torque) / rb2 / lp[L.K_CON]) ** (1.0 / lp[L.M1])
    dpen += open_steps / 16.0 * open_gap
    return ((1.0 if torque >= 0.0 else -1.0) * (pp[L.JN_HALF] + dpen) - rb1 * theta1) / rb2


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _unknown_rotations(phi, lst, nt):
    """A copy of the rotations [rad] of the nt unknown teeth lst[:nt]."""
    ph = np.empty(nt)
    for m in range(nt):
        ph[m] = phi[lst[m]]
    return ph


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _line_step(theta2, ph, dx, step, phi, lst, nt):
    """Move the unknowns from (theta2 [rad], the rotations ph [rad] of the teeth lst[:nt]) by
    step times the Newton correction dx (theta2 first): the teeth in phi; returns the new
    theta2 [rad]."""
    for m in range(nt):
        phi[lst[m]] = ph[m] + step * dx[m + 1]
    return theta2 + step * dx[0]


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _store(out, force1, a, rec, nc, row):
    """Results at the a-th angle: row = (TE [m], theta2 [rad], signed Newton iterations) and,
    from the contacts rec[:nc], the loaded ones, the force on each gear-1 tooth [N] and the
    driver torque [N m] (their moments about O1, friction included)."""
    out[a, L.S_TE], out[a, L.S_TH2], out[a, L.S_ITER] = row
    t1 = 0.0
    for k in range(force1.shape[1]):
        force1[a, k] = 0.0
    for c in range(nc):
        f = rec[c, L.C_FORCE]
        t1 += f * rec[c, L.C_G1] + rec[c, L.C_FT] * rec[c, L.C_H1]
        if f > 0.0:
            force1[a, int(rec[c, L.C_TOOTH1])] += f
    out[a, L.S_NC] = _loaded(rec, nc)
    out[a, L.S_T1] = t1


@njit(cache=True, nogil=True, no_cfunc_wrapper=True)
def static_sweep(mdl, ctooth, ctl, theta1s, phi, out, force1, sw):
    """Equilibrium at each driver angle theta1s[a] [rad].

    mdl: (gear_par, pair_par, law_par, k_phi, `layout.ContactParts`); ctl: (par, ipar) with the `layout` S_*
    columns (resisting torque [N m], start guess of theta2 [rad], tolerance, driver speed of
    the friction's sliding [rad/s], abort flag; Newton iterations). ``ctooth``: the tooth compliance matrix [rad/(N m)] of a model whose teeth
    are coupled through the body (`toothcoupling`; its k_phi are then zero), or None. The
    coupled code sits under ``if ctooth is not None`` (and ``ks``) so that numba prunes it
    from the plain model's compiled version (a switch inside a tuple would not be pruned).
    sw: the work arrays (`static_work`, its ``ks`` given exactly when ctooth is: an argument's
    None prunes, a None set inside the kernel would make ks an optional array).

    phi (Z1+Z2) is the start guess and is updated in place. Writes out[a, S_*] (TE [m],
    theta2 [rad], loaded contacts, Newton iterations, negative when not converged) and the
    force on each gear-1 tooth [N] force1[a, k]. Returns the number of angles that did not
    converge. Stops before the next angle once par[S_ABORT] is set (from another thread:
    `solver.mbs.interrupt`); the angles not reached keep their zero rows.

    The Newton of each angle is written out here, not in a helper kernel: a kernel around
    mesh_contacts costs its own optimisation of the whole contact search at compile time.
    """
    gp, pp, lp, _kphi, parts = mdl
    geo = (gp, pp, lp, parts)
    par, ipar = ctl
    torque = par[L.S_TORQUE]
    rec, pairs, zeros, lst, ks = sw.rec, sw.pairs, sw.zero_rates, sw.lst, sw.ks
    rb1 = gp[0, L.RB]
    rb2 = gp[1, L.RB]
    tol_abs = par[L.S_TOL] * max(abs(torque), 1e-3)
    theta2 = par[L.S_THETA2]
    w1 = par[L.S_W1]
    w2 = -rb1 / rb2 * w1 if w1 != 0.0 else 0.0
    open_gap = _open_gap(gp, pp)
    failures = 0
    nc = np.int64(0)        # not a literal 0: numba would compile the callees once more for it
    npair = np.int64(0)
    for a in range(theta1s.shape[0]):
        if par[L.S_ABORT] != 0.0:
            break
        theta1 = theta1s[a]
        if a > 0:
            theta2 -= rb1 / rb2 * (theta1s[a] - theta1s[a - 1])
        it = 0
        open_steps = np.int64(0)    # iterations at this angle without contact
        converged = False
        fresh = False       # rec and pairs already hold the search at this very state
        while it < ipar[L.S_MAX_ITER]:
            it += 1
            if not fresh:
                nc, npair = mesh_contacts((theta1, theta2, w1, w2), phi, zeros, geo, (rec, pairs))
            fresh = False
            # the unknowns: the teeth the pre-search finds at the current iterate
            nt = _unknown_set(sw, npair, gp, phi)
            if ctooth is not None:
                set_stiffness(ctooth, lst, nt, ks)
            if _loaded(rec, nc) == 0:
                if torque == 0.0:
                    converged = True
                    break
                theta2 = _closing_angle(theta1, torque, open_steps, open_gap, gp, pp, lp)
                open_steps += 1
                for m in range(nt):
                    phi[lst[m]] = 0.0
                continue
            # residual from the contacts just found (same state: no second search)
            rn = _unknown_forces(mdl, ks, sw, nc, nt, phi, torque)
            if rn < tol_abs:
                converged = True
                break
            dx = solve_dense(_tangent(mdl, ks, sw, nc, nt, phi), sw.r[:nt + 1].copy())
            # backtracking on the max-norm of the residual
            th_old = theta2
            ph_old = _unknown_rotations(phi, lst, nt)
            step = 1.0
            for _ in range(30):
                theta2 = _line_step(th_old, ph_old, dx, step, phi, lst, nt)
                nc, npair = mesh_contacts((theta1, theta2, w1, w2), phi, zeros, geo, (rec, pairs))
                rn2 = _unknown_forces(mdl, ks, sw, nc, nt, phi, torque)
                if rn2 < rn or rn2 < tol_abs:
                    break
                step *= 0.5
            fresh = True
            if abs(dx[0]) * step < 1e-16 and rn2 < 1e3 * tol_abs:
                converged = True
                break
        # outputs at the solution: a converged iteration ended on a search at this very state
        if not converged:
            nc, npair = mesh_contacts((theta1, theta2, w1, w2), phi, zeros, geo, (rec, pairs))
            failures += 1
        _store(out, force1, a, rec, nc, (rb1 * theta1 + rb2 * theta2, theta2, float(it if converged else -it)))
    return failures

"""Static equilibrium of the pair at a sequence of driver angles (numba).

Unknowns at each angle: the driven hub angle theta2 and the rotations of the teeth that the
pre-search finds near the mesh (the others are unloaded: phi = 0). Newton on the tangent
K = sum_c k_t G G^T + diag(spring tangents), with continuation from the previous angle and
a backtracking line search on the residual. The spring tangent n*k*|phi|^(n-1) vanishes at
phi = 0 for n > 1, so a tiny diagonal term (1e-9 of the tooth's k_phi) regularises teeth
that carry no load; the residual, and so the solution, is exact.
"""

import numpy as np
from numba import njit

from solver.mbs.kernels.gearmesh import generalized_forces, mesh_contacts, tooth_spring_tangent
from solver.mbs.kernels.layout import C_FORCE, C_G2, C_GA, C_GB, C_KT, C_TOOTH1, C_TOOTH2, JN_HALF, K_CON, M1, RB, TOOTH0
from solver.mbs.kernels.toothcoupling import set_moment, set_stiffness


@njit(cache=True)
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


@njit(cache=True)
def _unknown_forces(rec, nc, phi, zeros, lst, nt, kphi, gp, torque, ks, q, r):
    """Residual r on theta2 and the unknown teeth; a coupled model's tooth springs act
    through the set stiffness ks (its per-tooth kphi are zero; ks is None otherwise)."""
    generalized_forces(rec, nc, phi, zeros, lst, nt, kphi, gp, torque, q)
    r[0] = q[1]
    for a in range(nt):
        r[1 + a] = q[2 + lst[a]]
        if ks is not None:
            r[1 + a] -= set_moment(ks, lst, nt, phi, a)


@njit(cache=True)
def static_sweep(theta1s, torque, theta2_start, phi, gp, pp, lp, kphi, ctooth, tol, max_iter,
                 te_out, nc_out, force1_out, iter_out, theta2_out):
    """Equilibrium at each driver angle theta1s[a] [rad] under the resisting torque [N m].

    ``ctooth``: the tooth compliance matrix [rad/(N m)] of a model whose teeth are coupled
    through the body (`toothcoupling`; its kphi are then zero), or None. The coupled code
    sits under ``if ctooth is not None`` (and ``ks``) so that numba prunes it from the
    plain model's compiled version.

    phi (Z1+Z2) is the start guess and is updated in place. Writes TE [m], the number of
    loaded contacts, the force on each gear-1 tooth [N] (force1_out[a, k]), the Newton
    iterations (negative when not converged) and theta2 [rad]. Returns the number of
    angles that did not converge.
    """
    ntooth = phi.shape[0]
    zeros = np.zeros(ntooth)
    q = np.zeros(ntooth + 2)
    pos = np.zeros(ntooth, dtype=np.int64)     # set to -1 at each iteration
    lst = np.zeros(ntooth, dtype=np.int64)
    rec = np.zeros((64, 15))
    pairs = np.zeros((64, 3), dtype=np.int64)
    r = np.zeros(ntooth + 1)
    if ctooth is None:
        ks = None
    else:
        ks = np.zeros((ntooth, 2 * ntooth))
    rb1 = gp[0, RB]
    rb2 = gp[1, RB]
    tol_abs = tol * max(abs(torque), 1e-3)
    sgn = 1.0 if torque >= 0.0 else -1.0
    theta2 = theta2_start
    failures = 0
    nc = np.int64(0)        # not a literal 0: numba would compile the callees once more for it
    npair = np.int64(0)
    for a in range(theta1s.shape[0]):
        theta1 = theta1s[a]
        if a > 0:
            theta2 -= rb1 / rb2 * (theta1s[a] - theta1s[a - 1])
        it = 0
        converged = False
        fresh = False       # rec and pairs already hold the search at this very state
        while it < max_iter:
            it += 1
            # unknown set from the pre-search at the current iterate
            for i in range(ntooth):
                pos[i] = -1
            if not fresh:
                nc, npair = mesh_contacts(theta1, theta2, phi, 0.0, 0.0, zeros, gp, pp, lp, pairs, rec)
            fresh = False
            # the unknowns: the teeth of the candidate pairs, numbered 1.. in pos (0 is theta2)
            nt = np.int64(0)
            for i in range(npair):
                for g in range(2):
                    t = int(pairs[i, g]) + int(gp[g, TOOTH0])
                    if pos[t] < 0:
                        nt += 1
                        pos[t] = nt
                        lst[nt - 1] = t
            if ctooth is not None:
                set_stiffness(ctooth, lst, nt, ks)
            for i in range(ntooth):
                if pos[i] < 0:
                    phi[i] = 0.0
            nload = 0
            for c in range(nc):
                if rec[c, C_FORCE] > 0.0:
                    nload += 1
            if nload == 0:
                if torque == 0.0:
                    converged = True
                    break
                # no contact yet: close the gap rigidly, plus the contact-only penetration
                dpen = (abs(torque) / rb2 / lp[K_CON]) ** (1.0 / lp[M1])
                theta2 = (sgn * (pp[JN_HALF] + dpen) - rb1 * theta1) / rb2
                continue
            # residual from the contacts just found (same state: no second search)
            _unknown_forces(rec, nc, phi, zeros, lst, nt, kphi, gp, torque, ks, q, r)
            n = nt + 1
            rn = 0.0
            for i in range(n):
                rn = max(rn, abs(r[i]))
            if rn < tol_abs:
                converged = True
                break
            # tangent
            K = np.zeros((n, n))
            for c in range(nc):
                kt = rec[c, C_KT]
                if kt <= 0.0:
                    continue
                ia = int(rec[c, C_TOOTH1]) + int(gp[0, TOOTH0])
                ib = int(rec[c, C_TOOTH2]) + int(gp[1, TOOTH0])
                idx = (0, pos[ia], pos[ib])
                gv = (rec[c, C_G2], rec[c, C_GA], rec[c, C_GB])
                for x in range(3):
                    for y in range(3):
                        K[idx[x], idx[y]] += kt * gv[x] * gv[y]
            if ctooth is not None:
                for m in range(nt):
                    for m2 in range(nt):
                        K[m + 1, m2 + 1] += ks[m, m2]
            else:
                for m in range(nt):
                    i = lst[m]
                    K[m + 1, m + 1] += tooth_spring_tangent(i, phi, kphi, gp) + 1e-9 * kphi[i]
            if K[0, 0] <= 0.0:
                K[0, 0] = 1e-9
            dx = solve_dense(K, r[:n].copy())
            # backtracking on the max-norm of the residual
            th_old = theta2
            ph_old = np.empty(nt)
            for m in range(nt):
                ph_old[m] = phi[lst[m]]
            step = 1.0
            for _ in range(30):
                theta2 = th_old + step * dx[0]
                for m in range(nt):
                    phi[lst[m]] = ph_old[m] + step * dx[m + 1]
                # (written out, not a helper kernel: a kernel around mesh_contacts costs its own
                # optimisation of the whole contact search at compile time)
                nc, npair = mesh_contacts(theta1, theta2, phi, 0.0, 0.0, zeros, gp, pp, lp, pairs, rec)
                _unknown_forces(rec, nc, phi, zeros, lst, nt, kphi, gp, torque, ks, q, r)
                rn2 = 0.0
                for i in range(n):
                    rn2 = max(rn2, abs(r[i]))
                if rn2 < rn or rn2 < tol_abs:
                    break
                step *= 0.5
            fresh = True
            if abs(dx[0]) * step < 1e-16 and rn2 < 1e3 * tol_abs:
                converged = True
                break
        # outputs at the solution: a converged iteration ended on a search at this very state
        if not converged:
            nc, npair = mesh_contacts(theta1, theta2, phi, 0.0, 0.0, zeros, gp, pp, lp, pairs, rec)
        te_out[a] = rb1 * theta1 + rb2 * theta2
        theta2_out[a] = theta2
        nload = 0
        for k in range(force1_out.shape[1]):
            force1_out[a, k] = 0.0
        for c in range(nc):
            f = rec[c, C_FORCE]
            if f > 0.0:
                nload += 1
                force1_out[a, int(rec[c, C_TOOTH1])] += f
        nc_out[a] = nload
        iter_out[a] = it if converged else -it
        if not converged:
            failures += 1
    return failures

"""Two-phase contact search over the gear mesh and the generalised forces (numba).

Phase 1 (pre-search, O(1) per tooth pair): a gear-1 tooth can touch its neighbour on side s
(+1 drive, -1 coast) only while both rigid roll parameters of the pair lie within the flanks
(plus a margin for tip-corner contact), and only while the rigid gap bound
``s*TE - jn/2 + |phi_A|*R_A + |phi_B|*R_B`` is positive.
Phase 2 (detailed search): closed-form flank-to-flank penetration along the common tangent
of the moved base circles, or tip corner to flank (see `contact.py`).

State: theta1, theta2 hub angles [rad] (counter-clockwise positive), phi[Z1+Z2] tooth
rotations about their pivots relative to the hub [rad], gear-1 teeth first.
"""
import math

import numpy as np
from numba import njit

from solver.mbs.kernels.contact import cross, flank_flank, moved_center, point_flank, tip_corner, wrap
from solver.mbs.kernels.laws import contact_force, contact_tangent, spring_tangent, spring_torque
from solver.mbs.kernels.layout import (
    ALPHA,
    C_CON,
    C_DDELTA,
    C_DELTA,
    C_FORCE,
    C_G1,
    C_G2,
    C_GA,
    C_GB,
    C_KIND,
    C_KT,
    C_NX,
    C_NY,
    C_PHI,
    C_PX,
    C_PY,
    C_TOOTH1,
    C_TOOTH2,
    CX,
    CY,
    GAMMA0,
    JN_HALF,
    K_CON,
    M1,
    M2,
    M3,
    MARGIN,
    MAX_CONTACTS,
    N_C,
    N_K,
    NZ,
    PITCH,
    PSI_B,
    R_BND,
    R_PV,
    RB,
    TOOTH0,
    U_HI,
    U_LO,
)


@njit(cache=True)
def candidate_pairs(theta1, theta2, gp, pp, out):
    """Pre-search: fill out[n, :] = (gear-1 tooth, gear-2 tooth, side) of pairs that may touch.

    Returns n. Pairs are those whose rigid roll parameters lie within [u_lo - margin,
    u_hi + margin] on both flanks.
    """
    n = 0
    z1 = int(gp[0, NZ])
    z2 = int(gp[1, NZ])
    p1 = gp[0, PITCH]
    p2 = gp[1, PITCH]
    ratio = gp[0, RB] / gp[1, RB]
    alpha = pp[ALPHA]
    margin = pp[MARGIN]
    for side in (1, -1):
        s = float(side)
        # s*Psi1 + psi_b1 + alpha in [u_lo1 - margin, u_hi1 + margin]
        lo = gp[0, U_LO] - margin - gp[0, PSI_B] - alpha
        hi = gp[0, U_HI] + margin - gp[0, PSI_B] - alpha
        if side < 0:
            lo, hi = -hi, -lo
        base = theta1 + gp[0, GAMMA0]
        k0 = int(math.ceil((lo - base) / p1))
        k1 = int(math.floor((hi - base) / p1))
        for kk in range(k0, k1 + 1):
            k = kk % z1
            psi1 = base + kk * p1
            # gear-2 space facing tooth k under conjugate rolling, then its side-s neighbour
            x = (math.pi - psi1 * ratio - theta2 - gp[1, GAMMA0]) / p2
            j_space = int(math.floor(x))
            jj = j_space if side > 0 else j_space + 1
            j = jj % z2
            psi2 = theta2 + gp[1, GAMMA0] + j * p2
            ub = s * wrap(psi2 - math.pi) + gp[1, PSI_B] + alpha
            if ub < gp[1, U_LO] - margin or ub > gp[1, U_HI] + margin:
                continue
            if n < out.shape[0]:
                out[n, 0] = k
                out[n, 1] = j
                out[n, 2] = side
                n += 1
    return n


@njit(cache=True)
def _record(rec, nc, delta, g1, ga, g2, gb, px, py, nx, ny, k, j, kind, w1, wa, w2, wb, lp):
    ddelta = g1 * w1 + ga * wa + g2 * w2 + gb * wb
    f = contact_force(delta, ddelta, lp[K_CON], lp[M1], lp[C_CON], lp[M2], lp[M3])
    rec[nc, C_DELTA] = delta
    rec[nc, C_DDELTA] = ddelta
    rec[nc, C_FORCE] = f
    rec[nc, C_G1] = g1
    rec[nc, C_GA] = ga
    rec[nc, C_G2] = g2
    rec[nc, C_GB] = gb
    rec[nc, C_PX] = px
    rec[nc, C_PY] = py
    rec[nc, C_NX] = nx
    rec[nc, C_NY] = ny
    rec[nc, C_KT] = contact_tangent(delta, lp[K_CON], lp[M1])
    rec[nc, C_TOOTH1] = k
    rec[nc, C_TOOTH2] = j
    rec[nc, C_KIND] = kind


@njit(cache=True)
def pair_contacts(k, j, side, theta1, theta2, phi, w1, w2, dphi, gp, pp, lp, rec, nc):
    """Detailed search for gear-1 tooth k against gear-2 tooth j on side s; append to rec.

    Returns the new number of contacts. Each record holds the penetration, its rate, the
    force and the gradient G = d delta/d(theta1, phi_k, theta2, phi_j).
    """
    s = float(side)
    ia = int(gp[0, TOOTH0]) + k
    ib = int(gp[1, TOOTH0]) + j
    pa = phi[ia]
    pb = phi[ib]
    # phase 1b: rigid gap bound
    te = gp[0, RB] * theta1 + gp[1, RB] * theta2
    bound = s * te - pp[JN_HALF] + abs(pa) * gp[0, R_BND] + abs(pb) * gp[1, R_BND]
    if bound <= 0.0:
        return nc
    o1x, o1y = gp[0, CX], gp[0, CY]
    o2x, o2y = gp[1, CX], gp[1, CY]
    axa = theta1 + gp[0, GAMMA0] + k * gp[0, PITCH]
    axb = theta2 + gp[1, GAMMA0] + j * gp[1, PITCH]
    cax, cay = moved_center(o1x, o1y, gp[0, R_PV], axa, pa)
    cbx, cby = moved_center(o2x, o2y, gp[1, R_PV], axb, pb)
    rba = gp[0, RB]
    rbb = gp[1, RB]
    ba = axa + pa + s * gp[0, PSI_B]
    bb = axb + pb + s * gp[1, PSI_B]
    pvax = o1x + gp[0, R_PV] * math.cos(axa)
    pvay = o1y + gp[0, R_PV] * math.sin(axa)
    pvbx = o2x + gp[1, R_PV] * math.cos(axb)
    pvby = o2y + gp[1, R_PV] * math.sin(axb)
    wa = dphi[ia]
    wb = dphi[ib]
    delta, ua, ub, nx, ny, px, py = flank_flank(cax, cay, rba, ba, cbx, cby, rbb, bb, s)
    a_in = gp[0, U_LO] <= ua <= gp[0, U_HI]
    b_in = gp[1, U_LO] <= ub <= gp[1, U_HI]
    if a_in and b_in:
        if delta > 0.0 and nc < rec.shape[0]:
            # owner A (gear 1): G_A = +(x - O1) x n, (x - PvA) x n; gear 2 negative
            g1 = cross(px - o1x, py - o1y, nx, ny)
            ga = cross(px - pvax, py - pvay, nx, ny)
            g2 = -cross(px - o2x, py - o2y, nx, ny)
            gb = -cross(px - pvbx, py - pvby, nx, ny)
            _record(rec, nc, delta, g1, ga, g2, gb, px, py, nx, ny, k, j, 1.0 * s, w1, wa, w2, wb, lp)
            nc += 1
        return nc
    if ua > gp[0, U_HI]:
        # tip corner of A against flank B (owner B)
        qx, qy = tip_corner(cax, cay, rba, ba, s, gp[0, U_HI])
        d, uf, mx, my = point_flank(qx, qy, cbx, cby, rbb, bb, s)
        if d > 0.0 and gp[1, U_LO] <= uf <= gp[1, U_HI] and nc < rec.shape[0]:
            g2 = cross(qx - o2x, qy - o2y, mx, my)
            gb = cross(qx - pvbx, qy - pvby, mx, my)
            g1 = -cross(qx - o1x, qy - o1y, mx, my)
            ga = -cross(qx - pvax, qy - pvay, mx, my)
            _record(rec, nc, d, g1, ga, g2, gb, qx, qy, mx, my, k, j, 2.0 * s, w1, wa, w2, wb, lp)
            nc += 1
    if ub > gp[1, U_HI]:
        # tip corner of B against flank A (owner A)
        qx, qy = tip_corner(cbx, cby, rbb, bb, s, gp[1, U_HI])
        d, uf, mx, my = point_flank(qx, qy, cax, cay, rba, ba, s)
        if d > 0.0 and gp[0, U_LO] <= uf <= gp[0, U_HI] and nc < rec.shape[0]:
            g1 = cross(qx - o1x, qy - o1y, mx, my)
            ga = cross(qx - pvax, qy - pvay, mx, my)
            g2 = -cross(qx - o2x, qy - o2y, mx, my)
            gb = -cross(qx - pvbx, qy - pvby, mx, my)
            _record(rec, nc, d, g1, ga, g2, gb, qx, qy, mx, my, k, j, 3.0 * s, w1, wa, w2, wb, lp)
            nc += 1
    return nc


@njit(cache=True)
def mesh_contacts(theta1, theta2, phi, w1, w2, dphi, gp, pp, lp, pairs, rec):
    """All contacts of the mesh at this state. Returns (n_contacts, n_pairs); pairs holds the candidates."""
    npair = candidate_pairs(theta1, theta2, gp, pp, pairs)
    nc = np.int64(0)    # not a literal 0: numba would compile pair_contacts once more for Literal[int](0)
    for i in range(npair):
        nc = pair_contacts(pairs[i, 0], pairs[i, 1], pairs[i, 2], theta1, theta2, phi, w1, w2, dphi,
                           gp, pp, lp, rec, nc)
    return nc, npair


@njit(cache=True)
def generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, torque2, q):
    """Generalised forces: q[0] on theta1, q[1] on theta2, q[2 + i] on tooth i.

    Contacts: Q = -F * G; springs: eq. (1.2) on the active teeth; the resisting torque
    ``torque2`` [N m] acts counter-clockwise on gear 2 (it opposes the driven rotation).
    Only entries of active teeth are written (others are left at zero).
    """
    q[0] = 0.0
    q[1] = torque2
    for a in range(nact):
        i = act[a]
        g = 0 if i < int(gp[1, TOOTH0]) else 1
        q[2 + i] = spring_torque(phi[i], dphi[i], kphi[i], gp[g, N_K], gp[g, C_PHI], gp[g, N_C])
    for c in range(nc):
        f = rec[c, C_FORCE]
        ia = int(rec[c, C_TOOTH1]) + int(gp[0, TOOTH0])
        ib = int(rec[c, C_TOOTH2]) + int(gp[1, TOOTH0])
        q[0] -= f * rec[c, C_G1]
        q[2 + ia] -= f * rec[c, C_GA]
        q[1] -= f * rec[c, C_G2]
        q[2 + ib] -= f * rec[c, C_GB]


@njit(cache=True)
def tooth_spring_tangent(i, phi, kphi, gp):
    g = 0 if i < int(gp[1, TOOTH0]) else 1
    return spring_tangent(phi[i], kphi[i], gp[g, N_K])


def new_contact_buffer():
    """Preallocated contact records and candidate-pair table."""
    from solver.mbs.kernels.layout import N_C_COLS
    return np.zeros((MAX_CONTACTS, N_C_COLS)), np.zeros((MAX_CONTACTS, 3), dtype=np.int64)

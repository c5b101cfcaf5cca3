"""Loaded-tooth-contact analysis (LTCA) with FE influence coefficients: the STE reference.

Each gear body enters through its bulk compliance between candidate contact points on the
+ flanks (`solver.fe.flank_compliance.BodyCompliance`: the FE influence coefficients, read at
the tooth centreline so that the local flattening stays in the contact law), so that the
pseudo-rigid model and this reference differ only in how the bodies deform.

Per driver angle theta1 the candidate tooth pairs and their rigid roll parameters come from
the pre-search of the pseudo-rigid model (same frames and indices). In the path of contact the
perfect involutes touch with zero initial separation; beyond the tip of either gear the tip
corner meets the mating flank (extended contact) with the separation of the rigid corner from
that flank. Unknowns: the local contact approaches delta_i >= 0 (F_i = k_con*delta_i**m1) and
the rigid mesh approach w along the line of action; equations (active set A):

    sum_j (G1 + G2)_ij F_j + delta_i = w - e_i    (i in A),     sum_i F_i * rb2 = T2,

inactive pairs keep a gap w - e_i - sum_j G_ij F_j <= 0. Solved by Newton on the active set,
adding the most violated gap and dropping negative forces until both conditions hold.
TE = rb1*theta1 + rb2*theta2 of the hubs = jn/2 + w (rigid teeth in drive contact read the
backlash offset jn/2), the same convention and zero as the pseudo-rigid model.

Profile modifications (`solver.modification`) add each flank's deviation at the contact
point's roll parameter (a tip corner: at the tip) to the initial separation e_i, as in the
contact search of the pseudo-rigid model (first order: `solver.mbs.kernels.gearmesh`).

Pitch errors and eccentricities (`solver.pitch_errors`) subtract each tooth pair's first-order
approach along the line of action from e_i (`error_approach`); the candidate pairs and their
rolls stay those of the perfect gears (the errors shift a roll by ~1e-4 rad).

Approximation: corner contacts are loaded along the line of action at the tip-corner roll
(their true normal turns by a few degrees); their moment arm is taken as the base radius.
Their local law is the flanks' unless a tip edge radius is given (`TipEdge`): a corner then
meets the mating flank as a cylinder of that radius, far narrower than the two flanks the law
was fitted to, and its contact carries the extra compliance of that narrower Hertz patch
(`solver.identify.weber.edge_compliance`) in series. Where the corners carry load (a single
pair beside the extended contact of its neighbours: a third of the load at 100 N·m on the
paper pair) the STE there depends on it. A gear whose model has a rounded tip (gear_par
EDGE_*, the scene's ``gearN.modification.tip_edge_radius``) also has the round's geometry: its
flank ends at the round's tangent roll and its corner contact is the round's circle, whose
centre lies r inside that point (`_corner_flank`, as the contact search of the models), and the
edge's compliance ramps in from the round's tangent roll to the tip's (`corner_compliance`); a
`TipEdge` without it (`lightgear reference --tip-edge-radius` on a sharp-cornered scene) is the
compliance alone, on the sharp corner's geometry.

Units: SI (m, N, rad, N·m).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.contact import point_flank, tip_corner
from solver.mbs.kernels.gearmesh import EDGE_BLEND, candidate_pairs, edge_ramp, flank_deviation
from solver.mbs.model import Model

# ------------------------------------------------------------------ mesh kinematics

@dataclass(frozen=True)
class MeshPoints:
    """Candidate contacts at one driver angle (rigid geometry, drive flanks)."""

    tooth1: np.ndarray      # gear-1 tooth index
    tooth2: np.ndarray      # gear-2 tooth index
    u1: np.ndarray          # roll parameter of the gear-1 load point [-]
    u2: np.ndarray          # roll parameter of the gear-2 load point [-]
    gap: np.ndarray         # initial separation e at rigid drive contact [m] (0 in the path of contact)
    kind: np.ndarray        # 1 flank-flank, 2 gear-1 tip corner, 3 gear-2 tip corner
    # roll parameter [-] of the corner's gear on the line of action (its flank contact's, were its
    # flank longer; u1 on flank contacts), where a round's edge compliance ramps in (`corner_compliance`)
    u_line: np.ndarray | None = None


def mesh_points(model: Model, theta1: float, max_gap: float = 50e-6) -> MeshPoints:
    """Candidate drive-side contacts at driver angle theta1 [rad] with the rigid bodies at the
    zero-load drive contact (TE = jn/2); pairs separated by more than ``max_gap`` [m] are left out
    (plus the largest flank deviation of either gear: a relieved tip is still a candidate)."""
    gp, pp = model.gear_par, model.pair_par
    max_gap += float(np.abs(gp[:, L.DEV0:L.DEV0 + L.N_DEV]).max())
    if pp.size > L.N_PAIR_PAR:
        max_gap += float(pp[L.E_BOUND])
    jn2 = float(pp[L.JN_HALF])
    theta2 = float(model.theta2_for_te(theta1, jn2))
    pairs = np.zeros((L.MAX_CONTACTS, 3), dtype=np.int64)
    n = candidate_pairs(theta1, theta2, gp, pp, pairs)
    alpha = pp[L.ALPHA]
    rb1, rb2 = gp[0, L.RB], gp[1, L.RB]
    line = model.pair.center_distance * math.sin(alpha)
    # a rounded tip (gear_par EDGE_*): the flank ends at the round's tangent roll, beyond it the
    # round meets the mating flank (as in `solver.mbs.kernels.gearmesh.pair_contacts`)
    hi = [gp[g, L.EDGE_U] if gp[g, L.EDGE_INV_R] > 0 else gp[g, L.U_HI] for g in range(2)]
    rows = []
    for k, j, side in pairs[:n]:
        if side != 1:
            continue
        ax1 = theta1 + gp[0, L.GAMMA0] + k * gp[0, L.PITCH]
        ax2 = theta2 + gp[1, L.GAMMA0] + j * gp[1, L.PITCH]
        u1 = (ax1 + gp[0, L.PSI_B] + alpha + math.pi) % (2 * math.pi) - math.pi
        u2 = (line - rb1 * u1) / rb2
        b1 = ax1 + gp[0, L.PSI_B]
        b2 = ax2 + gp[1, L.PSI_B]
        if u1 <= hi[0] and u2 <= hi[1]:
            if u1 >= gp[0, L.U_LO] and u2 >= gp[1, L.U_LO]:
                rows.append((k, j, u1, u2, 0.0, 1, u1))
        elif u1 > hi[0]:
            d, uf = _corner_flank(gp, 0, b1, b2)
            if gp[1, L.U_LO] <= uf <= hi[1] and -d < max_gap:
                rows.append((k, j, gp[0, L.U_HI], uf, -d, 2, u1))
        else:
            d, uf = _corner_flank(gp, 1, b2, b1)
            if gp[0, L.U_LO] <= uf <= hi[0] and -d < max_gap:
                rows.append((k, j, uf, gp[1, L.U_HI], -d, 3, u2))
    a = np.array(rows, dtype=float).reshape(-1, 7)
    gap = np.maximum(a[:, 4], 0.0)
    for i in range(a.shape[0]):
        # a round's own deviation is in its centre (`_corner_flank`)
        own = [not (a[i, 5] == 2 + g and gp[g, L.EDGE_INV_R] > 0) for g in range(2)]
        gap[i] += own[0] * flank_deviation(gp, 0, a[i, 2])[0] + own[1] * flank_deviation(gp, 1, a[i, 3])[0]
    if pp.size > L.N_PAIR_PAR:
        gap -= error_approach(model, theta1, theta2, a[:, 0].astype(int), a[:, 1].astype(int))
    return MeshPoints(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2], a[:, 3], gap, a[:, 5].astype(int), a[:, 6])


def _corner_flank(gp, g: int, b_g: float, b_f: float) -> tuple[float, float]:
    """(penetration [m], mating flank's roll [-]) of gear g's tip corner into the other gear's +
    flank, rigid bodies; b_g, b_f: the flanks' base angles [rad]. A rounded tip (EDGE_INV_R > 0)
    meets it with its circle: the centre (r plus the deviation inside the flank point at EDGE_U)
    penetrates r less."""
    f = 1 - g
    rb_g, rb_f = gp[g, L.RB], gp[f, L.RB]
    if gp[g, L.EDGE_INV_R] > 0:
        ue = gp[g, L.EDGE_U]
        qx, qy = tip_corner(gp[g, L.CX], gp[g, L.CY], rb_g, b_g, 1.0, ue)
        off = gp[g, L.EDGE_R] + gp[g, L.EDGE_DEV]
        qx, qy = qx + off * math.sin(b_g - ue), qy - off * math.cos(b_g - ue)
        d, uf, _, _ = point_flank(qx, qy, gp[f, L.CX], gp[f, L.CY], rb_f, b_f, 1.0)
        return d + gp[g, L.EDGE_R], uf
    qx, qy = tip_corner(gp[g, L.CX], gp[g, L.CY], rb_g, b_g, 1.0, gp[g, L.U_HI])
    d, uf, _, _ = point_flank(qx, qy, gp[f, L.CX], gp[f, L.CY], rb_f, b_f, 1.0)
    return d, uf


def error_approach(model: Model, theta1: float, theta2: float, tooth1, tooth2) -> np.ndarray:
    """How much closer [m] the pitch errors and eccentricities (`solver.pitch_errors`) bring the drive
    flanks of the tooth pairs (tooth1[i], tooth2[i]) at hub angles theta1, theta2 [rad], to first
    order: each tooth's turn eps about the teeth's centre moves its flank rb*eps along the line of
    action, and the centre offsets d1, d2 move the flanks by (d1 - d2).n, n the drive line of
    action (gear 1's outward flank normal, at 90 deg - alpha in the pair frame; also used for
    tip-corner contacts, whose normal turns by a few degrees)."""
    gp, pp = model.gear_par, model.pair_par
    psi_n = 0.5 * math.pi - pp[L.ALPHA]
    z1 = model.teeth[0]
    eps1 = pp[L.E_EPS + np.asarray(tooth1) % z1]
    eps2 = pp[L.E_EPS + z1 + np.asarray(tooth2) % model.teeth[1]]
    out = gp[0, L.RB] * eps1 + gp[1, L.RB] * eps2
    for g, th, sign in ((0, theta1, 1.0), (1, theta2, -1.0)):
        c = th + gp[g, L.GAMMA0] + pp[L.E_ECC + 2 * g + 1]
        out = out + sign * pp[L.E_ECC + 2 * g] * math.cos(c - psi_n)
    return out


# ------------------------------------------------------------------ tip corners

@dataclass(frozen=True)
class TipEdge:
    """A rounded tip edge of a gear, for the local law of its tip-corner contacts (SI)."""

    radius: float           # tip edge radius [m]
    youngs_modulus: float   # Pa
    face_width: float       # m
    law_radius: float       # equivalent radius of curvature [m] the contact law describes (the pitch point's)

    def compliance(self, flank_radius: float) -> float:
        """Extra compliance [m/N] of a corner contact on a mating flank of radius of curvature
        ``flank_radius`` [m] (`solver.identify.weber.edge_compliance`)."""
        from solver.identify.weber import edge_compliance
        return edge_compliance(self.youngs_modulus, self.face_width, self.law_radius, self.radius, flank_radius)


def gear_edges(edge) -> tuple:
    """(gear 1's, gear 2's) `TipEdge` or None of ``edge``: one TipEdge (both gears), a pair, or None."""
    if edge is None or isinstance(edge, TipEdge):
        return edge, edge
    e1, e2 = edge
    return e1, e2


def corner_compliance(model: Model, mp: MeshPoints, edge) -> np.ndarray:
    """(n,) compliance [m/N] each candidate contact of ``mp`` adds in series with the law: the
    tip edge's (`TipEdge.compliance`) of the corner's gear on tip-corner contacts, measured on
    the mating flank's radius of curvature rb*u at its roll; 0 on flank contacts and where the
    corner's gear has no edge. ``edge``: a `TipEdge` of both gears, (gear 1's, gear 2's) each a
    TipEdge or None, or None. On a gear whose model has the round's geometry (gear_par EDGE_*) the
    compliance ramps in from 0 at the round's tangent roll to the tip's roll, along the corner
    gear's line-of-action roll ``mp.u_line`` (the ramp of `solver.mbs.kernels.gearmesh`, as the default model's c_loc:
    no jump where a contact passes from the flank onto the round)."""
    out = np.zeros(mp.gap.size)
    e1, e2 = gear_edges(edge)
    if e1 is None and e2 is None:
        return out
    rb1, rb2 = model.base_radii
    gp = model.gear_par
    for i, kind in enumerate(mp.kind):
        if kind == 2 and e1 is not None:        # gear 1's corner on gear 2's flank
            out[i] = e1.compliance(rb2 * mp.u2[i])
        elif kind == 3 and e2 is not None:      # gear 2's corner on gear 1's flank
            out[i] = e2.compliance(rb1 * mp.u1[i])
        g = int(kind) - 2
        if g >= 0 and gp[g, L.EDGE_INV_R] > 0 and mp.u_line is not None:
            span = EDGE_BLEND * (gp[g, L.U_HI] - gp[g, L.EDGE_U])
            out[i] *= edge_ramp.py_func(mp.u_line[i], gp[g, L.EDGE_U], span)[0]
    return out


# ------------------------------------------------------------------ contact problem

class LTCAError(RuntimeError):
    """The contact problem at some angle has no solution (no candidate contact, no convergence)."""


def solve_contact(G: np.ndarray, gap: np.ndarray, load: float, k_con: float, m1: float,
                  tol: float = 1e-9, max_iter: int = 60) -> tuple[np.ndarray, float]:
    """Contact forces F (n,) [N] >= 0 and mesh approach w [m] with sum(F) = load [N] and

        G F + (F/k_con)**(1/m1) = w - gap   where F > 0,     G F <= w - gap  where F = 0.

    G (n, n) symmetric positive semi-definite [m/N]; the local law F = k_con*delta**m1 [N/m^m1].
    Active-set Newton in the local approaches delta (F = k_con*delta**m1 is smooth at 0 for m1 >= 1).
    """
    n = gap.size
    if n == 0:
        raise LTCAError("no candidate contact")
    if load <= 0:
        return np.zeros(n), float(gap.min())
    active = np.zeros(n, bool)
    active[np.argmin(gap)] = True
    d = np.zeros(n)
    d0 = (load / k_con) ** (1.0 / m1)
    d[active] = d0
    w = d0 + float(gap.min())
    for _ in range(4 * n + 4):
        A = np.flatnonzero(active)
        for _it in range(max_iter):
            dA = np.maximum(d[A], 0.0)
            F = k_con * dA**m1
            dF = k_con * m1 * np.maximum(dA, 1e-30) ** (m1 - 1.0)
            r = np.concatenate([G[np.ix_(A, A)] @ F + dA - w + gap[A], [F.sum() - load]])
            J = np.zeros((A.size + 1, A.size + 1))
            J[:A.size, :A.size] = G[np.ix_(A, A)] * dF[None, :] + np.eye(A.size)
            J[:A.size, A.size] = -1.0
            J[A.size, :A.size] = dF
            step = np.linalg.solve(J, -r)
            d[A] = dA + step[:A.size]
            w += step[A.size]
            if np.max(np.abs(step[:A.size])) < tol * d0 and abs(step[A.size]) < tol * d0:
                break
        else:
            raise LTCAError("Newton did not converge on the active set")
        F = np.where(active, k_con * np.maximum(d, 0.0) ** m1, 0.0)
        neg = active & (d < -tol * d0)
        if neg.any():
            i = np.flatnonzero(neg)[np.argmin(d[neg])]
            active[i] = False
            d[i] = 0.0
            continue
        viol = w - gap - G @ F
        viol[active] = -np.inf
        if viol.max() > tol * d0:
            i = int(np.argmax(viol))
            active[i] = True
            d[i] = 0.0
            continue
        return np.where(active, k_con * np.maximum(d, 0.0) ** m1, 0.0), float(w)
    raise LTCAError("active set did not settle")


@dataclass
class LTCAResult:
    """STE reference and load sharing over driver angles."""

    angle: np.ndarray          # driver rotation [rad]
    te: np.ndarray             # transmission error rb1*theta1 + rb2*theta2 [m]
    approach: np.ndarray       # mesh approach w = TE - jn/2 [m]
    n_contacts: np.ndarray     # loaded contacts [-]
    tooth_force: np.ndarray    # (angle, gear-1 tooth) normal force [N]
    extended: np.ndarray       # (angle,) force carried by tip-corner (extended) contacts [N]
    torque: float              # resisting torque on gear 2 [N·m]
    backlash_offset: float     # jn/2 [m]


def ltca_sweep(model: Model, compliance: tuple, angles, torque: float, k_con: float | None = None,
               m1: float | None = None, edge=None) -> LTCAResult:
    """Solve the loaded contact at every driver angle [rad] under ``torque`` [N·m] on gear 2.

    ``compliance`` = (BodyCompliance of gear 1, of gear 2), or (None, None) for rigid bodies
    (only the contact law deforms). The contact law defaults to the model's. ``edge``: the tip
    edge of both gears (a `TipEdge`) or of each ((gear 1's, gear 2's), TipEdge or None);
    tip-corner contacts then carry its compliance in series with the law (`corner_compliance`);
    None: the flanks' law alone.
    """
    k_con = float(model.law_par[L.K_CON]) if k_con is None else k_con
    m1 = float(model.law_par[L.M1]) if m1 is None else m1
    angles = np.asarray(angles, float)
    rb2 = model.base_radii[1]
    load = abs(torque) / rb2
    z1 = model.teeth[0]
    n = angles.size
    te = np.empty(n); w_out = np.empty(n); nc = np.zeros(n, int); ext = np.zeros(n)
    f1 = np.zeros((n, z1))
    jn2 = model.backlash_offset
    for a, th in enumerate(angles):
        mp = mesh_points(model, float(th))
        if mp.gap.size == 0:
            raise LTCAError(f"no candidate contact at {math.degrees(th):.3f} deg")
        G = np.zeros((mp.gap.size, mp.gap.size))
        if compliance[0] is not None:
            G += compliance[0].matrix(mp.tooth1, mp.u1)
        if compliance[1] is not None:
            G += compliance[1].matrix(mp.tooth2, mp.u2)
        G[np.diag_indices_from(G)] += corner_compliance(model, mp, edge)
        try:
            F, w = solve_contact(G, mp.gap, load, k_con, m1)
        except LTCAError as e:
            raise LTCAError(f"{e} at {math.degrees(th):.3f} deg") from None
        te[a] = jn2 + w
        w_out[a] = w
        nc[a] = int(np.count_nonzero(F > 0))
        np.add.at(f1[a], mp.tooth1 % z1, F)
        ext[a] = F[mp.kind != 1].sum()
    return LTCAResult(angles, te, w_out, nc, f1, ext, float(torque), jn2)


def teeth_in_mesh(model, angles) -> tuple[list, list, int]:
    """Teeth of each gear that meet the mesh at ``angles`` [rad], and the largest index spread
    between simultaneous candidates (for the solid body's symmetric columns)."""
    s1, s2, spread = set(), set(), 1
    z = model.teeth
    for th in angles:
        mp = mesh_points(model, float(th))
        s1.update(int(t) % z[0] for t in mp.tooth1)
        s2.update(int(t) % z[1] for t in mp.tooth2)
        for t, zz in ((mp.tooth1, z[0]), (mp.tooth2, z[1])):
            if t.size > 1:
                d = (t[:, None] - t[None, :] + zz // 2) % zz - zz // 2
                spread = max(spread, int(np.abs(d).max()))
    return sorted(s1), sorted(s2), spread

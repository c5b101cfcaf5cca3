"""Two-phase contact search over the gear mesh and the generalised forces (numba).

Phase 1 (pre-search, O(1) per tooth pair): a gear-1 tooth can touch its neighbour on side s
(+1 drive, -1 coast) only while both rigid roll parameters of the pair lie within the flanks
(plus a margin for tip-corner contact), and only while the rigid gap bound
``s*TE - jn/2 + |phi_A|*R_A + |phi_B|*R_B`` is positive.
Phase 2 (detailed search): closed-form flank-to-flank penetration along the common tangent
of the moved base circles, or tip corner to flank (see `contact.py`).

Profile modifications (`solver.modification`, gear_par columns DEV_*): the penetration of a
contact point is reduced by each flank's deviation at that point's roll parameter (the tip
corner: the deviation at the tip). First order in the deviations: the force keeps the
involutes' line of action, and the modified flanks touch where the involutes do (the true
first touch is closer by sigma**2/(2*kappa), sigma the deviations' slope per length of flank,
kappa the relative curvature: tens of nm for a 10 um relief; a kinked profile gives no smooth
term to add). The gradient of a flank-flank contact carries the deviations' change with the
roll parameters, which the tooth rotations also change by turning the line of action; a
tip-corner contact's keeps the rigid one but for the blend below.

Where a modified flank's contact runs off its tip onto the tip corner, the first-order model
has a kink: the flank contact's deviation changes with the roll parameter, the corner's is
fixed. The real flanks pass smoothly (their contact point is shifted by sigma/kappa along the
flank), and a kink at an equilibrium stalls the statics' Newton. The corner therefore takes
the tip deviation plus slope*TIP_BLEND*(1 - exp(-(u - u_tip)/TIP_BLEND)), u the flank contact's
roll parameter beyond the tip: the penetration is C1 across the switch and differs from the
plain corner's by at most slope*TIP_BLEND (below 1 nm for any relief steeper than real ones).

Local compliance in series with the contact (gear_par CLOC_*, compliance model only): a contact
at rolls (u1, u2) has c_loc = c1(u1) + c2(u2) [m/N] (a tip corner: its gear's value at the tip)
in series with the contact law (`laws.series_contact`). Since c_loc changes with the rolls, the
potential of the series spring depends on the state through it too: d E/d c_loc = -F_e**2/2 at
fixed penetration, so the recorded gradient is G - F_e**2/(2F) * d c_loc/dq (exact for flank
contacts; a tip corner takes the roll derivative of the flank contact it continues, its own
differs by the corner's slide along the flank, a small energy leak where c_loc's slope is).

A rounded tip edge (gear_par EDGE_*, with the local compliances only): the flank of a gear whose
EDGE_INV_R > 0 ends at the round's tangent roll EDGE_U, and beyond it the tooth meets the mating
flank with the round, a circle of radius r: its penetration is its centre's plus r, along the
mating flank's normal through the centre (the round's normal there), so that the contact passes
from the flank onto the round without a jump (they share the point and the normal at EDGE_U),
and the round keeps the neighbouring pairs' tips off by up to r (1/cos(theta/2) - 1) more than a
sharp corner (theta = 90 deg - alpha_a: 0.16-0.19 r on the pairs of the scenes). The contact carries the compliance of the
round's narrower Hertz patch in its c_loc (`edge_compliance`); it changes with the mating flank's
roll as its radius of curvature does, and that slope joins the flank's c_loc slope in the
gradient (conservative). c_loc is also continuous where the contact leaves the flank: the round's
contact takes its tooth's own compliance at the roll u_g the flank contact would have
(`flank_flank`'s, EDGE_U at the switch; the tip's value beyond U_HI), and the edge's times a C1
ramp from 0 at EDGE_U to 1 at U_HI (`edge_ramp`: the Hertz patch straddles the tangent point
there), both slopes in u_g in its tooth's part of the gradient. (The edge's full compliance from
EDGE_U on made c_loc, and with it the series spring's force and energy, jump by about its own
size at every switch: a dynamic run's energy balance failed at any step, and the static STE
jumped by 0.27 um at 100 N m where a tooth's round took over at 3.35 deg on the paper pair.) The
round's centre is a material point of its tooth, so the moments and the gradient are those of a
tip corner at the centre.

Pitch errors and eccentricity (`solver.pitch_errors`, the pair_par block E_*, present only when a
gear has them): each tooth's axis turns by its offset eps about the teeth's centre, which sits
off the bearing axis by the eccentricity; the flanks follow exactly, the moment arms of the hub
rotations stay about the bearing axes, and the rigid gap bound grows by E_BOUND.

Sliding friction (law_par MU > 0; `_friction`): Coulomb, regularised, mu_eff =
mu*tanh(v_s/v_reg), with v_s = (v_A - v_B).t the sliding speed of the gear-1 tooth's material
point over the gear-2 tooth's at the contact point (hub rotation about its centre plus the tooth
rotation about its pivot), t the normal turned by +90 deg. The force mu_eff*F acts along -t on
gear 1 and +t on gear 2; its generalised forces are -mu_eff*F*H, H = d v_s/d(theta1', phi_A',
theta2', phi_B') (the lever arms of t), the sign of t dropping out. With MU = 0 the friction
columns of the records stay zero and nothing is computed.

State: theta1, theta2 hub angles [rad] (counter-clockwise positive), phi[Z1+Z2] tooth
rotations about their pivots relative to the hub [rad], gear-1 teeth first.
"""
import math

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels import njit
from solver.mbs.kernels.contact import cross, flank_flank, moved_center, point_flank, tip_corner, wrap
from solver.mbs.kernels.laws import contact_force, contact_tangent, series_contact, signed_pow, spring_tangent, spring_torque
from solver.mbs.kernels.layout import contact_geo, contact_parts, new_contact_buffer  # noqa: F401 - plain Python

# roll-parameter length [-] over which a modified tip corner blends into its flank (see above)
TIP_BLEND = 1e-6
# the roll span [-] over which a round's edge compliance ramps in, as a fraction of U_HI - EDGE_U
EDGE_BLEND = 1.0


@njit(cache=True, no_cfunc_wrapper=True)
def candidate_pairs(theta1, theta2, gp, pp, out):
    """Pre-search: fill out[n, :] = (gear-1 tooth, gear-2 tooth, side) of pairs that may touch.

    Returns n. Pairs are those whose rigid roll parameters lie within [u_lo - margin,
    u_hi + margin] on both flanks.
    """
    n = 0
    z1 = int(gp[0, L.NZ])
    z2 = int(gp[1, L.NZ])
    p1 = gp[0, L.PITCH]
    p2 = gp[1, L.PITCH]
    ratio = gp[0, L.RB] / gp[1, L.RB]
    alpha = pp[L.ALPHA]
    margin = pp[L.MARGIN]
    for side in (1, -1):
        s = float(side)
        # s*Psi1 + psi_b1 + alpha in [u_lo1 - margin, u_hi1 + margin]
        lo = gp[0, L.U_LO] - margin - gp[0, L.PSI_B] - alpha
        hi = gp[0, L.U_HI] + margin - gp[0, L.PSI_B] - alpha
        if side < 0:
            lo, hi = -hi, -lo
        base = theta1 + gp[0, L.GAMMA0]
        k0 = int(math.ceil((lo - base) / p1))
        k1 = int(math.floor((hi - base) / p1))
        for kk in range(k0, k1 + 1):
            k = kk % z1
            psi1 = base + kk * p1
            # gear-2 space facing tooth k under conjugate rolling, then its side-s neighbour
            x = (math.pi - psi1 * ratio - theta2 - gp[1, L.GAMMA0]) / p2
            j_space = int(math.floor(x))
            jj = j_space if side > 0 else j_space + 1
            j = jj % z2
            psi2 = theta2 + gp[1, L.GAMMA0] + j * p2
            ub = s * wrap(psi2 - math.pi) + gp[1, L.PSI_B] + alpha
            if ub < gp[1, L.U_LO] - margin or ub > gp[1, L.U_HI] + margin:
                continue
            if n < out.shape[0]:
                out[n, 0] = k
                out[n, 1] = j
                out[n, 2] = side
                n += 1
    return n


@njit(cache=True, no_cfunc_wrapper=True)
def _catmull_rom(gp, g, u, u0, du, first, n):
    """Value and slope d/du of the cubic Hermite (Catmull-Rom) curve through the n values
    gp[g, first:first + n] (gear_par row g) on the grid u0 + i*du: the slope is continuous (Newton in the statics
    does not chatter across grid nodes) and linear stretches are exact; constant beyond the
    grid's ends. (The row by its index, not as a view: a view in the contact search is an
    array whose references numba counts, with an atomic operation each.)"""
    x = (u - u0) / du
    last = n - 1
    if x <= 0.0:
        return gp[g, first], 0.0
    if x >= last:
        return gp[g, first + last], 0.0
    i = int(x)
    t = x - i
    p1 = gp[g, first + i]
    p2 = gp[g, first + i + 1]
    m1 = p2 - p1 if i == 0 else 0.5 * (p2 - gp[g, first + i - 1])
    m2 = p2 - p1 if i + 1 == last else 0.5 * (gp[g, first + i + 2] - p1)
    t2 = t * t
    t3 = t2 * t
    dev = (2.0 * t3 - 3.0 * t2 + 1.0) * p1 + (t3 - 2.0 * t2 + t) * m1 + (3.0 * t2 - 2.0 * t3) * p2 + (t3 - t2) * m2
    dx = (6.0 * t2 - 6.0 * t) * (p1 - p2) + (3.0 * t2 - 4.0 * t + 1.0) * m1 + (3.0 * t2 - 2.0 * t) * m2
    return dev, dx / du


@njit(cache=True, no_cfunc_wrapper=True)
def flank_deviation(gp, g, u):
    """Deviation [m] of the flanks of gear g (its gear_par row gp[g]) at roll parameter u, and
    its slope d deviation / d u [m]: a cubic Hermite (Catmull-Rom) curve through the DEV grid
    (`_catmull_rom`)."""
    return _catmull_rom(gp, g, u, gp[g, L.DEV_U0], gp[g, L.DEV_DU], L.DEV0, L.N_DEV)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def local_compliance(gp, g, u):
    """Local compliance [m/N] of gear g (its gear_par row gp[g]) at roll parameter u and
    its slope d c_loc/d u [m/N]: the same Catmull-Rom curve through the CLOC grid (a continuous
    slope: the force term of c_loc's change along the profile has no jump at grid nodes, and
    the slope is the exact derivative of what is read, so the series spring stays conservative)."""
    return _catmull_rom(gp, g, u, gp[g, L.CLOC_U0], gp[g, L.CLOC_DU], L.CLOC0, L.N_CLOC)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def edge_compliance(gp, g, rb_f, u_f):
    """Compliance [m/N] that the rounded tip edge of gear g (gear_par row gp[g]) adds in series
    with the contact law where it meets the mating flank (base radius ``rb_f`` [m]) at roll u_f,
    and its slope d c/d u_f [m/N]: the edge against the flank's radius of curvature
    rho = rb_f*u_f has the equivalent radius 1/(1/r + 1/rho), and
    c = EDGE_A ln(EDGE_R_LAW/r_eq) (`solver.identify.weber.edge_compliance`), 0 where negative."""
    rho = rb_f * max(u_f, 1e-6)
    x = gp[g, L.EDGE_INV_R] + 1.0 / rho      # 1/r_eq [1/m]
    c = gp[g, L.EDGE_A] * math.log(gp[g, L.EDGE_R_LAW] * x)
    if c <= 0.0:
        return 0.0, 0.0
    return c, -gp[g, L.EDGE_A] / (x * rho * max(u_f, 1e-6))


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def edge_ramp(u, u0, span):
    """Weight [-] of a round's edge compliance at its tooth's flank-contact roll u [-], and its
    slope d w/d u [-]: 0 up to the round's tangent roll u0, the C1 cubic 3t^2 - 2t^3 of
    t = (u - u0)/span over the roll span ``span`` [-], 1 beyond (c_loc and its slope continuous:
    no jump of the series force, and none of its generalised forces, as a contact passes from
    the flank onto the round)."""
    t = (u - u0) / span
    if t <= 0.0:
        return 0.0, 0.0
    if t >= 1.0:
        return 1.0, 0.0
    return t * t * (3.0 - 2.0 * t), 6.0 * t * (1.0 - t) / span


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _tangent_turn(dx, dy, length, kc, ddx, ddy):
    """Change of the common tangent's angle ta [rad] of two base circles whose centre offset
    (dx, dy) [m] (length [m]) changes by (ddx, ddy) [m]; kc = (rb_a + rb_b)/(L**2 sqrt(1 - c**2))."""
    return (dx * ddy - dy * ddx) / (length * length) - kc * (dx * ddx + dy * ddy) / length


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _deviation_gradient(sa, sb, s, centres, trig, ecc, gp):
    """d(da + db)/d(theta1, phi_A, theta2, phi_B) [m] of the flank deviations whose slopes are
    sa, sb [m] per unit roll at the flank-flank contact of side s; centres = (moved base-circle
    centres A x, y, B x, y [m], base radii A, B [m]), trig = (cos, sin of tooth A's axis angle,
    cos, sin of that angle plus its rotation, the same four of B) as `moved_center` gives
    them, ecc = the teeth's centres' offsets from the bearing axes
    (gear 1 x, y, gear 2 x, y) [m]. With ua = s*(beta_a - ta), ub = s*(beta_b - ta - pi), the
    common tangent's angle ta turns as the tooth rotations move the base-circle centres."""
    cax, cay, cbx, cby, rba, rbb = centres
    ca, sna, cpa, spa, cb, snb, cpb, spb = trig
    dx, dy = cbx - cax, cby - cay
    ln = math.sqrt(dx * dx + dy * dy)
    c = (rba + rbb) / ln
    kc = s * (rba + rbb) / (ln * ln * math.sqrt(1.0 - c * c))
    ra, rb_ = gp[0, L.R_PV], gp[1, L.R_PV]
    t1 = _tangent_turn(dx, dy, ln, kc, ra * (sna - spa), ra * (cpa - ca))
    ta_ = _tangent_turn(dx, dy, ln, kc, -ra * spa, ra * cpa)
    t2 = _tangent_turn(dx, dy, ln, kc, rb_ * (spb - snb), rb_ * (cb - cpb))
    tb = _tangent_turn(dx, dy, ln, kc, rb_ * spb, -rb_ * cpb)
    e1x, e1y, e2x, e2y = ecc
    if e1x != 0.0 or e1y != 0.0 or e2x != 0.0 or e2y != 0.0:
        # a hub rotation also swings the eccentric centre about the bearing axis
        t1 += _tangent_turn(dx, dy, ln, kc, e1y, -e1x)
        t2 += _tangent_turn(dx, dy, ln, kc, -e2y, e2x)
    return (-s * (sa * (1.0 - t1) - sb * t1), -s * (sa * (1.0 - ta_) - sb * ta_),
            -s * (-sa * t2 + sb * (1.0 - t2)), -s * (-sa * tb + sb * (1.0 - tb)))


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _friction(rec, nc, f, px, py, nx, ny, frame, vel, lp):
    """Friction columns (`layout` C_VS .. C_HB) of contact record nc with normal force f [N]
    at the point (px, py) [m] with unit normal (nx, ny); frame, vel as `_record`."""
    tx, ty = -ny, nx
    o1x, o1y, pvax, pvay, o2x, o2y, pvbx, pvby = frame
    w1, wa, w2, wb = vel
    h1 = cross(px - o1x, py - o1y, tx, ty)
    ha = cross(px - pvax, py - pvay, tx, ty)
    h2 = -cross(px - o2x, py - o2y, tx, ty)
    hb = -cross(px - pvbx, py - pvby, tx, ty)
    vs = h1 * w1 + ha * wa + h2 * w2 + hb * wb
    th = math.tanh(vs / lp[L.V_REG])
    rec[nc, L.C_VS] = vs
    rec[nc, L.C_FT] = lp[L.MU] * f * th
    rec[nc, L.C_DFT] = lp[L.MU] * f * (1.0 - th * th) / lp[L.V_REG]
    rec[nc, L.C_H1] = h1
    rec[nc, L.C_HA] = ha
    rec[nc, L.C_H2] = h2
    rec[nc, L.C_HB] = hb


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _record(rec, nc, hit, own, ids, frame, vel, lp, dg, blend, ser, series, friction):
    """Write contact record nc (`layout` C_* columns) for hit = (penetration [m], contact
    point x, y [m], normal x, y); own = +1 when gear 1 owns the normal (its flank, or the
    flank-flank case), -1 when gear 2 does; ids = (gear-1 tooth, gear-2 tooth, kind);
    frame = (O1, pivot A, O2, pivot B) as x, y pairs [m]; vel = (theta1', phi_A', theta2',
    phi_B') [rad/s]. The gradient G = d delta/d(theta1, phi_A, theta2, phi_B): the owner's
    entries +(x - centre) x n, the other gear's negative, plus dg, the same four of the flank
    deviations' part [m]. blend = (c [1/m], v [-]): the curvature d2 delta/dq2 = c * v v^T of a
    modified tip corner's blend into its flank (c = 0 otherwise), stored times the force.
    ser = (c_loc [m/N], -d c_loc/d(theta1, phi_A, theta2, phi_B) [m/N]): the local compliance in
    series with the contact law (0 and zeros: the plain law). series, friction: the model's
    `ContactParts` of those names (None: the model has none, and the code is not compiled)."""
    delta, px, py, nx, ny = hit
    o1x, o1y, pvax, pvay, o2x, o2y, pvbx, pvby = frame
    w1, wa, w2, wb = vel
    g1 = own * cross(px - o1x, py - o1y, nx, ny) + dg[0]
    ga = own * cross(px - pvax, py - pvay, nx, ny) + dg[1]
    g2 = -own * cross(px - o2x, py - o2y, nx, ny) + dg[2]
    gb = -own * cross(px - pvbx, py - pvby, nx, ny) + dg[3]
    ddelta = g1 * w1 + ga * wa + g2 * w2 + gb * wb
    cl, gc = ser
    if series is None or cl == 0.0:
        f = contact_force(delta, ddelta, lp[L.K_CON], lp[L.M1], lp[L.C_CON], lp[L.M2], lp[L.M3])
        dcon = delta
        kt = contact_tangent(delta, lp[L.K_CON], lp[L.M1])
    else:
        dcon, fe, kt = series_contact(delta, cl, lp[L.K_CON], lp[L.M1])
        f = fe
        if lp[L.C_CON] != 0.0:
            f += lp[L.C_CON] * signed_pow(ddelta, lp[L.M2]) * delta ** lp[L.M3]
        if f > 0.0:
            # the series spring's energy also changes with c_loc along the profile (gc is
            # -d c_loc/dq, as `_deviation_gradient` gives a deviation's effect on the penetration)
            w = 0.5 * fe * fe / f
            g1 += w * gc[0]
            ga += w * gc[1]
            g2 += w * gc[2]
            gb += w * gc[3]
        else:
            f = 0.0
    rec[nc, L.C_DELTA] = delta
    rec[nc, L.C_DCON] = dcon
    rec[nc, L.C_CLOC] = cl
    rec[nc, L.C_DDELTA] = ddelta
    rec[nc, L.C_FORCE] = f
    rec[nc, L.C_G1] = g1
    rec[nc, L.C_GA] = ga
    rec[nc, L.C_G2] = g2
    rec[nc, L.C_GB] = gb
    rec[nc, L.C_PX] = px
    rec[nc, L.C_PY] = py
    rec[nc, L.C_NX] = nx
    rec[nc, L.C_NY] = ny
    rec[nc, L.C_KT] = kt
    rec[nc, L.C_TOOTH1], rec[nc, L.C_TOOTH2], rec[nc, L.C_KIND] = ids
    rec[nc, L.C_KGEO] = f * blend[0]
    rec[nc, L.C_DG1], rec[nc, L.C_DGA], rec[nc, L.C_DG2], rec[nc, L.C_DGB] = blend[1]
    if friction is not None and lp[L.MU] > 0.0:
        _friction(rec, nc, f, px, py, nx, ny, frame, vel, lp)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def pair_contacts(state, phi, dphi, geo, buf, deviations, series, errors, friction, edges):
    """`mesh_contacts` with the model's `ContactParts` (geo[3]) as arguments of their own:
    deviations, series, errors, friction, edges, so that numba prunes the code of each part that is
    None (it prunes on an argument's type only); the stepping loops call it so, with the parts
    taken out of geo once a run. The pre-search (`candidate_pairs`), then the detailed search
    of each candidate pair (gear-1 tooth k, gear-2 tooth j, side s) at state = (theta1,
    theta2 [rad], theta1', theta2' [rad/s]) with the tooth rotations phi [rad] and rates dphi
    [rad/s]. Fills rec (buf = (rec, pairs)) and returns (n_contacts, n_pairs). Each record
    holds the penetration, its rate, the force and the gradient G = d delta/d(theta1, phi_k,
    theta2, phi_j).

    One function on purpose, its stages (gap bound, the teeth's poses, flank-flank contact,
    tip corners) marked by comments, and one call a step: numba counts the references to every
    array a kernel holds across a call of a compiled function (an atomic operation each, at
    its entry and its exit), so a search called once per candidate pair, through
    `mesh_contacts`, counted them some 60 times a step, a third of the paper model's step.
    Split into small kernels, the same search made the paper model's dynamic step about a
    fifth dearer.
    """
    theta1, theta2, w1, w2 = state
    gp, pp, lp, _parts = geo
    rec, pairs = buf
    npair = candidate_pairs(theta1, theta2, gp, pp, pairs)
    # the gears' rows by index, not as literals (numba would compile a callee once per literal)
    gear1, gear2 = np.int64(0), np.int64(1)
    nc = np.int64(0)
    for i in range(npair):
        k, j, side = pairs[i, 0], pairs[i, 1], pairs[i, 2]
        s = float(side)
        ia = int(gp[0, L.TOOTH0]) + k
        ib = int(gp[1, L.TOOTH0]) + j
        pa = phi[ia]
        pb = phi[ib]
        # phase 1b: rigid gap bound
        te = gp[0, L.RB] * theta1 + gp[1, L.RB] * theta2
        bound = s * te - pp[L.JN_HALF] + abs(pa) * gp[0, L.R_BND] + abs(pb) * gp[1, L.R_BND]
        if deviations is not None:
            bound += gp[0, L.DEV_NEG] + gp[1, L.DEV_NEG]
        if errors is not None:
            bound += pp[L.E_BOUND]
        if bound <= 0.0:
            continue
        o1x, o1y = gp[0, L.CX], gp[0, L.CY]
        o2x, o2y = gp[1, L.CX], gp[1, L.CY]
        axa = theta1 + gp[0, L.GAMMA0] + k * gp[0, L.PITCH]
        axb = theta2 + gp[1, L.GAMMA0] + j * gp[1, L.PITCH]
        # the teeth's centres: off the bearing axes O by the eccentricity (the moment arms stay about O)
        e1x, e1y, e2x, e2y = 0.0, 0.0, 0.0, 0.0
        if errors is not None:
            axa += pp[L.E_EPS + ia]
            axb += pp[L.E_EPS + ib]
            c1 = theta1 + gp[0, L.GAMMA0] + pp[L.E_ECC + 1]
            c2 = theta2 + gp[1, L.GAMMA0] + pp[L.E_ECC + 3]
            e1x, e1y = pp[L.E_ECC] * math.cos(c1), pp[L.E_ECC] * math.sin(c1)
            e2x, e2y = pp[L.E_ECC + 2] * math.cos(c2), pp[L.E_ECC + 2] * math.sin(c2)
        # the sines and cosines of the tooth axes, once for the moved centres, the pivots and the
        # deviations' gradient
        ca, sna = math.cos(axa), math.sin(axa)
        cb, snb = math.cos(axb), math.sin(axb)
        cax, cay, cpa, spa = moved_center(o1x + e1x, o1y + e1y, gp[0, L.R_PV], (ca, sna), axa, pa)
        cbx, cby, cpb, spb = moved_center(o2x + e2x, o2y + e2y, gp[1, L.R_PV], (cb, snb), axb, pb)
        trig = (ca, sna, cpa, spa, cb, snb, cpb, spb)
        rba = gp[0, L.RB]
        rbb = gp[1, L.RB]
        ba = axa + pa + s * gp[0, L.PSI_B]
        bb = axb + pb + s * gp[1, L.PSI_B]
        frame = (o1x, o1y, o1x + e1x + gp[0, L.R_PV] * ca, o1y + e1y + gp[0, L.R_PV] * sna,
                 o2x, o2y, o2x + e2x + gp[1, L.R_PV] * cb, o2y + e2y + gp[1, L.R_PV] * snb)
        vel = (w1, dphi[ia], w2, dphi[ib])
        delta, ua, ub, nx, ny, px, py = flank_flank(cax, cay, rba, ba, cbx, cby, rbb, bb, s)
        hi_a = gp[0, L.U_HI]
        hi_b = gp[1, L.U_HI]
        if edges is not None:
            # a rounded tip: the flank ends where the round leaves it
            if gp[0, L.EDGE_INV_R] > 0.0:
                hi_a = gp[0, L.EDGE_U]
            if gp[1, L.EDGE_INV_R] > 0.0:
                hi_b = gp[1, L.EDGE_U]
        if gp[0, L.U_LO] <= ua <= hi_a and gp[1, L.U_LO] <= ub <= hi_b:
            dg = (0.0, 0.0, 0.0, 0.0)
            if deviations is not None:
                da, sa = flank_deviation(gp, gear1, ua)
                db, sb = flank_deviation(gp, gear2, ub)
                delta -= da + db
                dg = _deviation_gradient(sa, sb, s, (cax, cay, cbx, cby, rba, rbb), trig, (e1x, e1y, e2x, e2y), gp)
            if delta > 0.0 and nc < rec.shape[0]:
                ser = (0.0, (0.0, 0.0, 0.0, 0.0))
                if series is not None:
                    c1, s1 = local_compliance(gp, gear1, ua)
                    c2, s2 = local_compliance(gp, gear2, ub)
                    ser = (c1 + c2, _deviation_gradient(s1, s2, s, (cax, cay, cbx, cby, rba, rbb), trig, (e1x, e1y, e2x, e2y), gp))
                # owner A (gear 1)
                _record(rec, nc, (delta, px, py, nx, ny), 1.0, (k, j, 1.0 * s), frame, vel, lp, dg, (0.0, dg), ser, series,
                        friction)
                nc += 1
            continue
        flanks = ((cax, cay, rba, ba), (cbx, cby, rbb, bb))
        u = (ua, ub)
        hi = (hi_a, hi_b)
        for g in range(2):
            if u[g] > hi[g]:
                # tip corner of gear g against the other gear's flank (owner: the flank's gear)
                f = 1 - g
                rounded = False
                if edges is not None:
                    if gp[g, L.EDGE_INV_R] > 0.0:
                        rounded = True
                cx, cy, rb, b = flanks[g]
                if rounded:
                    # the round's centre, r (and the flank's deviation there) inside its tangent point
                    ue = gp[g, L.EDGE_U]
                    qx, qy = tip_corner(cx, cy, rb, b, s, ue)
                    off = gp[g, L.EDGE_R] + gp[g, L.EDGE_DEV]
                    qx += off * s * math.sin(b - s * ue)
                    qy -= off * s * math.cos(b - s * ue)
                else:
                    qx, qy = tip_corner(cx, cy, rb, b, s, gp[g, L.U_HI])
                cx, cy, rb, b = flanks[f]
                d, uf, mx, my = point_flank(qx, qy, cx, cy, rb, b, s)
                if rounded:
                    # the circle reaches r beyond its centre along the flank's normal: its deepest
                    # point, on the force line through the centre (the same moments)
                    d += gp[g, L.EDGE_R]
                    qx -= gp[g, L.EDGE_R] * mx
                    qy -= gp[g, L.EDGE_R] * my
                dg = (0.0, 0.0, 0.0, 0.0)
                du = (0.0, 0.0, 0.0, 0.0)
                blend = 0.0
                if deviations is not None and rounded:
                    # the round's own deviation is in its centre; the flank's at the contact
                    d -= flank_deviation(gp, f, uf)[0]
                elif deviations is not None:
                    # the tip's deviation, blended C1 into the flank's beyond the tip (TIP_BLEND)
                    last = L.DEV0 + L.N_DEV - 1
                    slope = (gp[g, last] - gp[g, last - 1]) / gp[g, L.DEV_DU]
                    w = math.exp(-(u[g] - gp[g, L.U_HI]) / TIP_BLEND)
                    d -= gp[g, last] + slope * TIP_BLEND * (1.0 - w) + flank_deviation(gp, f, uf)[0]
                    sw = slope * w
                    if w > 1e-12:
                        # d delta/dq gains -sw*du/dq, d2 delta/dq2 gains (sw/TIP_BLEND)*(du/dq)(du/dq)^T
                        ta, tb = (1.0, 0.0) if g == 0 else (0.0, 1.0)
                        du = _deviation_gradient(ta, tb, s, (cax, cay, cbx, cby, rba, rbb), trig, (e1x, e1y, e2x, e2y), gp)
                        dg = (sw * du[0], sw * du[1], sw * du[2], sw * du[3])
                        blend = sw / TIP_BLEND
                if d > 0.0 and gp[f, L.U_LO] <= uf <= hi[f] and nc < rec.shape[0]:
                    ser = (0.0, (0.0, 0.0, 0.0, 0.0))
                    if series is not None:
                        cf, sf = local_compliance(gp, f, uf)
                        cg, sg = local_compliance(gp, g, gp[g, L.U_HI])[0], 0.0
                        if edges is not None:
                            if rounded:
                                # continuous with the flank contact it continues (see the docstring):
                                # the tooth's own compliance at the roll that contact would have, the
                                # edge's ramped in over EDGE_BLEND of the round's roll span
                                cg, sg = local_compliance(gp, g, u[g])
                                ce, se = edge_compliance(gp, g, rb, uf)
                                w, dw = edge_ramp(u[g], gp[g, L.EDGE_U], EDGE_BLEND * (gp[g, L.U_HI] - gp[g, L.EDGE_U]))
                                cg += w * ce
                                sg += dw * ce
                                sf += w * se
                        sfa, sfb = (sf, sg) if f == 0 else (sg, sf)
                        ser = (cg + cf,
                               _deviation_gradient(sfa, sfb, s, (cax, cay, cbx, cby, rba, rbb), trig, (e1x, e1y, e2x, e2y), gp))
                    own = 1.0 if f == 0 else -1.0
                    _record(rec, nc, (d, qx, qy, mx, my), own, (k, j, (2.0 + g) * s), frame, vel, lp, dg, (blend, du), ser,
                            series, friction)
                    nc += 1
    return nc, npair


@njit(cache=True, no_cfunc_wrapper=True)
def mesh_contacts(state, phi, dphi, geo, buf):
    """All contacts of the mesh at state = (theta1, theta2 [rad], theta1', theta2' [rad/s])
    with the tooth rotations phi [rad] and rates dphi [rad/s]; geo = (gear_par, pair_par,
    law_par, `ContactParts`) (`contact_geo`), buf = (rec, pairs) (`new_contact_buffer`).
    Returns (n_contacts, n_pairs); pairs holds the candidates. Compiled once for each
    combination of the parts a model has (the types of geo[3])."""
    parts = geo[3]
    return pair_contacts(state, phi, dphi, geo, buf, parts.deviations, parts.series, parts.errors, parts.friction,
                         parts.edges)


@njit(cache=True, no_cfunc_wrapper=True, inline="always")
def generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, torque2, q):
    """Generalised forces: q[0] on theta1, q[1] on theta2, q[2 + i] on tooth i.

    Contacts: Q = -F * G, plus -F_t * H where a friction force F_t is recorded; springs:
    eq. (1.2) on the active teeth; the resisting torque
    ``torque2`` [N m] acts counter-clockwise on gear 2 (it opposes the driven rotation).
    Only entries of active teeth are written (others are left at zero).
    """
    q[0] = 0.0
    q[1] = torque2
    for a in range(nact):
        i = act[a]
        g = 0 if i < int(gp[1, L.TOOTH0]) else 1
        q[2 + i] = spring_torque(phi[i], dphi[i], kphi[i], gp[g, L.N_K], gp[g, L.C_PHI], gp[g, L.N_C])
    for c in range(nc):
        f = rec[c, L.C_FORCE]
        ia = int(rec[c, L.C_TOOTH1]) + int(gp[0, L.TOOTH0])
        ib = int(rec[c, L.C_TOOTH2]) + int(gp[1, L.TOOTH0])
        q[0] -= f * rec[c, L.C_G1]
        q[2 + ia] -= f * rec[c, L.C_GA]
        q[1] -= f * rec[c, L.C_G2]
        q[2 + ib] -= f * rec[c, L.C_GB]
        ft = rec[c, L.C_FT]
        if ft != 0.0:
            q[0] -= ft * rec[c, L.C_H1]
            q[2 + ia] -= ft * rec[c, L.C_HA]
            q[1] -= ft * rec[c, L.C_H2]
            q[2 + ib] -= ft * rec[c, L.C_HB]


@njit(cache=True, no_cfunc_wrapper=True)
def tooth_spring_tangent(i, phi, kphi, gp):
    g = 0 if i < int(gp[1, L.TOOTH0]) else 1
    return spring_tangent(phi[i], kphi[i], gp[g, L.N_K])

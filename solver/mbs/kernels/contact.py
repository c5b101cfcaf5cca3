"""Contact geometry between involute teeth on pivots, in closed form (numba).

A tooth rotated by phi about its pivot Pv is still an involute of a base circle of the same
radius, whose centre moved to ``C' = Pv + R(phi)(O - Pv)``. A flank is described by
(cx, cy, rb, beta0, s, u_lo, u_hi): base-circle centre [m], base radius [m], polar angle
where the involute leaves the circle [rad], sense s (+1 for the "+" flank, -1 for "-"),
and the roll-parameter range of the real flank (form circle to tip).

Flank point at roll u: P = C + rb*e(t) + rb*u*n, t = beta0 - s*u, outward normal
n = s*(-sin t, cos t). Its projection on n is n.C + rb*u, the "support" used below.

* Flank-to-flank: two flanks of the same sense touch along the internal common tangent of
  their base circles; the penetration is the overlap of their supports on that line.
* Tip corner to flank: the normal from a point Q to an involute is tangent to the base
  circle; the penetration is rb*(u_flank - u_Q) along that tangent.
"""
import math

from solver.mbs.kernels import njit


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def wrap(a):
    """Angle wrapped to [-pi, pi). The angles of the flanks in contact lie within a turn of it:
    there the remainder is the shifted angle itself (the same bits as the remainder, whose
    library call was 7-9 % of a step)."""
    t = a + math.pi
    if 0.0 <= t < 2.0 * math.pi:
        return t - math.pi
    return t % (2.0 * math.pi) - math.pi


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def flank_flank(ca_x, ca_y, rb_a, beta_a, cb_x, cb_y, rb_b, beta_b, s):
    """Penetration of flank A (gear 1) and flank B (gear 2) of sense s along their common normal.

    Returns (delta [m], u_a, u_b, n_x, n_y, p_x, p_y): n is A's outward normal, p the point
    of flank A on the line of action (the force line; any point on it gives the same moments).
    """
    dx = cb_x - ca_x
    dy = cb_y - ca_y
    L = math.sqrt(dx * dx + dy * dy)
    c = (rb_a + rb_b) / L
    if c >= 1.0:
        return -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ta = math.atan2(dy, dx) - s * math.acos(c)
    ct = math.cos(ta)
    st = math.sin(ta)
    nx = -s * st
    ny = s * ct
    ua = s * wrap(beta_a - ta)
    ub = s * wrap(beta_b - ta - math.pi)
    ha = nx * ca_x + ny * ca_y + rb_a * ua
    hb = -(nx * cb_x + ny * cb_y) + rb_b * ub
    px = ca_x + rb_a * ct + rb_a * ua * nx
    py = ca_y + rb_a * st + rb_a * ua * ny
    return ha + hb, ua, ub, nx, ny, px, py


@njit(cache=True, no_cfunc_wrapper=True)
def point_flank(qx, qy, c_x, c_y, rb, beta, s):
    """Penetration of point Q into the involute flank (c, rb, beta, s).

    Returns (delta [m], u_flank, n_x, n_y) with n the flank's outward normal; u_flank < 0
    flags a point inside the base circle (no normal to the involute exists).
    """
    wx = qx - c_x
    wy = qy - c_y
    r2 = wx * wx + wy * wy
    if r2 <= rb * rb:
        return -1.0, -1.0, 0.0, 0.0
    uq = math.sqrt(r2 / (rb * rb) - 1.0)
    t = math.atan2(wy, wx) - s * math.atan(uq)
    nx = -s * math.sin(t)
    ny = s * math.cos(t)
    uf = s * wrap(beta - t)
    return rb * (uf - uq), uf, nx, ny


@njit(cache=True, no_cfunc_wrapper=True)
def tip_corner(c_x, c_y, rb, beta, s, u_tip):
    """Tip corner point of a flank (c, rb, beta, s) [m]."""
    t = beta - s * u_tip
    ct = math.cos(t)
    st = math.sin(t)
    return c_x + rb * ct - s * rb * u_tip * st, c_y + rb * st + s * rb * u_tip * ct


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def moved_center(ox, oy, r_pv, cs_axis, axis, phi):
    """Base-circle centre [m] of a tooth whose axis is at angle ``axis`` [rad] rotated by phi
    [rad] about its pivot, and (cos, sin) of axis + phi; cs_axis: (cos, sin) of axis (the
    caller has them). A tooth at rest on its hub (phi = 0) costs no trigonometry: the centre
    is then exactly the gear's."""
    ca, sa = cs_axis
    if phi == 0.0:
        return ox, oy, ca, sa
    cm = math.cos(axis + phi)
    sm = math.sin(axis + phi)
    return ox + r_pv * (ca - cm), oy + r_pv * (sa - sm), cm, sm


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def cross(ax, ay, bx, by):
    return ax * by - ay * bx

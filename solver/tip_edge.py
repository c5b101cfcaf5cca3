"""A rounded tip edge: the tip corner of a tooth replaced by a circular arc of radius r, tangent
to the flank and to the tip circle (SI: m, rad).

The models end the flank at the round's tangent point and meet the mating flank beyond it with
the round's circle (gear_par EDGE_*: `solver.mbs.kernels.gearmesh.pair_contacts`,
`solver.fe.ltca.mesh_points`), whose contact carries the extra compliance of its narrower
Hertz patch (`solver.identify.weber.edge_compliance`, `edge_columns`); the CalculiX peer meshes
the arc itself (`TipRound.points`, used by `solver.fe.mesh.tooth_pieces`). Against a sharp
corner the round lies up to r (1/cos(theta/2) - 1) inside it (theta = pi/2 - alpha_a: 0.19 r on
the paper's pair, 19 um for r = 0.1 mm), which keeps the neighbouring pairs' tips off at single
contact: a short, steep tip relief.

Geometry of the + flank of a tooth in its frame (`solver.geometry.GearGeometry.flank_point`): the
flank point P(u) at roll u, t = psi_base - u, has the tangent (cos t, sin t) and the outward
normal (-sin t, cos t). The round's centre lies on the flank's inward offset by r,
Q(u) = P(u) + r (sin t, -cos t), and on the circle of radius r_a - r: |Q(u)| = r_a - r fixes
the roll u_r of the tangent point on the flank; the tangent point on the tip circle is the
centre's projection onto it. The flank between the two tangent points turns from the flank's
direction at the tip to the tip circle's: by pi/2 - alpha_a (alpha_a the profile angle at the
tip), so each tangent point lies r tan((pi/2 - alpha_a)/2) from the sharp corner.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.geometry import GearGeometry


def tangent_length(g: GearGeometry, r: float) -> float:
    """Distance [m] from the sharp tip corner to each tangent point of a round of radius r [m]
    (along the tip circle and along the flank, to first order): r tan((pi/2 - alpha_a)/2)."""
    alpha_a = math.acos(g.base_radius / g.tip_radius)
    return r * math.tan(0.5 * (0.5 * math.pi - alpha_a))


def edge_limit(g: GearGeometry) -> tuple[float, str]:
    """(largest tip edge radius [m] the tooth holds, what bounds it, in words): below the module,
    and both rounds of a tooth's tip (one on each flank) must leave tip land between them and end
    on the flank above the form circle."""
    unit = tangent_length(g, 1.0)
    land = g.tip_radius * g.tip_half_angle / unit            # the two rounds meet on the tip
    flank = 0.5 * g.base_radius * (g.u_tip**2 - g.u_form**2) / unit   # the round reaches the form circle
    m = g.spec.module
    return min((m, "the module"), (land, "half the tip land (the rounds of both flanks would meet)"),
               (flank, "the flank's length from the form circle"))


def law_radius(g1: GearGeometry, g2: GearGeometry) -> float:
    """The equivalent radius of curvature [m] the contact law describes: the two involutes' at
    the pitch point (rb tan alpha each), where its Weber fit is taken (`solver.identify.weber`)."""
    alpha = g1.spec.pressure_angle
    rho1, rho2 = (g.base_radius * math.tan(alpha) for g in (g1, g2))
    return rho1 * rho2 / (rho1 + rho2)


def edge_columns(radius: float, youngs_modulus: float, face_width: float, law_r: float) -> tuple:
    """(1/r [1/m], 2/(pi E b) [m/N], law radius [m]): the gear_par columns EDGE_INV_R, EDGE_A,
    EDGE_R_LAW (`solver.mbs.kernels.layout`) of a tip edge of ``radius`` [m] (0: a sharp corner,
    all three 0) on a face of ``face_width`` [m] of Young's modulus [Pa], under a contact law fitted
    to the equivalent radius ``law_r`` [m] (`law_radius`)."""
    if radius == 0.0:
        return 0.0, 0.0, 0.0
    if not (radius > 0 and math.isfinite(radius)):
        raise ValueError(f"tip edge radius: must be positive and finite, got {radius}")
    return 1.0 / radius, 2.0 / (math.pi * youngs_modulus * face_width), law_r


@dataclass(frozen=True)
class TipRound:
    """The round of the + flank's tip corner, tooth frame [m, rad]."""

    radius: float           # r [m]
    centre: tuple           # (x, y) [m]
    u_flank: float          # roll parameter of the tangent point on the flank [-]
    flank_point: tuple      # (x, y) of that point [m]
    tip_point: tuple        # (x, y) of the tangent point on the tip circle [m]

    def points(self, n: int) -> np.ndarray:
        """(n, 2) points on the arc from the tip circle's tangent point to the flank's [m]."""
        cx, cy = self.centre
        a0 = math.atan2(self.tip_point[1] - cy, self.tip_point[0] - cx)
        a1 = math.atan2(self.flank_point[1] - cy, self.flank_point[0] - cx)
        da = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi
        a = a0 + da * np.linspace(0.0, 1.0, n)
        return np.column_stack([cx + self.radius * np.cos(a), cy + self.radius * np.sin(a)])


def tip_round(g: GearGeometry, r: float, deviation=None) -> TipRound:
    """The round of radius ``r`` [m] at the + flank's tip corner (module docstring). ``deviation``:
    None or u -> the flank's deviation along its normal [m] (a profile modification, positive
    where material is removed), as `solver.fe.mesh.tooth_pieces` takes it; the offset keeps the
    involute's normal (a relief's slope of ~1e-3 moves the centre by ~r 1e-6)."""
    from scipy.optimize import brentq
    if not 0 < r < edge_limit(g)[0]:
        raise ValueError(f"tip edge radius: must lie in (0, {edge_limit(g)[0] * 1e3:.4g} mm) ({edge_limit(g)[1]}), "
                         f"got {r * 1e3:.4g} mm")

    def point(u):
        t = g.psi_base - u
        x, y = g.flank_point(u, 1)
        d = 0.0 if deviation is None else float(np.asarray(deviation(np.array([u])), float)[0])
        # the (modified) flank point, and the centre r inside it along the normal
        px, py = float(x) + d * math.sin(t), float(y) - d * math.cos(t)
        return (px, py), (px + r * math.sin(t), py - r * math.cos(t))

    def excess(u):
        return math.hypot(*point(u)[1]) - (g.tip_radius - r)

    u_r = brentq(excess, g.u_form, g.u_tip, xtol=1e-14)
    p, c = point(u_r)
    k = g.tip_radius / math.hypot(*c)
    return TipRound(r, c, u_r, p, (c[0] * k, c[1] * k))

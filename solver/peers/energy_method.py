"""Potential-energy tooth compliance with the Sainsot-Velex-Duverger body term (independent check).

The tooth is a cantilever along its axis, clamped where the fillets meet the root circle, with
the exact section (involute, fillet) of `GearGeometry`. A force F along the line of action at a
point of the + flank stores bending, shear (factor 1.2) and axial energy; the deflection of its
point of application along the force is delta = 2 U / F. The body below the root ("fillet
foundation") adds Sainsot, Velex & Duverger's (2004) 2D formula

    delta_f = F cos^2(beta) / (E b) * [ L* (u_f/S_f)^2 + M* (u_f/S_f) + P* (1 + Q* tan^2(beta)) ],

beta the angle of the force to the normal of the tooth axis, u_f the distance from the root
circle to where the force line crosses the axis, S_f the tooth thickness at the root circle,
and X* = A/theta_f^2 + B h_f^2 + C h_f/theta_f + D/theta_f + E h_f + F with h_f = r_f/r_int
(r_int: the body's inner radius) and theta_f the half tooth angle at the root.
Plane stress (E), like the FE, so the two compare directly. SI units.
"""
from __future__ import annotations

import math

import numpy as np

from solver.geometry import GearGeometry, Material

#                A            B            C            D            E        F
SAINSOT = {"L": (-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045),
           "M": (60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086),
           "P": (-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236),
           "Q": (-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904)}


def _sainsot(name: str, h_f: float, theta_f: float) -> float:
    A, B, C, D, E, F = SAINSOT[name]
    return A / theta_f**2 + B * h_f**2 + C * h_f / theta_f + D / theta_f + E * h_f + F


def half_thickness(g: GearGeometry, n: int = 400):
    """(x, y) of the + flank from the root-circle junction of the fillet to the tip [m], tooth frame."""
    from solver.fe.mesh import tooth_pieces
    plus = tooth_pieces(g, n=n)
    k = next(i for i, (_, f) in enumerate(plus) if f is False and i > len(plus) // 2)  # first + piece (involute)
    pts = np.concatenate([p for p, _ in plus[k:-1]])   # involute (tip -> down), [radial], fillet; no root arc
    pts = pts[::-1]                                     # root -> tip
    keep = np.concatenate([[True], np.diff(pts[:, 0]) > 0])
    return pts[keep, 0], pts[keep, 1]


def tooth_compliance(g: GearGeometry, material: Material, r_int: float, u: float | None = None) -> dict:
    """Compliances [m/N] of a tooth loaded at roll parameter u (default: the pitch point).

    Returns bending, shear, axial, foundation and total, each the deflection along the force per
    unit force.
    """
    E, nu = material.youngs_modulus, material.poisson_ratio
    G = E / (2 * (1 + nu))
    b = g.spec.face_width
    u = math.tan(g.spec.pressure_angle) if u is None else u
    t = g.psi_base - u
    rb = g.base_radius
    xp, yp = rb * math.cos(t) - rb * u * math.sin(t), rb * math.sin(t) + rb * u * math.cos(t)
    dx, dy = math.sin(t), -math.cos(t)
    xs, ys = half_thickness(g)
    x0 = xs[0]
    x = np.linspace(x0, xp, 2000)
    y = np.interp(x, xs, ys)
    area = 2 * y * b
    inertia = b * (2 * y) ** 3 / 12
    m = (xp - x) * dy - yp * dx
    bending = np.trapezoid(m**2 / (E * inertia), x)
    shear = np.trapezoid(1.2 * dy**2 / (G * area), x)
    axial = np.trapezoid(dx**2 / (E * area), x)
    # foundation: Sainsot et al.
    s_f = 2 * ys[0]
    theta_f = math.atan2(ys[0], xs[0])
    h_f = g.root_radius / r_int
    x_c = xp - yp * dx / dy                 # force line on the axis
    u_f = x_c - x0
    beta = math.atan2(abs(dx), abs(dy))
    L, M, P, Q = (_sainsot(k, h_f, theta_f) for k in "LMPQ")
    found = math.cos(beta) ** 2 / (E * b) * (L * (u_f / s_f) ** 2 + M * (u_f / s_f) + P * (1 + Q * math.tan(beta) ** 2))
    total = bending + shear + axial + found
    return dict(bending=bending, shear=shear, axial=axial, foundation=found, total=total)

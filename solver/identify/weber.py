"""Weber's contact deflection of two involute flanks and its fit to F = k_con * delta**m1.

Convention (stated because the fit depends on it; the paper does not give its own):

* plane strain, equal materials, contact at the pitch point (radii of curvature of the two
  involutes there, rho_i = r_b,i * tan(alpha));
* Weber's (1949) approach of the contact point to a point at depth h_i below it, per body

      u_i = 2 q (1 - nu^2) / (pi E) * [ ln(2 h_i / b) - nu / (2 (1 - nu)) ],

  q = F / face width, b = Hertz half-width sqrt(8 q R (1 - nu^2) / (pi E)), R = rho1 rho2 /
  (rho1 + rho2);
* depth h_i = ``depth_fraction`` times the distance from the pitch point to the tooth
  centreline along the line of action (half the tooth thickness at the pitch circle over
  cos(alpha));
* least-squares fit of ln F against ln delta over ``F_ref * span``, F_ref = the scene's
  quasi-static torque over the base radius (1059 N for Table 1).

The default (depth_fraction 0.5, span 0.5 .. 1: the upper half of the load one tooth carries)
reproduces the paper's Table 1 values, k_con = 5.73e6 N/mm^1.225 against 5.64e6 N/mm^1.24.
With the full depth to the centreline (depth_fraction 1, where `solver.fe.body` reads the tooth
spring, so the two would add without overlap) the same range gives 2.97e6 N/mm^1.17: a softer
contact by about 0.15 um at 1 kN. `lightgear fit-contact` prints both.

Units: SI in (m, N, Pa); the fit is returned in SI (N/m^m1) and converted for display with
`solver.units.contact_stiffness_to_si`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.geometry import GearGeometry, GeometryError, Material


@dataclass(frozen=True)
class ContactFit:
    k_con: float        # N/m^m1 (SI)
    m1: float           # 1
    force_range: tuple  # (F_min, F_max) [N]
    depth: tuple        # (h1, h2) [m]
    radius: float       # equivalent radius of curvature R [m]
    rms_log_error: float  # RMS of the fit residual in ln F


def pitch_point_depth(g: GearGeometry) -> float:
    """Distance [m] from the pitch point to the tooth centreline along the line of action."""
    alpha = g.spec.pressure_angle
    s = 2 * g.pitch_radius * (g.psi_base - (math.tan(alpha) - alpha))  # tooth thickness at the pitch circle
    return s / 2 / math.cos(alpha)


def weber_deflection(force, face_width: float, radius: float, depths: tuple, material: Material) -> np.ndarray:
    """Contact deflection delta [m] (approach of the two centrelines) under normal force(s) F [N]."""
    F = np.asarray(force, dtype=float)
    E, nu = material.youngs_modulus, material.poisson_ratio
    q = F / face_width
    b = np.sqrt(8 * q * radius * (1 - nu**2) / (math.pi * E))
    c = 2 * q * (1 - nu**2) / (math.pi * E)
    return sum(c * (np.log(2 * h / b) - nu / (2 * (1 - nu))) for h in depths)


def fit_contact(g1: GearGeometry, g2: GearGeometry, material: Material, force_ref: float,
                span: tuple = (0.5, 1.0), depth_fraction: float = 0.5, samples: int = 40) -> ContactFit:
    """Fit F = k_con * delta**m1 to Weber's deflection over force_ref * span [N]."""
    if not force_ref > 0:
        raise GeometryError("quasi_static.torque", f"must be positive to set the fit's load range, got {force_ref}")
    a = math.tan(g1.spec.pressure_angle)
    r1, r2 = g1.base_radius * a, g2.base_radius * a
    R = r1 * r2 / (r1 + r2)
    if not 0 < depth_fraction <= 1:
        raise ValueError(f"depth_fraction: must lie in (0, 1], got {depth_fraction}")
    depths = (depth_fraction * pitch_point_depth(g1), depth_fraction * pitch_point_depth(g2))
    b = min(g1.spec.face_width, g2.spec.face_width)
    F = force_ref * np.geomspace(span[0], span[1], samples)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = weber_deflection(F, b, R, depths, material)
    if not np.all(np.isfinite(d) & (d > 0)):
        # the contact half-width 2b reaches the depth of the tooth: Weber's half-space
        # flattening has no meaning there (its log turns negative)
        raise GeometryError("material.youngs_modulus", f"the contact of {F[-1]:.4g} N over {b * 1e3:.4g} mm of face is "
                            f"wider than the teeth are deep with E = {material.youngs_modulus / 1e6:.4g} MPa: no Weber "
                            "contact deflection to fit (a stiffer material, a smaller quasi_static.torque)")
    A = np.column_stack([np.log(d), np.ones_like(d)])
    (m1, logk), *_ = np.linalg.lstsq(A, np.log(F), rcond=None)
    res = np.log(F) - A @ np.array([m1, logk])
    return ContactFit(float(math.exp(logk)), float(m1), (float(F[0]), float(F[-1])), depths, R,
                      float(np.sqrt(np.mean(res**2))))


def plane_stress_approach(force, face_width: float, radius: float, depth: float, youngs_modulus: float,
                          poisson_ratio: float) -> np.ndarray:
    """Weber's approach [m] of the contact point to a point at ``depth`` [m] below it in ONE body,
    plane stress (the FE bodies' and the CalculiX peer's state), under a normal force ``force`` [N]
    over ``face_width`` [m] with the pair's equivalent radius of curvature ``radius`` [m]:

        u = 2 q / (pi E) * [ ln(2 h / b) - nu / 2 ],   b = sqrt(8 q R / (pi E)),   q = F / face width,

    the plane-strain formula of `weber_deflection` with E -> E (1 + 2 nu) / (1 + nu)^2 and
    nu -> nu / (1 + nu). The load enters through b as well as q: per unit force the approach
    falls by (1 / (pi E face width)) * ln 2 per doubled load (a power law fitted at one load
    misses that at another)."""
    F = np.asarray(force, dtype=float)
    q = F / face_width
    b = np.sqrt(8.0 * q * radius / (math.pi * youngs_modulus))
    return 2.0 * q / (math.pi * youngs_modulus) * (np.log(2.0 * depth / b) - 0.5 * poisson_ratio)


def edge_compliance(youngs_modulus: float, face_width: float, law_radius: float, edge_radius: float,
                    flank_radius: float = math.inf) -> float:
    """Compliance [m/N] that a tip corner's contact adds to a contact law fitted to two flanks of
    equivalent radius ``law_radius`` [m]: the corner, rounded to ``edge_radius`` [m], meets the
    mating flank (radius of curvature ``flank_radius`` [m]) with the equivalent radius
    r = 1 / (1/edge_radius + 1/flank_radius). Both bodies' plane-stress approaches
    (`plane_stress_approach`) hold ln(1/b) with b ~ sqrt(r), so for the same force

        delta(r) - delta(law_radius) = 2 F / (pi E face width) * ln(law_radius / r),

    linear in F: a compliance. Zero where r >= law_radius (a corner as blunt as the flanks)."""
    if not edge_radius > 0:
        raise ValueError(f"tip edge radius: must be positive, got {edge_radius}")
    r = 1.0 / (1.0 / edge_radius + 1.0 / flank_radius)
    return max(0.0, 2.0 / (math.pi * youngs_modulus * face_width) * math.log(law_radius / r))

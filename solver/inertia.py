"""Mass properties of a gear: the rigid tooth (from its outline polygon) and the body below the
root circle (rings at their thickness, less the openings: round holes, slots or windows, from
their exact outline). SI: kg, m, kg·m².
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from solver.geometry import BodySpec, GearGeometry
from solver.openings import opening_area_moment, shape_of


@dataclass(frozen=True)
class ToothInertia:
    """Rigid tooth above the root circle: mass [kg], centroid radius [m], inertia [kg·m²]."""

    mass: float
    centroid_radius: float
    inertia_centroid: float      # about the centroid (axis along the gear axis)
    pivot_radius: float
    inertia_pivot: float         # about the pivot
    inertia_center: float        # about the gear centre


def polygon_properties(x, y):
    """Area [m²], centroid (x, y) [m] and polar second moment about the origin [m⁴]."""
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    cr = x * y1 - x1 * y
    area = 0.5 * cr.sum()
    cx = ((x + x1) * cr).sum() / (6 * area)
    cy = ((y + y1) * cr).sum() / (6 * area)
    j0 = ((x * x + x * x1 + x1 * x1 + y * y + y * y1 + y1 * y1) * cr).sum() / 12.0
    return area, cx, cy, j0


def tooth_inertia(g: GearGeometry, density: float, pivot_radius: float) -> ToothInertia:
    """Mass and inertia of one tooth (the part above the root circle) of face width b."""
    x, y = g.tooth_polygon()
    area, cx, cy, j0 = polygon_properties(x, y)
    b = g.spec.face_width
    mass = density * area * b
    j_c = j0 - area * (cx**2 + cy**2)
    i_c = density * b * j_c
    i_p = i_c + mass * ((cx - pivot_radius) ** 2 + cy**2)
    i_o = density * b * j0
    return ToothInertia(mass, cx, i_c, pivot_radius, i_p, i_o)


def hole_inertia(body: BodySpec, density: float) -> tuple[float, float]:
    """Mass [kg] and polar inertia about the gear axis [kg·m²] of the web material the openings
    take out, at the web thickness; zero without holes. Round holes: each a disc moved to the
    hole circle; slots and windows: their exact outline integrated (`solver.openings`)."""
    if body.opening != "round" and body.holes:
        area, j0 = opening_area_moment(shape_of(body))
        return density * body.web_thickness * area, density * body.web_thickness * j0
    mh = density * math.pi * body.hole_radius**2 * body.web_thickness
    return body.holes * mh, body.holes * mh * (0.5 * body.hole_radius**2 + body.hole_circle_radius**2)


def body_inertia(g: GearGeometry, body: BodySpec, density: float) -> tuple[float, float]:
    """Mass [kg] and polar inertia [kg·m²] of the body inside the root circle (no teeth)."""
    rf = g.root_radius
    b = g.spec.face_width
    r_rim = rf - body.rim_height
    r_hub = r_rim - body.web_height
    r_bore = r_hub - body.hub_height

    def ring(r_out, r_in, t):
        m = density * math.pi * (r_out**2 - r_in**2) * t
        return m, 0.5 * m * (r_out**2 + r_in**2)

    parts = [ring(rf, r_rim, b), ring(r_rim, r_hub, body.web_thickness), ring(r_hub, r_bore, b)]
    m_holes, i_holes = hole_inertia(body, density)
    return sum(p[0] for p in parts) - m_holes, sum(p[1] for p in parts) - i_holes


@dataclass(frozen=True)
class GearMass:
    """Mass properties of a whole gear (body and teeth) and of the same gear solid
    (`solver.geometry.solid_body`: no holes, web as thick as the face). SI: kg, kg·m²."""

    mass: float            # kg
    inertia: float         # kg·m² about the gear axis
    mass_solid: float      # kg
    inertia_solid: float   # kg·m²

    @property
    def mass_saving(self) -> float:
        """Mass saved against the solid gear [%]."""
        return 100.0 * (1.0 - self.mass / self.mass_solid)

    @property
    def inertia_saving(self) -> float:
        """Inertia saved against the solid gear [%]."""
        return 100.0 * (1.0 - self.inertia / self.inertia_solid)


def gear_inertia(g: GearGeometry, body: BodySpec, density: float) -> tuple[float, float]:
    """Mass [kg] and polar inertia about the axis [kg·m²] of the whole gear: the body inside the
    root circle plus the z teeth. The inertia is the model's total inertia of the gear (the
    hub plus every tooth about the gear centre, `solver.mbs.model` I_TOT)."""
    tooth = tooth_inertia(g, density, g.root_radius)
    m_body, i_body = body_inertia(g, body, density)
    return m_body + g.teeth * tooth.mass, i_body + g.teeth * tooth.inertia_center


def gear_mass(g: GearGeometry, body: BodySpec, density: float) -> GearMass:
    """Mass and inertia of the gear and of the same gear solid (see `GearMass`)."""
    from solver.geometry import solid_body
    m, i = gear_inertia(g, body, density)
    ms, is_ = gear_inertia(g, solid_body(body, g.spec.face_width), density)
    return GearMass(m, i, ms, is_)


# The field that sizes each opening shape for a mass: what a drawing scales to take out more or less.
SIZE_FIELDS = {"round": "hole_radius", "slot": "slot_width", "window": "spoke_width"}


def removed_mass(body: BodySpec, density: float) -> float:
    """Mass [kg] the openings take out of the web (at the web thickness); zero without holes."""
    return hole_inertia(body, density)[0]


def size_for_removed_mass(g: GearGeometry, body: BodySpec, density: float, mass: float,
                          prefix: str = "gear.body") -> BodySpec:
    """The body with its openings sized to take ``mass`` [kg] out of the web: the hole radius of
    round holes, the width of slots, the spoke width of windows (`SIZE_FIELDS`; every other field
    kept). The size is found within the range where the body is valid (`validate_body`);
    GeometryError naming the field when no valid size removes that mass."""
    from scipy.optimize import brentq

    from solver.geometry import GeometryError, validate_body
    if body.holes == 0:
        raise GeometryError(f"{prefix}.holes", "a body without openings cannot be sized for a mass")
    field = SIZE_FIELDS[body.opening]

    def sized(x):
        return replace(body, **{field: x})

    def valid(x):
        try:
            validate_body(g, sized(x), prefix)
            return True
        except GeometryError:
            return False
    small = 1e-9 * g.root_radius
    validate_body(g, sized(small), prefix)              # the place of the openings must fit at all
    lo, hi = small, g.root_radius                        # valid, invalid: bisection to the largest valid size
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if valid(mid) else (lo, mid)
    ends = sorted([removed_mass(sized(small), density), removed_mass(sized(lo), density)])
    if not ends[0] <= mass <= ends[1]:
        raise GeometryError(f"{prefix}.{field}", f"no valid {field} makes {body.holes} {body.opening} openings take out "
                            f"{mass:.5g} kg: between {ends[0]:.5g} and {ends[1]:.5g} kg (the other fields as given)")
    x = brentq(lambda v: removed_mass(sized(v), density) - mass, small, lo, xtol=1e-12 * g.root_radius, rtol=1e-13)
    return sized(x)

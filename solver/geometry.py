"""Standard involute spur gears: radii, flanks, tooth outline, the body below the root circle.

All lengths in m, angles in rad (see `solver.units`). Masses and inertias: `solver.inertia`; the
body below the root circle: `solver.body` (its names importable from here).

Conventions
-----------
* Tooth frame: origin at the gear centre, tooth symmetry axis along +x. The "+" flank is
  the one at positive polar angles, the "-" flank its mirror image.
* An involute flank of base radius ``rb`` is written with the roll parameter ``u``
  (``u = tan(alpha_r)``, ``r = rb*sqrt(1 + u**2)``). The + flank point is
  ``P(u) = rb*e(t) + rb*u*n(t)`` with ``t = psi_b - u``, ``e(t) = (cos t, sin t)`` and the
  outward normal ``n(t) = (-sin t, cos t)``; its polar angle is ``psi_b - inv(alpha_r)``.
* ``psi_b`` is the half angular tooth thickness on the base circle, including the tooth
  thinning that produces the backlash.
* Root fillet: a circular arc of radius ``fillet_radius`` tangent to the root circle and to
  the flank (the involute, or its radial extension when the root circle lies inside the base
  circle). The flank is involute from the form radius up to the tip.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from solver.body import (  # noqa: F401 - the body, importable from here
    SHAPE_FIELDS,
    BodySpec,
    body_settings,
    hole_angles,
    hole_offset,
    opening_half_angle,
    opening_radii,
    solid_body,
)
from solver.openings import between_openings, shape_of, window_corners


class GeometryError(ValueError):
    """Invalid gear geometry. ``field`` is the dotted scene field at fault."""

    def __init__(self, field: str, reason: str):
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


def involute(alpha: float) -> float:
    """inv(alpha) = tan(alpha) - alpha [rad]."""
    return math.tan(alpha) - alpha


@dataclass(frozen=True)
class Material:
    """Linear elastic, isotropic: Young's modulus [Pa], Poisson's ratio [-], density [kg/m³]."""

    youngs_modulus: float = 206e9
    poisson_ratio: float = 0.3
    density: float = 7850.0


@dataclass(frozen=True)
class ToothSpec:
    """Generating data of a standard (unshifted) involute spur gear. SI units."""

    module: float                 # m
    teeth: int                    # -
    pressure_angle: float         # rad
    addendum_coef: float = 1.0    # -, addendum = coef * module
    dedendum_coef: float = 1.25   # -, dedendum = coef * module
    fillet_radius: float = 0.0    # m
    face_width: float = 0.01      # m
    thinning: float = 0.0         # m, reduction of the circular tooth thickness on the pitch circle


@dataclass(frozen=True)
class GearGeometry:
    """Derived geometry of one gear. Build with `gear_geometry`."""

    spec: ToothSpec
    pitch_radius: float
    base_radius: float
    tip_radius: float
    root_radius: float
    form_radius: float
    psi_base: float        # half tooth angle on the base circle [rad]
    u_form: float          # roll parameter at the form radius [-]
    u_tip: float           # roll parameter at the tip [-]
    fillet_center: tuple   # (x, y) of the + side fillet centre in the tooth frame [m]
    fillet_root_angle: float   # polar angle where the + fillet meets the root circle [rad]
    radial_flank: bool     # True when the flank runs radially below the base circle

    @property
    def teeth(self) -> int:
        return self.spec.teeth

    @property
    def pitch_angle(self) -> float:
        """Angular pitch 2*pi/z [rad]."""
        return 2.0 * math.pi / self.spec.teeth

    @property
    def tip_half_angle(self) -> float:
        """Half angular tooth thickness at the tip [rad]."""
        return self.psi_base - (self.u_tip - math.atan(self.u_tip))

    def flank_point(self, u, side: int = 1):
        """Flank points at roll parameter(s) u on the +1 / -1 flank, tooth frame [m]."""
        u = np.asarray(u, dtype=float)
        rb = self.base_radius
        t = self.psi_base - u
        x = rb * np.cos(t) - rb * u * np.sin(t)
        y = rb * np.sin(t) + rb * u * np.cos(t)
        return x, side * y

    def radius_at(self, u) -> np.ndarray:
        return self.base_radius * np.sqrt(1.0 + np.asarray(u, dtype=float) ** 2)

    def roll_at(self, r) -> np.ndarray:
        """Roll parameter of the involute at radius r >= rb."""
        return np.sqrt(np.maximum(np.asarray(r, dtype=float) ** 2 / self.base_radius**2 - 1.0, 0.0))

    def outline(self, n_involute: int = 24, n_fillet: int = 8, n_tip: int = 4, n_root: int = 4):
        """One tooth, from mid-space at -pi/z to mid-space at +pi/z, counter-clockwise.

        Returns (x, y) arrays in the tooth frame [m]; consecutive teeth rotated by the pitch
        angle join into the closed gear outline (see `gear_outline`).
        """
        half = self._half_outline(n_involute, n_fillet, n_tip, n_root)  # + side, from tip down
        xs, ys = half
        # - side is the mirror, traversed outward; + side traversed inward from the tip.
        x = np.concatenate([xs[::-1], xs[1:]])
        y = np.concatenate([-ys[::-1], ys[1:]])
        return x, y

    def _half_outline(self, n_involute, n_fillet, n_tip, n_root):
        """+ half of the tooth: tip centre -> tip corner -> flank -> fillet -> root mid-space."""
        rb, ra, rf = self.base_radius, self.tip_radius, self.root_radius
        pts_x, pts_y = [], []
        # tip arc from the axis to the corner
        a_tip = self.tip_half_angle
        a = np.linspace(0.0, a_tip, n_tip + 1)
        pts_x.append(ra * np.cos(a)); pts_y.append(ra * np.sin(a))
        # involute from tip to form radius
        u = np.linspace(self.u_tip, self.u_form, n_involute + 1)[1:]
        fx, fy = self.flank_point(u, 1)
        pts_x.append(fx); pts_y.append(fy)
        if self.radial_flank:
            r_tan = math.sqrt((rf + self.spec.fillet_radius) ** 2 - self.spec.fillet_radius**2)
            r = np.linspace(rb, r_tan, 4)[1:]
            pts_x.append(r * math.cos(self.psi_base)); pts_y.append(r * math.sin(self.psi_base))
            start = (r_tan * math.cos(self.psi_base), r_tan * math.sin(self.psi_base))
        else:
            start = (pts_x[-1][-1], pts_y[-1][-1])
        # fillet arc from the flank tangency to the root tangency
        cx, cy = self.fillet_center
        rho = self.spec.fillet_radius
        if rho > 0:
            a0 = math.atan2(start[1] - cy, start[0] - cx)
            a1 = self.fillet_root_angle + math.pi
            da = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi
            a = a0 + da * np.linspace(0.0, 1.0, n_fillet + 1)[1:]
            pts_x.append(cx + rho * np.cos(a)); pts_y.append(cy + rho * np.sin(a))
        # root arc to mid-space
        half_pitch = math.pi / self.spec.teeth
        a = np.linspace(self.fillet_root_angle, half_pitch, n_root + 1)[1:]
        pts_x.append(rf * np.cos(a)); pts_y.append(rf * np.sin(a))
        return np.concatenate(pts_x), np.concatenate(pts_y)

    def tooth_polygon(self, n_involute: int = 60, n_fillet: int = 20):
        """Closed polygon of the tooth body above the root circle (tooth frame) [m]."""
        xs, ys = self._half_outline(n_involute, n_fillet, 16, 0)
        # stop at the fillet's root tangency, close along the root circle
        rf = self.root_radius
        a = np.linspace(self.fillet_root_angle, -self.fillet_root_angle, 33)[1:-1]
        # - half reversed (root -> tip, without the tip-centre point the + half starts with),
        # + half (tip -> root), then back along the root circle.
        x = np.concatenate([xs[::-1][:-1], xs, rf * np.cos(a)])
        y = np.concatenate([-ys[::-1][:-1], ys, rf * np.sin(a)])
        return x, y


def gear_geometry(spec: ToothSpec, prefix: str = "gear") -> GearGeometry:
    """Derive radii, flank parameters and fillet of a gear; raise GeometryError if invalid."""
    m, z, alpha = spec.module, spec.teeth, spec.pressure_angle
    _positive(f"{prefix}.module", m)
    if int(z) != z or z < 6:
        raise GeometryError(f"{prefix}.teeth", f"must be an integer >= 6, got {z}")
    if not (math.radians(10) <= alpha <= math.radians(35)):
        raise GeometryError(f"{prefix}.pressure_angle", f"must lie in 10..35 deg, got {math.degrees(alpha):.3g} deg")
    _positive(f"{prefix}.addendum", spec.addendum_coef)
    _positive(f"{prefix}.dedendum", spec.dedendum_coef)
    _positive(f"{prefix}.face_width", spec.face_width)
    if spec.fillet_radius < 0:
        raise GeometryError(f"{prefix}.fillet_radius", f"must be >= 0, got {spec.fillet_radius * 1e3:.4g} mm")
    if spec.thinning < 0:
        raise GeometryError("pair.backlash", "must be >= 0")

    rp = m * z / 2.0
    rb = rp * math.cos(alpha)
    ra = rp + spec.addendum_coef * m
    rf = rp - spec.dedendum_coef * m
    if rf <= 0:
        raise GeometryError(f"{prefix}.dedendum", "root radius is not positive")
    # undercut: the straight part of the generating rack reaches (dedendum - rho*(1 - sin a))*m
    ha_tool = spec.dedendum_coef - spec.fillet_radius / m * (1.0 - math.sin(alpha))
    z_min = 2.0 * ha_tool / math.sin(alpha) ** 2
    if z < z_min - 1e-9:
        raise GeometryError(f"{prefix}.teeth", f"{z} teeth are undercut by the generating rack (needs >= {math.ceil(z_min)} at this pressure angle and dedendum)")

    s_pitch = math.pi * m / 2.0 - spec.thinning
    if s_pitch <= 0:
        raise GeometryError("pair.backlash", "tooth thinning consumes the whole tooth")
    psi_b = s_pitch / (2.0 * rp) + involute(alpha)
    u_tip = math.sqrt(ra**2 / rb**2 - 1.0)
    if psi_b - (u_tip - math.atan(u_tip)) <= 0:
        raise GeometryError(f"{prefix}.addendum", "the tooth is pointed below the tip circle")

    rho = spec.fillet_radius
    # + fillet centre: at distance rho from the flank (outward) and rf + rho from the centre.
    # For the involute the normal offset keeps e(t) orthogonal, so |C|^2 = rb^2 + (rb*u + rho)^2.
    arg = (rf + rho) ** 2 - rb**2
    u_c = (math.sqrt(arg) - rho) / rb if arg > 0 else -1.0
    if u_c > 0:
        radial = False
        t = psi_b - u_c
        px, py = rb * math.cos(t) - rb * u_c * math.sin(t), rb * math.sin(t) + rb * u_c * math.cos(t)
        cx, cy = px - rho * math.sin(t), py + rho * math.cos(t)
        u_form = u_c
    else:
        # root circle inside the base circle: flank continues radially below rb
        radial = True
        if rho >= rf:
            raise GeometryError(f"{prefix}.fillet_radius", "larger than the root radius")
        gamma = psi_b + math.asin(rho / (rf + rho))
        cx, cy = (rf + rho) * math.cos(gamma), (rf + rho) * math.sin(gamma)
        u_form = 0.0
        if math.sqrt((rf + rho) ** 2 - rho**2) > rb:
            raise GeometryError(f"{prefix}.fillet_radius", "fillet does not reach the radial flank below the base circle")
    root_angle = math.atan2(cy, cx)
    if rho > 0 and root_angle > math.pi / z:
        raise GeometryError(f"{prefix}.fillet_radius", f"{rho * 1e3:.4g} mm fillets of neighbouring teeth overlap in the tooth space")
    if rho == 0:
        root_angle = psi_b if radial else math.atan2(py, px)
    r_form = rb * math.sqrt(1.0 + u_form**2)
    return GearGeometry(spec, rp, rb, ra, rf, r_form, psi_b, u_form, u_tip, (cx, cy), root_angle, radial)


def _positive(field: str, value: float) -> None:
    if not (value > 0) or not math.isfinite(value):
        raise GeometryError(field, f"must be positive, got {value}")


@dataclass(frozen=True)
class PairGeometry:
    """Geometry of the meshing pair at the standard centre distance (gear 1 drives)."""

    center_distance: float       # m
    pressure_angle: float        # rad (operating = standard)
    base_pitch: float            # m
    path_of_contact: float       # m, length of the active line of action
    contact_ratio: float         # -
    sap_radius: tuple            # (gear1, gear2) start-of-active-profile radii [m]
    u_sap: tuple                 # (gear1, gear2) roll parameters at the SAP [-]
    normal_backlash: float       # m, along the line of action (sum of both sides' clearance)


def pair_geometry(g1: GearGeometry, g2: GearGeometry) -> PairGeometry:
    """Standard centre distance mesh of two gears of equal module and pressure angle."""
    if abs(g1.spec.module - g2.spec.module) > 1e-12:
        raise GeometryError("gear2.module", "must equal gear1.module")
    if abs(g1.spec.pressure_angle - g2.spec.pressure_angle) > 1e-12:
        raise GeometryError("gear2.pressure_angle", "must equal gear1.pressure_angle")
    alpha = g1.spec.pressure_angle
    a = g1.pitch_radius + g2.pitch_radius
    rb1, rb2 = g1.base_radius, g2.base_radius
    l1 = math.sqrt(g1.tip_radius**2 - rb1**2)
    l2 = math.sqrt(g2.tip_radius**2 - rb2**2)
    for g, mate, name in ((g1, g2, "gear1"), (g2, g1, "gear2")):
        # a tip circle past the mate's root circle: the tip would cut the mate's root (radial
        # interference); no mesh, and no contact ratio to speak of
        if g.tip_radius + mate.root_radius >= a:
            raise GeometryError(f"{name}.addendum", f"the tip circle (radius {g.tip_radius * 1e3:.4g} mm) reaches past the "
                                f"mate's root circle ({mate.root_radius * 1e3:.4g} mm) at the centre distance "
                                f"{a * 1e3:.4g} mm (radial interference): the addendum must stay below the mate's dedendum")
    line = a * math.sin(alpha)
    path = l1 + l2 - line
    pb = 2 * math.pi * rb1 / g1.teeth
    eps = path / pb
    if eps < 1.0:
        raise GeometryError("gear1.addendum", f"contact ratio {eps:.3f} < 1: the mesh is not continuous")
    u_sap1 = (line - l2) / rb1
    u_sap2 = (line - l1) / rb2
    for g, u, name in ((g1, u_sap1, "gear1"), (g2, u_sap2, "gear2")):
        if u < g.u_form - 1e-12:
            raise GeometryError(f"{name}.fillet_radius", f"the mating tip reaches below the form circle (interference): SAP {g.base_radius*math.sqrt(1+max(u,0)**2)*1e3:.4f} mm < form {g.form_radius*1e3:.4f} mm")
    jn = (g1.spec.thinning + g2.spec.thinning) * math.cos(alpha)
    sap = (rb1 * math.sqrt(1 + u_sap1**2), rb2 * math.sqrt(1 + u_sap2**2))
    return PairGeometry(a, alpha, pb, path, eps, sap, (u_sap1, u_sap2), jn)


def validate_body(g: GearGeometry, body: BodySpec, prefix: str = "gear.body") -> None:
    """Raise GeometryError naming the field when the body does not fit the gear."""
    for name in ("rim_height", "web_height", "hub_height"):
        v = getattr(body, name)
        if not (v >= 0) or not math.isfinite(v):
            raise GeometryError(f"{prefix}.{name}", f"must be >= 0, got {v * 1e3:.4g} mm")
    rf = g.root_radius
    bore = rf - body.rim_height - body.web_height - body.hub_height
    if bore <= 0:
        raise GeometryError(f"{prefix}.hub_height", f"rim + web + hub heights ({(rf - bore) * 1e3:.4g} mm) reach the centre (root radius {rf * 1e3:.4g} mm)")
    if not (0 < body.web_thickness <= g.spec.face_width * (1 + 1e-12)):
        raise GeometryError(f"{prefix}.web_thickness", f"must lie in (0, face_width = {g.spec.face_width * 1e3:.4g} mm], got {body.web_thickness * 1e3:.4g} mm")
    if int(body.holes) != body.holes or body.holes < 0:
        raise GeometryError(f"{prefix}.holes", f"must be an integer >= 0, got {body.holes}")
    if body.holes == 0:
        return
    if body.opening not in SHAPE_FIELDS:
        raise GeometryError(f"{prefix}.opening", f"must be one of {', '.join(repr(k) for k in SHAPE_FIELDS)}, got {body.opening!r}")
    r_rim = rf - body.rim_height
    r_hub = r_rim - body.web_height
    if body.opening == "round":
        _validate_round(body, r_rim, r_hub, prefix)
    elif body.opening == "slot":
        _validate_slot(body, r_rim, r_hub, prefix)
    else:
        _validate_window(body, r_rim, r_hub, prefix)


def _validate_round(body: BodySpec, r_rim: float, r_hub: float, prefix: str) -> None:
    if not (body.hole_radius > 0):
        raise GeometryError(f"{prefix}.hole_radius", f"must be positive when holes > 0, got {body.hole_radius * 1e3:.4g} mm")
    rc, rh = body.hole_circle_radius, body.hole_radius
    if rc + rh > r_rim + 1e-12:
        raise GeometryError(f"{prefix}.hole_radius", f"holes cut the rim: hole_circle_radius + hole_radius = {(rc + rh) * 1e3:.4g} mm > {r_rim * 1e3:.4g} mm (root radius - rim_height)")
    if rc - rh < r_hub - 1e-12:
        raise GeometryError(f"{prefix}.hole_radius", f"holes cut the hub: hole_circle_radius - hole_radius = {(rc - rh) * 1e3:.4g} mm < {r_hub * 1e3:.4g} mm (rim and web end there)")
    if body.holes >= 2 and 2 * rc * math.sin(math.pi / body.holes) <= 2 * rh:
        raise GeometryError(f"{prefix}.holes", f"{body.holes} holes of radius {rh * 1e3:.4g} mm on radius {rc * 1e3:.4g} mm cut each other")


def _radial_fit(body: BodySpec, field: str, what: str, half: float, r_rim: float, r_hub: float, prefix: str) -> None:
    """The opening's radial extent hole_circle_radius -/+ ``half`` [m] within the web."""
    rc = body.hole_circle_radius
    if rc + half > r_rim + 1e-12:
        raise GeometryError(f"{prefix}.{field}", f"{what} cut the rim: they reach out to hole_circle_radius + {half * 1e3:.4g} mm = "
                            f"{(rc + half) * 1e3:.4g} mm > {r_rim * 1e3:.4g} mm (root radius - rim_height)")
    if rc - half < r_hub - 1e-12:
        raise GeometryError(f"{prefix}.{field}", f"{what} cut the hub: they reach in to hole_circle_radius - {half * 1e3:.4g} mm = "
                            f"{(rc - half) * 1e3:.4g} mm < {r_hub * 1e3:.4g} mm (rim and web end there)")


def _validate_slot(body: BodySpec, r_rim: float, r_hub: float, prefix: str) -> None:
    w, theta = body.slot_width, body.slot_angle
    if not (w > 0) or not math.isfinite(w):
        raise GeometryError(f"{prefix}.slot_width", f"must be positive for slots, got {w * 1e3:.4g} mm")
    if not (0 <= theta < 2 * math.pi):
        raise GeometryError(f"{prefix}.slot_angle", f"must lie in [0, 360) deg, got {math.degrees(theta):.4g} deg")
    _radial_fit(body, "slot_width", "slots", 0.5 * w, r_rim, r_hub, prefix)
    gap = between_openings(shape_of(body))
    if gap <= 0:
        what = "its two ends meet" if body.holes == 1 else "neighbouring slots cut each other"
        raise GeometryError(f"{prefix}.slot_angle", f"{what}: {body.holes} slot(s) of {math.degrees(theta):.4g} deg and width "
                            f"{w * 1e3:.4g} mm on radius {body.hole_circle_radius * 1e3:.4g} mm leave {gap * 1e3:.4g} mm "
                            f"between them (at most {math.degrees(_slot_angle_max(body)):.4g} deg)")


def _slot_angle_max(body: BodySpec) -> float:
    """The largest slot_angle [rad] at which the slots' ends just touch."""
    x = min(1.0, 0.5 * body.slot_width / body.hole_circle_radius)
    return max(2 * math.pi / body.holes - 2 * math.asin(x), 0.0)


def _validate_window(body: BodySpec, r_rim: float, r_hub: float, prefix: str) -> None:
    if body.holes < 2:
        raise GeometryError(f"{prefix}.holes", f"windows between spokes need at least 2 (spokes and windows alternate), got {body.holes}")
    for name in ("spoke_width", "window_height"):
        v = getattr(body, name)
        if not (v > 0) or not math.isfinite(v):
            raise GeometryError(f"{prefix}.{name}", f"must be positive for windows, got {v * 1e3:.4g} mm")
    rho, height, ws = body.corner_radius, body.window_height, body.spoke_width
    if not (rho >= 0) or not math.isfinite(rho):
        raise GeometryError(f"{prefix}.corner_radius", f"must be >= 0, got {rho * 1e3:.4g} mm")
    _radial_fit(body, "window_height", "windows", 0.5 * height, r_rim, r_hub, prefix)
    r_in = body.hole_circle_radius - 0.5 * height
    sharp = window_corners(shape_of(replace(body, corner_radius=0.0)))
    if not sharp[3] > 0:
        raise GeometryError(f"{prefix}.spoke_width", f"{body.holes} spokes of {ws * 1e3:.4g} mm meet outside the windows' inner "
                            f"radius {r_in * 1e3:.4g} mm (hole_circle_radius - window_height/2): no window is left between them")
    if rho > 0.5 * height * (1 + 1e-12):
        raise GeometryError(f"{prefix}.corner_radius", f"{rho * 1e3:.4g} mm is more than half the window height "
                            f"({0.5 * height * 1e3:.4g} mm): the corners of one side overlap")
    if not window_corners(shape_of(body))[3] >= 0:
        raise GeometryError(f"{prefix}.corner_radius", f"{rho * 1e3:.4g} mm is too large for the window: the fillets of its two "
                            f"inner corners overlap on the inner arc (radius {r_in * 1e3:.4g} mm between spokes of {ws * 1e3:.4g} mm)")


def bore_radius(g: GearGeometry, body: BodySpec) -> float:
    return g.root_radius - body.rim_height - body.web_height - body.hub_height


def gear_outline(g: GearGeometry, **kw):
    """Closed outline of the whole gear (all teeth), counter-clockwise, gear frame [m]."""
    x, y = g.outline(**kw)
    x, y = x[:-1], y[:-1]  # last point is the next tooth's first
    xs, ys = [], []
    for k in range(g.teeth):
        a = k * g.pitch_angle
        c, s = math.cos(a), math.sin(a)
        xs.append(c * x - s * y)
        ys.append(s * x + c * y)
    return np.concatenate(xs), np.concatenate(ys)


def fillet_band(centroids: np.ndarray, g: GearGeometry, tooth: int) -> np.ndarray:
    """Mask of the elements (by their centroids (m, 2) [m]) in the root/fillet band of ``tooth``:
    radius within one module of the root circle, within one pitch of the tooth axis (both fillets
    of the tooth, clear of the pitch-point load patch 1.25 modules above the root)."""
    r = np.hypot(centroids[:, 0], centroids[:, 1])
    a = np.arctan2(centroids[:, 1], centroids[:, 0]) - tooth * g.pitch_angle
    a = (a + math.pi) % (2 * math.pi) - math.pi
    return (np.abs(r - g.root_radius) < g.spec.module) & (np.abs(a) < g.pitch_angle)



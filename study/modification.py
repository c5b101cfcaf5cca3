"""Scene fields of a gear's profile modification (``gearN.modification.*``) and their
conversion to `solver.modification.ProfileModification` (SI, roll parameters in rad).

A relief starts at one of: a roll angle (deg), a diameter (mm) or a length along the path of
contact from the flank end (mm: the tip relief's length is rb*(u_tip - u_start), the root
relief's rb*(u_start - u_form)). A deviation table gives its positions as roll angles or
diameters, and the deviations in um (positive: material removed). ``tip_edge_radius`` (mm; 0: a
sharp corner) rounds the tip corners (`solver.tip_edge`): below the module and the tip land's
share of each round (`solver.tip_edge.edge_limit`); the models without a series contact law
refuse it (`study.scene_checks.check_tip_edges`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from solver import units
from solver.geometry import GearGeometry
from solver.modification import ProfileModification, Relief
from study.errors import SceneError

SHAPES = {"linear": 1.0, "parabolic": 2.0}


def _f(default, unit: str, doc: str, lo=None, choices=None, hi=None):
    return field(default=default, metadata=dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=False, choices=choices,
                                                optional=False))


# roll angles [deg] beyond a turn are a slip (an involute's tip is at some 20-100 deg of roll)
ROLL_MAX = 360.0


@dataclass(frozen=True)
class ModificationSection:
    """Deviation of the flanks along their normal (both flanks of every tooth); 0 = none."""
    tip_relief: float = _f(0.0, "um", "tip relief: deviation at the tip circle (material removed)", 0.0)
    tip_shape: str = _f("linear", "", "tip relief profile: 'linear' or 'parabolic' from its start", choices=tuple(SHAPES))
    tip_start_roll: float = _f(0.0, "deg", "roll angle where the tip relief starts (or tip_start_diameter, or tip_length)", 0.0, hi=ROLL_MAX)
    tip_start_diameter: float = _f(0.0, "mm", "diameter where the tip relief starts", 0.0)
    tip_length: float = _f(0.0, "mm", "length of the tip relief along the path of contact, from the tip", 0.0)
    root_relief: float = _f(0.0, "um", "root relief: deviation at the form circle (material removed)", 0.0)
    root_shape: str = _f("linear", "", "root relief profile: 'linear' or 'parabolic' from its start", choices=tuple(SHAPES))
    root_start_roll: float = _f(0.0, "deg", "roll angle where the root relief starts (or root_start_diameter, or root_length)", 0.0, hi=ROLL_MAX)
    root_start_diameter: float = _f(0.0, "mm", "diameter where the root relief starts", 0.0)
    root_length: float = _f(0.0, "mm", "length of the root relief along the path of contact, from the form circle", 0.0)
    profile_roll: tuple[float, ...] = _f((), "deg", "positions of the profile deviation table as roll angles (or profile_diameter)",
                                            0.0, hi=ROLL_MAX)
    profile_diameter: tuple[float, ...] = _f((), "mm", "positions of the profile deviation table as diameters")
    profile_deviation: tuple[float, ...] = _f((), "um", "profile deviation at those positions (positive: material removed), "
                                              "linear between them, constant beyond; added to the reliefs")
    tip_edge_radius: float = _f(0.0, "mm", "radius of the rounded tip edge (an arc tangent to the flank and the tip circle; "
                                "0: a sharp corner): a tip-corner contact carries its narrower Hertz patch's compliance in "
                                "series with the contact law (compliance model, LTCA); the CalculiX peer meshes the round", 0.0)

    @property
    def is_zero(self) -> bool:
        return (self.tip_relief == 0.0 and self.root_relief == 0.0 and not any(self.profile_deviation)
                and self.tip_edge_radius == 0.0)


def _roll_of_diameter(d_mm: float, g: GearGeometry) -> float:
    r = 0.5 * d_mm * units.MM
    return math.sqrt(max(r * r / g.base_radius**2 - 1.0, 0.0)) if r > g.base_radius else -1.0


def _start(m: ModificationSection, which: str, g: GearGeometry, prefix: str) -> float:
    """Start roll [rad] of the tip or root relief from whichever of its three fields is given."""
    roll, dia, length = (getattr(m, f"{which}_{k}") for k in ("start_roll", "start_diameter", "length"))
    given = [k for k, v in (("start_roll", roll), ("start_diameter", dia), ("length", length)) if v > 0]
    if len(given) > 1:
        raise SceneError(f"{prefix}.{which}_{given[1]}", f"give one of {which}_start_roll, {which}_start_diameter, "
                         f"{which}_length, not both {which}_{given[0]} and {which}_{given[1]}")
    if not given:
        raise SceneError(f"{prefix}.{which}_relief", f"needs its start: {which}_start_roll, {which}_start_diameter "
                         f"or {which}_length")
    if roll > 0:
        u = roll * units.DEG
    elif dia > 0:
        u = _roll_of_diameter(dia, g)
    else:
        u = (g.u_tip - length * units.MM / g.base_radius if which == "tip"
             else g.u_form + length * units.MM / g.base_radius)
    if not g.u_form < u < g.u_tip:
        field = f"{prefix}.{which}_{given[0]}"
        lo, hi = g.form_radius * 2e3, g.tip_radius * 2e3
        raise SceneError(field, f"the relief would start off the flank (form diameter {lo:.4f} mm, roll "
                         f"{math.degrees(g.u_form):.3f} deg, to tip diameter {hi:.4f} mm, roll {math.degrees(g.u_tip):.3f} deg)")
    return u


def _table(m: ModificationSection, g: GearGeometry, prefix: str) -> tuple[tuple, tuple]:
    dev = m.profile_deviation
    if m.profile_roll and m.profile_diameter:
        raise SceneError(f"{prefix}.profile_diameter", "give profile_roll or profile_diameter, not both")
    pos = m.profile_roll or m.profile_diameter
    if not dev and not pos:
        return (), ()
    if len(pos) != len(dev) or len(dev) < 2:
        raise SceneError(f"{prefix}.profile_deviation", f"needs at least two values, one per position "
                         f"(profile_roll or profile_diameter), got {len(dev)} for {len(pos)}")
    u = (np.asarray(m.profile_roll) * units.DEG if m.profile_roll
         else np.array([_roll_of_diameter(d, g) for d in m.profile_diameter]))
    if np.any(np.diff(u) <= 0) or u[0] < 0:
        what = "profile_roll" if m.profile_roll else "profile_diameter"
        raise SceneError(f"{prefix}.{what}", "positions must be strictly increasing and outside the base circle")
    return tuple(float(x) for x in u), tuple(float(x) * units.UM for x in dev)


def half_thickness_normal(g: GearGeometry, r: float) -> float:
    """Material between a flank and the tooth's centreline at radius r [m], normal to the flank
    [m]: half the tooth's arc thickness there, times the cosine of the profile angle."""
    alpha = math.acos(min(g.base_radius / r, 1.0))
    half_arc = r * (g.psi_base - (math.tan(alpha) - alpha))
    return half_arc * math.cos(alpha)


def modification_spec(m: ModificationSection, g: GearGeometry, prefix: str) -> ProfileModification | None:
    """The SI modification of a gear (None: perfect involutes); SceneError naming the field."""
    if m.is_zero:
        return None
    reliefs = {}
    for which in ("tip", "root"):
        amount = getattr(m, f"{which}_relief")
        start = _start(m, which, g, prefix) if amount > 0 else 0.0
        reliefs[which] = Relief(amount * units.UM, start, SHAPES[getattr(m, f"{which}_shape")])
    for which, r in (("tip", g.tip_radius), ("root", g.form_radius)):
        amount = getattr(m, f"{which}_relief") * units.UM
        bound = half_thickness_normal(g, r)
        if amount >= bound:     # the relief would cut the tooth through at that circle
            raise SceneError(f"{prefix}.{which}_relief", f"{amount / units.UM:.4g} um removes the whole tooth at the "
                             f"{'tip' if which == 'tip' else 'form'} circle, where each flank has only "
                             f"{bound / units.UM:.4g} um of material to its centreline (normal to the flank)")
    if m.tip_relief > 0 and m.root_relief > 0 and reliefs["root"].start > reliefs["tip"].start:
        raise SceneError(f"{prefix}.root_relief", "the root relief starts above the tip relief's start")
    roll, dev = _table(m, g, prefix)
    return ProfileModification(reliefs["tip"], reliefs["root"], roll, dev, _tip_edge(m, g, prefix))


def _tip_edge(m: ModificationSection, g: GearGeometry, prefix: str) -> float:
    """The tip edge radius [m]; SceneError where the tooth cannot hold it (`solver.tip_edge.edge_limit`)."""
    from solver.tip_edge import edge_limit
    r = m.tip_edge_radius * units.MM
    if r > 0:
        limit, why = edge_limit(g)
        if not r < limit:
            raise SceneError(f"{prefix}.tip_edge_radius", f"must be below {why}: {limit / units.MM:.4g} mm, got "
                             f"{m.tip_edge_radius:g} mm")
    return r


def tip_edge_radii(gears) -> tuple[float, float]:
    """(gear 1, gear 2) tip edge radius [m] of the scene's gear sections ``gears`` (0: sharp)."""
    return tuple(gs.modification.tip_edge_radius * units.MM for gs in gears)


def tip_edge_attrs(radii) -> dict:
    """The archive attribute ``tip_edge_radius_mm`` (gear 1, gear 2) [mm] of tip edge radii
    (gear 1, gear 2) [m]; none where both corners are sharp (the archives of sharp-cornered
    pairs stay as they were)."""
    if not any(radii):
        return {}
    return {"tip_edge_radius_mm": np.array([r * units.MM_PER_M for r in radii])}

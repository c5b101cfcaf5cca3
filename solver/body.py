"""The gear body below the root circle (paper fig. 1): its spec (`BodySpec`, SI units), the
fields each opening shape reads, the openings' polar angles and extents, and the solid twin of
a body. Whether a body fits its gear is `solver.geometry.validate_body`.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from solver.openings import angular_half_width, radial_extent, shape_of


@dataclass(frozen=True)
class BodySpec:
    """Gear body below the root circle (paper fig. 1). SI units.

    From the root circle inwards: rim of radial height ``rim_height`` (l1) at the full face
    width, web of radial height ``web_height`` (l2) and axial thickness ``web_thickness`` (t1),
    hub of radial height ``hub_height`` (l3) at the full face width, then the bore.
    ``holes`` openings centred on the circle ``hole_circle_radius`` pierce the web, the first at
    polar angle ``hole_phase`` from tooth 0's axis. Their shape is ``opening``
    (`solver.openings`): 'round' holes of radius ``hole_radius``; 'slot', arc slots of radial width
    ``slot_width`` over ``slot_angle`` [rad] (between the centres of their round ends); 'window',
    the web between spokes of width ``spoke_width`` over a radial height ``window_height``, the
    corners rounded with ``corner_radius``. The fields of the other shapes are not read.
    A solid gear has ``web_thickness`` = face width (or ``web_height`` = 0) and no holes.
    """

    rim_height: float
    web_height: float
    hub_height: float
    web_thickness: float
    holes: int = 0
    hole_radius: float = 0.0
    hole_circle_radius: float = 0.0
    hole_phase: float = 0.0
    opening: str = "round"
    slot_width: float = 0.0
    slot_angle: float = 0.0
    spoke_width: float = 0.0
    corner_radius: float = 0.0
    window_height: float = 0.0


# The fields each opening shape reads besides holes, hole_circle_radius and hole_phase.
SHAPE_FIELDS = {"round": ("hole_radius",), "slot": ("slot_width", "slot_angle"),
                "window": ("spoke_width", "corner_radius", "window_height")}


def body_settings(body: BodySpec) -> dict:
    """The body as a dict of the fields that shape it, for cache keys: a round-holed body (or one
    without holes) exactly as before the other shapes existed; a slot or a window with its own
    fields and without the round hole's radius."""
    out = asdict(body)
    for name in ("opening", *SHAPE_FIELDS["slot"], *SHAPE_FIELDS["window"]):
        del out[name]
    if body.holes == 0:
        out.update(hole_radius=0.0, hole_circle_radius=0.0, hole_phase=0.0)
    elif body.opening != "round":
        del out["hole_radius"]
        out["opening"] = body.opening
        out.update({name: getattr(body, name) for name in SHAPE_FIELDS[body.opening]})
    return out


def hole_angles(holes: int, first: float, turn: float = 2.0 * math.pi) -> np.ndarray:
    """Polar angles of the centres of ``holes`` equally spaced holes, the first at ``first``,
    measured from tooth 0's axis, in the unit of ``first`` and ``turn`` (one full turn): rad by
    default (`BodySpec.hole_phase`), deg with ``turn=360.0`` (a scene's ``body.hole_phase``)."""
    return first + turn * np.arange(int(holes)) / holes


def opening_half_angle(body: BodySpec) -> float:
    """Half the polar angle [rad] one opening of the body covers seen from the gear centre
    (`solver.openings.angular_half_width`; round holes: asin(hole_radius / hole_circle_radius))."""
    return angular_half_width(shape_of(body))


def opening_radii(body: BodySpec) -> tuple[float, float]:
    """(innermost, outermost) radius [m] the body's openings reach (`solver.openings.radial_extent`)."""
    return radial_extent(shape_of(body))


def solid_body(body: BodySpec, face_width: float) -> BodySpec:
    """The same body made solid: the web as thick as the face [m], no holes (hole sizes zeroed,
    so every solid variant of a body is the same BodySpec)."""
    return replace(body, web_thickness=face_width, holes=0, hole_radius=0.0, hole_circle_radius=0.0, hole_phase=0.0,
                   opening="round", slot_width=0.0, slot_angle=0.0, spoke_width=0.0, corner_radius=0.0, window_height=0.0)


def hole_offset(teeth: int, holes: int, hole_phase_deg: float) -> np.ndarray:
    """Angular distance [tooth pitches] of each of ``teeth`` tooth axes to the nearest of ``holes``
    hole centres (the first at ``hole_phase_deg`` [deg]); NaN without holes."""
    if holes == 0:
        return np.full(teeth, np.nan)
    tooth = np.arange(teeth) * 360.0 / teeth
    centres = hole_angles(holes, hole_phase_deg, 360.0)
    d = (tooth[:, None] - centres[None, :] + 180.0) % 360.0 - 180.0
    return d[np.arange(teeth), np.argmin(np.abs(d), axis=1)] / (360.0 / teeth)

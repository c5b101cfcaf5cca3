"""Openings sized for a mass: a gear whose openings (round holes, slots or windows) take out of
its web what makes it weigh as much as another body of the same gear, for comparisons of
lightening shapes at equal mass.

    scene = equal_mass(slots, reference=paper)    # slot_width sized: gear 2 weighs what paper's does

The field sized is the one a drawing scales (`solver.inertia.SIZE_FIELDS`): ``hole_radius``,
``slot_width`` or ``spoke_width`` [mm]; the rest of the body stays as given.
"""
from __future__ import annotations

import dataclasses

from solver import units
from solver.geometry import GeometryError
from solver.inertia import SIZE_FIELDS, gear_inertia, size_for_removed_mass
from study.errors import check_scene_argument
from study.scene import Scene, SceneError, opening_text


def gear_mass_kg(scene: Scene, g: int) -> float:
    """Mass [kg] of gear g, body and teeth."""
    return gear_inertia(scene.geometry(g), scene.body_spec(g), scene.material.density)[0]


def equal_mass(scene: Scene, reference: Scene | float, g: int = 2) -> Scene:
    """``scene`` with gear g's openings sized so that the gear weighs what gear g of
    ``reference`` weighs (a Scene), or ``reference`` kg (a number). SceneError naming the size
    field when no valid size reaches that mass (or the sized body fails a scene check)."""
    check_scene_argument("equal_mass", scene)
    target = gear_mass_kg(reference, g) if isinstance(reference, Scene) else float(reference)
    body, geo = scene.body_spec(g), scene.geometry(g)
    field = SIZE_FIELDS[body.opening]
    plain = gear_inertia(geo, dataclasses.replace(body, holes=0), scene.material.density)[0]
    try:
        sized = size_for_removed_mass(geo, body, scene.material.density, plain - target, prefix=f"gear{g}.body")
    except GeometryError as e:
        raise SceneError(e.field, e.reason) from None
    return scene.replace(**{f"gear{g}.body.{field}": getattr(sized, field) / units.MM})


def describe_openings(scene: Scene, g: int = 2) -> str:
    """Gear g's openings in words [mm, deg] ('6 slots 5.35 mm wide over 30 deg on R 32.36 mm') -> str."""
    check_scene_argument("describe_openings", scene)
    return opening_text(scene.gear(g).body)


def opening_outline(scene: Scene, g: int = 2, angle: float | None = None):
    """The exact outline of gear g's first opening sampled every 10 um -> (x, y) [mm] in the gear
    frame, turned to polar angle ``angle`` [deg] (default: where the scene puts it, hole_phase);
    (empty, empty) without holes."""
    import math

    import numpy as np

    from solver.openings import local_outline, place, polygon, shape_of
    check_scene_argument("opening_outline", scene)
    body = scene.body_spec(g)
    if not body.holes:
        return np.empty(0), np.empty(0)
    turn = body.hole_phase if angle is None else math.radians(angle)
    x, y = polygon(place(local_outline(shape_of(body)), turn), 10 * units.UM)
    return x / units.MM, y / units.MM


def opening_order_amplitude(scene: Scene, angle, te) -> float:
    """Amplitude of ``te`` (any unit, over the driver angles ``angle`` [deg]) at the order N of
    the driven gear's openings, fitted with the first three mesh harmonics and their sidebands
    (`study.verify.model_validation.order_amplitude`); NaN without openings."""
    import numpy as np

    from study.verify.model_validation import order_amplitude
    check_scene_argument("opening_order_amplitude", scene)
    n = scene.gear2.body.holes
    if not n:
        return float("nan")
    driven = np.radians(np.asarray(angle, float)) * scene.gear1.teeth / scene.gear2.teeth
    return order_amplitude(driven, np.asarray(te, float), n, scene.gear2.teeth)

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
from study.scene import Scene, SceneError


def gear_mass_kg(scene: Scene, g: int) -> float:
    """Mass [kg] of gear g, body and teeth."""
    return gear_inertia(scene.geometry(g), scene.body_spec(g), scene.material.density)[0]


def equal_mass(scene: Scene, reference: Scene | float, g: int = 2) -> Scene:
    """``scene`` with gear g's openings sized so that the gear weighs what gear g of
    ``reference`` weighs (a Scene), or ``reference`` kg (a number). SceneError naming the size
    field when no valid size reaches that mass (or the sized body fails a scene check)."""
    target = gear_mass_kg(reference, g) if isinstance(reference, Scene) else float(reference)
    body, geo = scene.body_spec(g), scene.geometry(g)
    field = SIZE_FIELDS[body.opening]
    plain = gear_inertia(geo, dataclasses.replace(body, holes=0), scene.material.density)[0]
    try:
        sized = size_for_removed_mass(geo, body, scene.material.density, plain - target, prefix=f"gear{g}.body")
    except GeometryError as e:
        raise SceneError(e.field, e.reason) from None
    return scene.replace(**{f"gear{g}.body.{field}": getattr(sized, field) / units.MM})

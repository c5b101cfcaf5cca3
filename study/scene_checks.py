"""The checks of a scene across its fields (geometry, bodies, mesh, the integrator and the
model, the static analysis's angles): `check_scene` raises a SceneError naming the field, before
any work starts. The field-by-field checks (keys, types, ranges) are `study.scene`'s.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

from solver import units
from solver.geometry import GeometryError, pair_geometry, validate_body
from study.damping import check_damping
from study.errors import SceneError
from study.modification import modification_spec
from study.pitch_errors import errors_spec

if TYPE_CHECKING:
    from study.scene import Scene


def check_scene(scene: Scene) -> None:
    """Physical consistency across fields (geometry, bodies, mesh). Raises SceneError."""
    try:
        geoms = []
        for g in (1, 2):
            geo = scene.geometry(g)
            validate_body(geo, scene.body_spec(g), prefix=f"gear{g}.body")
            geoms.append(geo)
            gs = scene.gear(g)
            if gs.pivot_radius > 0 and not (geo.base_radius * 0.5 < gs.pivot_radius * units.MM < geo.tip_radius):
                raise GeometryError(f"gear{g}.pivot_radius", f"must lie between half the base radius and the tip radius ({geo.tip_radius * 1e3:.4g} mm), got {gs.pivot_radius} mm")
            modification_spec(gs.modification, geo, f"gear{g}.modification")
            errors_spec(gs.errors, geo, f"gear{g}.errors")
        check_jamming(scene, pair_geometry(*geoms))
    except GeometryError as e:
        raise SceneError(e.field, e.reason) from None
    check_damping(scene)
    check_tip_edges(scene)
    d = scene.dynamic
    if d.output_step > d.duration:
        raise SceneError("dynamic.output_step", f"longer than dynamic.duration ({d.duration} s)")
    if d.time_step > d.output_step:
        raise SceneError("dynamic.time_step", f"must not exceed dynamic.output_step ({d.output_step} s)")
    if d.torque_change_time > 0 and not d.ramp_time < d.torque_change_time < d.duration:
        raise SceneError("dynamic.torque_change_time", f"must lie after the ramp ({d.ramp_time} s) and before the end "
                         f"of the run ({d.duration} s), got {d.torque_change_time} s")
    if d.spectrum_start >= d.duration:
        raise SceneError("dynamic.spectrum_start", f"must be before the end of the run ({d.duration} s)")
    if scene.quasi_static.enabled:
        check_two_angles(scene, scene.quasi_static.angle_step)
    check_integrator_model(scene)
    from study.plausibility import check_plausibility  # mesh, steady window and load bounds
    check_plausibility(scene)


def check_tip_edges(scene: Scene) -> None:
    """A rounded tip edge (``gearN.modification.tip_edge_radius`` > 0) adds its compliance to the
    series law of the compliance model's contacts; the paper model and body-torsion coupling have
    no compliance in series with the contact law to add it to: SceneError naming the field."""
    if scene.coupling_model == "compliance":
        return
    for g in (1, 2):
        if scene.gear(g).modification.tip_edge_radius > 0:
            raise SceneError(f"gear{g}.modification.tip_edge_radius",
                             f"a rounded tip edge needs the compliance model's contact law (coupling.model = 'compliance' "
                             f"or 'auto'); the {scene.coupling_model_name} model has no compliance in series with the "
                             f"contact law to add the edge's to (0: a sharp corner)")


def error_period(scene: Scene) -> float:
    """Driver rotation [deg] after which the TE of a scene with pitch errors or eccentricity
    repeats: one revolution of the gear that has them (gear 2: Z2/Z1 driver revolutions), the
    hunting period lcm(Z1, Z2)/Z1 driver revolutions when both have them; 0 without errors."""
    z1, z2 = scene.gear1.teeth, scene.gear2.teeth
    on = (not scene.gear1.errors.is_zero, not scene.gear2.errors.is_zero)
    if on == (False, False):
        return 0.0
    if on == (True, True):
        return 360.0 * math.lcm(z1, z2) / z1
    return 360.0 if on[0] else 360.0 * z2 / z1


def static_rotation(scene: Scene) -> float:
    """Driver rotation [deg] of the quasi-static analysis: quasi_static.rotation, or with errors
    whole periods of them (`error_period`, at least one) at the same angle step, so that the STE
    and its spectrum hold every tooth pair."""
    rot = scene.quasi_static.rotation
    period = error_period(scene)
    if period > 0:
        rot = period * max(1, math.ceil(rot / period - 1e-9))
    return rot


def check_two_angles(scene: Scene, step_deg: float, field: str = "quasi_static.angle_step") -> None:
    """SceneError naming ``field`` when an angle step of ``step_deg`` [deg] leaves one driver
    angle over the static rotation: an STE needs two at least (its peak-to-peak over one angle
    would read 0)."""
    rot = static_rotation(scene)
    if step_deg > rot * (1 + 1e-9):
        raise SceneError(field, f"a step of {step_deg:g} deg leaves one driver angle over the rotation of {rot:g} deg "
                                "(quasi_static.rotation): the STE needs two at least; give a step no larger than the rotation")


def check_integrator_model(scene: Scene) -> None:
    """The implicit integrator (HHT-alpha) carries the paper's plain model only: with a coupled
    model (coupling.model named, or 'auto' resolved to it) dynamic.method = 'implicit' is refused
    before any work, naming both fields and the two ways out. The choice of an integrator never
    changes the physics silently; 'auto' picks the explicit integrator for a coupled model."""
    d = scene.dynamic
    if not (d.enabled and d.method == "implicit") or scene.coupling_model == "none":
        return
    how = ("coupling.model = 'auto' runs the compliance model here (the default unless both gears' "
           "spring.stiffness is 'uniform')" if scene.coupling.model == "auto"
           else f"coupling.model = {scene.coupling.model!r} is a coupled model")
    raise SceneError("dynamic.method", f"'implicit' (HHT-alpha) integrates the paper's plain model only, and {how}: "
                                       "set coupling.model = 'paper' to integrate the paper's model implicitly, or "
                                       "dynamic.method = 'explicit' (or 'auto') to keep the coupled model")


def check_jamming(scene: Scene, pair) -> None:
    """The eccentricities must not close the backlash: where both offsets point at the mate,
    the centre distance shrinks by their sum and the normal backlash by 2 sin(alpha) times it;
    beyond that the teeth are wedged on both flanks at once (a jammed pair, forces far above
    the load). GeometryError naming the larger eccentricity."""
    ecc = [scene.gear(g).errors.eccentricity * units.UM for g in (1, 2)]
    closing = 2.0 * sum(ecc) * math.sin(pair.pressure_angle)
    if closing >= pair.normal_backlash:
        g = 1 if ecc[0] >= ecc[1] else 2
        limit = pair.normal_backlash / (2.0 * math.sin(pair.pressure_angle)) / units.UM
        raise GeometryError(f"gear{g}.errors.eccentricity",
                            f"the eccentricities ({ecc[0] / units.UM:.4g} + {ecc[1] / units.UM:.4g} um) close the "
                            f"backlash ({scene.pair.backlash * 1e3:.4g} um on the pitch circle) where they point at the "
                            f"mate, which jams the pair: their sum must stay below {limit:.4g} um (or give more "
                            "pair.backlash)")

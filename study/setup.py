"""Scene -> solver model: the tooth springs (uniform, or from the FE body), the foundation
coupling, the contact law in SI, and the solver arguments a scene implies (static angles,
load profile).
"""
from __future__ import annotations

import functools
import math

import numpy as np

from solver import units
from solver.mbs.model import ContactLaw, GearInput, Model, build_model
from study.scene import Scene


def tooth_springs(scene: Scene, g: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-tooth k_phi [N·mm/rad^n_k] and FE stiffness ratio [1] of gear g.

    A solid gear needs no FE: every tooth gets the scene's k_phi. A lightened gear's springs
    come from the FE body model (`study.inputs.springs`), unless its spring.stiffness is 'uniform'.
    """
    gs = scene.gear(g)
    z = gs.teeth
    if not scene.is_lightened(g) or gs.spring.stiffness == "uniform":
        return np.full(z, gs.spring.k_phi), np.ones(z)
    from study.inputs.springs import tooth_springs as fe_springs
    return fe_springs(scene, g)


@functools.lru_cache(maxsize=16)
def coupling_fit(scene: Scene, g: int):
    """Gear g's foundation coupling identified from its FE body: a `BodyTorsionFit`
    ('body-torsion'), a `ToothComplianceFit` ('compliance'), or None (the plain model).
    Kept per scene: a run asks for it for the springs and again for the model."""
    from study.inputs import coupling
    model = scene.coupling.model
    if model == "body-torsion":
        return coupling.body_torsion(scene, g)
    if model == "compliance":
        return coupling.tooth_compliance(scene, g)
    return None


def coupled_springs(scene: Scene, g: int) -> tuple[np.ndarray, np.ndarray]:
    """Gear g's tooth springs without the body wind-up [N·mm/rad] (linear, n_k = 1; with the
    compliance model each tooth's own spring, loaded alone) and the FE stiffness ratio [1] of
    the plain model's springs."""
    fit = coupling_fit(scene, g)
    k = fit.k_tooth if scene.coupling.model == "body-torsion" else fit.k_own
    return k / units.spring_stiffness_to_si(1.0), tooth_springs(scene, g)[1]


def scene_springs(scene: Scene):
    """((k1, r1), (k2, r2)): per-tooth springs [N·mm/rad^n_k] and stiffness ratios of both gears."""
    if scene.coupling.model != "none":
        return coupled_springs(scene, 1), coupled_springs(scene, 2)
    return tooth_springs(scene, 1), tooth_springs(scene, 2)


def build_scene_model(scene: Scene, springs=None) -> Model:
    """The solver model of a scene (SI). ``springs`` = ((k1, r1), (k2, r2)) skips the FE of
    the tooth springs (a coupled model still takes its body springs from the FE)."""
    springs = springs or scene_springs(scene)
    gears = []
    for g in (1, 2):
        gs = scene.gear(g)
        fit = coupling_fit(scene, g)
        cmat = None
        if fit is not None:
            k_body, n_k, pivot = fit.k_body, 1.0, fit.pivot_radius
            if scene.coupling.model == "compliance":
                cmat = fit.compliance
        else:
            k_body, n_k, pivot = math.inf, gs.spring.n_k, scene.pivot_radius(g)
        gears.append(GearInput(tooth=scene.tooth_spec(g), body=scene.body_spec(g),
                               pivot_radius=pivot,
                               k_phi=units.spring_stiffness_to_si(np.asarray(springs[g - 1][0], float)),
                               n_k=n_k, c_phi=units.spring_damping_to_si(gs.spring.c_phi),
                               n_c=gs.spring.n_c, body_stiffness=k_body, tooth_compliance=cmat))
    c = scene.contact
    law = ContactLaw(units.contact_stiffness_to_si(c.k_con, c.m1), c.m1,
                     units.contact_damping_to_si(c.c_con, c.m2, c.m3), c.m2, c.m3)
    return build_model(gears[0], gears[1], law, scene.material_spec())


def geometry_model(scene: Scene) -> Model:
    """The pair's geometry, inertia and contact law without any FE: plain uniform springs of
    the scene's k_phi and no foundation coupling. For what needs the kinematics and the
    contact law only (the mesh positions, the FE reference), not the tooth springs."""
    plain = scene.replace(**{"coupling.model": "none"})
    z1, z2 = scene.gear1.teeth, scene.gear2.teeth
    return build_scene_model(plain, springs=((np.full(z1, scene.gear1.spring.k_phi), np.ones(z1)),
                                             (np.full(z2, scene.gear2.spring.k_phi), np.ones(z2))))


def static_angles(scene: Scene) -> np.ndarray:
    """Driver angles [rad] of the quasi-static analysis."""
    qs = scene.quasi_static
    n = int(math.floor(qs.rotation / qs.angle_step + 1e-9)) + 1
    return np.radians(np.arange(n) * qs.angle_step)


def load_table(scene: Scene) -> np.ndarray | None:
    """The resisting-torque profile [time s, torque N·m] of a scene whose load changes during
    the run (dynamic.torque_change_time > 0): ramp to dynamic.torque, hold, then linear to
    dynamic.torque_after; None for the plain ramp."""
    d = scene.dynamic
    if d.torque_change_time <= 0:
        return None
    t1 = d.torque_change_time
    return np.array([[0.0, 0.0], [d.ramp_time, d.torque], [t1, d.torque],
                     [t1 + d.torque_change_duration, d.torque_after]])

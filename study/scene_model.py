"""Scene -> gear setups -> solver model: the tooth springs (uniform, or from the FE body), the
foundation coupling, the contact law in SI, and the solver arguments a scene implies (static
angles, load profile).

The scene's gears are prepared once (`gear_setups`, `study.inputs.gearsetup`); the FE-derived
inputs (`study.inputs`) take those setups and the model is assembled from them.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from solver import units
from solver.mbs.kernels import layout as L
from solver.mbs.model import ContactLaw, GearInput, Model, build_model, with_flank_deviations
from solver.store import STORE, digest
from study.errors import BudgetError
from study.inputs import coupling
from study.inputs.cache import FE_CACHE
from study.inputs.gearsetup import GearSetup, gear_setup, gear_setups
from study.inputs.springs import tooth_springs
from study.memory import available_memory, bytes_text
from study.scene import (
    MESH_DAMPING_RATIO,
    TOOTH_DAMPING_RATIO,
    Scene,
    SceneError,
    check_two_angles,
    static_rotation,
)

__all__ = ["GearSetup", "gear_setup", "gear_setups", "coupling_fit", "scene_springs",
           "build_scene_model", "kept_scene_model", "scene_model", "geometry_model", "static_angles", "static_angle_count",
           "check_static_memory", "dynamic_choice", "load_table", "damping_ratios", "mean_load",
           "nominal_dampers", "damping_conversion", "study_damping_conversion", "has_flanks"]


def coupling_fit(scene: Scene, g: int, model: str | None = None, setups: tuple | None = None, kinematics=None):
    """Gear g's foundation coupling identified from its FE body: a `BodyTorsionFit`
    ('body-torsion'), a `ToothComplianceFit` ('compliance'), or None (the plain model).
    ``model``: the coupling model (default: the scene's); ``setups``: the scene's gear setups
    when already made; ``kinematics``: a function giving the pair's `geometry_model` (the
    compliance fit's mesh positions; default: built here). Kept in `FE_CACHE` by both gears'
    FE settings: a run asks for it for the springs and again for the model."""
    model = scene.coupling_model if model is None else model
    if model not in ("body-torsion", "compliance"):
        return None
    setups = setups or gear_setups(scene)
    setup = setups[g - 1]

    def fit():
        if model == "body-torsion":
            return coupling.body_torsion(setup)
        pair = kinematics() if kinematics is not None else geometry_model(scene, setups)
        return coupling.tooth_compliance(setup, coupling.mesh_samples(pair, g))
    # both gears' FE settings in the key: the compliance fit reads the pair's rigid geometry too
    return FE_CACHE.fit((model, g, setups[0].key, setups[1].key), fit)


def coupled_springs(scene: Scene, setup: GearSetup, setups: tuple, kinematics=None) -> tuple[np.ndarray, np.ndarray]:
    """The gear's tooth springs without the body wind-up [N·mm/rad] (linear, n_k = 1; with the
    compliance model each tooth's own spring, loaded alone) and the FE stiffness ratio [1] of
    the plain model's springs (``kinematics`` as `coupling_fit`'s)."""
    fit = coupling_fit(scene, setup.gear, setups=setups, kinematics=kinematics)
    k = fit.k_tooth if scene.coupling_model == "body-torsion" else fit.k_own
    return k / units.spring_stiffness_to_si(1.0), tooth_springs(setup)[1]


def scene_springs(scene: Scene, setups: tuple | None = None):
    """((k1, r1), (k2, r2)): per-tooth springs [N·mm/rad^n_k] and stiffness ratios of both gears."""
    setups = setups or gear_setups(scene)
    if scene.coupling_model != "none":
        pair = []       # the pair's kinematics for both gears' fits, built once when a fit needs it

        def kinematics():
            if not pair:
                pair.append(geometry_model(scene, setups))
            return pair[0]
        return tuple(coupled_springs(scene, s, setups, kinematics) for s in setups)
    return tuple(tooth_springs(s) for s in setups)


MODEL_SLOTS = 4     # built models kept in a process: a study's worker runs many points of one body
MODELS = STORE.shelf("scene models", MODEL_SLOTS)


def model_key(scene: Scene, springs, convert_damping: bool, flanks: bool = True) -> str:
    """What a scene's model depends on: every field but ``dynamic.*`` (the run, not the model)
    except the mean load the damping ratios are converted at, the springs given and whether the
    ratios are converted. Points of a study that differ only in speed share it. Without
    ``flanks``, the gears' ``modification`` and ``errors`` are left out too (`flankless_model`)."""
    data = dataclasses.asdict(scene)
    data.pop("dynamic", None)
    if not flanks:
        for g in ("gear1", "gear2"):
            data[g].pop("modification", None)
            data[g].pop("errors", None)
    data["mean_load"] = mean_load(scene)
    data["convert_damping"] = convert_damping
    if springs is not None:
        data["springs"] = [[np.asarray(a, float).tolist() for a in pair] for pair in springs]
    return digest(data)


def kept_scene_model(scene: Scene, springs=None) -> Model:
    """`build_scene_model`, kept: the last `MODEL_SLOTS` models by `model_key`, so that a study
    point that differs from an earlier one of the process only in ``dynamic.*`` builds nothing,
    its damping conversion (dozens of modal analyses) included. For callers that never change
    a model in place (the solver does not; the sweep's tasks do not): the object is shared."""
    return scene_model(scene, springs, gear_setups(scene), keep=True)[0]


def build_scene_model(scene: Scene, springs=None, convert_damping: bool = True) -> Model:
    """The solver model of a scene (SI). ``springs`` = ((k1, r1), (k2, r2)) skips the FE of
    the tooth springs (a coupled model still takes its body springs from the FE).
    ``convert_damping=False`` leaves the dampers given as ratios at zero (`damping_from_ratios`).
    The model without the flank deviations and pitch errors is made once for the scenes that
    differ only in those (`flankless_model`); the scene's own are written into a copy."""
    setups = gear_setups(scene)
    if not convert_damping:
        return _with_flanks(scene, springs, setups)
    return scene_model(scene, springs, setups)[0]


def scene_model(scene: Scene, springs, setups: tuple, keep: bool = False) -> tuple[Model, list | None]:
    """(model, loaded equilibria under the mean load at 12 positions, or None where the damping
    conversion needed none) of a scene whose gear setups are ``setups``: the model of
    `build_scene_model`, its dampers converted from the scene's ratios at those equilibria
    (`damping_from_ratios`); a scene with flank deviations or pitch errors takes the dampers of
    its nominal flanks (`nominal_dampers`), so that a run and a study's point of the same scene
    carry the same dampers. ``keep``: a study's worker (`kept_scene_model`): the model kept,
    model and equilibria shared."""
    if keep:
        return MODELS.kept(model_key(scene, springs, True), lambda: _damped_model(scene, springs, setups))
    return _damped_model(scene, springs, setups)


def has_flanks(scene: Scene) -> bool:
    """True when a gear of the scene has a profile modification or pitch errors / runout."""
    return any(scene.modification_spec(g) is not None or scene.errors_spec(g) is not None for g in (1, 2))


def damping_conversion(scene: Scene) -> str:
    """Where the dampers the scene gives as ratios (`damping_ratios`) are converted, in words
    for a run's or a study's attributes."""
    if not damping_ratios(scene):
        return "none: every damper given as a coefficient"
    if has_flanks(scene):
        return NOMINAL_NOTE
    return "at the scene's own loaded equilibria (its flanks as given)"


def study_damping_conversion(scenes) -> str:
    """`damping_conversion` of a study's point scenes (None: an invalid point), for its archive."""
    scenes = [s for s in scenes if s is not None]
    flanked = [s for s in scenes if has_flanks(s) and damping_ratios(s)]
    return NOMINAL_NOTE if flanked else damping_conversion(scenes[0]) if scenes else ""


NOMINAL_NOTE = ("at the nominal flanks (perfect involutes, no pitch errors or runout) under the mean load, once "
                "for the scenes that differ only in their flanks: the scene's own flank deviations leave its dampers alone")
NOMINAL_SLOTS = 2
NOMINAL = STORE.shelf("nominal dampers", NOMINAL_SLOTS)


def nominal_dampers(scene: Scene, springs=None, setups: tuple | None = None, flankless: Model | None = None) -> tuple:
    """(c_phi (gear 1, gear 2) [N·m·s/rad], c_con [SI, as law_par C_CON], c_body (gear 1, gear 2)
    [N·m·s/rad]):
    the dampers the scene gives as ratios converted at its nominal flanks, the pair with
    perfect involutes and no pitch errors or runout (`flankless_model`), under its mean load.

    A study's builds that differ in their flanks (a tolerance study's drawn pitch deviations,
    runout and reliefs, a relief study's grid) share these: the ratio says how much the pair is
    damped, a ratio of critical of the nominal mesh mode, and a build's deviations change its
    mesh stiffness, not what dissipates energy in it (the materials, the lubricant, the
    joints). Converting at each build's own equilibria would retune its dampers to its
    deviations (by a few per cent), and would cost each build the modal searches over its 12
    equilibria (about a tenth of a tolerance build with 0.2 s of dynamics, benchmarks/README.md).
    Kept for the last `NOMINAL_SLOTS`
    models by `model_key` without the flanks and the FE cache read. ``flankless``: the
    scene's `flankless_model` when the caller has it."""
    key = digest(model_key(scene, springs, True, flanks=False), str(FE_CACHE.folder))

    def convert():
        m, _ = converted_damping(scene, flankless or flankless_model(scene, springs, setups or gear_setups(scene)))
        return (tuple(float(c) for c in m.gear_par[:, L.C_PHI]), float(m.law_par[L.C_CON]),
                tuple(float(c) for c in m.gear_par[:, L.C_BODY]))
    return NOMINAL.kept(key, convert)


def _damped_model(scene: Scene, springs, setups: tuple) -> tuple[Model, list | None]:
    """A scene's (model, equilibria) (`scene_model`): a scene with flanks and
    damping ratios takes `nominal_dampers`; its own loaded equilibria are still solved (the
    load check and the explicit step bound read them)."""
    flankless = flankless_model(scene, springs, setups)
    model = with_flank_deviations(flankless, *_flanks(scene))
    if not damping_ratios(scene) or not has_flanks(scene):
        return converted_damping(scene, model)
    from solver.mbs.modes import with_damping
    from study.plausibility import carrying_equilibria
    c_phi, c_con, c_body = nominal_dampers(scene, springs, setups, flankless)
    eqs = carrying_equilibria(scene, model, mean_load(scene))      # SceneError when the teeth cannot carry it
    return with_damping(model, c_con=c_con, c_phi=c_phi, c_body=c_body), eqs


def _with_flanks(scene: Scene, springs, setups: tuple) -> Model:
    """The scene's model, dampers as given: the kept flankless model with the scene's flank
    deviations and pitch errors written into a copy."""
    return with_flank_deviations(flankless_model(scene, springs, setups), *_flanks(scene))


def _flanks(scene: Scene) -> tuple:
    """(modification specs, errors specs) of both gears, as `with_flank_deviations` takes them."""
    return tuple(scene.modification_spec(g) for g in (1, 2)), tuple(scene.errors_spec(g) for g in (1, 2))


FLANKLESS_SLOTS = 2     # a tolerance study's builds share one; its geometry model a second
FLANKLESS = STORE.shelf("flankless models", FLANKLESS_SLOTS)


def flankless_model(scene: Scene, springs=None, setups: tuple | None = None) -> Model:
    """The scene's model with perfect involutes and no pitch errors, its dampers as given (the
    ratios not converted): what the builds of a tolerance study, which draw the reliefs, pitch
    deviations and runout, have in common (geometry, inertia, FE springs and body coupling,
    contact law). Kept for the last `FLANKLESS_SLOTS` scenes by `model_key` without the flanks
    and the FE cache it read; shared, never changed in place (`build_scene_model` hands out
    `with_flank_deviations`' copies)."""
    # the FE cache's folder: springs read from another cache are made again (as
    # `study.plan.kept_springs_and_model`; `solver.store.STORE.clear` empties this shelf too)
    key = digest(model_key(scene, springs, False, flanks=False), str(FE_CACHE.folder))
    return FLANKLESS.kept(key, lambda: _build_flankless(scene, springs, setups or gear_setups(scene)))


def _build_flankless(scene: Scene, springs, setups: tuple, fit_of=None) -> Model:
    """The flankless model (`flankless_model`) built; ``fit_of``: a function of a gear setup
    giving its foundation coupling in place of `coupling_fit` (`study.stand_in`: no FE)."""
    springs = springs or scene_springs(scene, setups)
    gears = []
    for setup, (k_phi, _) in zip(setups, springs):
        sp = setup.spring
        fit = coupling_fit(scene, setup.gear, setups=setups) if fit_of is None else fit_of(setup)
        cmat = cloc = None
        if fit is not None:
            k_body, n_k, pivot = fit.k_body, 1.0, fit.pivot_radius
            if scene.coupling_model == "compliance":
                cmat = fit.compliance
                if fit.local_compliance is not None:
                    cloc = (fit.local_u, fit.local_compliance)
        else:
            k_body, n_k, pivot = math.inf, sp.n_k, setup.pivot_radius
        gears.append(GearInput(tooth=setup.tooth, body=setup.body, pivot_radius=pivot,
                               k_phi=units.spring_stiffness_to_si(np.asarray(k_phi, float)),
                               n_k=n_k, c_phi=units.spring_damping_to_si(0.0 if math.isnan(sp.c_phi) else sp.c_phi),
                               n_c=sp.n_c, body_stiffness=k_body, tooth_compliance=cmat,
                               contact_compliance=cloc))
    c = scene.contact
    law = ContactLaw(units.contact_stiffness_to_si(c.k_con, c.m1), c.m1,
                     units.contact_damping_to_si(0.0 if math.isnan(c.c_con) else c.c_con, c.m2, c.m3), c.m2, c.m3,
                     mu=c.friction, friction_velocity=c.friction_velocity * units.MM)
    return build_model(gears[0], gears[1], law, setups[0].material)


def damping_ratios(scene: Scene) -> dict:
    """The dampers a scene gives as ratios of critical [1]: 'contact' (of the mesh mode),
    'gear1' / 'gear2' (of the tooth's own mode). A contact given by neither coefficient nor
    ratio takes MESH_DAMPING_RATIO; tooth springs given neither take TOOTH_DAMPING_RATIO when
    the contact gives c_con, else the mesh ratio sets them (`damping_from_ratios`)."""
    out = {}
    c = scene.contact
    if math.isnan(c.c_con):
        out["contact"] = MESH_DAMPING_RATIO if math.isnan(c.damping_ratio) else c.damping_ratio
    for g in (1, 2):
        sp = scene.gear(g).spring
        if not math.isnan(sp.damping_ratio):
            out[f"gear{g}"] = sp.damping_ratio
        elif math.isnan(sp.c_phi) and "contact" not in out:
            out[f"gear{g}"] = TOOTH_DAMPING_RATIO
    return out


def mean_load(scene: Scene) -> float:
    """The scene's mean load [N·m], where damping ratios are converted and modes computed: the
    dynamic run's torque (before any load change), else the quasi-static torque."""
    d = scene.dynamic
    return d.torque if d.enabled and d.torque != 0 else scene.quasi_static.torque


def damping_from_ratios(scene: Scene, model: Model) -> Model:
    """The model with the dampers the scene gives as ratios of critical converted, once, to the
    coefficients of the laws (`solver.mbs.modes`), at the static equilibria under the mean load
    at 12 positions over one mesh period (the pair linearised there: mesh stiffness = contact
    tangents in series with the tooth-spring tangents, the mass of the mesh mode from its
    mass-normalised shape):
    * tooth ratios (with a contact given by c_con): c_phi = 2 zeta_t sqrt(k_t I_P) on the
      tooth's own mode;
    * the mesh ratio: the joint dampers c_phi of both gears (the same ratio of their own modes)
      such that the mesh mode's ratio, averaged over the mesh positions, is the requested one;
      the contact law then has no damper (c_con = 0). The springs may then give no damper of
      their own. The contact damper cannot carry it: the contact is stiff in series with the
      tooth springs, so even 1 % of critical on the mesh mode needs c_con some 200 000 times
      the old 3640 N·s/mm^2.5, which overdamps the tooth-on-contact modes near 200 kHz, cuts
      the explicit step twenty-fold and still lets a run from rest grow energy (Table 1);
      5 % is beyond what it can give at all (at most about 2.6 % with 2 % tooth dampers).
      A body-coupled pair whose joint dampers alone cannot reach the ratio (a very stiff joint
      locks; about 4.7 % at most on a small 24-tooth pair with a thin web) scales its body
      dampers with them, all at one ratio of their own modes."""
    return converted_damping(scene, model)[0]


def converted_damping(scene: Scene, model: Model) -> tuple[Model, list | None]:
    """(`damping_from_ratios`' model, the loaded equilibria under the mean load it was converted
    at, or None when the scene gives no ratio)."""
    ratios = damping_ratios(scene)
    if not ratios:
        return model, None
    from study.plausibility import carrying_equilibria
    eqs = carrying_equilibria(scene, model, mean_load(scene))      # SceneError when the teeth cannot carry it
    return _converted(model, eqs, ratios), eqs


def _converted(model: Model, eqs: list, ratios: dict) -> Model:
    """The model with the dampers of ``ratios`` (`damping_ratios`) converted at ``eqs``."""
    from solver.mbs.modes import (
        joint_and_body_damping_for_ratio,
        joint_damping_for_ratio,
        tooth_damping_for_ratio,
        with_damping,
    )
    c_phi = tuple(tooth_damping_for_ratio(model, eqs, ratios[f"gear{g}"], g) if f"gear{g}" in ratios
                  else float(model.gear_par[g - 1, L.C_PHI]) for g in (1, 2))
    model = with_damping(model, c_phi=c_phi)
    if "contact" not in ratios:
        return model
    # check_scene has made sure the springs give no damper of their own, with n_c = 1
    try:
        return with_damping(model, c_con=0.0, c_phi=joint_damping_for_ratio(model, eqs, ratios["contact"]))
    except SceneError:
        raise
    except ValueError as e:
        if not model.coupled:
            raise SceneError("contact.damping_ratio", str(e)) from None
    try:   # a coupled pair whose joints alone cannot: the body dampers take part too
        c_phi, c_body = joint_and_body_damping_for_ratio(model, eqs, ratios["contact"])
    except ValueError as e:
        raise SceneError("contact.damping_ratio", str(e)) from None
    return with_damping(model, c_con=0.0, c_phi=c_phi, c_body=c_body)


def geometry_model(scene: Scene, setups: tuple | None = None) -> Model:
    """The pair's geometry, inertia and contact law without any FE: plain uniform springs of
    the scene's k_phi, no foundation coupling and the dampers given as ratios left at zero. For what needs the kinematics and the
    contact law only (the mesh positions, the FE reference), not the tooth springs. ``setups``:
    the scene's gear setups when already made (they do not depend on the coupling model)."""
    # the tip edges, refused by the plain model's contact law (`study.scene_checks.check_tip_edges`),
    # come with the scene's own flanks: its model carries them (the LTCA and the CalculiX peer
    # read them there), its plain contact law leaves them out (`layout.contact_parts`)
    plain = scene.replace(**{"coupling.model": "none", "gear1.modification.tip_edge_radius": 0.0,
                             "gear2.modification.tip_edge_radius": 0.0})
    z1, z2 = scene.gear1.teeth, scene.gear2.teeth
    springs = ((np.full(z1, scene.gear1.spring.k_phi), np.ones(z1)), (np.full(z2, scene.gear2.spring.k_phi), np.ones(z2)))
    return with_flank_deviations(flankless_model(plain, springs, setups or gear_setups(plain)), *_flanks(scene))


def static_angle_count(scene: Scene, step_deg: float | None = None) -> float:
    """Driver angles of the quasi-static analysis (`static_angles`) at quasi_static.angle_step
    or ``step_deg`` [deg], counted without building them."""
    step = scene.quasi_static.angle_step if step_deg is None else step_deg
    return math.floor(static_rotation(scene) / step + 1e-9) + 1.0


# bytes a driver angle holds in a static analysis: the kernel's results (S_* columns and the
# force on each gear-1 tooth), the result's and the archive's copies; the FE reference holds
# about four times that (contacts and load sharing per angle)
STATIC_BYTES_PER_ANGLE_TOOTH = 3 * 8.0
STATIC_BYTES_PER_ANGLE = 3 * 8.0 * (L.N_S_OUT + 8)


def check_static_memory(scene: Scene, step_deg: float | None = None, factor: float = 1.0,
                        field: str = "quasi_static.angle_step") -> float:
    """Refuse, before the angles are built, a static analysis whose arrays do not fit in memory
    (`study.errors.BudgetError` naming ``field``, the lever); returns the number of angles."""
    n = static_angle_count(scene, step_deg)
    need = factor * n * (STATIC_BYTES_PER_ANGLE + STATIC_BYTES_PER_ANGLE_TOOTH * scene.gear1.teeth)
    have = available_memory()
    if need > 0.8 * have:
        step = scene.quasi_static.angle_step if step_deg is None else step_deg
        raise BudgetError(field, f"the static analysis needs about {bytes_text(need)} for its {n:.3g} driver angles "
                                 f"({static_rotation(scene):.4g} deg at {step:.3g} deg), more than the "
                                 f"{bytes_text(have)} of memory available; raise the angle step or shorten "
                                 "quasi_static.rotation")
    return n


def static_angles(scene: Scene, step_deg: float | None = None, memory_factor: float = 1.0) -> np.ndarray:
    """Driver angles [rad] of the quasi-static analysis: `static_rotation` (whole periods of the
    pitch errors and eccentricities) at quasi_static.angle_step, or at ``step_deg`` [deg] (the
    ``--step`` of a command). `study.errors.BudgetError` before they are built when
    ``memory_factor`` times a static analysis's arrays would not fit in memory (the FE
    reference holds about `study.verify.fe_reference.REFERENCE_MEMORY_FACTOR` times that)."""
    step = scene.quasi_static.angle_step if step_deg is None else step_deg
    if not (math.isfinite(step) and step > 0):
        raise SceneError("--step", f"the driver angle step must be a positive number of degrees, got {step}")
    field = "quasi_static.angle_step" if step_deg is None else "--step"
    check_two_angles(scene, step, field)
    n = int(check_static_memory(scene, step, factor=memory_factor, field=field))
    return np.radians(np.arange(n) * step)


def dynamic_choice(scene: Scene, model: Model, equilibria=None, equilibria_load: float | None = None):
    """Integrator and step of the scene's dynamic run (`solver.mbs.method.choose_method`).
    ``equilibria``: the model's loaded equilibria under ``equilibria_load`` [N·m] when already
    solved (the step bound linearises there when that is the run's step torque)."""
    from solver.mbs.dynamics import run_loads  # the integrators load numba: not for `lightgear --help`
    from solver.mbs.method import choose_method
    d = scene.dynamic
    step_torque = run_loads(load_table(scene), d.torque)[1]
    eqs = equilibria if equilibria is not None and step_torque == equilibria_load else None
    return choose_method(model, step_torque, d.duration, d.method, d.time_step or None, d.alpha, equilibria=eqs)


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

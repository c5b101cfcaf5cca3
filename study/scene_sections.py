"""The sections of a scene (`study.scene.Scene`): each field's default (the paper's example,
Table 1, with solid bodies), unit (mm, deg, N·m, rad/s, s, MPa, kg/m³), description and range,
declared once (`study.scene.field_unit`, `field_doc`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from solver.materials import DEFAULT_MATERIAL, MATERIALS
from study.damping import MESH_DAMPING_RATIO, NOT_GIVEN, TOOTH_DAMPING_RATIO
from study.modification import ModificationSection
from study.pitch_errors import ErrorsSection


def declare(default, unit: str, doc: str, lo=None, hi=None, **bounds):
    """A scene field: its ``default``, ``unit``, description ``doc`` and range [``lo``, ``hi``]
    (None: open); ``bounds``: ``lo_open``/``hi_open`` (the bound itself excluded), ``choices``
    (the values allowed), ``optional`` (may be left out: NaN in a saved scene)."""
    unknown = set(bounds) - {"lo_open", "hi_open", "choices", "optional"}
    if unknown:
        raise TypeError(f"declare: unknown bounds {sorted(unknown)}")
    return field(default=default, metadata=dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=bounds.get("lo_open", False),
                                                choices=bounds.get("choices"), optional=bounds.get("optional", False),
                                                hi_open=bounds.get("hi_open", False)))


_f = declare     # (short: the declarations below are many)


@dataclass(frozen=True)
class MaterialSection:
    youngs_modulus: float = _f(206000.0, "MPa", "Young's modulus", 0, lo_open=True)
    poisson_ratio: float = _f(0.3, "1", "Poisson's ratio", 0.0, 0.499)
    density: float = _f(7850.0, "kg/m^3", "density", 0, lo_open=True)


@dataclass(frozen=True)
class PairSection:
    backlash: float = _f(0.07, "mm", "circumferential backlash on the pitch circle, made by thinning both gears' teeth equally", 0.0)


@dataclass(frozen=True)
class BodySection:
    rim_height: float = _f(6.075, "mm", "l1: rim height under the root circle", 0.0)
    web_height: float = _f(23.25, "mm", "l2: radial height of the web", 0.0)
    hub_height: float = _f(7.425, "mm", "l3: hub height above the bore", 0.0)
    web_thickness: float = _f(17.0, "mm", "t1: axial thickness of the web (= face width for a solid gear)", 0, lo_open=True)
    holes: int = _f(0, "1", "N: number of lightening holes in the web", 0)
    hole_radius: float = _f(6.0, "mm", "R_h: hole radius", 0.0)
    hole_circle_radius: float = _f(32.36, "mm", "R_ch: radius of the circle through the hole centres", 0.0)
    hole_phase: float = _f(0.0, "deg", "polar angle of the first hole centre from tooth 0's axis", -360.0, 360.0)
    opening: str = _f("round", "", "shape of the openings: 'round' holes of hole_radius, 'slot' arc (kidney) slots "
                      "of slot_width over slot_angle, 'window' windows between spokes of spoke_width over window_height "
                      "with corner_radius; holes counts them, hole_circle_radius and hole_phase place their centres",
                      choices=("round", "slot", "window"))
    slot_width: float = _f(8.0, "mm", "radial width of an arc slot (its two ends are half circles of this diameter)",
                           0, lo_open=True)
    slot_angle: float = _f(30.0, "deg", "angular span of an arc slot between the centres of its two end arcs "
                           "(0: a round hole of diameter slot_width)", 0.0, 360.0, hi_open=True)
    spoke_width: float = _f(8.0, "mm", "width of the straight spokes between the windows", 0, lo_open=True)
    window_height: float = _f(12.0, "mm", "radial height of a window: outer minus inner radius, centred on "
                              "hole_circle_radius", 0, lo_open=True)
    corner_radius: float = _f(2.0, "mm", "fillet radius of a window's four corners (0: sharp)", 0.0)


OPENING_WORDS = {"round": "holes", "slot": "slots", "window": "windows"}


def opening_text(b: BodySection) -> str:
    """A body section's openings in words [mm, deg]: '6 holes of R_h 6 mm', '6 slots 8 mm wide
    over 30 deg', '5 windows 12 mm high between spokes of 8 mm, corners R 2 mm'; 'no holes'."""
    if not b.holes:
        return "no holes"
    if b.opening == "slot":
        return f"{b.holes} slots {b.slot_width:g} mm wide over {b.slot_angle:g} deg on R {b.hole_circle_radius:g} mm"
    if b.opening == "window":
        return (f"{b.holes} windows {b.window_height:g} mm high between spokes of {b.spoke_width:g} mm, "
                f"corners R {b.corner_radius:g} mm")
    return f"{b.holes} holes of R_h {b.hole_radius:g} mm"


@dataclass(frozen=True)
class SpringSection:
    """Torsion spring of each tooth about its pivot (eq. 1.2): T = k_phi phi^n_k + c_phi dphi^n_c."""
    k_phi: float = _f(1.06e6, "N*mm/rad^n_k", "torsion spring stiffness of a tooth of the solid gear (eq. 1.2)", 0, lo_open=True)
    n_k: float = _f(1.1, "1", "stiffness exponent (>= 1: a finite tangent at zero deflection)", 1.0, 3.0)
    # Damping: with a contact given by c_con, give c_phi (a coefficient) or damping_ratio (of
    # the tooth's own mode), not both; neither: damping_ratio = TOOTH_DAMPING_RATIO. With a mesh
    # damping ratio (contact.damping_ratio, the default) the ratio sets c_phi: give neither. For Table 1, 2 % of critical on the tooth
    # mode (66 kHz, I_pivot 3.7e-9 kg·m², tangent 640 N·m/rad at 50 N·m) is
    # c = 2*0.02*sqrt(640*3.7e-9) = 6.2e-5 N·m·s/rad = 0.062 N·mm·s/rad.
    c_phi: float = _f(NOT_GIVEN, "N*mm*s/rad^n_c", "torsion spring damping coefficient (or damping_ratio)", 0.0, optional=True)
    damping_ratio: float = _f(NOT_GIVEN, "1", "tooth damper as a ratio of critical damping of the tooth's own mode "
                              "(the tooth on its spring's tangent at the mean load, about its pivot), converted to c_phi "
                              "once per run; needs n_c = 1 and a contact given by c_con (or c_phi; neither: "
                              f"{TOOTH_DAMPING_RATIO} with c_con, else set by contact.damping_ratio)", 0.0, 0.5, optional=True)
    n_c: float = _f(1.0, "1", "damping exponent", 0.5, 2.0)
    EXCLUSIVE = ("c_phi", "damping_ratio", None, "n_c")   # coefficient, ratio, default ratio (None: see damping_ratios), exponent = 1
    stiffness: str = _f("fe-ratio", "", "per-tooth springs of a lightened body: 'fe-ratio' scales k_phi by the FE stiffness ratio to the solid body, 'fe' uses FE values directly, 'uniform' ignores the lightening",
                        choices=("fe-ratio", "fe", "uniform"))


@dataclass(frozen=True)
class GearSection:
    module: float = _f(1.5, "mm", "module", 0, 100.0, lo_open=True)
    teeth: int = _f(67, "1", "number of teeth", 6)
    pressure_angle: float = _f(20.0, "deg", "pressure angle", 10.0, 35.0)
    addendum: float = _f(1.0, "1", "addendum coefficient", 0, lo_open=True)
    dedendum: float = _f(1.25, "1", "dedendum coefficient", 0, lo_open=True)
    fillet_radius: float = _f(0.45, "mm", "root fillet radius", 0.0)
    face_width: float = _f(17.0, "mm", "face width t2", 0, lo_open=True)
    pivot_radius: float = _f(0.0, "mm", "radius of the tooth pivot on the tooth axis; 0 = root circle", 0.0)
    # the bending rating's steel (solver.materials); the elastic constants stay those of [material]
    material: str = _f(DEFAULT_MATERIAL, "", "gear steel of the bending rating: its sigma_Flim (ISO 6336-5, grade MQ) "
                       "sets the safety factors S_F; one of " + ", ".join(f"{k} ({m.treatment}, sigma_Flim "
                       f"{m.sigma_f_lim / 1e6:g} MPa)" for k, m in MATERIALS.items()), choices=tuple(MATERIALS))
    body: BodySection = field(default_factory=BodySection)
    spring: SpringSection = field(default_factory=SpringSection)
    modification: ModificationSection = field(default_factory=ModificationSection)
    errors: ErrorsSection = field(default_factory=ErrorsSection)


@dataclass(frozen=True)
class ContactSection:
    """Penalty contact between the flanks (eq. 1.3), for a penetration delta > 0:
    F = k_con delta^m1 + c_con ddelta^m2 delta^m3."""
    k_con: float = _f(5.64e6, "N/mm^m1", "contact stiffness (eq. 1.3; paper: fit of Weber's deflection)", 0, lo_open=True)
    m1: float = _f(1.24, "1", "stiffness exponent (>= 1)", 1.0, 3.0)
    # Damping: give c_con (a coefficient) or damping_ratio (of the mesh mode), not both;
    # neither: damping_ratio = MESH_DAMPING_RATIO. The coefficient the scenes used before,
    # c_con = 3640 (5 % of a local contact mode at 1 um), damps the Table 1 mesh mode at 0.003 %
    # (with c_phi = 0.062 at 0.14 %). A ratio is carried by the tooth-root joint dampers, the
    # contact law then has none (why: study/scene_model.py, damping_from_ratios).
    c_con: float = _f(NOT_GIVEN, "N*s/mm^(1+m3)", "contact damping coefficient (or damping_ratio)", 0.0, optional=True)
    damping_ratio: float = _f(NOT_GIVEN, "1", "mesh damping as a ratio of critical damping of the mesh mode (the "
                              "pair linearised at the mean load, mean over one mesh period), converted once per run to "
                              "the tooth-root joint dampers c_phi of both gears (at the nominal flanks for a scene "
                              "with flank deviations, once a study; the springs then give no damper; "
                              f"c_con = 0); or c_con; neither: {MESH_DAMPING_RATIO}",
                              0.0, 0.5, optional=True)
    EXCLUSIVE = ("c_con", "damping_ratio", MESH_DAMPING_RATIO, None)    # m2 = 1 checked where c_con carries it
    m2: float = _f(1.0, "1", "damping (velocity) exponent", 0.5, 2.0)
    m3: float = _f(1.5, "1", "indentation exponent of the damping term", 0.0, 3.0)
    # Sliding friction on the flanks: mu_eff = friction*tanh(v_s/friction_velocity), v_s the
    # sliding speed of the flanks at the contact point (it reverses at the pitch point). The
    # default 10 mm/s spreads the reversal over 0.05 mm of the 8 mm path of contact of the
    # paper's pair at 100 rad/s (v_s = (w1 + w2)*s: 200 rad/s x 0.05 mm). Statics take the
    # kinematic sliding speed at quasi_static.speed (study/run.py, run_static): at its 1 rad/s
    # the reversal spreads over 5 mm, most of the path; give the running speed there.
    friction: float = _f(0.0, "1", "Coulomb coefficient of sliding friction on the flanks (0 = frictionless, the paper)",
                         0.0, 0.5, hi_open=True)
    friction_velocity: float = _f(10.0, "mm/s", "sliding speed over which the friction force reverses (regularisation: "
                                  "mu*tanh(v_s/friction_velocity))", 0.0, lo_open=True)


@dataclass(frozen=True)
class QuasiStaticSection:
    enabled: bool = _f(True, "", "compute the static transmission error")
    method: str = _f("static", "", "'static': equilibrium at each angle; 'transient': the paper's slow ramp", choices=("static", "transient"))
    torque: float = _f(50.0, "N*m", "resisting torque on gear 2")
    rotation: float = _f(120.0, "deg", "driver rotation covered", 0, lo_open=True)
    angle_step: float = _f(0.1, "deg", "driver angle resolution", 0, lo_open=True)
    speed: float = _f(1.0, "rad/s", "driver speed of the slow-ramp transient; with flank friction, also the speed whose "
                      "rolling kinematics set the equilibria's sliding speed", 0, lo_open=True)
    ramp_time: float = _f(1e-3, "s", "speed and torque ramp time of the slow-ramp transient", 0, lo_open=True)


@dataclass(frozen=True)
class DynamicSection:
    enabled: bool = _f(True, "", "compute the dynamic transmission error")
    method: str = _f("explicit", "", "time integrator: 'explicit' (velocity Verlet), 'implicit' (HHT-alpha), 'auto' (explicit when its stability step is affordable for the duration, implicit otherwise)", choices=("explicit", "implicit", "auto"))
    alpha: float = _f(0.0, "1", "HHT-alpha numerical damping of the implicit integrator: 0 = none (trapezoidal rule), down to -1/3", -1.0 / 3.0, 0.0)
    speed: float = _f(100.0, "rad/s", "final driver speed (the driver turns forward; a reversed load is a negative torque)", 0.0)
    speed_end: float = _f(0.0, "rad/s", "run-up: the driver speed rises linearly from 0 to speed_end over the whole run "
                          "(dynamic.speed is then not used; the torque still ramps over ramp_time) and the archive "
                          "gets the computed order tracking (order_amplitude); 0 = a run at dynamic.speed", 0.0)
    torque: float = _f(50.0, "N*m", "final resisting torque on gear 2")
    ramp_time: float = _f(0.01, "s", "speed and torque ramp time", 0, lo_open=True)
    torque_change_time: float = _f(0.0, "s", "time at which the resisting torque starts to move, linearly, from dynamic.torque to dynamic.torque_after (a load step or a reversal during the run); 0 = never", 0.0)
    torque_change_duration: float = _f(1e-3, "s", "duration of that change", 0, lo_open=True)
    torque_after: float = _f(0.0, "N*m", "resisting torque on gear 2 after the change")
    duration: float = _f(0.2, "s", "simulated time", 0, lo_open=True)
    time_step: float = _f(0.0, "s", "integration step; 0 = from the scene's highest natural frequency", 0.0)
    output_step: float = _f(1e-5, "s", "sampling interval of the stored DTE", 0, lo_open=True)
    spectrum_start: float = _f(0.0, "s", "start of the steady part used for spectra; 0 = twice the ramp time", 0.0)


@dataclass(frozen=True)
class FESection:
    mesh_size: float = _f(0.0, "mm", "target element size in the body; 0 = default from the module", 0.0)
    mesh_grading: str = _f("graded", "", "how the elements grow away from the gear outline: 'graded' (the outline size "
                           "along the outline, the fillets at half of it, coarser at once deeper in the teeth and rim: every tooth's "
                           "stiffness within 0.5 % of 'fine' for a quarter of the cost) or 'fine' (the outline size through 1.5 "
                           "modules into the body: the reference)", choices=("graded", "fine"))


@dataclass(frozen=True)
class CouplingSection:
    model: str = _f("auto", "", "foundation coupling between the teeth: 'auto' (the default: 'compliance', the model "
                    "that agrees with the FE reference, for solid and lightened bodies alike; 'paper' only when both "
                    "gears' spring.stiffness is 'uniform', springs that ignore the body and ask for no FE), 'paper' (the "
                    "paper's MUBOCO-PR: per-tooth springs that each hold the body's wind-up; 'none' is "
                    "the same; the only model of dynamic.method 'implicit'), 'body-torsion' (hub -> body torsion spring -> rigid rim -> tooth springs, all linear and "
                    "identified from the FE body, tooth pivot included; the gears' pivot_radius, k_phi and n_k are then not "
                    "used) or 'compliance' (the same, with the tooth springs coupled through the FE compliance between the "
                    "teeth: neighbours and hole positions; the model that agrees with the FE reference, see docs/models.md)",
                    choices=("auto", "paper", "none", "body-torsion", "compliance"))

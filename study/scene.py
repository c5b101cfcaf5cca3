"""Scenes: TOML files in engineering units, validated into typed, frozen objects.

A scene file has the sections of `Scene` (``material``, ``pair``, ``gear1`` and ``gear2`` with
``body`` and ``spring`` subtables, ``contact``, ``quasi_static``, ``dynamic``, ``fe``,
``coupling``). Every key is optional; a missing key takes the default declared below (the
paper's example, Table 1, with solid bodies; ``study/scenes/paper.toml``, the embedded
default scene, lightens the driven gear). Each field declares its unit (mm, deg, N·m, rad/s,
s, MPa, kg/m³), description and range once (`field_unit`, `field_doc`). The conversion to
the solver's SI happens in `Scene.tooth_spec`, `geometry`, `body_spec`, `material_spec` and `pivot_radius`.

Errors: `SceneError` names the dotted field and the reason, before any work starts.
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
import functools
import math
import tomllib
import typing
from dataclasses import dataclass, field, fields
from pathlib import Path

from solver import units
from solver.geometry import (
    BodySpec,
    GearGeometry,
    GeometryError,
    Material,
    ToothSpec,
    gear_geometry,
    pair_geometry,
    validate_body,
)
from solver.materials import DEFAULT_MATERIAL, MATERIALS
from study.damping import MESH_DAMPING_RATIO, NOT_GIVEN, TOOTH_DAMPING_RATIO, check_damping, damping_partner, resolve_exclusive
from study.errors import SceneError
from study.modification import ModificationSection, modification_spec
from study.pitch_errors import ErrorsSection, errors_spec
from study.toml_writer import dumps_toml


def _f(default, unit: str, doc: str, lo=None, hi=None, lo_open=False, choices=None, optional=False, hi_open=False):
    return field(default=default, metadata=dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=lo_open, choices=choices,
                                                optional=optional, hi_open=hi_open))


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
                              "the tooth-root joint dampers c_phi of both gears (the springs then give no damper; "
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


@dataclass(frozen=True)
class Scene:
    title: str = _f("", "", "free text")
    material: MaterialSection = field(default_factory=MaterialSection)
    pair: PairSection = field(default_factory=PairSection)
    gear1: GearSection = field(default_factory=GearSection)
    gear2: GearSection = field(default_factory=GearSection)
    contact: ContactSection = field(default_factory=ContactSection)
    quasi_static: QuasiStaticSection = field(default_factory=QuasiStaticSection)
    dynamic: DynamicSection = field(default_factory=DynamicSection)
    fe: FESection = field(default_factory=FESection)
    coupling: CouplingSection = field(default_factory=CouplingSection)

    # ---- conversion to the solver (the one place where units change) ----
    def tooth_spec(self, g: int) -> ToothSpec:
        gs = self.gear(g)
        return ToothSpec(module=gs.module * units.MM, teeth=gs.teeth,
                         pressure_angle=gs.pressure_angle * units.DEG,
                         addendum_coef=gs.addendum, dedendum_coef=gs.dedendum,
                         fillet_radius=gs.fillet_radius * units.MM,
                         face_width=gs.face_width * units.MM,
                         thinning=0.5 * self.pair.backlash * units.MM)

    def geometry(self, g: int) -> GearGeometry:
        """Gear g's derived geometry (radii, flanks, fillet; SI) from `tooth_spec`; GeometryError
        naming the gear's field when the teeth cannot be made."""
        return gear_geometry(self.tooth_spec(g), prefix=f"gear{g}")

    def body_spec(self, g: int) -> BodySpec:
        b = self.gear(g).body
        return BodySpec(rim_height=b.rim_height * units.MM, web_height=b.web_height * units.MM,
                        hub_height=b.hub_height * units.MM, web_thickness=b.web_thickness * units.MM,
                        holes=b.holes, hole_radius=b.hole_radius * units.MM,
                        hole_circle_radius=b.hole_circle_radius * units.MM,
                        hole_phase=b.hole_phase * units.DEG, opening=b.opening,
                        slot_width=b.slot_width * units.MM, slot_angle=b.slot_angle * units.DEG,
                        spoke_width=b.spoke_width * units.MM, corner_radius=b.corner_radius * units.MM,
                        window_height=b.window_height * units.MM)

    def material_spec(self) -> Material:
        m = self.material
        return Material(m.youngs_modulus * units.MPA, m.poisson_ratio, m.density)

    def gear(self, g: int) -> GearSection:
        if g not in (1, 2):
            raise ValueError("gear index is 1 or 2")
        return self.gear1 if g == 1 else self.gear2

    @property
    def coupling_model(self) -> str:
        """The coupling model the scene runs: 'none' (the paper's plain model, also named
        'paper'), 'body-torsion' or 'compliance'. 'auto' resolves to 'compliance' (the model that
        agrees with the FE reference, for a solid pair as for a lightened one: the plain model's
        springs hold the body's wind-up in every tooth and miss half the STE ripple of a solid
        pair) unless both gears' spring.stiffness is 'uniform': springs that ignore the body
        ask for no FE, and only the plain model reads them (k_phi, n_k)."""
        m = self.coupling.model
        if m == "auto":
            uniform = all(self.gear(g).spring.stiffness == "uniform" for g in (1, 2))
            return "none" if uniform else "compliance"
        return "none" if m == "paper" else m

    @property
    def coupling_model_name(self) -> str:
        """`coupling_model` as a user reads it: 'paper' for the plain MUBOCO-PR model."""
        m = self.coupling_model
        return "paper" if m == "none" else m

    def model_sections(self) -> tuple:
        """Every section of the scene but ``dynamic``: what its model depends on (the points of a
        study that differ only in their dynamic run share one model)."""
        return tuple(getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "dynamic")

    def is_lightened(self, g: int) -> bool:
        """True when gear g's body differs from a solid disc (holes or a thinner web)."""
        gs = self.gear(g)
        return gs.body.holes > 0 or (gs.body.web_height > 0 and gs.body.web_thickness < gs.face_width)

    def solid(self, gears=(1, 2)) -> "Scene":
        """The same scene with solid bodies for ``gears``: the web as thick as the face, no holes
        (the scene-level twin of `solver.geometry.solid_body`, which a `GearSetup` uses)."""
        return self.replace(**{k: v for g in gears for k, v in ((f"gear{g}.body.holes", 0),
                                                                (f"gear{g}.body.web_thickness", self.gear(g).face_width))})

    def modification_spec(self, g: int):
        """Gear g's profile modification in SI (`solver.modification`), None for perfect involutes."""
        return modification_spec(self.gear(g).modification, self.geometry(g), f"gear{g}.modification")

    def errors_spec(self, g: int):
        """Gear g's pitch deviations and eccentricity in SI (`solver.pitch_errors`), None for a perfect gear."""
        return errors_spec(self.gear(g).errors, self.geometry(g), f"gear{g}.errors")

    @property
    def has_errors(self) -> bool:
        """True when either gear has pitch deviations or an eccentricity."""
        return not (self.gear1.errors.is_zero and self.gear2.errors.is_zero)

    def pivot_radius(self, g: int) -> float:
        """Tooth pivot radius [m]; the root circle when the scene gives 0."""
        r = self.gear(g).pivot_radius
        return r * units.MM if r > 0 else self.geometry(g).root_radius

    # ---- text ----
    def to_toml(self) -> str:
        return dumps_toml(dataclasses.asdict(self))

    def replace(self, **dotted) -> "Scene":
        """A copy with fields overridden by dotted path, validated: ``replace(**{"gear2.body.holes": 3})``."""
        data = dataclasses.asdict(self)
        for path, value in dotted.items():
            set_dotted(data, path, value)
        return scene_from_dict(data)


# ---------------------------------------------------------------- building and checking

# the integers a scene field or a study's seed may hold: those a NetCDF archive stores (int64)
INT_MIN, INT_MAX = -2 ** 63, 2 ** 63 - 1


def _coerce(value, typ, path):
    """``value`` as ``typ`` (bool, int, float or str), else SceneError; a bool is no number.
    NumPy scalars and arrays count as the Python numbers and lists they hold."""
    value = _python_value(value)
    if typ == tuple[float, ...]:    # a list of numbers (a table's column)
        if not isinstance(value, list | tuple):
            raise SceneError(path, f"must be a list of numbers, got {value!r}")
        return tuple(_coerce(x, float, path) for x in value)
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if (typ is bool and isinstance(value, bool)) or (typ is str and isinstance(value, str)):
        return value
    if typ is int and number and (isinstance(value, int) or (math.isfinite(value) and value.is_integer())):
        # (a Python int as it is: 2^53 + 1 has no float of its own)
        if not INT_MIN <= int(value) <= INT_MAX:
            raise SceneError(path, f"must fit in 64 bits (the archive's integers), from {INT_MIN} to {INT_MAX}, "
                                   f"got {int(value)}")
        return int(value)
    if typ is float and number and math.isfinite(value):
        return float(value)
    what = "finite" if typ is float and number else {bool: "true or false", int: "an integer",
                                                     float: "a number", str: "a string"}[typ]
    raise SceneError(path, f"must be {what}, got {value!r}")


def _python_value(value):
    """A NumPy scalar or array as the Python number, bool or list it holds; anything else as is."""
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        return value.tolist()
    return value


# the section classes never change: resolve their annotations once (a sampled study builds
# thousands of scenes, and resolving them took two thirds of each build)
_type_hints = functools.cache(typing.get_type_hints)


def _build(cls, table, path: str):
    if not isinstance(table, dict):
        raise SceneError(path or "scene", f"must be a table, got {table!r}")
    hints = _type_hints(cls)
    known = {f.name: f for f in fields(cls)}
    for key in table:
        if key not in known:
            where = f"{path}.{key}" if path else key
            close = difflib.get_close_matches(str(key), list(known), n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise SceneError(where, f"unknown key (expected one of: {', '.join(known)}){hint}")
    kwargs = {}
    for name, f in known.items():
        where = f"{path}.{name}" if path else name
        typ = hints[name]
        if dataclasses.is_dataclass(typ):
            kwargs[name] = _build(typ, table.get(name, {}), where)
            continue
        if name not in table:
            continue
        md = f.metadata
        if md.get("optional") and isinstance(table[name], float) and math.isnan(table[name]):
            continue      # left out (a saved scene writes nan)
        v = _coerce(table[name], typ, where)
        unit = f" {md['unit']}" if md.get("unit") not in (None, "", "1") else ""
        if md.get("choices") and v not in md["choices"]:
            raise SceneError(where, f"must be one of {', '.join(map(repr, md['choices']))}, got {v!r}")
        lo, hi = md.get("lo"), md.get("hi")
        for x in (v if isinstance(v, tuple) else (v,)):     # (a list: each of its numbers)
            if lo is not None and (x < lo or (md.get("lo_open") and x == lo)):
                rel = ">" if md.get("lo_open") else ">="
                raise SceneError(where, f"must be {rel} {lo}{unit}, got {x}{unit}")
            if hi is not None and (x > hi or (md.get("hi_open") and x == hi)):
                rel = "<" if md.get("hi_open") else "<="
                raise SceneError(where, f"must be {rel} {hi}{unit}, got {x}{unit}")
        kwargs[name] = v
    resolve_exclusive(cls, kwargs, path)
    return cls(**kwargs)


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


# ---------------------------------------------------------------- the static analysis's angles

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


def scene_from_dict(data: dict) -> Scene:
    """A checked Scene from its tables (as parsed from TOML): field and cross-field checks."""
    scene = _build(Scene, data, "")
    check_scene(scene)
    return scene


def scene_fields_from_dict(data: dict) -> Scene:
    """Field-by-field validation only (keys, types, ranges), without the cross-field checks of
    `check_scene`: a study uses it to check each grid value alone before checking combinations."""
    return _build(Scene, data, "")


def _tables(text: str, source: str) -> dict:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(source, f"not valid TOML: {e}") from None


def read_text(path: str | Path, field: str = "scene") -> str:
    """The text of a scene or study file; SceneError naming ``field`` when it cannot be read as
    UTF-8 text (TOML files are UTF-8) or at all."""
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise SceneError(field, f"{p} is not UTF-8 text (byte {e.start}: {e.reason}); TOML files are UTF-8") from None
    except OSError as e:
        raise SceneError(field, f"cannot read {p}: {e.strerror or e}") from None


def loads_scene(text: str, source: str = "scene") -> Scene:
    """A checked Scene from TOML text; ``source`` names the text in a parse error."""
    return scene_from_dict(_tables(text, source))


SCENES_DIR = Path(__file__).parent / "scenes"


# the tables that make a TOML file a study (`study.sweep.grid`), and those only a scene has
STUDY_SECTIONS = ("grid", "points", "sample")


def is_study_table(data: dict) -> bool:
    """A TOML file's tables are a study's: a [grid], [[points]] or [sample], or a [scene] table
    of overrides (a scene has no section of that name)."""
    return any(k in data for k in STUDY_SECTIONS) or isinstance(data.get("scene"), dict)


def is_scene_table(data: dict) -> bool:
    """A TOML file's tables are a scene's: sections of a Scene and none of a study."""
    return not is_study_table(data) and any(f.name in data for f in dataclasses.fields(Scene) if f.name != "title")


def embedded_scenes() -> dict[str, tuple[Path, str, str]]:
    """The scenes and studies that ship with lightgear: name -> (file, 'scene' or 'study', title)."""
    out = {}
    for p in sorted(SCENES_DIR.glob("*.toml")):
        try:
            raw = tomllib.loads(p.read_text())
        except (OSError, tomllib.TOMLDecodeError):
            continue
        kind = "study" if is_study_table(raw) else "scene"
        out[p.stem] = (p, kind, str(raw.get("title", "")))
    return out


def scene_path(name: str | Path, what: str = "scene") -> Path:
    """The file of a scene or study given by path or by the name of an embedded one
    (``"runup"``, ``"runup.toml"``; a file that exists wins). SceneError names both ways."""
    p = Path(name)
    if p.is_file():
        return p
    stem = p.stem if p.suffix == ".toml" else p.name
    known = embedded_scenes()
    if len(p.parts) == 1 and stem in known:
        return known[stem][0]
    names = ", ".join(k for k, v in known.items() if v[1] == what) or ", ".join(known)
    close = difflib.get_close_matches(stem, list(known), n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise SceneError(what, f"no such file or embedded {what}: {name} (embedded {'studies' if what == 'study' else 'scenes'}: {names}; "
                     f"`lightgear scenes` lists them){hint}")


def load_scene(path: str | Path | None = None, overrides: typing.Iterable[str] | dict = ()) -> Scene:
    """A scene -> Scene: ``path`` a TOML file or the name of an embedded scene (``"runup"``;
    `embedded_scenes` lists them; None: the paper example), with ``overrides`` as
    ``["key=value", ...]`` or ``{"dotted.key": value}``. SceneError names the offending field."""
    from collections.abc import Mapping

    from study.errors import check_argument, is_path
    check_argument(path is None or is_path(path), "load_scene", "path",
                   "a scene file's path or an embedded scene's name (str or os.PathLike; None: the paper example); "
                   "for fields given in Python use study.default_scene().replace(**{...})", path)
    if isinstance(overrides, Mapping):
        scene = load_scene(path)
        return scene.replace(**dict(overrides)) if overrides else scene
    check_argument(not isinstance(overrides, str | bytes) and all(isinstance(o, str) for o in overrides), "load_scene",
                   "overrides", 'a list of "key=value" strings or a dict {dotted key: value}', overrides)
    text = default_scene_text() if path is None else read_text(scene_path(path))
    data = _tables(text, str(path or "scene"))
    if is_study_table(data):
        raise SceneError("scene", f"{path} is a study (its {', '.join(f'[{k}]' for k in STUDY_SECTIONS if k in data)} "
                                  "over a [scene]), not a scene: run it with `lightgear sweep` (study.load_study)")
    items = [parse_override(item) for item in overrides]
    keys = {k for k, _v in items}
    for key, _v in items:
        partner = damping_partner(key.split("."))
        if partner and key.rsplit(".", 1)[0] + "." + partner in keys:
            raise SceneError(key, f"give either {key} or {key.rsplit('.', 1)[0]}.{partner}, not both")
    base = copy.deepcopy(data) if items else None
    for key, value in items:
        set_dotted(data, key, value)
    try:
        return scene_from_dict(data)
    except SceneError as e:
        raise override_at_fault(e, base, items) from None


def override_at_fault(error: SceneError, base: dict | None, items: list) -> SceneError:
    """``error`` of a scene with overrides ``items`` [(key, value)] on ``base`` (its tables),
    naming the override at fault where the error names another field that only the override
    made invalid (``--set gear2.module=2``: the module, not the holes it made cut the hub);
    the error as it is otherwise."""
    if not items or error.field in {k for k, _v in items}:
        return error
    try:
        scene_from_dict(copy.deepcopy(base))
    except SceneError:
        return error                # the scene is invalid without the overrides too
    for key, value in items:
        alone = copy.deepcopy(base)
        set_dotted(alone, key, value)
        try:
            scene_from_dict(alone)
        except SceneError as e:
            if e.field == error.field:
                return SceneError(key, f"{value!r} makes {error.field} invalid (valid before the override): {error.reason}")
    keys = ", ".join(k for k, _v in items)
    return SceneError(error.field, f"{error.reason} (valid before the overrides of {keys})")


def default_scene_text() -> str:
    """TOML text of the embedded paper example (``study/scenes/paper.toml``)."""
    return (Path(__file__).parent / "scenes" / "paper.toml").read_text()


def default_scene() -> Scene:
    """The embedded paper example: Table 1 with the lightened driven gear."""
    return loads_scene(default_scene_text(), "paper.toml")


def parse_override(item: str):
    """``'gear2.body.holes=3'`` -> ('gear2.body.holes', 3); values parse as TOML, else as text."""
    key, sep, raw = item.partition("=")
    if not sep:
        raise SceneError(item, "an override must look like key=value")
    try:
        return key.strip(), tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        return key.strip(), raw.strip()


def parse_overrides(items) -> dict:
    """``["gear2.body.holes=3", ...]`` -> {"gear2.body.holes": 3, ...} (values parse as TOML, else
    as text), for `Scene.replace` or `study.make_study`."""
    from study.errors import check_argument
    check_argument(not isinstance(items, str | bytes), "parse_overrides", "items", 'a list of "key=value" strings', items)
    return dict(parse_override(str(item)) for item in items)


def solid_scene(scene: Scene, gears=(1, 2)) -> Scene:
    """The scene with the bodies of ``gears`` made solid (no holes, the web as thick as the face) -> Scene."""
    from study.errors import check_scene_argument
    check_scene_argument("solid_scene", scene)
    return scene.solid(gears=tuple(gears))


def set_dotted(data: dict, path: str, value) -> None:
    """Set ``value`` at a dotted path in nested tables, creating the tables on the way."""
    parts = path.split(".")
    node = data
    for i, p in enumerate(parts[:-1]):
        nxt = node.setdefault(p, {})
        if not isinstance(nxt, dict):
            raise SceneError(".".join(parts[: i + 1]), "is a value, not a table")
        node = nxt
    node[parts[-1]] = value
    partner = damping_partner(parts)
    if partner and not (isinstance(value, float) and math.isnan(value)):
        node.pop(partner, None)     # a damper set one way replaces the scene's other way


def get_dotted(scene: Scene, path: str):
    """The value (or table) of a scene at a dotted path: ``get_dotted(scene, "gear2.body.holes")``."""
    scene_field(path)  # SceneError for a path that is no field
    node = scene
    for p in path.split("."):
        node = getattr(node, p)
    return node


def scene_field(path: str) -> dataclasses.Field:
    """The declaration (default, metadata) of a scene field or table given by its dotted path."""
    cls, f = Scene, None
    parts = path.split(".")
    for i, p in enumerate(parts):
        fs = {x.name: x for x in fields(cls)} if dataclasses.is_dataclass(cls) else {}
        if p not in fs:
            where = ".".join(parts[:i])
            # the names of this level that the typed part begins (gear2.bod -> gear2.body), else
            # the closest whole path, else the name of this level closest to it
            begun = [f"{where}.{n}" if where else n for n in fs if p and n.startswith(p)][:3]
            close = begun or difflib.get_close_matches(path, field_paths(), n=1, cutoff=0.6) or \
                [f"{where}.{n}" if where else n for n in difflib.get_close_matches(p, list(fs), n=1, cutoff=0.6)]
            hint = f"; did you mean {' or '.join(map(repr, close))}?" if close else ""
            valid = f" (fields of {where}: {', '.join(fs)})" if fs and where else (
                f" (sections: {', '.join(fs)})" if fs else f" ({where} is a value, not a table)")
            raise SceneError(path, f"no such scene field{valid}{hint}{' ' if hint else '; '}"
                             "`lightgear fields` lists them all")
        f, cls = fs[p], _type_hints(cls)[p]
    return f


def field_paths(cls=None, prefix: str = "") -> list[str]:
    """Dotted paths of every value field of the scene (tables left out), in declaration order."""
    cls = Scene if cls is None else cls
    out = []
    hints = typing.get_type_hints(cls)
    for f in fields(cls):
        path = f"{prefix}.{f.name}" if prefix else f.name
        if dataclasses.is_dataclass(hints[f.name]):
            out += field_paths(hints[f.name], path)
        else:
            out.append(path)
    return out


def field_unit(path: str) -> str:
    """Unit string of a scene field given by its dotted path ('' for none and for a table)."""
    return scene_field(path).metadata.get("unit", "")


def field_doc(path: str) -> str:
    """Description of a scene field given by its dotted path (its name for a table)."""
    f = scene_field(path)
    return f.metadata.get("doc", f.name)

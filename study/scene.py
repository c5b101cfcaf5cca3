"""Scenes: TOML files in engineering units, validated into typed, frozen objects.

A scene file has the sections of `Scene` (``material``, ``pair``, ``gear1`` and ``gear2`` with
``body`` and ``spring`` subtables, ``contact``, ``quasi_static``, ``dynamic``, ``fe``,
``coupling``). Every key is optional; a missing key takes the default declared below (the
paper's example, Table 1, with solid bodies; ``study/scenes/paper.toml``, the embedded
default scene, lightens the driven gear). Each field declares its unit (mm, deg, N·m, rad/s,
s, MPa, kg/m³), description and range once (`study.scene_sections`; `field_unit`, `field_doc`). The conversion to
the solver's SI happens in `Scene.tooth_spec`, `geometry`, `body_spec`, `material_spec` and `pivot_radius`.

Errors: `SceneError` names the dotted field and the reason, before any work starts.
"""
from __future__ import annotations

import copy
import dataclasses
import difflib
import math
import tomllib
import typing
from dataclasses import dataclass, field, fields
from pathlib import Path

from solver import units
from solver.geometry import BodySpec, GearGeometry, Material, ToothSpec, gear_geometry
from study.damping import MESH_DAMPING_RATIO, TOOTH_DAMPING_RATIO, damping_partner  # noqa: F401 - the ratios: importable from here
from study.errors import SceneError
from study.modification import modification_spec
from study.pitch_errors import errors_spec
from study.scene_checks import (  # noqa: F401 - the checks across fields, importable from here
    check_integrator_model,
    check_jamming,
    check_scene,
    check_two_angles,
    error_period,
    static_rotation,
)
from study.scene_files import (  # noqa: F401 - the files, importable from here
    SCENES_DIR,
    STUDY_SECTIONS,
    default_scene_text,
    embedded_scenes,
    is_study_table,
    read_text,
    scene_path,
    toml_tables,
)
from study.scene_sections import (  # noqa: F401 - the sections, importable from here
    OPENING_WORDS,
    BodySection,
    ContactSection,
    CouplingSection,
    DynamicSection,
    FESection,
    GearSection,
    MaterialSection,
    PairSection,
    QuasiStaticSection,
    SpringSection,
    declare,
    opening_text,
)
from study.scene_tables import INT_MAX, INT_MIN, build_section, type_hints  # noqa: F401 - INT_*: importable from here
from study.toml_writer import dumps_toml


@dataclass(frozen=True)
class Scene:
    title: str = declare("", "", "free text")
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


def scene_from_dict(data: dict) -> Scene:
    """A checked Scene from its tables (as parsed from TOML): field and cross-field checks."""
    scene = build_section(Scene, data, "")
    check_scene(scene)
    return scene


def scene_fields_from_dict(data: dict) -> Scene:
    """Field-by-field validation only (keys, types, ranges), without the cross-field checks of
    `check_scene`: a study uses it to check each grid value alone before checking combinations."""
    return build_section(Scene, data, "")






def loads_scene(text: str, source: str = "scene") -> Scene:
    """A checked Scene from TOML text; ``source`` names the text in a parse error."""
    return scene_from_dict(toml_tables(text, source))








def is_scene_table(data: dict) -> bool:
    """A TOML file's tables are a scene's: sections of a Scene and none of a study."""
    return not is_study_table(data) and any(f.name in data for f in dataclasses.fields(Scene) if f.name != "title")






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
    data = toml_tables(text, str(path or "scene"))
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
        f, cls = fs[p], type_hints(cls)[p]
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

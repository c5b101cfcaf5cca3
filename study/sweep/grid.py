"""Studies: a base scene and a grid of scene fields, validated before any work starts.

A study TOML file::

    title = "holes and speed"
    scene = "my_scene.toml"          # a scene file (relative to the study file); omitted: the
                                     # embedded paper example
    # or, instead, an inline scene: overrides on top of `file` (default: the paper example)
    # [scene]
    # gear2.body.web_thickness = 10.0

    [grid]                           # full factorial over every listed field (dotted scene path)
    gear2.body.holes = [0, 3, 6]
    "dynamic.speed" = {start = 50.0, stop = 200.0, num = 4}   # linspace, both ends included

    # dimension order = key order after TOML parsing: unquoted dotted keys with a common head
    # (gear2.body.*) are grouped into one table; quote a key ("dynamic.speed") to keep it apart

    [[points]]                       # optional explicit points (then the archive has a `point`
    gear2.body.holes = 9             # dimension: the factorial points first, then these)
    dynamic.speed = 300.0

    [sample]                         # optional: draws of scene fields (`study.sweep.sample`);
    size = 256                       # with a [grid], every grid point gets the whole sample
    "gear1.errors.eccentricity" = {uniform = [0.0, 6.0]}

    [outputs]
    scalars = ["ste_p2p", "dte_rms"]            # default: all of `outputs.SCALARS`
    curves = ["ste", "dte", "dte_amplitude"]    # default: none (only scalars are archived)

`make_study` builds the same study in Python (a Scene, a grid dict, outputs) and checks it the
same way: it writes the study's TOML text and reads it back, so the archive holds a study file
that gives the same points.

Every grid value is checked alone against the scene (unknown field, wrong type, out of range:
`SceneError` naming the dotted field). A combination that is physically invalid (holes cutting
the rim at one radius only, say) is not an error of the study: that point is recorded as
invalid with its message and the sweep goes on.
"""
from __future__ import annotations

import copy
import dataclasses
import tomllib
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from study.errors import StudyError, check_argument, is_path
from study.scene import (
    Scene,
    SceneError,
    default_scene_text,
    get_dotted,
    is_scene_table,
    read_text,
    scene_fields_from_dict,
    scene_path,
    set_dotted,
)
from study.sweep.design import (  # noqa: F401 - the design, importable from here
    DIM_NAMES,
    Axis,
    Point,
    Study,
    coupling_models,
    dim_name,
)
from study.sweep.outputs import Outputs, outputs_from_table
from study.sweep.sample import flatten_sample, parse_sample
from study.toml_writer import toml_value

STUDY_KEYS = ("title", "scene", "grid", "points", "outputs", "sample")
RANGE_KEYS = ("start", "stop", "num")


# ---------------------------------------------------------------- reading and checking

def _flatten(table: dict, where: str, prefix: str = "", repeat: bool = False) -> dict:
    """Nested TOML tables -> {dotted path: leaf}; a leaf is a list, a range table or a scalar.

    A path given twice (nested and quoted) is an error, unless ``repeat`` (scene overrides:
    the later one wins).
    """
    out = {}
    for k, v in table.items():
        path = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict) and not (set(v) & set(RANGE_KEYS)):
            sub = _flatten(v, where, path, repeat)
        else:
            sub = {path: v}
        for p in sub:
            if p in out and not repeat:
                raise SceneError(p, f"given twice in [{where}]")
            out.pop(p, None)
        out.update(sub)
    return out


def _field_kind(base: dict, path: str):
    """Python type of a scene value field; SceneError when the path is unknown or a table."""
    node = get_dotted(scene_fields_from_dict(base), path)
    if dataclasses.is_dataclass(node):
        raise SceneError(path, "is a table of the scene, not a value")
    return type(node)


def _check_value(base: dict, path: str, value, where: str):
    """Field-level check of one value (type, range) with the base scene; returns it coerced."""
    if isinstance(value, (list, dict)):
        raise SceneError(path, f"{where}: a value must be a number, string or boolean, got {value!r}")
    data = copy.deepcopy(base)
    set_dotted(data, path, value)
    try:
        return get_dotted(scene_fields_from_dict(data), path)
    except SceneError as e:
        raise SceneError(e.field, f"{where} value {value!r}: {e.reason}") from None


MAX_AXIS_VALUES = 100_000     # values of one grid axis (each is checked against the scene: ~ms)


def _axis_values(base: dict, path: str, spec) -> tuple:
    kind = _field_kind(base, path)
    if isinstance(spec, dict):
        unknown = set(spec) - set(RANGE_KEYS)
        if unknown or not set(RANGE_KEYS) <= set(spec):
            raise SceneError(path, f"a range is a table {{start, stop, num}}, got keys {sorted(spec)}")
        if kind not in (int, float):
            raise SceneError(path, f"a range needs a numeric field, this one is {kind.__name__}")
        num = spec["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise SceneError(path, f"range num must be a positive integer, got {num!r}")
        if num > MAX_AXIS_VALUES:     # each value is checked against the scene: refused before
            raise SceneError(path, f"range num = {num} values on one axis, more than the {MAX_AXIS_VALUES} a study "
                                   "can check and list: sweep fewer values")
        for k in ("start", "stop"):
            if isinstance(spec[k], bool) or not isinstance(spec[k], (int, float)):
                raise SceneError(path, f"range {k} must be a number, got {spec[k]!r}")
        vals = np.linspace(spec["start"], spec["stop"], num)
        if kind is int:
            if not np.allclose(vals, np.round(vals)):
                raise SceneError(path, f"range gives non-integer values {vals.tolist()} for an integer field")
            vals = np.round(vals).astype(int)
        values = [v.item() for v in vals]
    elif isinstance(spec, list):
        values = spec
    else:
        raise SceneError(path, f"[grid] takes a list of values or a range table, got {spec!r}")
    if not values:
        raise SceneError(path, "[grid] list is empty")
    out = tuple(_check_value(base, path, v, "[grid]") for v in values)
    if len(set(out)) != len(out):
        raise SceneError(path, f"[grid] repeats a value: {list(out)}")
    return out


def _base_scene(spec, folder: Path | None) -> dict:
    def read(path) -> dict:
        p = Path(path)
        if not p.is_absolute() and folder is not None and (folder / p).is_file():
            p = folder / p
        p = scene_path(p)      # a file, or an embedded scene by name
        try:
            return tomllib.loads(read_text(p))
        except tomllib.TOMLDecodeError as e:
            raise SceneError("scene", f"{p} is not valid TOML: {e}") from None

    if spec is None:
        return tomllib.loads(default_scene_text())
    if isinstance(spec, str):
        return read(spec)
    if isinstance(spec, dict):
        spec = copy.deepcopy(spec)
        file = spec.pop("file", None)
        if file is not None and not isinstance(file, str):      # (Path() of a number: a TypeError)
            raise SceneError("scene.file", f"must be a scene file or an embedded scene's name, got {file!r}")
        data = read(file) if file is not None else tomllib.loads(default_scene_text())
        for path, v in _flatten(spec, "scene", repeat=True).items():
            set_dotted(data, path, v)
        return data
    raise SceneError("scene", f"must be a file name or a table, got {spec!r}")


def loads_study(text: str, folder: str | Path | None = None) -> Study:
    """Parse and check a study (TOML text). ``folder`` resolves a relative scene file.
    Raises `StudyError` (a SceneError) naming the study key or the dotted scene field."""
    try:
        return _loads_study(text, folder)
    except StudyError:
        raise
    except SceneError as e:
        raise StudyError(e.field, e.reason) from None


def _loads_study(text: str, folder: str | Path | None = None) -> Study:
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError("study", f"not valid TOML: {e}") from None
    if is_scene_table(raw):
        raise SceneError("study", "this file is a scene (its sections are a scene's, with no [grid], [[points]] or "
                                  "[sample]), not a study: run it with `lightgear run`, or sweep it from a study whose "
                                  "scene = names it")
    for k in raw:
        if k not in STUDY_KEYS:
            raise SceneError(k, f"unknown study key (expected one of: {', '.join(STUDY_KEYS)})")
    base = _base_scene(raw.get("scene"), Path(folder) if folder is not None else None)
    scene_fields_from_dict(base)  # field errors of the base scene itself
    grid = raw.get("grid", {})
    if not isinstance(grid, dict):
        raise SceneError("grid", f"must be a table, got {grid!r}")
    axes = tuple(Axis(path, _axis_values(base, path, spec)) for path, spec in _flatten(grid, "grid").items())
    extra = raw.get("points", [])
    if not isinstance(extra, list) or not all(isinstance(p, dict) for p in extra):
        raise SceneError("points", "must be a list of tables (dotted field = value)")
    points = []
    for i, p in enumerate(extra):
        flat = _flatten(p, f"points[{i}]")
        for path in flat:
            _field_kind(base, path)
        points.append({path: _check_value(base, path, v, f"points[{i}]") for path, v in flat.items()})
    sample = parse_sample(raw["sample"], base, tuple(a.path for a in axes)) if "sample" in raw else None
    if sample and points:
        raise SceneError("points", "a sampled study takes a [grid] (every grid point gets the whole sample), "
                                   "not [[points]]")
    if not axes and not points and not sample:
        raise SceneError("grid", "the study sweeps nothing: give a [grid] table, [[points]] or a [sample]")
    check_swept_together([[a.path for a in axes]] + [list(pt) for pt in points], outputs_from_table(raw.get("outputs", {})))
    seen = {}
    for path in dict.fromkeys([a.path for a in axes] + [q for pt in points for q in pt]):
        if dim_name(path) in seen:
            raise SceneError(path, f"its dimension name {dim_name(path)!r} clashes with {seen[dim_name(path)]}")
        seen[dim_name(path)] = path
    return Study(str(raw.get("title", "lightgear study")), text, base, axes, tuple(points),
                 outputs_from_table(raw.get("outputs", {})), sample)


# scene fields that set the axis of a curve output (its length and spacing): a curve is
# archived on one axis for the whole study, so a study cannot sweep them and ask for the curve
CURVE_AXIS_FIELDS = {
    "ste": ("quasi_static.rotation", "quasi_static.angle_step"),
    "mesh_stiffness": ("quasi_static.rotation", "quasi_static.angle_step"),
    "dte": ("dynamic.duration", "dynamic.output_step"),
    "dte_amplitude": ("dynamic.duration", "dynamic.output_step", "dynamic.ramp_time", "dynamic.spectrum_start"),
}


def check_swept_together(groups, outputs: Outputs) -> None:
    """SceneError for swept fields that cannot vary together or with the asked outputs: a
    damper given two ways in one group of fields that are set together (the grid's axes, or
    one explicit point: a point takes the one set last, the other axis would do nothing), or a
    field that sets the axis of an asked-for curve."""
    from study.damping import damping_partner
    for group in groups:
        for path in group:
            partner = damping_partner(path.split("."))
            if partner and f"{path.rsplit('.', 1)[0]}.{partner}" in group:
                other = f"{path.rsplit('.', 1)[0]}.{partner}"
                raise SceneError(path, f"the study sweeps both {path} and {other}, which exclude each other (a point "
                                       "takes the one set last, the other axis would change nothing): sweep one of them")
    paths = list(dict.fromkeys(p for group in groups for p in group))
    for name in outputs.curves:
        for path in CURVE_AXIS_FIELDS.get(name, ()):
            if path in paths:
                raise SceneError(path, f"the curve {name!r} is archived on one axis for the whole study, and "
                                       f"{path} changes that axis from point to point: ask only for scalars "
                                       "(outputs.curves = []) or run one study per value")


def load_study(path: str | Path) -> Study:
    """A study file, or an embedded study by name (``"sensitivity"``; `study.scenes` lists them):
    base scene, [grid] and/or [[points]], [sample], [outputs], read and checked -> Study
    (StudyError names the field)."""
    check_argument(is_path(path), "load_study", "path",
                   "a study file's path or an embedded study's name (str or os.PathLike)", path)
    try:
        p = scene_path(path, "study")
    except SceneError as e:
        raise StudyError(e.field, e.reason) from None
    return loads_study(read_text(p, "study"), p.parent)


def study_from_dict(raw: dict, folder: str | Path | None = None) -> Study:
    """A study from the tables of a study file as a dict (title, scene, grid, points, sample,
    outputs), checked like the file; relative scene paths are read from ``folder``."""
    check_argument(isinstance(raw, dict), "study_from_dict", "raw", "a dict of study tables", raw)
    return loads_study(dumps_study(raw), folder)


def dumps_study(raw: dict) -> str:
    """A study as TOML text from its parsed tables (dotted keys quoted, so their order stays)."""
    out = [f"{k} = {toml_value(raw[k])}" for k in ("title", "scene") if k in raw and not isinstance(raw[k], dict)]
    for table in ("scene", "grid", "outputs"):
        if isinstance(raw.get(table), dict):
            out.append(f"\n[{table}]")
            flat = _flatten(raw[table], table, repeat=table == "scene") if table != "outputs" else raw[table]
            out += [f'"{k}" = {toml_value(v)}' for k, v in flat.items()]
    if isinstance(raw.get("sample"), dict):
        out.append("\n[sample]")
        out += [f'"{k}" = {toml_value(v)}' for k, v in flatten_sample(raw["sample"]).items()]
    for p in raw.get("points", []):
        out.append("\n[[points]]")
        out += [f'"{k}" = {toml_value(v)}' for k, v in _flatten(p, "points").items()]
    return "\n".join(out) + "\n"


def check_points(study: Study) -> list[Point]:
    """The study's points; SceneError when no point is valid (nothing could be computed)."""
    points = study.points()
    if not any(p.scene is not None for p in points):
        first = points[0].error
        field, _, reason = first.partition(": ")
        raise StudyError(field, f"every point of the study is invalid, e.g. {reason}")
    return points



def _plain(value):
    """numpy arrays and scalars as Python lists and numbers (what TOML holds)."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value.tolist() if hasattr(value, "tolist") else value


def make_study(scene: Scene | Mapping | None = None, grid: Mapping | None = None, points: Iterable[Mapping] = (),
               outputs: Outputs | Mapping | Iterable[str] | None = None, title: str = "lightgear study",
               sample: Mapping | None = None) -> Study:
    """A study built in Python, checked like a study file.

    scene   the base scene: a Scene, or scene tables / dotted overrides on the embedded paper
            example (what the [scene] table of a study file holds); None: the paper example
    grid    {dotted scene field: values}, values a list or a range {"start", "stop", "num"};
            the dimensions follow the dict's order
    points  explicit points, each {dotted scene field: value}
    outputs a list of output names (scalars and curves: `study.sweep.outputs`), {"scalars": [...],
            "curves": [...]} or an `Outputs`; None: every scalar, no curve
    sample  drawn fields, what the [sample] table of a study file holds (`study.sweep.sample`):
            {"size": 256, "method": "sobol", "seed": 1, "gear1.errors.eccentricity": {"uniform": [0, 6]}}
    """
    if not (scene is None or isinstance(scene, (Scene, Mapping))):
        raise TypeError(f"make_study: scene takes a Scene (study.load_scene(...)), a dict of scene fields or None "
                        f"(the paper example), got {type(scene).__name__}")
    if not (grid is None or isinstance(grid, Mapping)):
        raise TypeError(f"make_study: grid takes a dict {{dotted scene field: list of values or "
                        f"{{'start', 'stop', 'num'}}}}, got {type(grid).__name__}")
    if not isinstance(points, (str, Mapping)):
        points = list(points)
    if isinstance(points, (str, Mapping)) or not all(isinstance(p, Mapping) for p in points):
        raise TypeError("make_study: points takes a list of dicts {dotted scene field: value}")
    if not isinstance(title, str):
        raise TypeError(f"make_study: title takes a string, got {type(title).__name__}")
    raw: dict = {"title": title}
    if scene is not None:
        raw["scene"] = dataclasses.asdict(scene) if isinstance(scene, Scene) else _plain(scene)
    raw["grid"] = _plain(grid or {})
    raw["points"] = [_plain(p) for p in points]
    if outputs is not None:
        if not isinstance(outputs, (Outputs, Mapping, list, tuple, str)):
            raise TypeError(f"make_study: outputs takes a list of output names, {{'scalars': [...], 'curves': [...]}} "
                            f"or an Outputs, got {type(outputs).__name__}")
        try:
            outputs = outputs_from_table(_plain(outputs) if not isinstance(outputs, Outputs) else outputs)
        except SceneError as e:
            raise StudyError(e.field, e.reason) from None
        raw["outputs"] = _plain(dataclasses.asdict(outputs))
    if sample is not None:
        raw["sample"] = _plain(sample)
    return loads_study(dumps_study(raw))


__all__ = ["Study", "Axis", "Point", "Outputs", "loads_study", "load_study", "make_study", "dumps_study", "check_points",
           "dim_name", "DIM_NAMES"]

"""A study's design: its axes (the swept scene fields and their values), its points (each
with its scene, or why its combination is invalid) and the `Study` that holds them. Reading and
checking a study file is `study.sweep.grid`'s.
"""
from __future__ import annotations

import copy
import dataclasses
import itertools
from dataclasses import dataclass

import numpy as np

from study.plausibility import check_dynamic_window
from study.scene import Scene, SceneError, get_dotted, scene_fields_from_dict, scene_from_dict, set_dotted
from study.sweep.outputs import Outputs
from study.sweep.sample import Sample

# dimension names for the fields an engineer sweeps most; others get the dotted path with '_'
DIM_NAMES = {
    "gear2.body.holes": "n_holes",
    "gear2.body.hole_radius": "hole_radius",
    "gear2.body.hole_circle_radius": "hole_circle_radius",
    "gear2.body.rim_height": "rim_thickness",
    "gear2.body.web_thickness": "web_thickness",
    "gear2.body.web_height": "web_height",
    "gear2.body.opening": "opening",
    "gear2.body.slot_width": "slot_width",
    "gear2.body.slot_angle": "slot_angle",
    "gear2.body.spoke_width": "spoke_width",
    "gear2.body.window_height": "window_height",
    "gear2.body.corner_radius": "corner_radius",
    "dynamic.speed": "speed",
    "dynamic.torque": "torque",
    "quasi_static.torque": "static_torque",
}

def dim_name(path: str) -> str:
    """Archive dimension name of a dotted scene field (``gear2.body.holes`` -> ``n_holes``)."""
    return DIM_NAMES.get(path, path.replace(".", "_"))


@dataclass(frozen=True)
class Axis:
    path: str            # dotted scene field
    values: tuple        # in the scene's units

    @property
    def name(self) -> str:
        return dim_name(self.path)


@dataclass(frozen=True)
class Point:
    """One point of a study: its position, its field values, and its scene (or why it is invalid)."""
    index: tuple            # grid indices (factorial layout) or (i,) (point layout)
    values: dict            # dotted path -> value
    scene: Scene | None     # None when the combination is invalid
    error: str = ""         # the SceneError text of an invalid combination
    _keys: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)   # (outputs, code) -> its task keys


@dataclass(frozen=True)
class Study:
    title: str
    text: str                 # the study TOML as given (archived)
    base: dict                # base scene data (TOML tables)
    axes: tuple[Axis, ...]    # factorial grid
    extra: tuple[dict, ...]   # explicit points: dotted path -> value
    outputs: Outputs
    sample: Sample | None = None     # drawn fields: a last dimension `sample` (grid layout only)

    @property
    def layout(self) -> str:
        """'grid' (one dimension per swept field) or 'point' (explicit points present)."""
        return "point" if self.extra else "grid"

    @property
    def fields(self) -> tuple[str, ...]:
        """Every swept dotted path, grid fields first."""
        out = [a.path for a in self.axes]
        for p in self.extra:
            out += [k for k in p if k not in out]
        return tuple(out)

    @property
    def shape(self) -> tuple[int, ...]:
        if self.layout == "grid":
            return tuple(len(a.values) for a in self.axes) + ((self.sample.builds,) if self.sample else ())
        n_grid = int(np.prod([len(a.values) for a in self.axes])) if self.axes else 0
        return (n_grid + len(self.extra),)

    def base_scene(self) -> Scene:
        """The base scene, checked (SceneError when only the grid's values make it valid)."""
        return scene_from_dict(copy.deepcopy(self.base))

    def base_scene_toml(self) -> str:
        """The base scene with every field spelled out (defaults included)."""
        return scene_fields_from_dict(self.base).to_toml()

    def base_value(self, path: str):
        """Value of a dotted field in the base scene (the Scene default when the base omits it)."""
        return get_dotted(scene_fields_from_dict(self.base), path)

    def points(self) -> list[Point]:
        """All points (cheap: builds and checks each scene, runs nothing)."""
        combos = []
        grid = list(itertools.product(*[range(len(a.values)) for a in self.axes])) if self.axes else []
        for idx in grid:
            combos.append((idx, {a.path: a.values[i] for a, i in zip(self.axes, idx)}))
        if self.sample:     # every grid point (or the base scene alone) gets the whole sample
            combos = [(idx + (i,), {**vals, **self.sample.point_values(i)})
                      for idx, vals in (combos or [((), {})]) for i in range(self.sample.builds)]
        if self.layout == "point":
            combos = [((i,), vals) for i, (_, vals) in enumerate(combos)]
            combos += [((len(combos) + i,), dict(p)) for i, p in enumerate(self.extra)]
        out = []
        for idx, vals in combos:
            data = copy.deepcopy(self.base)
            for path, v in vals.items():
                set_dotted(data, path, v)
            try:
                scene = scene_from_dict(data)
                if self.outputs.dynamic:    # a DTE summary needs a steady part after the ramps
                    check_dynamic_window(scene)
                out.append(Point(idx, vals, scene))
            except SceneError as e:
                out.append(Point(idx, vals, None, str(e)))
        return _one_coupling_model(out)


def _one_coupling_model(points: list[Point]) -> list[Point]:
    """The points with one coupling model for the whole study: where the scenes leave it to
    'auto' and the grid mixes bodies with and without FE springs (solid and lightened), every
    point takes 'compliance' (a study's trade-off is only fair when each point is answered by
    the same model)."""
    auto = {id(p) for p in points if p.scene is not None and p.scene.coupling.model == "auto"}
    if len({p.scene.coupling_model for p in points if id(p) in auto}) <= 1:
        return points
    return [dataclasses.replace(p, scene=p.scene.replace(**{"coupling.model": "compliance"})) if id(p) in auto else p
            for p in points]


def coupling_models(points: list[Point]) -> str:
    """The coupling model(s) the study's valid points run, as a user names them."""
    return ", ".join(sorted({p.scene.coupling_model_name for p in points if p.scene is not None}))

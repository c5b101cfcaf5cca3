"""Run one scene: scene -> run plan -> stages -> run archive (xarray).

`lightgear run [SCENE.toml] [-o OUT.nc] [--set key=value ...]` runs the embedded paper
example when no scene is given, writes the archive and prints a summary. The plan of a run
(`study.plan`) is made once from the scene; the stages (`study.stages`) each take it and return
their variables; the archive (`study.archive`) packs them.
"""
from __future__ import annotations

import contextlib
import math

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.kernels.layout import R_PV
from study.archive import run_variables
from study.archive.netcdf import provenance
from study.errors import check_argument, check_scene_argument, is_number
from study.modification import tip_edge_attrs, tip_edge_radii
from study.plan import STAGES, RunOptions, RunPlan, kept_springs_and_model, make_plan, scene_stages
from study.plausibility import critical_speed_warning
from study.scene import Scene
from study.stages import (
    dynamic_stage,
    gear_stage,
    mesh_stage,
    modes_stage,
    run_static,
    static_stage,
    strength_stage,
)

__all__ = ["RunFields", "run_scene", "run_fields", "run_static", "kept_springs_and_model", "STAGES"]


class RunFields:
    """A run's variables and global attributes before they become its archive (`dataset`),
    read the way `study.archive.summary.summarize` and a study's task read an archive:
    ``name in run``, ``run[name]`` (an xarray.Variable: ``.values``, ``.dims``, ``.attrs``,
    ``float()``), ``run.variables``, ``run.attrs``. A study's task reads a few numbers of a
    run: assembling the run's xarray.Dataset (indexes, alignment, merge) cost it more than any
    other step but the dynamic run itself."""

    def __init__(self, coords: dict, data: dict, attrs: dict):
        self.coords, self.data, self.attrs = coords, data, attrs
        self.variables = {**coords, **data}

    def __contains__(self, name) -> bool:
        return name in self.variables

    def __getitem__(self, name: str) -> xr.Variable:
        var = self.variables.get(name)
        if var is None:
            # a dimension without a coordinate reads as its positions, as in a Dataset
            size = next((v.sizes[name] for v in self.variables.values() if name in v.dims), None)
            if size is None:
                raise KeyError(name)
            return xr.Variable((name,), np.arange(size))
        return var

    def dataset(self) -> xr.Dataset:
        """The run archive."""
        return xr.Dataset(self.data, coords=self.coords, attrs=self.attrs)


def run_scene(scene: Scene, static: bool | None = None, dynamic: bool | None = None, max_time: float | None = None,
              progress: bool = False, warn: bool = True, keep_model: bool = False,
              compile_ahead: bool = False) -> xr.Dataset:
    """Run a scene -> run archive (xarray.Dataset): tooth springs, then the quasi-static STE and
    the dynamic DTE with their spectra. ``static``/``dynamic`` force an analysis on or off
    (None: as the scene's ``quasi_static.enabled`` / ``dynamic.enabled``). Output arrays that
    would not fit in memory, or with ``max_time`` [s] an estimated run time beyond it, raise
    `BudgetError` before any work; ``progress``: bars on stderr for long parts. Plausibility
    warnings (see `study.plausibility_warnings`, and a speed far above the highest critical
    speed of the mesh orders) go to stderr (unless ``warn`` is False) and the archive's
    ``plausibility_warnings`` attribute. ``keep_model``: as a study's worker, the model kept
    for the scenes that differ only in their dynamic run (`study.plan.RunOptions`).
    ``compile_ahead``: the solver kernels this run calls that numba's disk cache lacks are
    compiled by a second process while the run builds its FE, when a core is idle
    (`study.stand_in.compiling_ahead`): a machine's first run of a model ends sooner, its
    results the same to the bit."""
    check_scene_argument("run_scene", scene)
    for name, v in (("static", static), ("dynamic", dynamic)):
        check_argument(v is None or isinstance(v, bool), "run_scene", name, "True, False or None (as the scene says)", v)
    check_argument(max_time is None or (is_number(max_time) and max_time > 0), "run_scene", "max_time",
                   "a positive number of seconds or None", max_time)
    check_argument(isinstance(compile_ahead, bool), "run_scene", "compile_ahead", "True or False", compile_ahead)
    options = RunOptions(max_time, bool(progress), warn, keep_model)
    from study.stand_in import compiling_ahead
    with compiling_ahead(scene, dynamic=dynamic) if compile_ahead else contextlib.nullcontext():
        return run_fields(scene, scene_stages(scene, static, dynamic), options).dataset()


def run_fields(scene: Scene, stages=None, options: RunOptions = RunOptions()) -> RunFields:
    """Run the ``stages`` (`study.plan.STAGES`; None: those of a whole run, `scene_stages`) of
    a scene -> the run archive's variables and attributes (`RunFields`; `run_scene` makes the
    archive of them). The plan is made first (`study.plan.make_plan`: the checks before any
    work, the springs, the model, the equilibria); each stage asked then runs once, on the plan
    and what the stages before it returned, its variables merged in the order of `STAGES` (the
    statics and the mesh run before the modes: see below). A study's task asks
    for the stages its outputs need (`study.sweep.outputs.stages_of`) with
    ``options.archive`` False: the attributes that only document an archive (the scene's TOML,
    the provenance) and, without 'mesh', the dynamic run's loaded contacts are left out."""
    plan = make_plan(scene, scene_stages(scene) if stages is None else stages, options)
    coords, data = springs_variables(plan)
    attrs = {}
    if plan.asks("gear"):
        _merge((coords, data, attrs), gear_stage(plan))
    attrs.update(run_attrs(plan))
    # the statics and the mesh computed before the modes, whose free decay is the first call of
    # the time stepping: on a cold kernel cache a second process compiles it meanwhile
    # (`solver.precompile`), so the run does what does not need it first; merged in the order
    # of STAGES all the same (the same archive)
    st, static_fields, mesh_fields = None, None, None
    if plan.asks("static"):
        *static_fields, st = static_stage(plan)
        if plan.asks("mesh"):
            mesh_fields = mesh_stage(plan, st)
    if plan.asks("modes"):
        _merge((coords, data, attrs), modes_stage(plan))
        if plan.asks("dynamic"):
            cs = data["critical_speed"]
            plan.warn_also(critical_speed_warning(scene, float(cs.values[list(coords["excitation"].values).index("1Z"), 0])))
    attrs["plausibility_warnings"] = "\n".join(plan.warnings)
    for fields in (static_fields, mesh_fields):
        if fields is not None:
            _merge((coords, data, attrs), fields)
    if plan.asks("dynamic"):
        _merge((coords, data, attrs), dynamic_stage(plan))
    if plan.asks("strength") and st is not None:
        kv = float(data["dynamic_factor"].values) if "dynamic_factor" in data else None
        _merge((coords, data, attrs), strength_stage(plan, st, kv))
    if plan.archive:        # a run's archive is rendered next: its body fields, while the body is factorised
        from study.inputs.springs import keep_render_fields
        keep_render_fields(plan.setups, data["tooth_stiffness"].values)
    return RunFields(coords, data, attrs)


def _merge(into: tuple, fields) -> None:
    """A stage's (coordinates, data, attributes) into the run's."""
    for whole, part in zip(into, fields):
        whole.update(part)


def springs_variables(plan: RunPlan) -> tuple[dict, dict]:
    """The tooth springs of both gears (`study.archive.run_variables.stiffness_variables`)."""
    springs, model = plan.springs, plan.model
    coords, data = run_variables.stiffness_variables((springs[0][0], springs[1][0]), (springs[0][1], springs[1][1]))
    data["tooth_stiffness"].attrs["body_windup"] = (
        "in it: the plain model's spring holds its body's wind-up from the bore" if not model.coupled else
        "not in it: the body spring holds the wind-up from the bore (attribute body_stiffness_N_m_rad)")
    return coords, data


def run_attrs(plan: RunPlan) -> dict:
    """The run's global attributes that describe the scene and its model."""
    scene, model = plan.scene, plan.model
    d = scene.dynamic
    z1, z2 = model.teeth
    return {
        "title": run_variables.scene_title(scene),
        **({"scene": scene.to_toml()} if plan.archive else {}),
        "backlash_offset_um": model.backlash_offset * units.UM_PER_M,
        "contact_ratio": model.pair.contact_ratio,
        "mesh_order": float(z2),
        "hole_order": float(scene.gear2.body.holes),
        **run_variables.opening_attrs(scene),
        "driven_speed_rad_s": d.speed * z1 / z2,
        "ramp_time_s": d.ramp_time,
        "wall_time_springs_s": plan.springs_s,
        "coupling": scene.coupling_model,
        "coupling_model": scene.coupling_model_name,
        "coupling_model_setting": scene.coupling.model,
        "damping_conversion": plan.damping_at,
        "body_stiffness_N_m_rad": np.array([k if math.isfinite(k) else 0.0 for k in model.body_stiffness]),
        "pivot_radius_mm": model.gear_par[:, R_PV] * units.MM_PER_M,
        **tip_edge_attrs(tip_edge_radii((scene.gear1, scene.gear2))),
        "teeth_coupled": int(model.teeth_coupled),
        "te_convention": "TE = rb1*theta1 + rb2*theta2, positive when the driven gear lags, zero at the zero-backlash conjugate position",
        **(provenance() if plan.archive else {}),
    }

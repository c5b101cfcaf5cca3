"""One study point: `run_point(scene, outputs)` runs only the analyses the outputs need and
never raises: it returns a status (ok / diverged / invalid / failed / inaccurate), a message,
its wall time [s], the requested scalars and curves (`study.sweep.outputs`).
"""
from __future__ import annotations

import math
import time
import traceback
from pathlib import Path

from study.errors import BudgetError
from study.scene import Scene, SceneError
from study.sweep.grid import Point
from study.sweep.outputs import Outputs, analysis_of, stages_of


def run_point(scene: Scene | dict | str, outputs: Outputs) -> dict:
    """Run one scene (a Scene, scene data or TOML text) for ``outputs``; never raises.

    Returns ``{"status", "message", "wall_time" [s], "scalars": {name: value},
    "curves": {name: (axis name, axis values, axis attrs, values, attrs)}}``; scalars of an
    analysis that failed are NaN. The run is not assembled into a run archive
    (`study.run.run_fields`: its variables only, without the attributes and per-gear
    variables the outputs do not read); its numbers are read as from the archive
    (`point_values`).
    """
    from study.plan import RunOptions
    from study.run import run_fields
    from study.scene import loads_scene, scene_from_dict

    t0 = time.perf_counter()
    scalars = {k: math.nan for k in outputs.scalars}
    curves: dict = {}
    status, message = "ok", "ok"
    try:
        if isinstance(scene, dict):
            scene = scene_from_dict(scene)
        elif isinstance(scene, str):
            scene = loads_scene(scene)
        if outputs.static or outputs.dynamic or outputs.modes:
            # the sweep warns once; a body's points share its model
            run = run_fields(scene, stages_of(outputs), RunOptions(warn=False, keep_model=True, archive=False))
        else:   # geometry (and root stress) only: no model, no solve
            from study.inputs.springs import lightening_dataset
            run = lightening_dataset(scene, stress=outputs.fe)
        status, message, scalars, curves = point_values(run, outputs)
    except (SceneError, BudgetError) as e:
        status, message = "invalid", str(e)
    except Exception as e:  # noqa: BLE001 - a point must never stop the sweep
        from solver.geometry import GeometryError
        from solver.mbs.dynamics import DivergenceError
        if isinstance(e, DivergenceError):
            status, message = "diverged", str(e)
        elif isinstance(e, GeometryError):
            status, message = "invalid", f"{e.field}: {e.reason}"
        else:
            status = "failed"
            where = traceback.extract_tb(e.__traceback__)[-1]
            message = f"{type(e).__name__}: {e} ({Path(where.filename).name}:{where.lineno})"
    return {"status": status, "message": message, "wall_time": time.perf_counter() - t0,
            "scalars": scalars, "curves": curves}


def point_values(run, outputs: Outputs) -> tuple[str, str, dict, dict]:
    """(status, message, scalars, curves) of a point from its run: a run archive (xarray.Dataset)
    or its variables (`study.run.RunFields`), read alike. The scalars are
    `study.archive.summary.summarize`'s; those of an analysis whose numbers are not to be
    trusted (statics not converged, a dynamic run that stopped) are NaN and its curves left out."""
    from study.archive.summary import summarize
    status, message = "ok", "ok"
    s = summarize(run)
    bad = set()          # analyses whose numbers are not to be trusted
    problems = []
    if outputs.static:
        conv = run["ste_converged"].values
        if not conv.all():
            bad.add("static")
            problems.append(f"static equilibrium not reached at {int((conv == 0).sum())} of {conv.size} angles")
    dyn_status = run.attrs.get("dynamic_status", "ok") if outputs.dynamic else "ok"
    if dyn_status.startswith("inaccurate"):
        status, message = "inaccurate", dyn_status
    elif dyn_status != "ok":
        bad.add("dynamic")
        problems.append(f"dynamic run stopped: {dyn_status}")
    if problems:
        status, message = "diverged", "; ".join(problems)
    scalars = {k: float(s.get(k, math.nan)) if analysis_of(k) not in bad else math.nan for k in outputs.scalars}
    curves = {}
    for name in outputs.curves:
        if name in run and analysis_of(name) not in bad:
            var = run[name]
            axis = var.dims[0]
            curves[name] = (axis, run[axis].values.copy(), dict(run[axis].attrs), var.values.copy(), dict(var.attrs))
    return status, message, scalars, curves


def invalid_result(point: Point, outputs: Outputs) -> dict:
    """The record of a point whose combination of values is invalid (nothing computed)."""
    return {"status": "invalid", "message": point.error, "wall_time": 0.0,
            "scalars": {k: math.nan for k in outputs.scalars}, "curves": {}}

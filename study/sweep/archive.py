"""The archive of a study: one labelled xarray.Dataset (written as NetCDF by results.write_netcdf).

Layout
  grid layout:  one dimension per swept field (``n_holes``, ``hole_radius``, ``rim_thickness``,
                ``web_thickness``, ``speed``, or the dotted path with '_'), in [grid] order;
  point layout: one ``point`` dimension, each swept field a coordinate along it.
Each coordinate carries ``units``, ``long_name`` (from the scene's field metadata) and
``scene_field`` (the dotted path). Variables, over the study dimensions:
  status      CF flags 0 pending, 1 ok, 2 diverged, 3 invalid, 4 failed
  message     text: 'ok', or why the point is not ok
  wall_time   s, compute time of the point (its share of the analyses it shares with others)
  <scalar>    each requested scalar (`outputs.SCALARS`), NaN where its analysis failed
  <curve>     each requested curve over its own dimension (angle, time, frequency)
In the grid layout an output lies only over the swept dimensions its analysis reads
(`outputs.ANALYSIS_FIELDS`): ``ste_p2p`` over the body fields but not over ``speed``,
``mass_gear2`` over the body fields only; ``status`` says which points are ok (an output is
read with ``.where(ds.status == 1)``, which broadcasts it over every dimension). In the point
layout every variable lies over ``point``. Archives of a split study open together with
``xr.open_mfdataset(paths, combine="by_coords", data_vars="minimal")`` (outputs that do not lie
over the split dimension are then taken once, checked equal).
Global attributes: title, the study TOML, the base scene TOML, the study key (a hash of all
its points), software versions, machine and date (`results.provenance`).
"""
from __future__ import annotations

import hashlib
import json

import numpy as np
import xarray as xr

from study.report.results import provenance
from study.scene import field_doc, field_unit
from study.sweep.grid import Point, Study, dim_name
from study.sweep.outputs import CURVES, SCALARS, STATUS, analysis_of, reads
from study.sweep.tasks import point_task_keys

CF_UNITS = {"": "1", "deg": "degree", "N*m": "N m", "rad/s": "rad s-1", "kg/m^3": "kg m-3",
            "N*mm/rad^n_k": "N mm rad-n_k", "N/mm^m1": "N mm-m1"}


def cf_units(unit: str) -> str:
    """Scene unit strings in the spelling of CF / UDUNITS where they differ."""
    return CF_UNITS.get(unit, unit)


def _coord_values(values, path: str):
    vals = list(values)
    if all(isinstance(v, str) for v in vals):
        return np.array(vals, dtype=object), {"long_name": field_doc(path), "scene_field": path}
    if all(isinstance(v, bool) for v in vals):
        arr = np.array(vals, dtype=bool)
    elif all(isinstance(v, int) and not isinstance(v, bool) for v in vals):
        arr = np.array(vals, dtype=np.int64)
    else:
        arr = np.array(vals, dtype=np.float64)
    return arr, {"units": cf_units(field_unit(path)), "long_name": field_doc(path), "scene_field": path}


def study_layout(study: Study, points: list[Point]) -> tuple[tuple[str, ...], dict]:
    """Dimensions and coordinates of a study archive."""
    if study.layout == "grid":
        coords = {}
        for a in study.axes:
            arr, attrs = _coord_values(a.values, a.path)
            coords[a.name] = xr.Variable(a.name, arr, attrs)
        return tuple(a.name for a in study.axes), coords
    coords = {"point": xr.Variable("point", np.arange(len(points)), {"units": "1", "long_name": "study point"})}
    for path in study.fields:
        arr, attrs = _coord_values([p.values.get(path, study.base_value(path)) for p in points], path)
        coords[dim_name(path)] = xr.Variable("point", arr, attrs)
    return ("point",), coords


def study_key(study: Study, points: list[Point]) -> str:
    """Hash of everything the study computes (its points' tasks, or invalid values, in order)."""
    blob = "|".join([study.layout] + [",".join(point_task_keys(p, study.outputs)) or json.dumps(p.values, sort_keys=True)
                                      for p in points])
    return hashlib.sha256(blob.encode()).hexdigest()[:24]


def output_axes(study: Study, output: str) -> tuple[int, ...]:
    """Positions (in ``study.axes``) of the swept dimensions an output lies over: all of them in
    the point layout, else the fields its analysis reads."""
    if study.layout == "point":
        return ()
    return tuple(i for i, a in enumerate(study.axes) if reads(analysis_of(output), a.path))


def study_dataset(study: Study, points: list[Point], results: dict) -> xr.Dataset:
    """The labelled archive of a study from ``results`` (point index -> record of
    `tasks.point_result`: status, message, wall_time, scalars, curves).

    Points without a result are 'pending'. An output over fewer dimensions than the study takes
    its value at a position from the first point there that has a finite one (the points of one
    position agree on every field the output reads). A curve's axis comes from the first point
    that has it; a point whose axis differs (another duration or angle step, say) keeps NaN there
    and says so in its message.
    """
    out = study.outputs
    dims, coords = study_layout(study, points)
    shape = study.shape
    grid = study.layout == "grid"
    own = {k: output_axes(study, k) for k in out.scalars + out.curves}

    def dims_of(k):
        return tuple(dims[i] for i in own[k]) if grid else dims

    def shape_of(k):
        return tuple(shape[i] for i in own[k]) if grid else shape

    def at(k, idx):
        return tuple(idx[i] for i in own[k]) if grid else idx

    status = np.zeros(shape, np.int8)
    message = np.full(shape, "not computed yet", dtype=object)
    wall = np.full(shape, np.nan)
    scal = {k: np.full(shape_of(k), np.nan) for k in out.scalars}
    axes, curves, curve_attrs = {}, {}, {}
    for p in points:
        r = results.get(p.index)
        if r is None:
            continue
        idx = p.index
        status[idx] = STATUS.index(r["status"])
        message[idx] = r["message"]
        wall[idx] = r["wall_time"]
        for k in out.scalars:
            v = r["scalars"].get(k, np.nan)
            if np.isnan(scal[k][at(k, idx)]):
                scal[k][at(k, idx)] = v
        for name, (axis, ax_vals, ax_attrs, vals, attrs) in r["curves"].items():
            if name not in axes:
                axes[name] = (axis, ax_vals, ax_attrs)
                curves[name] = np.full(shape_of(name) + (ax_vals.size,), np.nan)
                curve_attrs[name] = attrs
            ref = axes[name][1]
            if ax_vals.shape == ref.shape and np.allclose(ax_vals, ref, rtol=1e-9, atol=0.0):
                if np.isnan(curves[name][at(name, idx)]).all():
                    curves[name][at(name, idx)] = vals
            else:
                message[idx] = f"{message[idx]}; {name} not stored: its {axis} axis differs from the archive's"
    data = {
        "status": xr.Variable(dims, status, {
            "long_name": "status of the study point", "units": "1",
            "flag_values": np.arange(len(STATUS), dtype=np.int8), "flag_meanings": " ".join(STATUS)}),
        "message": xr.Variable(dims, message, {"long_name": "why the point is not ok ('ok' when it is)"}),
        "wall_time": xr.Variable(dims, wall, {
            "units": "s", "long_name": "compute time of the point",
            "comment": "an analysis shared by several points (a static one over the speeds, say) counts "
                       "its time split equally over them"}),
    }
    for k in out.scalars:
        data[k] = xr.Variable(dims_of(k), scal[k], {"units": SCALARS[k].units, "long_name": SCALARS[k].long_name,
                                                    "analysis": SCALARS[k].analysis})
    for name in out.curves:
        if name not in axes:
            continue  # no point produced it (all failed): nothing to label its axis with
        axis, ax_vals, ax_attrs = axes[name]
        coords[axis] = xr.Variable(axis, ax_vals, {k: v for k, v in ax_attrs.items() if k in ("units", "long_name", "comment")})
        attrs = {k: v for k, v in curve_attrs[name].items() if k in ("units", "long_name", "window", "comment")}
        if CURVES[name].comment:
            attrs["comment"] = CURVES[name].comment
        attrs["analysis"] = CURVES[name].analysis
        data[name] = xr.Variable(dims_of(name) + (axis,), curves[name], attrs)
    attrs = {"title": study.title, "study": study.text, "base_scene": study.base_scene_toml(),
             "study_layout": study.layout, "study_key": study_key(study, points),
             "outputs": ", ".join(out.scalars + out.curves), **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)

"""The archive of a study: one labelled xarray.Dataset (written as NetCDF by results.write_netcdf).

Layout
  grid layout:  one dimension per swept field (``n_holes``, ``hole_radius``, ``rim_thickness``,
                ``web_thickness``, ``speed``, or the dotted path with '_'), in [grid] order;
  point layout: one ``point`` dimension, each swept field a coordinate along it.
Each coordinate carries ``units``, ``long_name`` (from the scene's field metadata) and
``scene_field`` (the dotted path). Variables, over the study dimensions:
  status      CF flags 0 pending, 1 ok, 2 diverged, 3 invalid, 4 failed, 5 inaccurate
  message     text: 'ok', or why the point is not ok
  wall_time   s, compute time of the point
  <scalar>    each requested scalar (`outputs.SCALARS`), NaN where not ok
  <curve>     each requested curve over its own dimension (angle, time, frequency)
Global attributes: title, the study TOML, the base scene TOML, the study key (a hash of all
its points), software versions, machine and date (`results.provenance`).
"""
from __future__ import annotations

import hashlib

import numpy as np
import xarray as xr

from study.report.results import provenance
from study.scene import field_doc, field_unit
from study.sweep.grid import Point, Study, dim_name
from study.sweep.outputs import CURVES, SCALARS, STATUS

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
    """Hash of everything the study computes (its points' keys in order)."""
    blob = "|".join([study.layout] + [p.key(study.outputs) for p in points])
    return hashlib.sha256(blob.encode()).hexdigest()[:24]


MERGE_BLOCK_BYTES = 8 * 2**20    # bytes: curve values the merge reads from the part files at once


def study_dataset(study: Study, points: list[Point], results: dict, read=None, lost: dict | None = None,
                  block_bytes: int | None = None) -> xr.Dataset:
    """The labelled archive of a study from ``results`` (point key -> `engine.run_point` dict).

    Points without a result are 'pending' (their message says why when ``lost`` maps their key
    to the cause). A curve's axis comes from the first point that has it; a point whose axis
    differs (another duration or angle step, say) keeps NaN there and says so in its message.

    With ``read(key)`` (the full record of a finished point, from its part file) the records in
    ``results`` may leave their curves out: the curves are then dask arrays whose blocks (at
    most ``block_bytes``, default `MERGE_BLOCK_BYTES`, each) read the part files when the archive is written, so that no
    more than one block of curves is ever held in memory. Without it the curves come from
    ``results`` and are held in memory.
    """
    out = study.outputs
    dims, coords = study_layout(study, points)
    shape = study.shape
    status = np.zeros(shape, np.int8)
    message = np.full(shape, "not computed yet", dtype=object)
    wall = np.full(shape, np.nan)
    scal = {k: np.full(shape, np.nan) for k in out.scalars}
    axes, where, curve_attrs = {}, {}, {}      # per curve: its axis, {point index: key} of the points stored
    for p in points:
        key = p.key(out)
        r = results.get(key)
        if r is None:
            if lost and key in lost:
                message[p.index] = f"lost: {lost[key]}; run the same command to compute it"
            continue
        idx = p.index
        status[idx] = STATUS.index(r["status"])
        message[idx] = r["message"]
        wall[idx] = r["wall_time"]
        for k in out.scalars:
            scal[k][idx] = r["scalars"].get(k, np.nan)
        if "curves" in r:
            point_curves = r["curves"]
        else:
            full = read(key) if read is not None else None
            point_curves = full["curves"] if full else {}
        for name, (axis, ax_vals, ax_attrs, _, attrs) in point_curves.items():
            if name not in axes:
                axes[name] = (axis, ax_vals, ax_attrs)
                where[name] = {}
                curve_attrs[name] = attrs
            ref = axes[name][1]
            if ax_vals.shape == ref.shape and np.allclose(ax_vals, ref, rtol=1e-9, atol=0.0):
                where[name][idx] = key
            else:
                message[idx] = f"{message[idx]}; {name} not stored: its {axis} axis differs from the archive's"
        del point_curves
    curves = {}
    for name in axes:
        n = axes[name][1].size
        if all("curves" in results[k] for k in where[name].values()):
            curves[name] = np.full(shape + (n,), np.nan)
            for idx, key in where[name].items():
                curves[name][idx] = results[key]["curves"][name][3]
        else:
            curves[name] = lazy_curve(name, shape, n, where[name], read, block_bytes or MERGE_BLOCK_BYTES)
    data = {
        "status": xr.Variable(dims, status, {
            "long_name": "status of the study point", "units": "1",
            "flag_values": np.arange(len(STATUS), dtype=np.int8), "flag_meanings": " ".join(STATUS)}),
        "message": xr.Variable(dims, message, {"long_name": "why the point is not ok ('ok' when it is)"}),
        "wall_time": xr.Variable(dims, wall, {"units": "s", "long_name": "compute time of the point"}),
    }
    for k in out.scalars:
        data[k] = xr.Variable(dims, scal[k], {"units": SCALARS[k].units, "long_name": SCALARS[k].long_name})
    for name in out.curves:
        if name not in axes:
            continue  # no point produced it (all failed): nothing to label its axis with
        axis, ax_vals, ax_attrs = axes[name]
        coords[axis] = xr.Variable(axis, ax_vals, {k: v for k, v in ax_attrs.items() if k in ("units", "long_name", "comment")})
        attrs = {k: v for k, v in curve_attrs[name].items() if k in ("units", "long_name", "window", "comment")}
        if CURVES[name].comment:
            attrs["comment"] = CURVES[name].comment
        data[name] = xr.Variable(dims + (axis,), curves[name], attrs)
    attrs = {"title": study.title, "study": study.text, "base_scene": study.base_scene_toml(),
             "study_layout": study.layout, "study_key": study_key(study, points),
             "outputs": ", ".join(out.scalars + out.curves), **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def lazy_curve(name: str, shape: tuple, n: int, where: dict, read, block_bytes: int):
    """The curve ``name`` of the points ``where`` ({point index: key}) as a dask array over the
    study dimensions and the curve axis (``n`` values), in blocks of at most ``block_bytes``
    (at least one point) that read the points' records with ``read(key)`` when computed."""
    import uuid

    import dask.array as da
    chunks = da.core.normalize_chunks(("auto",) * len(shape) + (n,), shape + (n,), limit=block_bytes, dtype=np.float64)

    def block(block_info=None):
        loc = block_info[None]["array-location"]
        values = np.full(tuple(b - a for a, b in loc), np.nan)
        for idx, key in where.items():
            if all(a <= i < b for i, (a, b) in zip(idx, loc)):
                values[tuple(i - a for i, (a, _) in zip(idx, loc))] = read(key)["curves"][name][3]
        return values
    return da.map_blocks(block, chunks=chunks, dtype=np.float64, meta=np.empty((0,) * (len(shape) + 1)),
                         name=f"study-curve-{name}-{uuid.uuid4().hex}")

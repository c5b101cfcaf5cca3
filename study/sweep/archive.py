"""The archive of a study: one labelled xarray.Dataset (written as NetCDF by `study.archive.netcdf.write_netcdf`).

Layout
  grid layout:  one dimension per swept field (``n_holes``, ``hole_radius``, ``rim_thickness``,
                ``web_thickness``, ``speed``, or the dotted path with '_'), in [grid] order;
  point layout: one ``point`` dimension, each swept field a coordinate along it.
Each coordinate carries ``units``, ``long_name`` (from the scene's field metadata) and
``scene_field`` (the dotted path). Variables, over the study dimensions:
  status      CF flags 0 pending, 1 ok, 2 diverged, 3 invalid, 4 failed, 5 inaccurate
  message     text: 'ok', or why the point is not ok
  wall_time   s, compute time of the point (its share of the analyses it shares with others)
  <scalar>    each requested scalar (`outputs.SCALARS`), NaN where its analysis failed
  <curve>     each requested curve over its own dimension (angle, time, frequency)
In the grid layout an output lies only over the swept dimensions its analysis reads
(`outputs.ANALYSIS_FIELDS`): ``ste_p2p`` over the body fields but not over ``speed``,
``mass_gear2`` over the body fields only; ``status`` says which points are ok (an output is
read with ``.where(ds.status == 1)``, which broadcasts it over every dimension; the flags are
`solver.mbs.kernels.status.POINT_STATUS`). In the point layout every variable lies over ``point``.
A sampled study (`study.sweep.sample`) has a last dimension ``sample`` (one build each), the
drawn values of each field as variables over it (named like a grid dimension, with its
``distribution``), ``sample_block`` and ``sample_row`` for the Saltelli design, and every output
over (the swept dimensions its analysis reads..., ``sample``). Archives of a split study open together with
``xr.open_mfdataset(paths, combine="by_coords", data_vars="minimal", compat="no_conflicts")`` (outputs that do not lie
over the split dimension are then taken once, checked equal).
Global attributes: title, the study TOML, the base scene TOML, the study key (a hash of all
its points), software versions, machine and date (`study.archive.netcdf.provenance`).
"""
from __future__ import annotations

import hashlib
import json

import numpy as np
import xarray as xr

from study.archive.netcdf import provenance
from study.scene import field_doc, field_unit
from study.sweep.grid import Point, Study, coupling_models, dim_name
from study.sweep.outputs import CURVES, SCALARS, STATUS, analysis_of, reads
from study.sweep.sample import Sample
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


def sample_variables(sample: Sample) -> dict:
    """The archive's variables over ``sample``: the drawn values of each field (named like a grid
    dimension, `grid.dim_name`), and for the Saltelli design ``sample_block`` and ``sample_row``."""
    out = {}
    for f in sample.fields:
        vals = sample.values[f.path]
        out[dim_name(f.path)] = xr.Variable("sample", vals, {
            "units": cf_units(field_unit(f.path)), "long_name": field_doc(f.path), "scene_field": f.path,
            "distribution": f.describe()})
    if sample.design == "saltelli":
        out["sample_block"] = xr.Variable("sample", sample.block, {
            "units": "1", "long_name": "matrix of the Saltelli design",
            "comment": "0: A, 1: B, 2 + i: A with drawn field i (in the order of sample_fields) from B"})
        out["sample_row"] = xr.Variable("sample", sample.row, {
            "units": "1", "long_name": "row of the build in its matrix of the Saltelli design"})
    return out


def sample_attrs(sample: Sample) -> dict:
    """Global attributes of a sampled study's archive."""
    return {"sample_method": sample.method, "sample_size": sample.size, "sample_seed": sample.seed,
            "sample_design": sample.design, "sample_fields": " ".join(sample.paths)}


def study_layout(study: Study, points: list[Point]) -> tuple[tuple[str, ...], dict]:
    """Dimensions and coordinates of a study archive."""
    if study.layout == "grid":
        coords = {}
        for a in study.axes:
            arr, attrs = _coord_values(a.values, a.path)
            coords[a.name] = xr.Variable(a.name, arr, attrs)
        dims = tuple(a.name for a in study.axes)
        if study.sample:
            coords["sample"] = xr.Variable("sample", np.arange(study.sample.builds),
                                           {"units": "1", "long_name": "build of the sample"})
            dims += ("sample",)
        return dims, coords
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


MERGE_BLOCK_BYTES = 8 * 2**20    # bytes: curve values the merge reads from the part files at once


def output_axes(study: Study, output: str) -> tuple[int, ...]:
    """Positions (in ``study.axes``) of the swept dimensions an output lies over: all of them in
    the point layout, else the fields its analysis reads, and the sample (last) when drawn."""
    if study.layout == "point":
        return ()
    sample = (len(study.axes),) if study.sample else ()
    return tuple(i for i, a in enumerate(study.axes) if reads(analysis_of(output), a.path)) + sample


class _Placement:
    """Where each output of a study lies: its dimensions, shape and a point's position in it (a
    grid study's output over the swept dimensions it reads, `output_axes`; others over all)."""

    def __init__(self, study: Study, dims: tuple):
        self.dims, self.shape, self.grid = dims, study.shape, study.layout == "grid"
        out = study.outputs
        self.own = {k: output_axes(study, k) for k in out.scalars + out.curves}

    def dims_of(self, k):
        return tuple(self.dims[i] for i in self.own[k]) if self.grid else self.dims

    def shape_of(self, k):
        return tuple(self.shape[i] for i in self.own[k]) if self.grid else self.shape

    def at(self, k, idx):
        return tuple(idx[i] for i in self.own[k]) if self.grid else idx


class _Gathered:
    """The records of a study's points laid out: status, message, compute time, scalars, and per
    curve its axis, attributes and per position the values held ({position: values}) or the
    task whose part file has them ({position: key})."""

    def __init__(self, study: Study, place: _Placement):
        shape = place.shape
        self.status = np.zeros(shape, np.int8)
        self.message = np.full(shape, "not computed yet", dtype=object)
        self.wall = np.full(shape, np.nan)
        self.scalars = {k: np.full(place.shape_of(k), np.nan) for k in study.outputs.scalars}
        self.axes, self.held, self.where, self.curve_attrs = {}, {}, {}, {}

    def add(self, idx, r: dict, place: _Placement, read) -> None:
        """Point ``idx``'s record ``r`` (`tasks.point_result`)."""
        self.status[idx] = STATUS.index(r["status"])
        self.message[idx] = r["message"]
        self.wall[idx] = r["wall_time"]
        for k, arr in self.scalars.items():
            v = r["scalars"].get(k, np.nan)
            if np.isnan(arr[place.at(k, idx)]):
                arr[place.at(k, idx)] = v
        point_curves = dict(r.get("curves", {}))
        keys = {key for name, key in r.get("curve_keys", {}).items()
                if place.at(name, idx) not in self.where.get(name, {}) and place.at(name, idx) not in self.held.get(name, {})}
        for key in keys:            # read once for the axes of the curves it brings to new positions
            full = read(key) if read is not None else None
            for name, curve in (full["curves"] if full else {}).items():
                if r["curve_keys"].get(name) == key:
                    point_curves[name] = (*curve[:3], key, curve[4])
            del full
        for name, curve in point_curves.items():
            self._add_curve(idx, name, curve, place)

    def _add_curve(self, idx, name: str, curve: tuple, place: _Placement) -> None:
        axis, ax_vals, ax_attrs, vals, attrs = curve
        if name not in self.axes:
            self.axes[name] = (axis, ax_vals, ax_attrs)
            self.held[name], self.where[name] = {}, {}
            self.curve_attrs[name] = attrs
        ref = self.axes[name][1]
        pos = place.at(name, idx)
        if pos in self.held[name] or pos in self.where[name]:
            return
        if ax_vals.shape == ref.shape and np.allclose(ax_vals, ref, rtol=1e-9, atol=0.0):
            (self.where if isinstance(vals, str) else self.held)[name][pos] = vals
        else:
            self.message[idx] = f"{self.message[idx]}; {name} not stored: its {axis} axis differs from the archive's"

    def curve_arrays(self, place: _Placement, read, block_bytes: int | None) -> dict:
        """Each curve over its dimensions and axis: in memory, or a dask array reading the part files."""
        curves = {}
        for name in self.axes:
            n = self.axes[name][1].size
            if self.where[name]:
                curves[name] = lazy_curve(name, place.shape_of(name), n, self.where[name], read,
                                          block_bytes or MERGE_BLOCK_BYTES, self.held[name])
            else:
                curves[name] = np.full(place.shape_of(name) + (n,), np.nan)
                for pos, vals in self.held[name].items():
                    curves[name][pos] = vals
        return curves


def study_dataset(study: Study, points: list[Point], results: dict, read=None, lost: dict | None = None,
                  block_bytes: int | None = None) -> xr.Dataset:
    """The labelled archive of a study from ``results`` (point index -> record of
    `tasks.point_result`: status, message, wall_time, scalars, and curves or curve_keys).

    Points without a result are 'pending' (their message says why when ``lost`` maps their index
    to the cause). An output over fewer dimensions than the study takes its value at a position
    from the first point there that has a finite one (the points of one position agree on every
    field the output reads). A curve's axis comes from the first point that has it; a point whose
    axis differs (another duration or angle step, say) keeps NaN there and says so in its message.

    With ``read(key)`` (the full record of a task, from its part file) a record may give, instead
    of its curves, ``curve_keys`` ({curve: key of the task that produced it}): the curves are
    then dask arrays whose blocks (at most ``block_bytes``, default `MERGE_BLOCK_BYTES`, each)
    read the part files when the archive is written, each task's record once per position of
    the curve, so that no more than one block of curves is ever held in memory. Curves given in
    the records are held in memory.
    """
    out = study.outputs
    dims, coords = study_layout(study, points)
    place = _Placement(study, dims)
    got = _Gathered(study, place)
    for p in points:
        r = results.get(p.index)
        if r is not None:
            got.add(p.index, r, place, read)
        elif lost and p.index in lost:
            got.message[p.index] = f"lost: {lost[p.index]}; run the same command to compute it"
    curves = got.curve_arrays(place, read, block_bytes)
    data = {
        "status": xr.Variable(dims, got.status, {
            "long_name": "status of the study point", "units": "1",
            "flag_values": np.arange(len(STATUS), dtype=np.int8), "flag_meanings": " ".join(STATUS)}),
        "message": xr.Variable(dims, got.message, {"long_name": "why the point is not ok ('ok' when it is)"}),
        "wall_time": xr.Variable(dims, got.wall, {
            "units": "s", "long_name": "compute time of the point",
            "comment": "an analysis shared by several points (a static one over the speeds, say) counts "
                       "its time split equally over them"}),
    }
    for k in out.scalars:
        data[k] = xr.Variable(place.dims_of(k), got.scalars[k], {"units": SCALARS[k].units, "long_name": SCALARS[k].long_name,
                                                                 "analysis": SCALARS[k].analysis})
    for name in out.curves:
        if name not in got.axes:
            continue  # no point produced it (all failed): nothing to label its axis with
        axis, ax_vals, ax_attrs = got.axes[name]
        coords[axis] = xr.Variable(axis, ax_vals, {k: v for k, v in ax_attrs.items() if k in ("units", "long_name", "comment")})
        attrs = {k: v for k, v in got.curve_attrs[name].items() if k in ("units", "long_name", "window", "comment")}
        if CURVES[name].comment:
            attrs["comment"] = CURVES[name].comment
        attrs["analysis"] = CURVES[name].analysis
        data[name] = xr.Variable(place.dims_of(name) + (axis,), curves[name], attrs)
    if study.sample:
        data.update(sample_variables(study.sample))
    attrs = {"title": study.title, "study": study.text, "base_scene": study.base_scene_toml(),
             "study_layout": study.layout, "study_key": study_key(study, points),
             "outputs": ", ".join(out.scalars + out.curves), "coupling_model": coupling_models(points), **provenance(),
             **(sample_attrs(study.sample) if study.sample else {})}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def lazy_curve(name: str, shape: tuple, n: int, where: dict, read, block_bytes: int, held: dict | None = None):
    """The curve ``name`` at the positions ``where`` ({position: task key}) as a dask array over
    the dimensions it lies over (``shape``) and the curve axis (``n`` values), in blocks of at
    most ``block_bytes`` (at least one position) that read each task's record with ``read(key)``
    when computed; ``held`` ({position: values}) are curves already in memory."""
    import uuid

    import dask.array as da
    chunks = da.core.normalize_chunks(("auto",) * len(shape) + (n,), shape + (n,), limit=block_bytes, dtype=np.float64)

    def block(block_info=None):
        loc = block_info[None]["array-location"]
        values = np.full(tuple(b - a for a, b in loc), np.nan)
        for idx, src in [*where.items(), *(held or {}).items()]:
            if all(a <= i < b for i, (a, b) in zip(idx, loc)):
                values[tuple(i - a for i, (a, _) in zip(idx, loc))] = \
                    read(src)["curves"][name][3] if isinstance(src, str) else src
        return values
    return da.map_blocks(block, chunks=chunks, dtype=np.float64, meta=np.empty((0,) * (len(shape) + 1)),
                         name=f"study-curve-{name}-{uuid.uuid4().hex}")

"""An archive's variables as CSV files, for tools that do not read NetCDF.

One file per dimension group: the variables over the same dimensions share a file, in long
form (one row per combination of their dimensions' values: the dimension coordinates and
the other coordinates along them first, then the variables). Dimensionless variables go to
``scalars.csv`` (name, value, unit, long name), the global attributes to
``attributes.csv``. Every column's header is ``name [unit]`` (``[-]`` for a dimensionless
number, nothing for a label). Floats are written with 15 significant digits: a value reads
back within 1e-15 of the archive's, and a step of 0.1 degree prints as 0.3, not
0.30000000000000004.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import xarray as xr

FLOAT_FORMAT = "%.15g"


def header(name: str, var: xr.DataArray) -> str:
    """``name [unit]`` of a column (``unit_symbol`` where the CF unit cannot say it); a label
    (text) has no unit."""
    if var.dtype.kind in "OSU":
        return str(name)
    unit = str(var.attrs.get("unit_symbol", var.attrs.get("units", ""))).strip()
    return f"{name} [{'-' if unit in ('', '1') else unit}]"


def group_name(dims: tuple) -> str:
    """File stem of the variables over ``dims``."""
    return "__".join(dims) if dims else "scalars"


def _fmt(v) -> str:
    if isinstance(v, (float, np.floating)):
        return FLOAT_FORMAT % v
    return str(v.item() if hasattr(v, "item") else v)


def export_csv(ds: xr.Dataset, outdir) -> list[Path]:
    """Write the CSV files of ``ds`` into ``outdir`` (made if needed); return their paths."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    groups: dict[tuple, list] = {}
    for name, var in ds.data_vars.items():
        groups.setdefault(tuple(var.dims), []).append(name)
    paths = []
    for dims, names in groups.items():
        path = outdir / f"{group_name(dims)}.csv"
        if not dims:
            with path.open("w", newline="") as f:
                w = csv.writer(f)
                w.writerow(["name", "value", "unit", "long_name"])
                for n in names:
                    w.writerow([n, _fmt(ds[n].values[()]), ds[n].attrs.get("units", ""), ds[n].attrs.get("long_name", "")])
        else:
            sub = ds[names]
            df = sub.to_dataframe().reset_index()
            # the coordinates of these dimensions (dimension coordinates and those along them) first
            first = [c for c in df.columns if c in sub.coords]
            df = df[first + [c for c in df.columns if c not in first]]
            df.columns = [header(c, sub[c]) for c in df.columns]
            df.to_csv(path, index=False, float_format=FLOAT_FORMAT)
        paths.append(path)
    path = outdir / "attributes.csv"
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["name", "value"])
        for k, v in ds.attrs.items():
            w.writerow([k, " ".join(_fmt(x) for x in np.ravel(v)) if isinstance(v, np.ndarray) else _fmt(v)])
    paths.append(path)
    return paths


def export(archive, outdir=None) -> list[Path]:
    """The variables of an archive (path or Dataset) as CSV files in ``outdir`` (default: beside
    the archive, ``NAME_csv``), one per dimension group, with units in the headers -> their paths."""
    from study.errors import check_argument, is_path
    if isinstance(archive, xr.Dataset):
        check_argument(outdir is not None, "export", "outdir", "a folder (needed for a Dataset)", outdir)
        return export_csv(archive, Path(outdir))
    check_argument(is_path(archive), "export", "archive", "a NetCDF path or a Dataset", archive)
    path = Path(archive)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return export_csv(ds, Path(outdir) if outdir is not None else path.with_name(f"{path.stem}_csv"))


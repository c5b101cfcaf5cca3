"""Writing archives: CF encoding, atomic NetCDF writes, provenance and the code fingerprint.

The layer below everything in `study` that writes a file (run, sweep, inputs' FE cache,
verify, report): it imports only numpy, xarray and the standard library.

  provenance()        global attributes of every archive: versions, code fingerprint, machine,
                      creation time and CF ``history``
  cf_variable(...)    an xarray.Variable with its CF ``units`` and ``long_name``
  write_netcdf(...)   compressed CF NetCDF4, written atomically (temporary file, then rename)
"""
from __future__ import annotations

import datetime
import functools
import hashlib
import platform
from importlib import metadata
from pathlib import Path

import numpy as np
import xarray as xr


def cf_variable(dims, data, unit: str, long_name: str, **attrs) -> xr.Variable:
    """An xarray.Variable over ``dims`` with CF ``units`` and ``long_name`` and further
    attributes (the run archive's own variables are declared in `study.archive.schema`)."""
    return xr.Variable(dims, data, {"units": unit, "long_name": long_name, **attrs})


@functools.lru_cache(maxsize=1)
def versions() -> str:
    """The installed versions of the packages a result depends on; read once per process (the
    package metadata lookups took 0.09 s a call, a third of a sampled build's statics)."""
    out = []
    for pkg in ("lightgear", "numpy", "numba", "scipy", "xarray", "netCDF4", "dask", "scikit-fem", "gmsh"):
        try:
            out.append(f"{pkg} {metadata.version(pkg)}")
        except metadata.PackageNotFoundError:
            pass
    return ", ".join(out)


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """Hash of the source of the `solver` and `study` packages (file names and contents): any
    change to the code that computes results changes it. Computed once per process."""
    root = Path(__file__).resolve().parents[2]
    h = hashlib.sha256()
    for pkg in ("solver", "study"):
        for path in sorted((root / pkg).rglob("*.py")):
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


def history_line(created: str | None = None) -> str:
    """CF ``history``: UTC time, then the program and its arguments."""
    import shlex
    import sys
    created = created or datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    spec = getattr(sys.modules.get("__main__"), "__spec__", None)
    program = f"python -m {spec.name.removesuffix('.__main__')}" if spec is not None and spec.name else Path(sys.argv[0]).name
    return f"{created} {program} {shlex.join(sys.argv[1:])}".strip()


def provenance() -> dict:
    """Global attributes of an archive: software versions, code fingerprint, machine, creation
    time (UTC), CF ``history`` and ``Conventions``."""
    created = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    return {
        "software": versions(),
        "code_fingerprint": code_fingerprint(),
        "machine": f"{platform.node()} {platform.machine()} {platform.processor() or ''} python {platform.python_version()}".strip(),
        "created": created,
        "history": history_line(created),
        "Conventions": "CF-1.8",
    }


def cf_ready(ds: xr.Dataset) -> tuple[xr.Dataset, dict]:
    """A shallow copy of ``ds`` and its NetCDF encoding in the form CF-1.8 asks for.

    Integers become int32 where the values fit (CF has no 64-bit integers), coordinate
    variables get no ``_FillValue`` (a coordinate has no missing values), floats and integers
    are compressed, and a dataset without ``history`` (one not made with `provenance`) gets
    one. Names, values and every other attribute stay as they are.
    """
    ds = ds.copy(deep=False)
    i32 = np.iinfo(np.int32)
    for name in list(ds.variables):
        v = ds[name]
        if v.dtype.kind in "iu" and v.dtype.itemsize > 4 and (v.size == 0 or i32.min <= int(v.min()) and int(v.max()) <= i32.max):
            ds[name] = v.astype(np.int32)
    enc = {v: {"zlib": True, "complevel": 4} for v in ds.data_vars if ds[v].dtype.kind in "fiu"}
    for c in ds.coords:
        enc.setdefault(c, {})["_FillValue"] = None
    if not str(ds.attrs.get("history", "")).strip():
        ds.attrs["history"] = history_line()
    return ds, enc


TMP_MARK = ".tmp"


def host_tag() -> str:
    """Short tag of this machine in temporary names: a shared folder on a cluster holds other
    hosts' temporary files, whose process ids mean nothing here."""
    return hashlib.sha256(platform.node().encode()).hexdigest()[:6]


def clean_stale_temporaries(path) -> list[Path]:
    """Remove the temporary files of ``path`` (``.NAME.tmpPID.HOST-XXXXXXXX``) left by writers
    on this machine that no longer run (a kill during a write) -> the paths removed. Files
    of live processes and of other hosts are left alone."""
    import os
    path = Path(path)
    removed = []
    for tmp in path.parent.glob(f".{path.name}{TMP_MARK}*"):
        pid_text, _, rest = tmp.name[len(path.name) + 1 + len(TMP_MARK):].partition(".")
        host = rest.partition("-")[0] if "-" in rest else host_tag()   # older names carry no host
        if not pid_text.isdigit() or host != host_tag() or int(pid_text) == os.getpid():
            continue
        try:
            os.kill(int(pid_text), 0)
            continue                       # its writer still runs
        except ProcessLookupError:
            pass
        except PermissionError:
            continue                       # alive, owned by another user
        try:
            tmp.unlink()
            removed.append(tmp)
        except OSError:
            pass
    return removed


def write_netcdf(ds: xr.Dataset, path) -> Path:
    """Write a run or study archive as compressed CF NetCDF4 (`cf_ready`) atomically (temporary
    file, then rename) -> its path.

    The temporary name is unique per process and call, so concurrent writers of the same path
    (dask workers filling the FE spring cache) never share a half-written file; the last
    rename wins and readers only ever open complete files. Temporaries that a killed writer
    left behind are removed on the next write of the same path.
    """
    import os
    import uuid

    from study.errors import check_argument, is_path
    check_argument(hasattr(ds, "data_vars"), "write", "ds", "an xarray.Dataset", ds)
    check_argument(is_path(path), "write", "path", "a file path ending in .nc", path)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_stale_temporaries(path)
    tmp = path.with_name(f".{path.name}{TMP_MARK}{os.getpid()}.{host_tag()}-{uuid.uuid4().hex[:8]}")
    ds, enc = cf_ready(ds)
    try:
        ds.to_netcdf(tmp, engine="netcdf4", encoding=enc)
        os.replace(tmp, path)
    except (OSError, RuntimeError) as e:
        full = disk_full(e, path.parent, ds.nbytes)
        if full:
            raise full from None
        raise
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


# room a write needs beyond the data [bytes]: NetCDF4/HDF5 headers, chunk indexes
WRITE_MARGIN = 16 * 2 ** 20


def disk_full(error: Exception, folder: Path, data_bytes: float) -> OSError | None:
    """The error of a write into ``folder`` that a full disk caused, said as such (an OSError
    with errno ENOSPC: 'no space left on device'), or None. HDF5 reports it as 'NetCDF: HDF
    error' without an errno: the file system's free space (less than the data and a margin)
    tells it then."""
    import errno
    import shutil
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        free = None
    if getattr(error, "errno", None) != errno.ENOSPC and not (free is not None and free < data_bytes + WRITE_MARGIN):
        return None
    left = f"{free / 2 ** 20:.1f} MiB" if free is not None else "no room"
    return OSError(errno.ENOSPC, f"no space left on device: {left} free in {folder} for an archive of about "
                                 f"{data_bytes / 2 ** 20:.1f} MiB of data; free some space or write elsewhere (-o)")


def read_netcdf(path) -> xr.Dataset:
    """A run or study archive (NetCDF) read into memory -> xarray.Dataset (the file is closed)."""
    from study.errors import check_argument, is_path
    check_argument(is_path(path), "read", "path", "a NetCDF file's path", path)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()

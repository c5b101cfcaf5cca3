"""The options the `lightgear` commands share and their checks before any work: the archive to
write (`checked_output`), the archive to read (`checked_archive`), the scene and its ``--set``
overrides (`scene_arguments`, `args_scene`), ``--max-time``. A bad value raises UsageError
naming the option.
"""
from __future__ import annotations

from pathlib import Path

from study.errors import UsageError


def writable_folder(folder: Path, option: str = "-o") -> None:
    """Create ``folder`` if needed and prove that a file can be written in it, before any work.
    Missing folders are created under the working directory (``results/...``), and elsewhere
    one new folder in an existing one: a slip such as ``/nonexistent/dir`` never makes folders
    at the root of the file system."""
    import tempfile
    if folder.exists() and not folder.is_dir():
        raise UsageError(option, f"{folder} is a file, not a directory")
    if not folder.exists() and not folder.parent.is_dir() \
            and not folder.resolve().is_relative_to(Path.cwd().resolve()):
        raise UsageError(option, f"the folder {folder.parent} does not exist: outside the working directory lightgear "
                                 f"creates only the last folder of a path; create {folder.parent} first")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".lightgear-probe"):
            pass
    except OSError as e:
        raise UsageError(option, f"cannot write in {folder}: {e.strerror or e}") from None


# bytes that names derived from an archive's add to it: the temporary file of the atomic write
# (".NAME.tmpPID.HOST-XXXXXXXX"), a sweep's ".NAME.parts", precision's NAME_dynamic.nc
NAME_MARGIN = 40


def checked_output(path, option: str = "-o") -> Path:
    """An archive path that ends in .nc, is no directory, whose folder is writable and whose
    name (with the names derived from it) the file system takes."""
    import os
    path = Path(path)
    try:
        name_max = os.pathconf(path.parent if path.parent.is_dir() else ".", "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    too_long = [part for part in path.parts if len(part.encode()) > name_max]
    if too_long or len(path.name.encode()) + NAME_MARGIN > name_max:
        raise UsageError(option, f"a name of {len((too_long or [path.name])[0].encode())} bytes is too long: this file "
                                 f"system takes {name_max} bytes a name, and the archive's temporary and parts names "
                                 f"add up to {NAME_MARGIN} to its own: give a name of at most {name_max - NAME_MARGIN} bytes")
    if path.is_dir():
        raise UsageError(option, f"{path} is a directory; give the archive's file name (e.g. {path / 'run.nc'})")
    if path.suffix != ".nc":
        raise UsageError(option, f"archives are NetCDF files ending in .nc, got {path.name[:60]!r}")
    writable_folder(path.parent, option)
    return path


def max_time_argument(p) -> None:
    from study.estimate import DEFAULT_MAX_TIME_S
    p.add_argument("--max-time", type=float, default=DEFAULT_MAX_TIME_S, metavar="SECONDS",
                   help=f"refuse (exit 2, before any work) a run estimated to take longer (default {DEFAULT_MAX_TIME_S:g} s); "
                        "a run expected to take more than a few seconds shows a progress bar")


def checked_max_time(args) -> float:
    if not args.max_time > 0:
        raise UsageError("--max-time", f"must be a positive number of seconds, got {args.max_time}")
    return args.max_time


def scene_arguments(p, output: str | None, output_help: str = "archive to write (NetCDF)") -> None:
    """The scene file, the archive (when the command writes one) and ``--set`` overrides."""
    p.add_argument("scene", nargs="?", help="scene TOML, or the name of an embedded scene (`lightgear scenes`; "
                                            "default: the embedded paper example)")
    if output is not None:
        p.add_argument("-o", "--output", default=output, help=output_help)
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene field by its dotted path, e.g. --set gear2.body.holes=3")


def args_scene(args):
    """The scene of a command's arguments; an override without '=' (``--set key value``) gets a
    hint before the value is taken for a scene file."""
    import study
    for item in args.overrides:
        if "=" not in item:
            fix = f"--set {item}={args.scene}" if args.scene else f"--set {item}=VALUE"
            raise UsageError("--set", f"{item!r} is not key=value: write {fix} (no space around '=')")
    return study.load_scene(args.scene, args.overrides)


def checked_archive(name) -> Path:
    """An existing NetCDF file written by lightgear (its provenance attributes), else UsageError."""
    import xarray as xr
    path = Path(name)
    if not path.exists():
        raise UsageError("archive", f"no such file: {path}")
    if not path.is_file():
        raise UsageError("archive", f"{path} is not a file")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            attrs = dict(ds.attrs)
    except Exception as e:  # noqa: BLE001 - netCDF4/HDF5 raise many kinds for a damaged file
        reason = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise UsageError("archive", f"{path} is not a readable NetCDF file ({reason}); empty, truncated or of another kind") from None
    if "code_fingerprint" not in attrs:
        raise UsageError("archive", f"{path} is NetCDF but not a lightgear archive (no lightgear provenance attributes)")
    return path

"""A study's finished tasks on disk and its archive: one small file per task in
``.OUT.nc.parts/`` (`PartStore`, each written atomically), the task records the client holds
(without their curves), and the reading of a study archive.
"""
from __future__ import annotations

import os
import pickle
import shutil
import uuid
from pathlib import Path

import xarray as xr

from study.sweep.archive import study_key
from study.sweep.grid import Point, Study
from study.sweep.outputs import CURVES


class PartStore:
    """Finished tasks of a study, one pickle per task key, each written atomically."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)

    def get(self, key: str) -> dict | None:
        try:
            with open(self.folder / f"{key}.pkl", "rb") as f:
                return pickle.load(f)
        except FileNotFoundError:
            return None
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ValueError):
            return None  # unreadable record: the point is computed again

    def put(self, key: str, result: dict) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        tmp = self.folder / f".{key}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp"
        with open(tmp, "wb") as f:
            pickle.dump(result, f, protocol=pickle.HIGHEST_PROTOCOL)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.folder / f"{key}.pkl")

    def clear(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def parts_folder(output: str | Path) -> Path:
    output = Path(output)
    return output.with_name(f".{output.name}.parts")


def without_curves(result: dict) -> dict:
    """A task's record without its curves, only their names (they stay in its part file until
    the merge)."""
    out = {k: v for k, v in result.items() if k != "curves"}
    out["curve_names"] = tuple(result.get("curves", ()))
    return out


def open_archive(path) -> xr.Dataset:
    """A study archive with its per-point variables in memory; the curves (study dimensions x
    their axis: the bulk of a large study) are read from the file when used."""
    ds = xr.open_dataset(path, engine="netcdf4")
    for name, var in ds.data_vars.items():
        if name not in CURVES:
            var.load()
    return ds


def complete_archive(study: Study, points: list[Point], output) -> xr.Dataset | None:
    """The archive at ``output`` when it already holds every point of this very study."""
    if not Path(output).is_file() or parts_folder(output).exists():
        return None
    try:
        ds = open_archive(output)
    except (OSError, KeyError, ValueError):
        return None
    if ds.attrs.get("study_key") == study_key(study, points) and "status" in ds and not (ds["status"].values == 0).any():
        return ds
    ds.close()
    return None

"""lightgear's Python API: build or load a scene, run it, sweep a study, render an archive.

    import study
    scene = study.load_scene("study/scenes/paper.toml", ["dynamic.duration=0.05"])  # or study.default_scene()
    scene = scene.replace(**{"gear2.body.holes": 3})       # any field by its dotted path, checked
    ds = study.run_scene(scene)                            # xarray.Dataset: STE, DTE, spectra, springs
    study.write(ds, "results/run.nc")
    grid = {"gear2.body.holes": [0, 3, 6], "dynamic.speed": [50.0, 100.0]}
    st = study.make_study(scene, grid, outputs={"scalars": ["ste_p2p", "dte_rms"]}, title="holes and speed")
    res = study.run_sweep(st, "results/holes.nc", workers=0)    # res.dataset: one dimension per grid field
    study.render("results/holes.nc", "results/holes")          # PNG plots (and renders) of an archive

Scenes are in engineering units (mm, deg, N·m, rad/s, s; see `study.scene`), archives in CF
units (um, degree, s, Hz; see `study.report.results` and `study.sweep.archive`). An invalid
scene or study raises `SceneError` naming the dotted field, before any work starts.

Nothing heavy is imported with this package: each function imports its module when first
called, so ``import study`` loads neither gmsh, VTK, dask nor the numba kernels.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from study.scene import Scene, SceneError
    from study.sweep.engine import SweepResult
    from study.sweep.grid import Study
    from study.sweep.outputs import Outputs

# classes of the API, imported on first access: name -> module
_CLASSES = {
    "Scene": "study.scene",            # a checked, frozen scene; Scene.replace(**{dotted: value})
    "SceneError": "study.scene",       # invalid input; .field is the dotted path, .reason why
    "Study": "study.sweep.grid",       # a base scene, a grid and/or points, outputs
    "Outputs": "study.sweep.outputs",  # the scalars and curves a study archives
    "SweepResult": "study.sweep.engine",
}


def __getattr__(name: str):
    if name in _CLASSES:
        value = getattr(importlib.import_module(_CLASSES[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'study' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_CLASSES))


def load_scene(path=None, overrides=()):
    """The scene of a TOML file (None: the embedded paper example) with ``key=value`` overrides
    (``["gear2.body.holes=3"]``) -> Scene. SceneError names the offending field."""
    from study.scene import load_scene
    return load_scene(path, overrides)


def default_scene():
    """The embedded paper example (Table 1, driven gear lightened) -> Scene."""
    from study.scene import default_scene
    return default_scene()


def run_scene(scene, static: bool | None = None, dynamic: bool | None = None, max_time: float | None = None,
              progress: bool = False):
    """Run a scene -> run archive (xarray.Dataset): tooth springs, then the quasi-static STE and
    the dynamic DTE with their spectra. ``static``/``dynamic`` force an analysis on or off
    (None: as the scene's ``quasi_static.enabled`` / ``dynamic.enabled``). Output arrays that
    would not fit in memory, or with ``max_time`` [s] an estimated run time beyond it, raise
    `study.errors.BudgetError` before any work; ``progress``: bars on stderr for long parts."""
    from study.run import run_scene
    return run_scene(scene, static=static, dynamic=dynamic, max_time=max_time, progress=progress)


def write(ds, path):
    """Write a run or study archive as NetCDF (compressed, atomically) -> its path."""
    from pathlib import Path

    from study.report.results import write_netcdf
    write_netcdf(ds, path)
    return Path(path)


def read(path):
    """A run or study archive (NetCDF) read into memory -> xarray.Dataset."""
    import xarray as xr
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


def summarize(ds) -> dict:
    """The summary scalars of a run archive (STE mean and peak-to-peak [um], DTE RMS [um],
    amplitudes at the mesh and hole orders [um], largest tooth force [N], ...)."""
    from study.report.summary import summarize
    return summarize(ds)


def load_study(path):
    """A study file (base scene, [grid] and/or [[points]], [outputs]) read and checked -> Study."""
    from study.sweep.grid import load_study
    return load_study(path)


def make_study(scene=None, grid=None, points=(), outputs=None, title: str = "lightgear study"):
    """A study built in Python, checked exactly like a study file -> Study.

    ``scene``: the base Scene (None: the paper example); ``grid``: {dotted field: list of values
    or {"start", "stop", "num"}}, one archive dimension per field in the dict's order;
    ``points``: explicit points [{dotted field: value}]; ``outputs``: {"scalars": [...],
    "curves": [...]} (None: every scalar of `study.sweep.outputs.SCALARS`, no curve).
    """
    from study.sweep.grid import make_study
    return make_study(scene, grid, points, outputs, title)


def run_sweep(study, output, workers: int | None = None, scheduler: str | None = None, progress: bool = True,
              keep_parts: bool = False):
    """Compute a study's points into one archive at ``output`` (NetCDF) -> SweepResult
    (``.dataset``, ``.computed``, ``.reused``, ``.invalid``, ``.pending``, ``.wall_time`` [s]).

    ``workers=0`` runs the points in this process; None: a dask LocalCluster with one worker per
    core; ``scheduler``: the address of an existing dask cluster. Finished points are kept on
    disk, so the same call after an interruption computes only the missing ones. The returned
    dataset is the archive as written, its curves read from the file when used.
    """
    from study.sweep.engine import run_sweep
    return run_sweep(study, output, workers=workers, scheduler=scheduler, progress=progress, keep_parts=keep_parts)


def render(archive, out_dir=None, renders: bool = True, limits: dict | None = None) -> list:
    """Plots (and, unless ``renders=False``, pyvista renders) of a run or study archive as PNG
    files in ``out_dir`` (default: beside the archive file) -> their paths. ``archive``: a
    path or an xarray.Dataset; ``limits`` ({output: value}, sampled studies): the probability
    of exceeding each."""
    from pathlib import Path

    from study.report.figures import make_figures
    if not hasattr(archive, "data_vars"):
        path = Path(archive)
        if not path.is_file():
            raise FileNotFoundError(f"no such archive: {path}")
        out_dir = path.parent if out_dir is None else out_dir
        archive = read(path)
    elif out_dir is None:
        raise ValueError("render: out_dir is needed for a dataset")
    return make_figures(archive, Path(out_dir), renders=renders, limits=limits)


__all__ = ["Scene", "SceneError", "Study", "Outputs", "SweepResult", "load_scene", "default_scene", "run_scene", "write",
           "read", "summarize", "load_study", "make_study", "run_sweep", "render"]

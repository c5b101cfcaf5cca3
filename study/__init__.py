"""lightgear's Python API: build or load a scene, run it, sweep a study, render an archive.

    import study
    scene = study.load_scene("paper", ["dynamic.duration=0.05"])   # an embedded scene by name, or a file
    scene = scene.replace(**{"gear2.body.holes": 3})       # any field by its dotted path, checked
    ds = study.run_scene(scene)                            # xarray.Dataset: STE, DTE, spectra, springs
    study.write(ds, "results/run.nc")
    grid = {"gear2.body.holes": [0, 3, 6], "dynamic.speed": [50.0, 100.0]}
    st = study.make_study(scene, grid, outputs={"scalars": ["ste_p2p", "dte_rms"]}, title="holes and speed")
    res = study.run_sweep(st, "results/holes.nc", workers=0)    # res.dataset: one dimension per grid field
    study.render("results/holes.nc", "results/holes")          # PNG plots (and renders) of an archive

Scenes are in engineering units (mm, deg, N·m, rad/s, s; see `study.scene`), archives in CF
units (um, degree, s, Hz; see `study.archive.schema` and `study.sweep.archive`). An invalid
scene or study raises `SceneError` naming the dotted field, before any work starts.

Nothing heavy is imported with this package: each function imports its module when first
called, so ``import study`` loads neither gmsh, VTK, dask nor the numba kernels.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from study.errors import BudgetError, StudyError
    from study.scene import Scene, SceneError
    from study.sweep.engine import SweepResult
    from study.sweep.grid import Study
    from study.sweep.outputs import STATUS, Outputs

# classes of the API, imported on first access: name -> module
_CLASSES = {
    "Scene": "study.scene",            # a checked, frozen scene; Scene.replace(**{dotted: value})
    "SceneError": "study.scene",       # invalid input; .field is the dotted path, .reason why
    "Study": "study.sweep.grid",       # a base scene, a grid and/or points, outputs
    "Outputs": "study.sweep.outputs",  # the scalars and curves a study archives
    "SweepResult": "study.sweep.engine",
    "StudyError": "study.errors",      # invalid study input (a SceneError)
    "BudgetError": "study.errors",     # a run refused by its estimate (memory, max_time)
    "STATUS": "study.sweep.outputs",   # a sweep point's status flags: pending, ok, diverged, invalid, failed, inaccurate
}


def __getattr__(name: str):
    if name in _CLASSES:
        value = getattr(importlib.import_module(_CLASSES[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'study' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_CLASSES))


# ---------------------------------------------------------------- argument checks

def _is_path(x) -> bool:
    import os
    return isinstance(x, str | os.PathLike)


def _check(ok: bool, function: str, argument: str, takes: str, value) -> None:
    """TypeError naming the function, the argument and what it takes, when not ``ok``."""
    if not ok:
        raise TypeError(f"{function}: {argument} takes {takes}, got {type(value).__name__} {value!r:.80}")


def _check_scene(function: str, scene) -> None:
    from study.scene import Scene
    _check(isinstance(scene, Scene), function, "scene", "a Scene (study.load_scene(path or name), "
           "study.default_scene(), Scene.replace(...))", scene)


# ---------------------------------------------------------------- scenes

def scenes() -> dict:
    """The scenes and studies that ship with lightgear, by name -> (file, 'scene' or 'study', title).
    `load_scene` and `load_study` take these names (``study.load_scene("runup")``)."""
    from study.scene import embedded_scenes
    return embedded_scenes()


def fields(prefix: str = "") -> list:
    """The scene fields under a dotted ``prefix`` ('' = all), each with its path, kind, unit,
    default, allowed range and meaning (`study.docs.FieldRow`), as `lightgear fields` lists them."""
    from study.docs import field_rows
    _check(isinstance(prefix, str), "fields", "prefix", "a dotted path such as 'gear2.body'", prefix)
    return field_rows(prefix)


def outputs() -> list:
    """The sweep outputs: (name, 'scalar' or 'curve over AXIS', units, analysis, meaning) each, as
    `lightgear outputs` lists them."""
    from study.docs import output_rows
    return output_rows()


def parse_overrides(items) -> dict:
    """``["gear2.body.holes=3", ...]`` -> {"gear2.body.holes": 3, ...} (values parse as TOML, else
    as text), for `Scene.replace` or `make_study`."""
    from study.scene import parse_override
    _check(not isinstance(items, str | bytes), "parse_overrides", "items", 'a list of "key=value" strings', items)
    return dict(parse_override(str(item)) for item in items)


def load_scene(path=None, overrides=()):
    """A scene -> Scene: ``path`` a TOML file or the name of an embedded scene (``"runup"``;
    `scenes` lists them; None: the paper example), with ``overrides`` as ``["key=value", ...]``
    or ``{"dotted.key": value}``. SceneError names the offending field."""
    from collections.abc import Mapping

    from study.scene import load_scene
    _check(path is None or _is_path(path), "load_scene", "path",
           "a scene file's path or an embedded scene's name (str or os.PathLike; None: the paper example); "
           "for fields given in Python use study.default_scene().replace(**{...})", path)
    if isinstance(overrides, Mapping):
        scene = load_scene(path)
        return scene.replace(**dict(overrides)) if overrides else scene
    _check(not isinstance(overrides, str | bytes) and all(isinstance(o, str) for o in overrides), "load_scene",
           "overrides", 'a list of "key=value" strings or a dict {dotted key: value}', overrides)
    return load_scene(path, overrides)


def default_scene():
    """The embedded paper example (Table 1, driven gear lightened) -> Scene."""
    from study.scene import default_scene
    return default_scene()


def solid_scene(scene, gears=(1, 2)):
    """The scene with the bodies of ``gears`` made solid (no holes, the web as thick as the face) -> Scene."""
    _check_scene("solid_scene", scene)
    return scene.solid(gears=tuple(gears))


def check_dynamic_window(scene) -> None:
    """SceneError when the scene's dynamic run leaves no steady part after its ramps for the DTE
    summary and spectrum (`lightgear run` checks it; integrator studies end with the ramps on purpose)."""
    from study.plausibility import check_dynamic_window as check
    _check_scene("check_dynamic_window", scene)
    check(scene)


def plausibility_warnings(scene) -> list:
    """Values that are valid but almost certainly a unit slip (a hole smaller than the FE mesh,
    a pitch-line velocity above 100 m/s) -> their messages; `run_scene` prints them on stderr and
    keeps them in the archive's ``plausibility_warnings`` attribute."""
    from study.plausibility import scene_warnings
    _check_scene("plausibility_warnings", scene)
    return scene_warnings(scene)


# ---------------------------------------------------------------- one run

def run_scene(scene, static: bool | None = None, dynamic: bool | None = None, max_time: float | None = None,
              progress: bool = False):
    """Run a scene -> run archive (xarray.Dataset): tooth springs, then the quasi-static STE and
    the dynamic DTE with their spectra. ``static``/``dynamic`` force an analysis on or off
    (None: as the scene's ``quasi_static.enabled`` / ``dynamic.enabled``). Output arrays that
    would not fit in memory, or with ``max_time`` [s] an estimated run time beyond it, raise
    `BudgetError` before any work; ``progress``: bars on stderr for long parts. Plausibility
    warnings (see `plausibility_warnings`, and a speed far above the highest critical speed of
    the mesh orders) go to stderr and the archive's ``plausibility_warnings`` attribute."""
    _check_scene("run_scene", scene)
    for name, v in (("static", static), ("dynamic", dynamic)):
        _check(v is None or isinstance(v, bool), "run_scene", name, "True, False or None (as the scene says)", v)
    _check(max_time is None or (_number(max_time) and max_time > 0), "run_scene", "max_time",
           "a positive number of seconds or None", max_time)
    from study.run import run_scene
    return run_scene(scene, static=static, dynamic=dynamic, max_time=max_time, progress=bool(progress))


def write(ds, path):
    """Write a run or study archive as NetCDF (compressed, atomically) -> its path."""
    from pathlib import Path

    from study.archive.netcdf import write_netcdf
    _check(hasattr(ds, "data_vars"), "write", "ds", "an xarray.Dataset", ds)
    _check(_is_path(path), "write", "path", "a file path ending in .nc", path)
    write_netcdf(ds, path)
    return Path(path)


def read(path):
    """A run or study archive (NetCDF) read into memory -> xarray.Dataset."""
    import xarray as xr
    _check(_is_path(path), "read", "path", "a NetCDF file's path", path)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


def summarize(ds) -> dict:
    """The summary scalars of an archive. A run archive: {name: float} (STE mean and
    peak-to-peak [um], DTE RMS [um], amplitudes at the mesh and hole orders [um], largest tooth
    force [N], ...). A sweep archive: {name: xarray.DataArray} of its scalars over the swept
    dimensions, NaN where a point is not ok (its status)."""
    from study.archive.summary import summarize
    from study.sweep.outputs import summarize_sweep
    _check(hasattr(ds, "data_vars"), "summarize", "ds", "a run or sweep archive (xarray.Dataset; study.read(path))", ds)
    if "status" in ds.data_vars and "study_key" in ds.attrs:
        return summarize_sweep(ds)
    return summarize(ds)


def print_summary(ds, path, wall_time: float) -> None:
    """The one-screen summary `lightgear run` prints for a run archive written to ``path`` after
    ``wall_time`` [s]."""
    from study.report.summary import print_summary as show
    show(ds, path, wall_time)


# ---------------------------------------------------------------- studies

def load_study(path):
    """A study file, or an embedded study by name (``"sensitivity"``; `scenes` lists them): base
    scene, [grid] and/or [[points]], [outputs], read and checked -> Study (StudyError names the field)."""
    from study.sweep.grid import load_study
    _check(_is_path(path), "load_study", "path", "a study file's path or an embedded study's name (str or os.PathLike)",
           path)
    return load_study(path)


def make_study(scene=None, grid=None, points=(), outputs=None, title: str = "lightgear study"):
    """A study built in Python, checked exactly like a study file -> Study.

    ``scene``: the base Scene (None: the paper example); ``grid``: {dotted field: list of values
    (NumPy arrays too) or {"start", "stop", "num"}}, one archive dimension per field in the
    dict's order; ``points``: explicit points [{dotted field: value}]; ``outputs``: a list of
    output names (`outputs` lists them: scalars and curves), or {"scalars": [...], "curves":
    [...]} (None: every scalar, no curve).
    """
    from study.sweep.grid import make_study
    return make_study(scene, grid, points, outputs, title)


def run_sweep(study, output, workers: int | None = None, scheduler: str | None = None, progress: bool = True,
              keep_parts: bool = False):
    """Compute a study's points into one archive at ``output`` (NetCDF) -> SweepResult
    (``.dataset``, ``.computed``, ``.reused``, ``.invalid``, ``.pending``, ``.wall_time`` [s]).

    ``workers=0`` runs the points in this process; None: a dask LocalCluster with one worker per
    core (its worker processes import the calling script again: a script needs
    ``if __name__ == "__main__":``); ``scheduler``: the address of an existing dask cluster.
    Finished points are kept on disk, so the same call after an interruption computes only the
    missing ones. The returned dataset is the archive as written, its curves read from the file
    when used.
    """
    from study.sweep.grid import Study
    _check(isinstance(study, Study), "run_sweep", "study", "a Study (study.make_study(scene, grid={...}) or "
           "study.load_study(path or name))", study)
    _check(_is_path(output), "run_sweep", "output", "the archive's path ending in .nc (str or os.PathLike)", output)
    workers = _workers("run_sweep", workers)
    _check(scheduler is None or isinstance(scheduler, str), "run_sweep", "scheduler",
           "a dask scheduler address such as 'tcp://host:8786', or None", scheduler)
    from study.sweep.engine import run_sweep
    return run_sweep(study, output, workers=workers, scheduler=scheduler, progress=bool(progress),
                     keep_parts=bool(keep_parts))


def _number(x) -> bool:
    import numbers
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _workers(function: str, workers):
    import numbers
    _check(workers is None or (isinstance(workers, numbers.Integral) and not isinstance(workers, bool)), function,
           "workers", "an integer >= 0 (0: in this process) or None (one per core)", workers)
    if workers is not None and workers < 0:
        raise ValueError(f"{function}: workers takes an integer >= 0 (0: in this process) or None (one per core), "
                         f"got {workers}")
    return None if workers is None else int(workers)


def local_cluster(workers: int | None = None):
    """A dask LocalCluster for several sweeps in a row, as a context manager that yields its
    scheduler address (give it to `run_sweep` as ``scheduler``); ``workers``: processes (None:
    one per core; 0: yields None, the sweeps then run in this process)."""
    import contextlib
    workers = _workers("local_cluster", workers)

    @contextlib.contextmanager
    def cluster():
        if workers == 0:
            yield None
            return
        from study.sweep.engine import check_main_guard, dask_client
        check_main_guard()
        with dask_client(None, workers) as client:
            yield client.scheduler.address
    return cluster()


def pareto(ds, stress_ratio: float = 1.15):
    """The Pareto sets of a study's points: lightest against ``ste_p2p`` and ``dte_rms`` among
    the points whose ``root_stress_ratio_gear2`` stays within ``stress_ratio`` -> Dataset of int8
    flags (`study.report.effects.pareto_table`)."""
    from study.report.effects import pareto_table
    return pareto_table(ds, stress_ratio)


def tradeoff_figure(ds, pareto_flags, path, te_limits=None, chosen=None):
    """The trade-off figure of a study (mass saving against STE p2p and DTE RMS, coloured by root
    stress, the Pareto set marked; optional TE limits {output: value} and a chosen point index)
    written to ``path`` (PNG) -> its path."""
    from study.report.study_views import tradeoff_figure as figure
    return figure(ds, pareto_flags, path, te_limits=te_limits, chosen=chosen)


def render(archive, out_dir=None, renders: bool = True, limits: dict | None = None) -> list:
    """Plots (and, unless ``renders=False``, pyvista renders) of a run or study archive as PNG
    files in ``out_dir`` (default: beside the archive file) -> their paths. ``archive``: a
    path or an xarray.Dataset; ``limits`` ({output: value}, sampled studies): the probability
    of exceeding each. The renders of a lightened body draw its FE fields from the FE cache
    (solved and cached once when missing)."""
    from pathlib import Path

    from study.report.figures import make_figures
    if not hasattr(archive, "data_vars"):
        _check(_is_path(archive), "render", "archive", "an archive's path or an xarray.Dataset", archive)
        path = Path(archive)
        if not path.is_file():
            raise FileNotFoundError(f"no such archive: {path}")
        out_dir = path.parent if out_dir is None else out_dir
        archive = read(path)
    elif out_dir is None:
        raise ValueError("render: out_dir is needed for a dataset")
    fields = None
    if renders and "scene" in archive.attrs and "tooth_stiffness" in archive and "status" not in archive:
        from study.inputs.springs import archive_body_fields
        fields = archive_body_fields(archive)      # what the renders of a lightened body draw: FE cache, else solved
    return make_figures(archive, Path(out_dir), renders=renders, limits=limits, fields=fields)


# ---------------------------------------------------------------- the other commands

def stiffness(scene, max_time: float | None = None, progress: bool = False):
    """Per-tooth FE stiffness map of both gears (`lightgear stiffness`) -> xarray.Dataset
    (``tooth_stiffness`` [N mm/rad^n], ``stiffness_ratio`` [1] over gear and tooth); ``max_time``
    [s]: refuse (BudgetError) a map estimated to take longer, before any work."""
    from study.commands import stiffness as run
    _check_scene("stiffness", scene)
    return run(scene, max_time, progress)


def identify_spring(scene, gear: int):
    """Tooth 0's spring of gear 1 or 2 fitted to its FE body's compliance along the profile
    (`lightgear stiffness --identify`) -> SpringIdentification (``pivot_radius_mm`` [mm],
    ``k_phi`` [N mm/rad^n], ``n`` [1], ``rms_rel_error`` [1])."""
    from study.commands import identify_spring as fit
    _check_scene("identify_spring", scene)
    return fit(scene, gear)


def fit_contact(scene, depth_fraction: float = 0.5):
    """Weber's contact deflection of the scene's pair fitted to F = k_con delta^m1 (`lightgear
    fit-contact`) -> ContactFit (``k_con`` [N/mm^m1], ``m1`` [1], ``depth_mm``, ``force_range_N``, ...)."""
    from study.commands import fit_contact as fit
    _check_scene("fit_contact", scene)
    return fit(scene, depth_fraction)


def reference(scene, step: float | None = None, max_time: float | None = None, progress: bool = False,
              solver: str = "ltca", flank_size: float | None = None, contact_stiffness: float | None = None):
    """FE reference STE (`lightgear reference`) -> xarray.Dataset (``ste`` [um] over ``angle``
    [degree], attribute ``backlash_offset_um``); ``step`` [deg]: driver angle step (None:
    quasi_static.angle_step); ``max_time`` [s]: refuse a longer estimate (BudgetError).
    ``solver``: "ltca" (default: loaded-tooth-contact analysis, also ``ste_tooth_force`` [N]) or
    "calculix" (the independent FE contact peer; needs ccx) with ``flank_size`` [mm] and
    ``contact_stiffness`` [MPa/mm] (None: the defaults)."""
    from study.commands import reference as run
    _check_scene("reference", scene)
    _check(step is None or _number(step), "reference", "step", "a number of degrees or None", step)
    _check(solver in ("ltca", "calculix"), "reference", "solver", "'ltca' or 'calculix'", solver)
    for name, v in (("flank_size", flank_size), ("contact_stiffness", contact_stiffness)):
        _check(v is None or _number(v), "reference", name, "a number or None", v)
    return run(scene, step, max_time, progress, solver, flank_size, contact_stiffness)


def precision(scene, output=None, duration: float = 0.002, ramp_fraction: float = 0.5, rotation: float = 6.0,
              repeats: int = 3, only: str | None = None, progress=None) -> dict:
    """Work-precision studies (`lightgear precision`): TE error [um] against wall time [s] for
    every solver -> {"static": Dataset, "dynamic": Dataset}; with ``output`` (BASE.nc) written to
    BASE_static.nc and BASE_dynamic.nc with their plots. See `study.commands.precision`."""
    from study.commands import precision as run
    _check_scene("precision", scene)
    _check(output is None or _is_path(output), "precision", "output", "an archive base name ending in .nc, or None",
           output)
    return run(scene, output, duration, ramp_fraction, rotation, repeats, only, progress)


def precision_table(ds) -> str:
    """A work-precision dataset as a text table (method, setting, errors, wall time) with the
    cheapest run for 0.1 um and 0.01 um."""
    from study.verify.precision import table
    return table(ds)


def stability_suite(scene, duration: float = 0.002, methods=None, scipy_wall: float = 20.0, names=None,
                    mesh_size: float = 1.0, progress=print):
    """Stiff and extreme variants of a scene, each run with every integrator -> Dataset over
    (scene, method): status, message, TE range [um], largest contact force [N], step [s], wall
    time [s] (`study.verify.stability`)."""
    from study.verify.stability import METHODS, run_suite
    _check_scene("stability_suite", scene)
    return run_suite(scene, duration, tuple(methods or METHODS), scipy_wall, names, mesh_size, progress)


def validation(scene, step: float | None = None):
    """STE of the pseudo-rigid models (plain, plain-fe, coupled, compliance) against the FE
    reference for the scene's pair with its driven gear solid and lightened -> Dataset over
    (pair, model, angle [degree]) with the error figures [um] (`study.verify.validation`)."""
    import time

    from study.scene_model import static_angles
    from study.verify.fe_reference import REFERENCE_MEMORY_FACTOR
    from study.verify.validation import validation_dataset
    _check_scene("validation", scene)
    _check(step is None or _number(step), "validation", "step", "a number of degrees or None", step)
    if scene.coupling.model != "none":       # the plain model is the scene's own; the coupled ones are built from it
        scene = scene.replace(**{"coupling.model": "none"})
    t0 = time.perf_counter()
    ds = validation_dataset(scene, static_angles(scene, step, REFERENCE_MEMORY_FACTOR))
    ds.attrs["wall_time_s"] = time.perf_counter() - t0
    return ds


def validate_design_space(scene, holes=(0, 3, 6, 9, 12), webs=(6.0, 10.0), rims=(5.0, 7.0), rotation: float = 120.0,
                          step: float = 0.1, log=None):
    """STE of every model (paper, body-torsion, compliance) and the FE reference over gear 2's
    body: hole counts x web thickness [mm] x rim height [mm], at the scene's quasi-static torque,
    over ``rotation`` [deg] at ``step`` [deg] -> Dataset (mean, elastic mean and p2p [um],
    hole-order amplitude [um]; `study.verify.model_validation`)."""
    from study.verify.model_validation import design_space_dataset
    _check_scene("validate_design_space", scene)
    return design_space_dataset(scene, holes=holes, webs=webs, rims=rims, rotation=rotation, step=step, log=log)


def validate_relief(scene, reliefs=(0.0, 1.0, 2.0, 3.0, 4.0, 6.0), torques=(25.0, 50.0, 100.0), step: float = 0.1,
                    log=None):
    """STE peak-to-peak of every model and the FE reference for the scene's pair with its driven
    gear solid and as given, with a linear tip relief [um] of each amount on both gears at each
    torque [N·m], and the relief that minimises it -> Dataset (`study.verify.model_validation`)."""
    from study.verify.model_validation import relief_dataset
    _check_scene("validate_relief", scene)
    return relief_dataset({"solid": scene.solid(), "paper": scene}, reliefs=reliefs, torques=torques,
                          rotations={"solid": 30.0, "paper": 60.0}, step=step, log=log)


def validation_errors(ds):
    """Relative errors [1] of every model of a `validate_design_space` or `validate_relief`
    dataset against the FE reference: elastic mean, p2p, hole order."""
    from study.verify.model_validation import relative_errors
    return relative_errors(ds)


def validation_misses(ds, model: str = "compliance") -> list:
    """The points of a validation dataset where ``model`` misses its target (text; empty: none)."""
    from study.verify.model_validation import check_targets
    return check_targets(ds, model)


# ---------------------------------------------------------------- sampled (tolerance) studies

def sample_outputs(ds) -> list:
    """The scalar outputs of a sampled study's archive (over ``sample`` and the grid dimensions)."""
    from study.report.distributions import sample_outputs as outputs_of
    return outputs_of(ds)


def sample_tables(ds, outputs=None, limits=None):
    """The statistics of a sampled study's archive -> Dataset: per output and grid point the mean
    and percentiles with their confidence intervals, per limit ({output: value}) the probability
    of exceeding it, and the Sobol indices of a Saltelli design (`study.report.distributions`)."""
    from study.report.distributions import sample_tables as tables
    return tables(ds, outputs, limits)


def sample_points(ds) -> list:
    """Every grid point of a sampled study's archive as {dimension: index} ([{}] without a grid)."""
    from study.report.distributions import grid_points
    return grid_points(ds)


def sample_point_label(ds, at: dict) -> str:
    """'gear1.errors.grade = 5' for a grid point {dimension: index} of a sampled study ('all builds' for {})."""
    from study.report.distributions import point_label
    return point_label(ds, at)


def study_from_dict(raw: dict, folder=None):
    """A study from the tables of a study file as a dict (title, scene, grid, points, sample,
    outputs), checked like the file; relative scene paths are read from ``folder``."""
    from study.sweep.grid import dumps_study, loads_study
    _check(isinstance(raw, dict), "study_from_dict", "raw", "a dict of study tables", raw)
    return loads_study(dumps_study(raw), folder)


def export(archive, outdir=None) -> list:
    """The variables of an archive (path or Dataset) as CSV files in ``outdir`` (default: beside
    the archive), one per dimension group, with units in the headers -> their paths
    (`study.report.export`)."""
    from pathlib import Path

    import xarray as xr

    from study.report.export import export_csv
    if isinstance(archive, xr.Dataset):
        _check(outdir is not None, "export", "outdir", "a folder (needed for a Dataset)", outdir)
        return export_csv(archive, Path(outdir))
    _check(_is_path(archive), "export", "archive", "a NetCDF path or a Dataset", archive)
    path = Path(archive)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return export_csv(ds, Path(outdir) if outdir is not None else path.with_name(f"{path.stem}_csv"))


def script_main(name: str, main) -> int:
    """Run a script's ``main()`` as the command line runs a command: the errors a user can meet
    as one line on stderr starting with ``name`` and the exit codes of `lightgear --help` (2 bad
    input, 130 interrupted by Ctrl-C or SIGTERM), no traceback."""
    from study.cli import script_main as run
    return run(name, main)


__all__ = ["Scene", "SceneError", "StudyError", "BudgetError", "Study", "Outputs", "SweepResult", "STATUS",
           "scenes", "fields", "outputs", "parse_overrides", "load_scene", "default_scene", "solid_scene",
           "check_dynamic_window", "plausibility_warnings", "run_scene", "write", "read", "summarize",
           "print_summary", "load_study", "make_study", "run_sweep", "local_cluster", "pareto", "tradeoff_figure",
           "render", "stiffness", "identify_spring", "fit_contact", "reference", "precision", "precision_table",
           "stability_suite", "validation", "validate_design_space", "validate_relief", "validation_errors",
           "validation_misses", "sample_outputs", "sample_tables", "sample_points", "sample_point_label",
           "study_from_dict", "export", "script_main"]

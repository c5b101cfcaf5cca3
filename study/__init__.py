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

Each name is the function or class of the module that does the work (`_OFFERED` says which),
imported on first use: ``import study`` loads neither gmsh, VTK, dask nor the numba kernels.
Each function checks its own arguments: a wrong type raises TypeError naming it, the argument
and what it takes.
"""
from __future__ import annotations

import importlib

# what the API offers: name -> (module, name there), imported on first access
_OFFERED = {
    # classes
    "Scene": ("study.scene", "Scene"),                  # a checked, frozen scene; Scene.replace(**{dotted: value})
    "SceneError": ("study.scene", "SceneError"),        # invalid input; .field is the dotted path, .reason why
    "Study": ("study.sweep.grid", "Study"),             # a base scene, a grid and/or points, outputs
    "Outputs": ("study.sweep.outputs", "Outputs"),      # the scalars and curves a study archives
    "SweepResult": ("study.sweep.engine", "SweepResult"),
    "StudyError": ("study.errors", "StudyError"),       # invalid study input (a SceneError)
    "BudgetError": ("study.errors", "BudgetError"),     # a run refused by its estimate (memory, max_time)
    "STATUS": ("study.sweep.outputs", "STATUS"),        # a sweep point's status flags: pending, ok, ...
    # scenes
    "scenes": ("study.scene", "embedded_scenes"),
    "fields": ("study.docs", "field_rows"),
    "outputs": ("study.docs", "output_rows"),
    "parse_overrides": ("study.scene", "parse_overrides"),
    "load_scene": ("study.scene", "load_scene"),
    "default_scene": ("study.scene", "default_scene"),
    "solid_scene": ("study.scene", "solid_scene"),
    "check_dynamic_window": ("study.plausibility", "check_dynamic_window"),
    "plausibility_warnings": ("study.plausibility", "scene_warnings"),
    # one run and its archive
    "run_scene": ("study.run", "run_scene"),
    "write": ("study.archive.netcdf", "write_netcdf"),
    "read": ("study.archive.netcdf", "read_netcdf"),
    "summarize": ("study.sweep.outputs", "archive_summary"),
    "print_summary": ("study.report.summary", "print_summary"),
    # studies
    "load_study": ("study.sweep.grid", "load_study"),
    "make_study": ("study.sweep.grid", "make_study"),
    "study_from_dict": ("study.sweep.grid", "study_from_dict"),
    "run_sweep": ("study.sweep.engine", "run_sweep"),
    "local_cluster": ("study.sweep.engine", "local_cluster"),
    "pareto": ("study.report.effects", "pareto_table"),
    "tradeoff_figure": ("study.report.study_views", "tradeoff_figure"),
    "render": ("study.commands", "render"),
    "export": ("study.commands", "export"),
    "write_report": ("study.commands", "write_report"),
    "add_default_model": ("study.archive.summary", "add_default_model"),
    # opening shapes
    "equal_mass": ("study.mass_match", "equal_mass"),
    "describe_openings": ("study.mass_match", "describe_openings"),
    "opening_outline": ("study.mass_match", "opening_outline"),
    "opening_order_amplitude": ("study.mass_match", "opening_order_amplitude"),
    "validate_bodies": ("study.verify.model_validation", "validate_bodies"),
    # the other commands
    "stiffness": ("study.commands", "stiffness"),
    "identify_spring": ("study.commands", "identify_spring"),
    "fit_contact": ("study.commands", "fit_contact"),
    "reference": ("study.commands", "reference"),
    "precision": ("study.commands", "precision"),
    "precision_table": ("study.verify.precision_report", "table"),
    "precision_mesh": ("study.commands", "precision_mesh"),
    "precision_mesh_table": ("study.verify.precision_mesh", "mesh_table"),
    "stability_suite": ("study.verify.stability", "run_suite"),
    "validation": ("study.verify.validation", "validation"),
    "validate_design_space": ("study.verify.model_validation", "design_space_dataset"),
    "validate_relief": ("study.verify.model_validation", "validate_relief"),
    "validation_errors": ("study.verify.model_validation", "relative_errors"),
    "validation_misses": ("study.verify.model_validation", "check_targets"),
    # sampled (tolerance) studies
    "sample_outputs": ("study.report.distributions", "sample_outputs"),
    "sample_tables": ("study.report.distributions", "sample_tables"),
    "sample_points": ("study.report.distributions", "grid_points"),
    "sample_point_label": ("study.report.distributions", "point_label"),
    # scripts
    "script_main": ("study.process", "script_main"),
}


def __getattr__(name: str):
    if name in _OFFERED:
        module, attribute = _OFFERED[name]
        value = getattr(importlib.import_module(module), attribute)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'study' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_OFFERED))


__all__ = list(_OFFERED)

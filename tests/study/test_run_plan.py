"""A run makes its plan once (`study.plan`): in one `run_scene` the gear setups are prepared
once, the scene's model built once and the loaded equilibria asked for once, whatever the
stages that read them (damping conversion, modes, step bound, free decay, mesh, strength).
Counted with counters put in place of the functions wherever they are imported."""
import importlib
import sys

import numpy as np
import pytest

import study
from solver.store import STORE

# the paper example, its whole run kept short: every stage runs (FE springs, compliance fits,
# damping conversion, modes and free decay, statics, mesh, dynamic run with K_v, strength)
SHORT = ["quasi_static.rotation=6.0", "quasi_static.angle_step=0.5", "dynamic.duration=0.03",
         "dynamic.ramp_time=0.005"]


def counter(monkeypatch, module: str, name: str) -> list:
    """Calls of ``module.name`` from here on, wherever the function is bound (a module's
    ``from ... import name`` included): the list of their positional arguments."""
    real = getattr(importlib.import_module(module), name)
    calls = []

    def counted(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)
    for mod in list(sys.modules.values()):
        if getattr(mod, "__name__", "").startswith(("study", "solver")) and getattr(mod, name, None) is real:
            monkeypatch.setattr(mod, name, counted)
    return calls


@pytest.fixture
def counted(monkeypatch):
    import study.plan  # noqa: F401  (every module that binds a counted function loaded first)
    import study.run  # noqa: F401
    import study.stages  # noqa: F401
    return {name: counter(monkeypatch, module, name) for module, name in (
        ("study.inputs.gearsetup", "gear_setups"),
        ("study.scene_model", "scene_model"),
        ("study.scene_model", "geometry_model"),
        ("solver.mbs.model", "build_model"),
        ("solver.mbs.equilibria", "loaded_equilibria"),
    )}


def test_one_run_of_the_paper_scene_makes_its_setups_model_and_equilibria_once(counted):
    scene = study.load_scene("paper", SHORT)
    STORE.clear()       # a new process: nothing held in memory (the disk FE cache may hold the bodies)
    ds = study.run_scene(scene, warn=False)
    assert len(counted["gear_setups"]) == 1
    assert len(counted["scene_model"]) == 1
    # the solver's assembly: the model, and for the compliance fits of both gears the pair's
    # kinematics (plain springs) once, when the fits are made rather than kept
    assert len(counted["geometry_model"]) <= 1
    assert len(counted["build_model"]) == 1 + len(counted["geometry_model"])
    assert len(counted["loaded_equilibria"]) == 1
    # ... and every stage ran on them: the damping ratio reached, the step bound and modes
    # from those equilibria, the free decay, the mesh, K_v and the strength
    assert ds.attrs["mesh_mode_damping"] == pytest.approx(ds.attrs["mesh_damping_ratio_requested"], rel=1e-3)
    assert np.isfinite(ds.attrs["mesh_mode_damping_decay"])
    for name in ("mesh_stiffness", "dte", "dynamic_factor", "bending_stress", "mass", "critical_speed"):
        assert name in ds, name
    assert np.isfinite(float(ds["dynamic_factor"])) and ds.attrs["dynamic_method"] == "explicit"


def test_the_stages_asked_are_the_only_ones_that_run(counted):
    """A study's statics-only task: no modes, no dynamic run, no strength; the plan asks no
    equilibria beyond the damping conversion's."""
    from study.plan import RunOptions
    from study.run import run_fields
    scene = study.load_scene("paper", SHORT)
    run = run_fields(scene, {"static"}, RunOptions(warn=False, archive=False))
    assert "ste" in run and "mode_frequency" not in run and "dte" not in run and "bending_stress" not in run
    assert "mass" not in run and "mesh_stiffness" not in run
    assert len(counted["gear_setups"]) == 1 and len(counted["scene_model"]) == 1
    assert len(counted["loaded_equilibria"]) <= 1
    with pytest.raises(ValueError, match="stages: unknown statics"):
        run_fields(scene, {"statics"})


def test_the_statics_and_the_mesh_run_before_the_free_decay_and_keep_their_place_in_the_archive(monkeypatch):
    """The modes' free decay is a run's first call of the time stepping, which a second process
    compiles on a cold kernel cache (`solver.precompile`): the statics and the mesh, which do not
    need it, run first; their variables and attributes still come in the order of the stages."""
    import study.run as run
    order = []
    for name in ("gear_stage", "modes_stage", "static_stage", "mesh_stage", "dynamic_stage", "strength_stage"):
        monkeypatch.setattr(run, name, lambda *a, _real=getattr(run, name), _name=name: order.append(_name) or _real(*a))
    ds = study.run_scene(study.load_scene("paper", SHORT), warn=False)
    assert order == ["gear_stage", "static_stage", "mesh_stage", "modes_stage", "dynamic_stage", "strength_stage"]
    assert [k for k in ds.attrs if k.startswith("wall_time_")] == [
        "wall_time_springs_s", "wall_time_modes_s", "wall_time_static_s", "wall_time_mesh_stiffness_s",
        "wall_time_dynamic_s", "wall_time_strength_s"]
    names = list(ds.data_vars)
    assert names.index("mode_frequency") < names.index("ste") < names.index("mesh_stiffness") < names.index("dte")

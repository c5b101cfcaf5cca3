"""The stand-in model (`study.stand_in`) types a scene's entry kernels as its real model does:
the static sweep and the time stepping are called with the same numba types by the solver on
the model built from the FE, for each part of the contact search and each coupling model."""
import numpy as np
import pytest
from helpers import scene_overrides

import study
from solver.mbs import interrupt
from solver.mbs.dynamics import simulate
from solver.mbs.statics import solve_static
from solver.precompile import argument_types, kernel_name
from study.scene_model import build_scene_model
from study.stand_in import entry_jobs, shared_kernels, stand_in_model

SMALL = {**scene_overrides("small_pair"), "coupling.model": "paper"}


class Called(Exception):
    pass


def called_types(model, monkeypatch) -> dict:
    """{kernel name: argument types} of the static sweep and the time stepping as the solver
    calls them on ``model`` (stopped at the call: nothing is compiled)."""
    seen = {}

    def call(kernel, args, *_a, **_k):
        seen[kernel_name(kernel)] = argument_types(kernel, args)
        raise Called
    monkeypatch.setattr(interrupt, "call", call)
    for run in (lambda: solve_static(model, np.zeros(2), 50.0),
                lambda: simulate(model, 100.0, 0.01, 50.0, 0.01, 0.001, dt=1e-6)):
        with pytest.raises(Called):
            run()
    return seen


CONTACTS = "solver.mbs.kernels.gearmesh.pair_contacts"


def stand_in_types(scene) -> dict:
    """{kernel name: argument types} of the stand-in's entry kernels (the contact search,
    compiled ahead as the loops call it, apart: tests/study/test_compile_ahead.py), in
    their order; the search comes after the stepping loop, before the static sweep."""
    jobs = entry_jobs(scene)
    names, shared = [kernel_name(k) for k, _ in jobs], [kernel_name(k) for k in shared_kernels(jobs)]
    assert names.count(CONTACTS) == 1 and shared[0] == CONTACTS and names[-1] == "solver.mbs.kernels.statics.static_sweep"
    assert names[-1 - len(shared):-1] == shared     # compiled ahead after the loop, before the sweep
    return {name: types for name, (_, types) in zip(names, jobs) if name not in shared}


@pytest.mark.parametrize("overrides", [
    {},                                                        # the plain search
    {"contact.friction": 0.05},                                # friction
    {"gear2.modification.tip_relief": 2.0, "gear2.modification.tip_length": 3.0},     # a flank deviation
    {"gear1.errors.grade": 6, "gear1.errors.eccentricity": 5.0},   # pitch errors
], ids=["plain", "friction", "relief", "errors"])
def test_the_stand_in_types_the_kernels_as_the_paper_model(overrides, monkeypatch):
    scene = study.load_scene(None, {**SMALL, **overrides})
    model = build_scene_model(scene, convert_damping=False)
    types = stand_in_types(scene)
    assert types == called_types(model, monkeypatch)
    if overrides:       # a variant of its own (another ContactParts): not the plain search's types
        assert types != stand_in_types(study.load_scene(None, SMALL))
    # and the parts the variant compiles are the model's
    stand_in = stand_in_model(scene)
    for a, b in ((stand_in.gear_par, model.gear_par), (stand_in.pair_par, model.pair_par)):
        assert a.shape == b.shape and a.dtype == b.dtype


@pytest.mark.parametrize("edges", [{}, {"gear1.modification.tip_edge_radius": 0.2, "gear2.modification.tip_edge_radius": 0.2}],
                         ids=["sharp", "rounded tips"])
def test_the_stand_in_types_the_kernels_as_the_compliance_model_from_its_fe(edges, monkeypatch):
    """The default model: teeth coupled through the body, body springs, the local compliance
    in series (from the coarse FE bodies of the small pair); with rounded tip edges, the
    contact search's variant that has them."""
    scene = study.load_scene(None, {**SMALL, "coupling.model": "compliance", **edges})
    model = build_scene_model(scene, convert_damping=False)
    assert model.coupled and model.teeth_coupled
    stand_in = stand_in_model(scene)
    assert stand_in.coupled and stand_in.teeth_coupled and stand_in.tooth_compliance.shape == model.tooth_compliance.shape
    types = stand_in_types(scene)
    assert set(types) == {"solver.mbs.kernels.explicit_coupled.verlet_coupled", "solver.mbs.kernels.statics.static_sweep"}
    assert types == called_types(model, monkeypatch)


def test_a_run_without_dynamics_leaves_the_time_stepping_out():
    scene = study.load_scene(None, SMALL)
    assert list(stand_in_types(scene)) == ["solver.mbs.kernels.explicit.verlet", "solver.mbs.kernels.statics.static_sweep"]
    assert list(kernel_name(k) for k, _ in entry_jobs(scene, dynamic=False)) == [CONTACTS, "solver.mbs.kernels.statics.static_sweep"]
    implicit = study.load_scene(None, {**SMALL, "dynamic.method": "implicit"})
    assert list(stand_in_types(implicit))[0] == "solver.mbs.kernels.implicit.hht"


def test_a_study_s_compile_task_never_fails_its_pilot(monkeypatch):
    """What cannot be compiled ahead (a stand-in that cannot be built, a kernel numba refuses)
    is left to the runs, which then compile it or say what is wrong: the task itself returns."""
    import study.stand_in as stand_in

    def broken(scene, dynamic=None):
        raise ValueError("gear2.body: no stand-in")
    monkeypatch.setattr(stand_in, "entry_jobs", broken)
    assert stand_in.compile_kernels((study.load_scene(None, SMALL),)) == []

    class Refusing:
        py_func = stand_in_model

        def compile(self, types):
            raise TypeError("refused")
    monkeypatch.setattr(stand_in, "entry_jobs", lambda scene, dynamic=None: [(Refusing(), ())])
    assert stand_in.compile_kernels((study.load_scene(None, SMALL),)) == []


def test_a_run_refused_before_any_work_builds_no_stand_in(monkeypatch):
    """The compile ahead starts from the run's plan once its checks passed: a run whose FE
    bodies cannot fit in memory is refused without a stand-in of its 10000-tooth gear (whose
    tooth compliance alone would take 800 MB)."""
    import study.stand_in as si
    from study import estimate
    from study.stand_in import compiling_ahead
    built = []
    monkeypatch.setattr(si, "entry_jobs", lambda *a, **k: built.append(a) or [])
    monkeypatch.setattr(estimate, "available_memory", lambda: 16.0 * 2 ** 30)
    scene = study.load_scene(None, {**SMALL, "coupling.model": "compliance", "gear2.teeth": 10000})
    with pytest.raises(study.BudgetError, match="fe.mesh_size"):
        with compiling_ahead(scene):
            study.run_scene(scene)
    assert built == []
    small = study.load_scene(None, SMALL)
    with compiling_ahead(small):             # asked, and started by the plan of its own run
        si.start_ahead(small)
    assert len(built) == 1 and built[0][0] is small



def test_run_scene_compiles_ahead_when_told(monkeypatch):
    """`run_scene(compile_ahead=True)` (what `lightgear run` and the paper example ask) starts
    the compile ahead of its own scene from its plan, with the run's dynamic choice; by default
    it starts none, and a value other than a bool is refused naming the argument."""
    import study.stand_in as si
    asked = []
    monkeypatch.setattr(si, "entry_jobs", lambda scene, dynamic=None: asked.append((scene, dynamic)) or [])
    small = study.load_scene(None, {**SMALL, "dynamic.enabled": False})
    study.run_scene(small, static=False)
    assert asked == []
    study.run_scene(small, static=False, compile_ahead=True)
    assert asked == [(small, None)] and not si._ASKED
    with pytest.raises(TypeError, match="run_scene: compile_ahead takes True or False"):
        study.run_scene(small, compile_ahead="yes")

# in a process of its own with an empty kernel cache: the coupled loop's late helpers compiled
# from the stand-in's types, then the loop (numba's compile events name what it compiles)
LATE = r"""
import json, sys
from numba.core import event
import study
from solver.precompile import kernel_name
from study.stand_in import entry_jobs, shared_kernels
jobs = entry_jobs(study.load_scene(None, json.loads(sys.argv[1])))
late = [(k, t) for k, t in jobs if k in shared_kernels(jobs)[1:]]
for k, t in late:
    k.compile(t)
compiled = []
class Compiles(event.Listener):
    def on_start(self, ev):
        compiled.append(kernel_name(ev.data["dispatcher"]))
    def on_end(self, ev):
        pass
with event.install_listener("numba:compile", Compiles()):
    jobs[0][0].compile(jobs[0][1])
print("RESULT", json.dumps({"loop": kernel_name(jobs[0][0]), "late": [kernel_name(k) for k, _ in late],
                            "signatures": [len(k.signatures) for k, _ in late], "compiled": compiled}))
"""


def test_the_coupled_loop_finds_its_late_helpers_compiled_for_the_stand_in_s_types(tmp_path):
    """The default model's stepping loop types the step's end and the dissipation power last;
    a cold run compiles them ahead (with the contact search) from the stand-in's types: the
    loop's own compile finds them and compiles neither again (no second signature)."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ, PYTHONPATH=str(root), NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    proc = subprocess.run([sys.executable, "-c", LATE, json.dumps({**SMALL, "coupling.model": "compliance"})],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=540)
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert line, proc.stderr[-3000:]
    res = json.loads(line[7:])
    assert res["loop"] == "solver.mbs.kernels.explicit_coupled.verlet_coupled"
    assert res["late"] == ["solver.mbs.kernels.stepping.end_step", "solver.mbs.kernels.mechanics.dissipation_power"]
    assert res["signatures"] == [1, 1]
    assert res["compiled"][0] == res["loop"] and not set(res["late"]) & set(res["compiled"]), res["compiled"]


def test_the_other_loops_have_no_late_helpers():
    """(the paper model's loop, the implicit one: only the contact search is shared)"""
    for overrides in ({}, {"dynamic.method": "implicit"}):
        jobs = entry_jobs(study.load_scene(None, {**SMALL, **overrides}))
        assert [kernel_name(k) for k in shared_kernels(jobs)] == [CONTACTS]

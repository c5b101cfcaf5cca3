"""The Python API as a careless script uses it: a wrong argument type raises at once naming the
argument and what it takes, NumPy numbers count as numbers, embedded scenes load by name, and a
script that starts worker processes without a main guard stops at once saying what to add."""
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import study

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def small():
    return study.load_study("example_study").base_scene()


@pytest.fixture(scope="module")
def api_loaded():
    """Every function the API offers, imported: the time of a refused call is then its check."""
    for name in study.__all__:
        getattr(study, name)


@pytest.mark.parametrize("call, words", [
    (lambda s: study.load_scene({"gear2.body.holes": 3}), ["load_scene", "path", "dict"]),
    (lambda s: study.load_scene(5), ["load_scene", "path", "int"]),
    (lambda s: study.load_scene(None, "gear2.body.holes=3"), ["load_scene", "overrides", "key=value"]),
    (lambda s: study.run_scene("scene.toml"), ["run_scene", "scene", "a Scene", "str"]),
    (lambda s: study.run_scene(s, static="yes"), ["run_scene", "static"]),
    (lambda s: study.run_sweep(s, "x.nc", workers=0), ["run_sweep", "study", "a Study", "Scene"]),
    (lambda s: study.run_sweep(study.make_study(s, {"gear2.body.holes": [0, 4]}), "x.nc", workers="2"),
     ["run_sweep", "workers", "integer", "str"]),
    (lambda s: study.run_sweep(study.make_study(s, {"gear2.body.holes": [0, 4]}), 3, workers=0),
     ["run_sweep", "output", ".nc"]),
    (lambda s: study.make_study(s, grid=[("gear2.body.holes", [0, 4])]), ["make_study", "grid", "list"]),
    (lambda s: study.make_study(s, {"gear2.body.holes": [0, 4]}, outputs=5), ["make_study", "outputs"]),
    (lambda s: study.summarize("run.nc"), ["summarize", "ds", "str"]),
    (lambda s: study.stiffness(None), ["stiffness", "scene", "NoneType"]),
    (lambda s: study.reference("paper"), ["reference", "scene", "str"]),
])
def test_a_wrong_argument_type_raises_at_once_naming_it(call, words, small, api_loaded, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    t0 = time.perf_counter()
    with pytest.raises(TypeError) as e:
        call(small)
    assert time.perf_counter() - t0 < 2.0
    assert all(w in str(e.value) for w in words), str(e.value)
    assert not list(tmp_path.iterdir())          # nothing written


def test_negative_workers_are_refused_instead_of_hanging(small, tmp_path):
    st = study.make_study(small, {"gear2.body.holes": [0, 4]}, outputs=["ste_p2p"])
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="workers takes an integer >= 0"):
        study.run_sweep(st, tmp_path / "s.nc", workers=-3)
    assert time.perf_counter() - t0 < 2.0


def test_numpy_numbers_are_numbers():
    scene = study.default_scene().replace(**{"gear2.body.holes": np.int64(3), "dynamic.speed": np.float32(150.0),
                                             "quasi_static.enabled": np.bool_(False)})
    assert scene.gear2.body.holes == 3 and type(scene.gear2.body.holes) is int
    assert scene.dynamic.speed == 150.0 and type(scene.dynamic.speed) is float
    assert scene.quasi_static.enabled is False
    with pytest.raises(study.SceneError, match="must be an integer, got 2.5"):
        study.default_scene().replace(**{"gear2.body.holes": np.float64(2.5)})
    # grids of NumPy arrays and scalars
    st = study.make_study(None, {"gear2.body.holes": np.array([0, 3, 6]), "dynamic.speed": np.linspace(50, 100, 2)},
                          outputs=["mass_gear2"])
    assert st.axes[0].values == (0, 3, 6) and st.axes[1].values == (50.0, 100.0)


def test_outputs_as_a_list_select_scalars_and_curves_and_unknown_names_are_refused():
    st = study.make_study(None, {"gear2.body.holes": [0, 3]}, outputs=["ste_p2p", "dte", "mass_gear2"])
    assert st.outputs.scalars == ("ste_p2p", "mass_gear2") and st.outputs.curves == ("dte",)
    # the study text the archive keeps gives the same study
    from study.sweep.grid import loads_study
    assert loads_study(st.text).outputs == st.outputs
    with pytest.raises(study.StudyError, match="unknown output 'ste_pp'.*lightgear outputs"):
        study.make_study(None, {"gear2.body.holes": [0, 3]}, outputs=["ste_pp"])


def test_embedded_scenes_and_studies_load_by_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    names = study.scenes()
    assert {"paper", "runup", "sensitivity", "example_study"} <= set(names)
    assert names["runup"][1] == "scene" and names["sensitivity"][1] == "study"
    assert study.load_scene("runup").dynamic.speed_end > 0
    assert study.load_scene("runup.toml") == study.load_scene("runup")
    assert study.load_scene("runup", {"gear2.body.holes": 3}) == study.load_scene("runup", ["gear2.body.holes=3"])
    assert study.load_study("sensitivity").title == names["sensitivity"][2]
    # a file of that name in the working directory wins over the embedded one
    (tmp_path / "runup.toml").write_text('title = "mine"\n')
    assert study.load_scene("runup.toml").title == "mine"
    with pytest.raises(study.SceneError, match="did you mean 'runup'"):
        study.load_scene("rnup")
    with pytest.raises(study.StudyError, match="embedded studies: .*sensitivity"):
        study.load_study("paper_study")


def test_a_misspelled_grid_field_names_the_closest_and_the_valid_ones():
    with pytest.raises(study.StudyError) as e:
        study.make_study(None, {"gear2.body.hole_raduis": [5.0, 6.0]})
    msg = str(e.value)
    assert "did you mean 'gear2.body.hole_radius'" in msg and "hole_circle_radius" in msg


def test_summarize_takes_a_run_or_a_sweep_archive_only():
    with pytest.raises(TypeError, match="summarize: ds takes a run or sweep archive"):
        study.summarize({"ste": [1, 2]})


def test_every_cli_command_has_its_function_in_the_api():
    from study.cli import COMMANDS
    api = {"run": "run_scene", "stiffness": "stiffness", "sweep": "run_sweep", "fit-contact": "fit_contact",
           "render": "render", "precision": "precision", "reference": "reference", "scenes": "scenes",
           "fields": "fields", "outputs": "outputs", "export": "export", "report": "write_report"}
    for command in COMMANDS:
        assert command in api and api[command] in study.__all__, command
        doc = getattr(study, api[command]).__doc__
        assert doc and len(doc) > 60, command


def test_fit_contact_from_the_api_reproduces_the_paper_law():
    f = study.fit_contact(study.default_scene())
    assert abs(f.k_con / 5.64e6 - 1) < 0.1 and abs(f.m1 / 1.24 - 1) < 0.1


MAIN_GUARD_SCRIPT = """
import study
st = study.make_study(study.load_study("example_study").base_scene(), {"gear2.body.holes": [0, 4]},
                      outputs=["mass_gear2"])
study.run_sweep(st, "s.nc", workers=1, progress=False)
print("finished")
"""


@pytest.mark.parametrize("guarded", [False, True])
def test_a_script_without_main_guard_stops_at_once_saying_what_to_add(guarded, tmp_path):
    body = MAIN_GUARD_SCRIPT
    if guarded:
        body = "if __name__ == '__main__':\n" + textwrap.indent(body, "    ")
    script = tmp_path / "sweep_script.py"
    script.write_text(body)
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "MPLBACKEND": "Agg"}
    import os
    env.update({k: v for k, v in os.environ.items() if k in ("NUMBA_CACHE_DIR", "LIGHTGEAR_CACHE", "HOME")})
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300, env=env)
    if guarded:
        assert r.returncode == 0 and "finished" in r.stdout, r.stderr[-2000:]
    else:
        assert r.returncode == 1 and time.perf_counter() - t0 < 30
        lines = [x for x in r.stderr.splitlines() if x.strip()]
        assert len(lines) == 1, r.stderr[-2000:]
        assert 'if __name__ == "__main__":' in lines[0] and "sweep_script.py" in lines[0]
        assert not (tmp_path / "s.nc").exists()


def test_make_study_takes_the_sample_table_the_tolerance_page_documents():
    """docs/tolerance.md: ``make_study(..., sample={...})`` draws scene fields like a study
    file's [sample] table: the same draws as the file, within the distribution's range."""
    sample = {"size": 8, "method": "sobol", "seed": 1, "gear1.errors.eccentricity": {"uniform": [0.0, 5.0]}}
    st = study.make_study(None, {"gear1.errors.grade": [5, 7]}, outputs=["ste_p2p"], sample=sample)
    assert st.sample.paths == ("gear1.errors.eccentricity",) and st.sample.builds == 8
    drawn = st.sample.values["gear1.errors.eccentricity"]
    assert drawn.shape == (8,) and (drawn >= 0.0).all() and (drawn <= 5.0).all() and np.unique(drawn).size == 8
    same = study.study_from_dict({"grid": {"gear1.errors.grade": [5, 7]}, "sample": sample,
                                  "outputs": {"scalars": ["ste_p2p"]}})
    np.testing.assert_array_equal(same.sample.values["gear1.errors.eccentricity"], drawn)
    with pytest.raises(study.StudyError, match="size"):
        study.make_study(None, sample={**sample, "size": 0})


def test_the_api_offers_each_function_itself_with_one_docstring():
    """`study.NAME` is the function of the module that does the work (no wrapper repeating its
    docstring), and each documents itself."""
    import importlib
    for name, (module, attribute) in study._OFFERED.items():
        value = getattr(study, name)
        assert value is getattr(importlib.import_module(module), attribute), name
        assert value.__doc__ and len(value.__doc__) > 20, name

"""Studies: every grid value and point checked before any work, base scenes, and studies built
in Python (`make_study`) checked and archived like study files."""
import pytest
from sweep_cases import BASE, assert_refused_before_any_work, tiny_study

from study.scene import SceneError, default_scene, loads_scene
from study.sweep.engine import run_sweep
from study.sweep.grid import loads_study, make_study


@pytest.mark.parametrize("grid, field, reason", [
    ("[grid]\ngear2.body.holez = [1, 2]", "gear2.body.holez", "no such scene field"),
    ("[grid]\n\"gear2.body\" = [1, 2]", "gear2.body", "is a table"),
    ("[grid]\ngear2.body.holes = [3, 4.5]", "gear2.body.holes", "must be an integer"),
    ("[grid]\ngear2.body.hole_radius = [1.0, -2.0]", "gear2.body.hole_radius", "must be >= 0"),
    ("[grid]\ndynamic.method = ['explicit', 'rk4']", "dynamic.method", "must be one of"),
    ("[grid]\ndynamic.speed = {start = 1.0, stop = 2.0}", "dynamic.speed", "range"),
    ("[grid]\ngear2.body.holes = {start = 0, stop = 3, num = 3}", "gear2.body.holes", "non-integer"),
    ("[grid]\ndynamic.speed = []", "dynamic.speed", "empty"),
    ("[grid]\ndynamic.speed = [50.0, 50.0]", "dynamic.speed", "repeats"),
    ("[grid]\ndynamic.speed = 50.0", "dynamic.speed", "list of values or a range"),
    ("[grid]\ndynamic.speed = [1.0]\n[outputs]\ncurves = ['dtee']", "outputs.curves", "unknown output"),
    ("[grd]\ndynamic.speed = [1.0]", "grd", "unknown study key"),
    ("[[points]]\ndynamic.sped = 3.0", "dynamic.sped", "no such scene field"),
    ("[[points]]\ngear2.teeth = 3", "gear2.teeth", "points[0] value 3: must be >= 6"),
    ("[outputs]\ncurves = ['ste']", "grid", "sweeps nothing"),
])
def test_study_errors_name_the_field_before_any_work(grid, field, reason, monkeypatch):
    assert_refused_before_any_work(monkeypatch, tiny_study, grid, field, reason)


def test_base_scene_from_a_file_or_a_table(tmp_path):
    (tmp_path / "sc").mkdir()
    (tmp_path / "sc" / "s.toml").write_text("[gear2.body]\nholes = 0\nweb_thickness = 17.0\n")
    grid = "\n[grid]\ndynamic.speed = [50.0]\n"
    st = loads_study('scene = "sc/s.toml"' + grid, tmp_path)
    assert st.points()[0].scene.gear2.body.holes == 0 and st.points()[0].scene.gear2.teeth == 67
    st = loads_study('[scene]\nfile = "sc/s.toml"\ngear2.body.web_thickness = 12.0' + grid, tmp_path)
    assert st.points()[0].scene.gear2.body.web_thickness == 12.0
    paper = loads_study(grid).points()[0].scene
    assert paper == default_scene().replace(**{"dynamic.speed": 50.0})
    with pytest.raises(SceneError, match="no such file"):
        loads_study('scene = "nope.toml"' + grid, tmp_path)


def test_a_study_whose_every_point_is_invalid_is_refused(tmp_path):
    st = tiny_study("[grid]\ngear2.body.holes = [3, 4]\ngear2.body.hole_radius = [2.5, 3.0]")
    with pytest.raises(SceneError, match="every point of the study is invalid.*holes cut the rim"):
        run_sweep(st, tmp_path / "x.nc", workers=0, progress=False)
    assert not (tmp_path / "x.nc").exists()


def test_a_study_built_in_python_equals_its_study_file():
    import numpy as np
    toml = tiny_study()
    base = toml.points()[0].scene.replace(**{"gear2.body.holes": 0, "dynamic.speed": 100.0, "gear2.body.web_thickness": 17.0})
    py = make_study(base, {"gear2.body.holes": [0, 4], "dynamic.speed": {"start": 50.0, "stop": 100.0, "num": 2},
                           "gear2.body.web_thickness": np.array([12.0, 17.0])},
                    outputs={"curves": ["ste", "dte_amplitude"]}, title="tiny")
    assert [a.name for a in py.axes] == ["n_holes", "speed", "web_thickness"]   # the dict's order
    assert py.shape == (2, 2, 2) and py.outputs == toml.outputs and py.title == "tiny"
    by_values = {tuple(sorted(p.values.items())): p.scene for p in toml.points()}
    for p in py.points():
        assert p.scene == by_values[tuple(sorted(p.values.items()))]
    # the archived text gives the same study back
    again = loads_study(py.text)
    assert again.axes == py.axes and [p.scene for p in again.points()] == [p.scene for p in py.points()]
    # points and the paper example as base
    pts = make_study(points=[{"dynamic.speed": 60.0}, {"gear2.body.holes": 3}], outputs={"scalars": ["ste_p2p"]})
    assert pts.layout == "point" and pts.shape == (2,)
    assert pts.points()[0].scene == default_scene().replace(**{"dynamic.speed": 60.0})
    assert pts.outputs.static and not pts.outputs.dynamic


@pytest.mark.parametrize("grid, field, reason", [
    ({"gear2.body.holez": [1, 2]}, "gear2.body.holez", "no such scene field"),
    ({"gear2.body.holes": [3, 4.5]}, "gear2.body.holes", "must be an integer"),
    ({"dynamic.speed": []}, "dynamic.speed", "empty"),
    ({}, "grid", "sweeps nothing"),
])
def test_a_study_built_in_python_is_checked_like_a_file(grid, field, reason):
    base = loads_scene(BASE.replace("[scene]\n", ""))
    with pytest.raises(SceneError) as e:
        make_study(base, grid)
    assert e.value.field == field and reason in str(e.value), str(e.value)
    with pytest.raises(SceneError, match="unknown output 'dtee'"):
        make_study(base, {"dynamic.speed": [50.0]}, outputs={"curves": ["dtee"]})


def test_a_point_whose_run_has_no_steady_part_is_invalid_when_dynamics_are_asked_for():
    """Twice the ramp (4 ms) plus 16 output steps is the shortest run a DTE summary can use: a
    shorter point is recorded invalid with the reason, before any work; a study asking only for
    STE keeps it."""
    grid = '[grid]\n"dynamic.duration" = [0.004, 0.01]\n'
    dyn = tiny_study(grid + '[outputs]\nscalars = ["dte_rms"]\n').points()
    assert dyn[0].scene is None and dyn[0].error.startswith("dynamic.duration: leaves no steady part")
    assert dyn[1].scene is not None
    static = tiny_study(grid + '[outputs]\nscalars = ["ste_p2p"]\n').points()
    assert all(p.scene is not None for p in static)

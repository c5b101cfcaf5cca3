"""What a new user meets first on the command line: scenes by name, the field and output
listings, hints for the usual slips, and warnings for values that are valid but almost
certainly a unit slip (stderr and the archive, not a refusal)."""
import xarray as xr

import study
from study.cli import main
from study.plausibility import CRITICAL_SPEED_FACTOR


def small(**over):
    """The example study's 20-tooth base scene (uniform springs: no FE), short DTE."""
    return study.load_study("example_study").base_scene().replace(**over)


def test_scenes_lists_the_embedded_scenes_and_studies_with_their_titles(capsys):
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    for name, (_path, _kind, title) in study.scenes().items():
        assert name in out and title in out
    assert "runup" in out and "sensitivity" in out


def test_run_and_sweep_take_an_embedded_name(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # by name, from a folder without scene files: refused for its output path, i.e. the scene was found
    assert main(["run", "runup", "-o", str(tmp_path / "x.txt")]) == 2
    assert "ending in .nc" in capsys.readouterr().err
    assert main(["sweep", "example_study", "-o", str(tmp_path / "e.nc"), "--workers", "0", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "4 points" in out and (tmp_path / "e.nc").is_file()
    assert main(["run", "runupp"]) == 2
    assert "did you mean 'runup'" in capsys.readouterr().err


def test_fields_lists_units_defaults_and_ranges_from_the_declarations(capsys):
    assert main(["fields", "gear2.body"]) == 0
    out = capsys.readouterr().out
    assert "gear2.body.hole_radius  [mm]" in out and "R_h: hole radius" in out and "default 6," in out
    assert "dynamic." not in out
    assert main(["fields"]) == 0
    out = capsys.readouterr().out
    assert all(r.path in out for r in study.fields())
    assert main(["fields", "--markdown"]) == 0
    from study.docs import fields_markdown
    assert capsys.readouterr().out == fields_markdown()
    assert main(["fields", "gear2.bdy"]) == 2
    assert "did you mean" in capsys.readouterr().err
    assert main(["outputs"]) == 0
    out = capsys.readouterr().out
    assert "ste_p2p" in out and "critical_speed_z" in out and "rad/s" in out and "curve over time" in out


def test_study_errors_say_study_and_name_the_closest_field(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text('scene = "paper"\n[grid]\n"gear2.body.hole_raduis" = [5.0, 6.0]\n')
    assert main(["sweep", str(path), "-o", str(tmp_path / "s.nc")]) == 2
    err = capsys.readouterr().err
    assert "invalid study" in err and "did you mean 'gear2.body.hole_radius'" in err and "hole_circle_radius" in err
    assert main(["run", "--set", "gear2.body.hols=3"]) == 2
    err = capsys.readouterr().err
    assert "invalid scene" in err and "did you mean 'holes'" in err


def test_set_without_equals_gets_the_fix(capsys):
    assert main(["run", "--set", "gear2.body.holes", "8"]) == 2
    err = capsys.readouterr().err
    assert "--set gear2.body.holes=8" in err and "no such file" not in err


def test_unit_slips_that_give_numbers_are_warned_about():
    assert study.plausibility_warnings(study.default_scene()) == []
    holes = study.plausibility_warnings(study.default_scene().replace(**{"gear2.body.hole_radius": 0.006}))
    assert len(holes) == 1 and holes[0].startswith("gear2.body.hole_radius") and "FE mesh size" in holes[0]
    # 3000 rad/s on the paper pair: 151 m/s at the pitch line
    fast = study.plausibility_warnings(study.default_scene().replace(**{"dynamic.speed": 3000.0}))
    assert len(fast) == 1 and fast[0].startswith("dynamic.speed") and "151 m/s" in fast[0]
    assert study.plausibility_warnings(study.default_scene().replace(**{"dynamic.speed": 1900.0})) == []  # 95 m/s
    # without a dynamic run the speed is not read
    assert study.plausibility_warnings(study.default_scene().replace(
        **{"dynamic.speed": 3000.0, "dynamic.enabled": False})) == []


def test_spring_fields_the_coupled_model_does_not_read_are_warned_about():
    """The coupled models take tooth springs and pivots from the FE body: a k_phi, n_k or
    pivot radius the scene sets (away from its default) has no effect there, and the warning
    names the field and the model that ignores it; the paper's model reads them: no warning."""
    scene = study.default_scene()
    assert scene.coupling_model == "compliance"
    w = study.plausibility_warnings(scene.replace(**{"gear1.spring.k_phi": 2.0e6}))
    assert len(w) == 1 and w[0].startswith("gear1.spring.k_phi: 2e+06") and "has no effect" in w[0]
    assert "coupling.model = 'auto' runs 'compliance'" in w[0] and "coupling.model = 'paper'" in w[0]
    w = study.plausibility_warnings(scene.replace(**{"gear2.spring.n_k": 1.0, "gear2.pivot_radius": 45.0,
                                                     "coupling.model": "body-torsion"}))
    assert [x.split(":")[0] for x in w] == ["gear2.spring.n_k", "gear2.pivot_radius"]
    assert all("coupling.model = 'body-torsion'" in x for x in w)
    # springs that ignore the lightening, under a model that reads the lightened body's FE
    w = study.plausibility_warnings(scene.replace(**{"gear2.spring.stiffness": "uniform"}))
    assert len(w) == 1 and w[0].startswith("gear2.spring.stiffness: 'uniform' has no effect")
    paper = scene.replace(**{"coupling.model": "paper", "gear1.spring.k_phi": 2.0e6, "gear2.spring.n_k": 1.0})
    assert study.plausibility_warnings(paper) == []


def test_a_speed_far_above_the_critical_speeds_is_warned_about_on_stderr_and_in_the_archive(tmp_path, capsys):
    scene = small(**{"quasi_static.enabled": False, "dynamic.duration": 0.006, "dynamic.ramp_time": 0.001,
                     "gear2.body.holes": 4})
    ds = study.run_scene(scene)
    assert ds.attrs["plausibility_warnings"] == "" and "warning" not in capsys.readouterr().err
    z1 = float(ds["critical_speed"].sel(excitation="1Z", mode=0))
    fast = scene.replace(**{"dynamic.speed": 1.2 * CRITICAL_SPEED_FACTOR * z1})
    out = tmp_path / "fast.nc"
    (tmp_path / "fast.toml").write_text(fast.to_toml())
    # a warning, not a refusal: the run goes on (at this speed its step may miss contact events: exit 3)
    assert main(["run", str(tmp_path / "fast.toml"), "-o", str(out)]) in (0, 3) and out.is_file()
    err = capsys.readouterr().err
    assert "lightgear: warning: dynamic.speed" in err and "highest critical speed" in err
    with xr.open_dataset(out) as a:
        assert "highest critical speed" in a.attrs["plausibility_warnings"]


def test_a_sweep_warns_once_per_slip_with_the_points_it_concerns(tmp_path, capsys):
    st = study.make_study(small(), {"gear2.body.hole_radius": [0.0015, 1.5], "gear2.body.holes": [2, 4]},
                          outputs=["mass_gear2"])
    res = study.run_sweep(st, tmp_path / "s.nc", workers=0, progress=True)
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if "warning" in x]
    assert len(lines) == 1 and "gear2.body.hole_radius: 0.0015 mm" in lines[0] and "(2 of 4 points)" in lines[0]
    assert "(2 of 4 points)" in res.dataset.attrs["plausibility_warnings"]
    assert "4/4" in err and "point" in err        # the bar counts points

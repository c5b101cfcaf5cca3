"""What a careless user or script meets: every bad input is exit 2 with the field or option
named, before any work; every refusal names the lever that helps."""
from pathlib import Path

import numpy as np
import pytest

from study.cli import main
from study.inputs.cache import FE_CACHE


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


# ---------------------------------------------------------------- files and output names

def test_a_scene_or_study_file_that_is_not_utf8_is_named(tmp_path, capsys):
    bad = tmp_path / "latin1.toml"
    bad.write_bytes('title = "engrenage allégé"\n'.encode("latin-1"))
    code, _, err = run_cli(capsys, "run", bad, "-o", tmp_path / "r.nc")
    assert code == 2 and "scene: " in err and "not UTF-8" in err
    code, _, err = run_cli(capsys, "sweep", bad, "-o", tmp_path / "s.nc")
    assert code == 2 and "study: " in err and "not UTF-8" in err


def test_a_study_whose_scene_is_a_number_is_named(tmp_path, capsys):
    st = tmp_path / "s.toml"
    st.write_text('scene = 5\n[grid]\n"dynamic.speed" = [50.0]\n')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc")
    assert code == 2 and "scene: must be a file name or a table" in err


@pytest.mark.parametrize("command", ["run", "stiffness", "reference", "precision"])
def test_an_output_name_too_long_for_the_file_system_is_refused_up_front(tmp_path, capsys, command):
    code, _, err = run_cli(capsys, command, "-o", tmp_path / ("a" * 300 + ".nc"))
    assert code == 2 and "-o: a name of 303 bytes is too long" in err
    # and one that leaves no room for the temporary file of the atomic write
    code, _, err = run_cli(capsys, command, "-o", tmp_path / ("b" * 240 + ".nc"))
    assert code == 2 and "at most 215 bytes" in err


def test_a_file_where_the_parts_folder_goes_is_refused(tmp_path, capsys):
    (tmp_path / ".s.nc.parts").write_text("not a folder")
    code, _, err = run_cli(capsys, "sweep", "study/scenes/example_study.toml", "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and ".s.nc.parts is a file" in err


# ---------------------------------------------------------------- options

@pytest.mark.parametrize("option, value, says", [("--duration", "0", "must be a positive number"),
                                                 ("--rotation", "0", "must be a positive number"),
                                                 ("--duration", "nan", "must be a positive number"),
                                                 ("--ramp-fraction", "2", "must lie in (0, 1]"),
                                                 ("--repeats", "0", "at least 1")])
def test_precision_options_are_checked_before_any_work(tmp_path, capsys, option, value, says):
    code, out, err = run_cli(capsys, "precision", option, value, "-o", tmp_path / "p.nc")
    assert code == 2 and f"{option}: " in err and says in err and "study ..." not in out


def test_workflow_scripts_options_give_exit_2_not_a_traceback(tmp_path, capsys):
    from study.process import script_main
    from workflows import sensitivity_sweep, validation
    assert script_main("validation", lambda: validation.main(["--step", "0", "-o", str(tmp_path / "v.nc")])) == 2
    assert "--step: the driver angle step must be a positive number" in capsys.readouterr().err
    assert script_main("sweep", lambda: sensitivity_sweep.main(["--grid", "bad", "-o", str(tmp_path / "s.nc")])) == 2
    assert "a grid axis must look like field=v1,v2" in capsys.readouterr().err


def test_a_material_too_soft_for_weber_is_named_by_fit_contact(capsys):
    code, _, err = run_cli(capsys, "fit-contact", "--set", "material.youngs_modulus=1e-9")
    assert code == 2 and "material.youngs_modulus" in err and "LinAlgError" not in err
    code, _, err = run_cli(capsys, "fit-contact", "--set", "quasi_static.torque=0")
    assert code == 2 and "quasi_static.torque" in err


# ---------------------------------------------------------------- estimates and their levers

def test_static_angles_that_do_not_fit_in_memory_are_refused_before_they_are_built(tmp_path, capsys):
    code, _, err = run_cli(capsys, "reference", "--step", "1e-9", "-o", tmp_path / "r.nc")
    assert code == 2 and "--step: the static analysis needs about" in err and "TiB" in err
    code, _, err = run_cli(capsys, "run", "--no-dynamic", "--set", "quasi_static.rotation=1e9", "--max-time", "1e30",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "quasi_static.angle_step: the static analysis needs" in err


def test_a_refusal_names_the_lever_of_its_largest_part(tmp_path, capsys):
    # 6e6 angles: some 10 GiB (fits), minutes of statics and hours of mesh linearisations
    code, _, err = run_cli(capsys, "run", "--no-dynamic", "--set", "quasi_static.angle_step=2e-5", "--max-time", "100",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "make the mesh stiffness cheaper: a larger quasi_static.angle_step" in err
    assert "fe.mesh_size" not in err
    code, _, err = run_cli(capsys, "run", "--no-static", "--set", "gear2.body.holes=0", "--set", "contact.friction=0.05",
                           "--set", "contact.friction_velocity=1e-9", "-o", tmp_path / "r.nc")
    assert code == 2 and "make the dynamics cheaper" in err and "contact.friction_velocity" in err
    assert "fe.mesh_size" not in err


# ---------------------------------------------------------------- results that would pass as ok

def write_study(tmp_path, grid: str, outputs: str = 'scalars = ["dte_rms"]', section: str = "grid") -> str:
    """The example study's scene with ``grid`` as its [grid] (or the table ``section``)."""
    text = (Path("study/scenes/example_study.toml").read_text().split("[grid]")[0]
            + f"[{section}]\n{grid}\n[outputs]\n{outputs}\n")
    path = tmp_path / "st.toml"
    path.write_text(text)
    return str(path)


def test_a_grid_over_two_ways_of_one_damper_is_refused(tmp_path, capsys):
    st = write_study(tmp_path, '"contact.c_con" = [1000.0, 3640.0]\n"contact.damping_ratio" = [0.02, 0.05]')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "sweeps both contact.c_con and contact.damping_ratio" in err
    assert not (tmp_path / ".s.nc.parts").exists()


@pytest.mark.parametrize("field, values, curve", [("dynamic.duration", "[0.01, 0.012]", "dte"),
                                                  ("quasi_static.rotation", "[6.0, 8.0]", "ste"),
                                                  ("dynamic.ramp_time", "[0.002, 0.003]", "dte_amplitude")])
def test_a_curve_whose_axis_the_grid_changes_is_refused_up_front(tmp_path, capsys, field, values, curve):
    st = write_study(tmp_path, f'"{field}" = {values}', f'scalars = ["dte_rms"]\ncurves = ["{curve}"]')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and f"{field}: the curve '{curve}' is archived on one axis" in err


def small_scene(**overrides):
    """The example study's 20-tooth pair (uniform springs, no FE), solid."""
    from study.sweep.grid import load_study
    scene = load_study("study/scenes/example_study.toml").points()[0].scene
    return scene.replace(**overrides)


def test_the_coast_flanks_elastic_mean_mirrors_the_drive_side():
    """A solid, unmodified pair is symmetric: under -T it sits on the coast flanks at the mirror
    image of its drive-flank equilibrium, so the elastic part of the mean STE (measured from
    the backlash offset of the loaded side) changes sign and keeps its size. (Over one whole
    mesh period, 18 deg for 20 teeth: the mirror image runs through the period backwards.)"""
    from study.archive.summary import summarize
    from study.run import run_scene
    period = {"quasi_static.rotation": 18.0 - 0.25, "quasi_static.angle_step": 0.25}
    drive = summarize(run_scene(small_scene(**period), static=True, dynamic=False))
    coast = summarize(run_scene(small_scene(**period, **{"quasi_static.torque": -50.0}), static=True, dynamic=False))
    assert drive["ste_elastic_mean"] > 0
    assert coast["ste_elastic_mean"] == pytest.approx(-drive["ste_elastic_mean"], rel=1e-3)
    assert coast["ste_p2p"] == pytest.approx(drive["ste_p2p"], rel=1e-3)


def test_the_transient_ste_holds_no_unloaded_sample():
    """The slow-ramp transient samples only angles the driver reaches under the whole load: its
    STE ripple is that of the equilibria (the first sample used to be the unloaded start)."""
    from study.archive.summary import summarize
    from study.run import run_scene
    static = run_scene(small_scene(), static=True, dynamic=False)
    transient = run_scene(small_scene(**{"quasi_static.method": "transient"}), static=True, dynamic=False)
    p2p_s, p2p_t = summarize(static)["ste_p2p"], summarize(transient)["ste_p2p"]
    assert float(transient["angle"][0]) > 0.0 == float(static["angle"][0])     # past the load ramp
    assert p2p_t < 1.5 * p2p_s and abs(summarize(transient)["ste_mean"] - summarize(static)["ste_mean"]) < 0.2 * p2p_s


def test_the_sweep_scalar_of_the_mesh_order_is_the_value_the_summary_prints():
    """A short run resolves orders coarsely: the scalar comes from the same named-peak table as
    the printed summary, not from a window narrower than a bin (NaN at status ok)."""
    from study.archive.summary import summarize
    from study.run import run_scene
    ds = run_scene(small_scene(**{"dynamic.speed": 100.0}), static=False, dynamic=True)
    s = summarize(ds)
    table = dict(zip(map(str, ds["dte_peak"].values), ds["dte_peak_amplitude"].values))
    assert np.isfinite(table["Z"]) and s["amp_mesh_order"] == table["Z"]


# ---------------------------------------------------------------- a sweep's estimate

def test_a_grid_too_large_to_list_is_refused_before_it_is_built(tmp_path, capsys, monkeypatch):
    from study.sweep.grid import Study
    built = []
    monkeypatch.setattr(Study, "points", lambda self: built.append(1) or [])
    st = write_study(tmp_path, '"dynamic.speed" = {start = 10.0, stop = 400.0, num = 1000}\n'
                               '"dynamic.torque" = {start = 10.0, stop = 60.0, num = 1000}\n'
                               '"gear2.body.holes" = [0, 2, 3, 4, 5, 6, 7, 8, 9, 10]')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "grid: the study has 1e+07 points (1000 x 1000 x 10)" in err and not built
    st = write_study(tmp_path, '"dynamic.speed" = {start = 10.0, stop = 400.0, num = 10000000}')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "dynamic.speed: range num = 10000000 values on one axis" in err


def test_a_sweep_gets_the_estimate_and_max_time_of_its_tasks(tmp_path, capsys):
    """Four dynamic runs of 1 s each at the explicit step: tens of seconds of CPU, refused under
    --max-time 5 with the parts and the lever, before any task runs."""
    st = write_study(tmp_path, '"dynamic.speed" = [50.0, 100.0]\n"dynamic.duration" = [1.0, 2.0]')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--max-time", 5)
    assert code == 2 and "--max-time: the run is estimated at" in err and "dynamics (4 runs" in err
    assert "a shorter dynamic.duration" in err and "fewer grid points" in err
    assert not (tmp_path / ".s.nc.parts").exists()


# ---------------------------------------------------------------- run-ups and render

@pytest.mark.parametrize("speed_end", ["1e-6", "100"])
def test_a_run_up_without_one_whole_driven_revolution_is_refused(tmp_path, capsys, speed_end):
    scene = tmp_path / "s.toml"
    scene.write_text(small_scene().to_toml())
    code, _, err = run_cli(capsys, "run", scene, "--no-static", "--set", f"dynamic.speed_end={speed_end}",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "dynamic.speed_end: the driven gear turns" in err and "needs at least 2" in err


def test_render_draws_a_run_at_standstill_or_says_what_it_skips(tmp_path, capsys):
    import study
    ds = study.run_scene(small_scene(**{"dynamic.speed": 0.0}), static=True, dynamic=True)
    study.write(ds, tmp_path / "still.nc")
    code, out, err = run_cli(capsys, "render", tmp_path / "still.nc", "--no-renders")
    assert code == 0, err
    assert "figure:" in out and "dte.png" in out
    # the STE's spectrum is drawn, the DTE's panel is left out with its reason
    assert "spectrum.png" in out and "skip DTE spectrum panel" in out and "driver speed 0" in out


# ---------------------------------------------------------------- geometry and physics bounds

def test_eccentricities_that_close_the_backlash_are_refused(tmp_path, capsys):
    """20-tooth pair, m 1.5 mm, 70 um backlash: the normal backlash 65.8 um closes where the
    centre distance shrinks by 65.8 / (2 sin 20 deg) = 96.2 um; beyond that the pair jams (the
    run used to say ok with ten times the nominal tooth force)."""
    import study
    scene = tmp_path / "s.toml"
    scene.write_text(small_scene().to_toml())
    code, _, err = run_cli(capsys, "run", scene, "--no-static", "--set", "gear1.errors.eccentricity=130",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "gear1.errors.eccentricity: the eccentricities (130 + 0 um) close the backlash" in err
    assert "below 96.16 um" in err
    with pytest.raises(study.SceneError, match="gear2.errors.eccentricity"):
        small_scene(**{"gear1.errors.eccentricity": 40.0, "gear2.errors.eccentricity": 60.0})
    small_scene(**{"gear1.errors.eccentricity": 40.0, "gear2.errors.eccentricity": 50.0})    # 90 um: meshes


def test_a_tip_past_the_mates_root_circle_is_radial_interference():
    import study
    with pytest.raises(study.SceneError, match="gear1.addendum: the tip circle .* reaches past the mate's root circle"):
        small_scene(**{"gear1.addendum": 1.3})
    with pytest.raises(study.SceneError, match="gear2.addendum"):
        small_scene(**{"gear2.addendum": 1.3, "gear1.dedendum": 1.25})
    small_scene(**{"gear1.addendum": 1.2})


def test_a_relief_deeper_than_the_tooth_is_thick_is_refused():
    """m 1.5 mm, 67 teeth: each flank has about 0.52 mm of material to the centreline at the tip
    (normal to the flank): a 2 mm tip relief would remove the tooth; 50 um is a relief."""
    import study
    start = {"gear1.modification.tip_start_roll": 25.0}
    with pytest.raises(study.SceneError, match=r"gear1.modification.tip_relief: 2000 um removes the whole tooth"):
        study.default_scene().replace(**start, **{"gear1.modification.tip_relief": 2000.0})
    study.default_scene().replace(**start, **{"gear1.modification.tip_relief": 50.0})


def test_a_hole_phase_beyond_a_turn_is_refused():
    import study
    with pytest.raises(study.SceneError, match="gear2.body.hole_phase"):
        study.default_scene().replace(**{"gear2.body.hole_phase": 1e300})


def test_very_stiff_tooth_springs_keep_the_mesh_mode():
    """At k_phi of 1e12..1e14 N mm/rad the teeth are rigid next to the contact: the mesh mode
    tends to the rigid-tooth limit, a few tens of kHz, while the tooth modes climb to tens of
    MHz; the mesh mode used to be dropped as 'rigid' next to them and a 33 MHz tooth mode
    taken for it (and the dampers tuned to that)."""
    from solver.mbs.modes import modal_analysis
    from study.scene_model import build_scene_model
    raw = {"contact.c_con": 3640.0, "gear1.spring.c_phi": 0.062, "gear2.spring.c_phi": 0.062}
    f = {}
    for k in (1e12, 1e14):
        model = build_scene_model(small_scene(**raw, **{"gear1.spring.k_phi": k, "gear2.spring.k_phi": k}))
        f[k] = float(np.nanmean(modal_analysis(model, 50.0).frequency[0]))
    assert f[1e14] < 1e5 and f[1e14] == pytest.approx(f[1e12], rel=0.01)
    with pytest.raises(Exception, match="contact.damping_ratio"):    # a mesh ratio the joints cannot carry
        small_scene(**{"gear1.spring.k_phi": 1e14, "gear2.spring.k_phi": 1e14}).replace()
        build_scene_model(small_scene(**{"gear1.spring.k_phi": 1e14, "gear2.spring.k_phi": 1e14}))


# ---------------------------------------------------------------- what reaches the terminal

def test_a_library_warning_reaches_the_user_as_one_line(capsys):
    import warnings

    from study.cli import guarded

    def noisy():
        warnings.warn("something a library says\nwith a second line", RuntimeWarning, stacklevel=1)
        return 0
    assert guarded("lightgear run", noisy) == 0
    err = capsys.readouterr().err
    assert err == "lightgear run: warning: RuntimeWarning: something a library says\n"


def test_an_undamped_run_warns_of_nothing(tmp_path, capsys):
    """Zero damping: the free decay of the modal check fits exactly, and scipy cannot estimate
    the fit's covariance (which is not used): no OptimizeWarning."""
    scene = tmp_path / "s.toml"
    scene.write_text(small_scene(**{"contact.c_con": 0.0, "gear1.spring.c_phi": 0.0,
                                    "gear2.spring.c_phi": 0.0}).to_toml())
    code, _, err = run_cli(capsys, "run", scene, "--no-static", "-o", tmp_path / "r.nc")
    assert code in (0, 3) and "Warning" not in err, err


def test_teeth_too_soft_for_the_load_are_named_not_a_solver_error(tmp_path, capsys, private_fe_cache):
    """FE springs of a 1 MPa material: the teeth would bend by metres under 50 N·m; the torque
    check (from the scene's laws) cannot see it, the springs built from the FE do."""
    scene = tmp_path / "s.toml"
    scene.write_text(small_scene(**{"gear2.spring.stiffness": "fe", "material.youngs_modulus": 1.0}).to_toml())
    code, _, err = run_cli(capsys, "run", scene, "--no-static", "-o", tmp_path / "r.nc")
    assert code == 2 and "dynamic.torque: implausible load" in err and "material.youngs_modulus" in err
    # with raw damping coefficients (no ratio to convert), the modal analysis meets it first
    raw = {"contact.c_con": 3640.0, "gear1.spring.c_phi": 0.062, "gear2.spring.c_phi": 0.062}
    scene.write_text(small_scene(**raw, **{"gear2.spring.stiffness": "fe", "material.youngs_modulus": 1.0}).to_toml())
    code, _, err = run_cli(capsys, "run", scene, "--no-static", "-o", tmp_path / "r.nc")
    assert code == 2 and "dynamic.torque: implausible load" in err


def test_a_face_width_that_only_changes_the_inertia_is_said(tmp_path, capsys):
    """With per-tooth laws (k_con, k_phi scaled by 'fe-ratio' or 'uniform') on the paper's
    model, a 0.1 mm face gives exactly the STE of 17 mm: the run says so and names the lever
    ('fe' springs). The compliance model (the default) follows the face width: no note."""
    import study
    from study.plausibility import face_width_note
    uniform = {"gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform"}
    assert face_width_note(small_scene(**uniform)) is None
    thin = small_scene(**{"gear1.face_width": 0.1, "gear2.face_width": 0.1, "gear1.body.web_thickness": 0.1,
                          "gear2.body.web_thickness": 0.1, **uniform})
    note = face_width_note(thin)
    assert thin.coupling_model == "none" and "masses and inertias only" in note and "'fe'" in note
    assert face_width_note(thin.replace(**{"gear1.spring.stiffness": "fe", "gear2.spring.stiffness": "fe"})) is None
    assert face_width_note(thin.replace(**{"coupling.model": "compliance"})) is None
    a = study.run_scene(small_scene(**uniform), static=True, dynamic=False)
    b = study.run_scene(thin, static=True, dynamic=False)
    np.testing.assert_allclose(a["ste"].values, b["ste"].values, rtol=1e-9)     # what the note is about
    scene = tmp_path / "s.toml"
    scene.write_text(thin.to_toml())
    code, out, _ = run_cli(capsys, "run", scene, "--no-dynamic", "-o", tmp_path / "r.nc")
    assert code == 0 and "face width acts on masses and inertias only" in out


def test_precision_gets_an_estimate_and_max_time(tmp_path, capsys):
    """A 10 s window is some 2e7 stability steps of plain-Python scipy integration: refused
    before any run with the lever (--duration); a 1 deg static study alone is cheap and says
    what it expects."""
    code, out, err = run_cli(capsys, "precision", "--duration", "10", "-o", tmp_path / "p.nc")
    assert code == 2 and "days" in err and "a shorter --duration (10 s" in err and "study ..." not in out
    code, out, err = run_cli(capsys, "precision", "--only", "static", "--rotation", "1", "--repeats", "1",
                             "-o", tmp_path / "p.nc")
    assert code == 0, err
    assert out.startswith("estimated ") and "static" in out.splitlines()[0]


def test_explicit_points_may_each_give_a_damper_their_own_way(tmp_path):
    from study.sweep.grid import load_study
    path = tmp_path / "p.toml"
    path.write_text(Path("study/scenes/example_study.toml").read_text().split("[grid]")[0]
                    + '[[points]]\n"contact.c_con" = 3640.0\n"gear1.spring.c_phi" = 0.062\n"gear2.spring.c_phi" = 0.062\n'
                      '[[points]]\n"contact.damping_ratio" = 0.03\n[outputs]\nscalars = ["ste_p2p"]\n')
    st = load_study(path)
    assert [p.scene is not None for p in st.points()] == [True, True]


def test_a_point_whose_curve_the_archive_cannot_hold_is_said_on_the_terminal(tmp_path, capsys):
    """An eccentricity stretches the STE to a whole revolution (its period): that point's
    angle axis differs from the others', its curve is not stored, and the sweep says so on
    stderr, not only in the point's message."""
    st = write_study(tmp_path, '"gear1.errors.eccentricity" = [0.0, 5.0]', 'scalars = ["ste_p2p"]\ncurves = ["ste"]')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--no-progress")
    assert code == 0 and "1 points without some of their curves" in err and "ste not stored" in err


# ---------------------------------------------------------------- outputs a run cannot support

def paper_pair(**kw):
    """The small pair on the paper's model (uniform springs: no FE), a short dynamic run."""
    from tests.helpers import small_scene
    return small_scene(**{"gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform",
                          "dynamic.duration": 0.02, "dynamic.ramp_time": 0.004, "dynamic.speed": 100.0, **kw})


def dynamic_fields(scene):
    import warnings

    from study.plan import RunOptions
    from study.run import run_fields
    with warnings.catch_warnings():
        warnings.simplefilter("error")      # no raw library warning either
        return run_fields(scene, {"dynamic", "mesh", "gear"}, RunOptions(warn=False))


def test_the_dynamic_factor_is_undefined_where_the_run_cannot_support_it():
    from study.archive.summary import summarize
    ok = dynamic_fields(paper_pair())
    assert 0.8 < float(ok["dynamic_factor"]) < 2.0 and np.isfinite(summarize(ok)["dte_rms"])
    for kw, says in (({"dynamic.torque": 0.0}, "no static load (dynamic.torque = 0"),
                     ({"dynamic.speed": 0.0}, "stands still (dynamic.speed = 0)"),
                     ({"dynamic.speed": 1.0}, "of a mesh period")):
        run = dynamic_fields(paper_pair(**kw))
        assert np.isnan(float(run["dynamic_factor"])), kw
        assert says in run["dynamic_factor"].attrs["comment"], kw
    # a window after the ramp of 0.11 of a mesh period: neither K_v nor the DTE spread
    short = dynamic_fields(paper_pair(**{"dynamic.speed": 1.0}))
    s = summarize(short)
    assert np.isnan(s["dte_rms"]) and np.isnan(s["dte_p2p"]) and "of a mesh period" in short.attrs["steady_window_note"]


def test_the_dynamic_factor_of_a_load_change_compares_forces_at_one_torque():
    """50 -> 20 N·m at 15 ms: K_v over the steady part before the change, at the torque of the
    static reference: the very number of the same run stopped at the change."""
    change = dynamic_fields(paper_pair(**{"dynamic.torque_change_time": 0.015, "dynamic.torque_after": 20.0}))
    stopped = dynamic_fields(paper_pair(**{"dynamic.duration": 0.015}))
    assert float(change["dynamic_factor"]) == pytest.approx(float(stopped["dynamic_factor"]), rel=1e-12)
    early = dynamic_fields(paper_pair(**{"dynamic.torque_change_time": 0.0085, "dynamic.torque_after": 20.0}))
    assert np.isnan(float(early["dynamic_factor"])) and "load change" in early["dynamic_factor"].attrs["comment"]


def test_a_static_only_run_is_titled_and_analysed_at_the_torque_of_its_ste(tmp_path, capsys):
    import xarray as xr
    scene = tmp_path / "s.toml"
    scene.write_text(paper_pair(**{"quasi_static.torque": 100.0, "dynamic.torque": 20.0}).to_toml())
    code, out, err = run_cli(capsys, "run", scene, "--no-dynamic", "-o", tmp_path / "r.nc")
    assert code == 0, err
    title = next(line for line in out.splitlines() if line.startswith("z 24/24"))
    assert "100 N·m" in title and "20 N·m" not in title
    scene.write_text(paper_pair(**{"quasi_static.torque": 100.0, "dynamic.torque": 100.0}).to_toml())
    code, _, err = run_cli(capsys, "run", scene, "--no-dynamic", "-o", tmp_path / "same.nc")
    with xr.open_dataset(tmp_path / "r.nc") as a, xr.open_dataset(tmp_path / "same.nc") as b:
        assert a.attrs["mesh_mode_frequency_hz"] == pytest.approx(b.attrs["mesh_mode_frequency_hz"], rel=1e-9)
        assert not np.isclose(a.attrs["mesh_mode_frequency_hz"], 0.0)


def test_the_summary_lists_the_critical_speeds_of_the_runs_speed_range():
    import xarray as xr

    from study.report.summary import critical_speed_line
    ds = xr.Dataset({"critical_speed": (("excitation", "mode"), [[3197.0], [1598.0], [1066.0]])},
                    coords={"excitation": ["1Z", "2Z", "3Z"], "mode": [0]}, attrs={"driver_speed_max_rad_s": 3300.0})
    assert "1Z 3197" in critical_speed_line(ds)
    ds.attrs["driver_speed_max_rad_s"] = 100.0
    assert "none up to 200" in critical_speed_line(ds) and "the lowest 3Z 1066" in critical_speed_line(ds)


def test_an_angle_step_past_the_rotation_is_refused_before_work(tmp_path, capsys):
    """One driver angle would print an STE peak-to-peak of 0 and archive ste_p2p = 0."""
    code, _, err = run_cli(capsys, "run", "--set", "quasi_static.rotation=18", "--set", "quasi_static.angle_step=30",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "quasi_static.angle_step: a step of 30 deg leaves one driver angle" in err
    code, _, err = run_cli(capsys, "reference", "--step", "500", "-o", tmp_path / "f.nc")
    assert code == 2 and "--step: a step of 500 deg leaves one driver angle" in err
    st = write_study(tmp_path, '"quasi_static.angle_step" = [0.5, 40.0]', 'scalars = ["ste_p2p"]')
    code, out, _ = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--no-progress")
    assert code == 0 and "invalid 1" in out and "quasi_static.angle_step: a step of 40 deg" in out
    import xarray as xr
    with xr.open_dataset(tmp_path / "s.nc") as ds:     # an invalid point, not a peak-to-peak of 0
        assert ds["ste_p2p"].values[0] > 0 and np.isnan(ds["ste_p2p"].values[1])


# ---------------------------------------------------------------- ranges, integers and seeds

@pytest.mark.parametrize("field, value", [("gear1.errors.eccentricity_phase", 1e19),
                                          ("gear2.errors.eccentricity_phase", -400.0),
                                          ("gear1.modification.tip_start_roll", 1e5),
                                          ("gear2.modification.profile_roll", [10.0, 1e6])])
def test_every_angle_valued_field_has_a_range(field, value):
    from study.scene import SceneError
    from tests.helpers import small_scene
    with pytest.raises(SceneError) as e:
        small_scene(**{field: value})
    assert e.value.field == field and "must be " in e.value.reason and "360.0 deg" in e.value.reason


def test_integers_beyond_64_bits_are_refused_and_those_within_kept_exactly():
    from study.scene import SceneError
    from tests.helpers import small_scene
    assert small_scene(**{"gear1.errors.seed": 2 ** 53 + 1}).gear1.errors.seed == 2 ** 53 + 1
    with pytest.raises(SceneError, match="must fit in 64 bits"):
        small_scene(**{"gear1.errors.seed": 2 ** 64})


def sample_study(tmp_path, sample: str) -> str:
    return write_study(tmp_path, sample, 'scalars = ["ste_p2p"]', section="sample")


def test_integer_draws_and_seeds_are_checked_before_any_build(tmp_path, capsys):
    st = sample_study(tmp_path, 'size = 4\n"gear1.errors.grade" = {integers = [5, 6]}\n'
                                '"gear1.errors.seed" = {integers = [0, 1e20]}')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "gear1.errors.seed: [sample] integers upper end" in err and "64 bits" in err
    st = sample_study(tmp_path, f'size = 4\nseed = {2 ** 64}\n"gear2.body.hole_radius" = {{uniform = [1.0, 1.5]}}')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "sample.seed: must fit in 64 bits" in err and not (tmp_path / ".s.nc.parts").exists()


def test_a_sample_is_counted_and_bounded_like_a_grid(tmp_path, capsys, monkeypatch):
    from study.sweep.grid import Study
    built = []
    monkeypatch.setattr(Study, "points", lambda self: built.append(1) or [])
    for size in ("1000000", "1000000000000"):
        st = sample_study(tmp_path, f'size = {size}\n"gear2.body.hole_radius" = {{uniform = [1.0, 1.5]}}')
        code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--max-time", 3600)
        assert code == 2 and f"sample.size: the study has {float(size):.4g} points" in err and not built
    monkeypatch.undo()
    st = sample_study(tmp_path, 'size = 3\n"gear2.body.hole_radius" = {uniform = [1.0, 1.5]}')
    code, out, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--no-progress")
    assert code == 0 and "3 points (3" in out, out + err


def test_a_hole_order_the_record_does_not_resolve_is_not_fitted():
    """4 holes (order 4 of the driven gear, 90 deg) on a 20/20 pair: a known amplitude over a
    whole hole period is found; over 18 deg (19 or 181 angles) it is NaN with the reason, not
    a least-squares fit of 21 columns reporting 1e7 times the STE."""
    from study.verify.model_validation import order_amplitude, order_unresolved
    z, holes = 20, 4

    def ste(x):
        return 1.0 + 0.3 * np.cos(holes * x + 0.4) + 0.8 * np.cos(z * x) + 0.1 * np.sin(2 * z * x)
    whole = np.radians(np.arange(0.0, 90.0, 0.5))
    assert order_amplitude(whole, ste(whole), holes, z) == pytest.approx(0.3, rel=1e-9)
    assert order_unresolved(whole, holes) is None
    for step in (1.0, 0.1):
        short = np.radians(np.arange(0.0, 18.0 + 1e-9, step))
        assert np.isnan(order_amplitude(short, ste(short), holes, z))
    assert "fewer than the 21 columns" in order_unresolved(np.radians(np.arange(0.0, 18.5, 1.0)), holes)
    assert "less than one period of order 4 (90 deg)" in order_unresolved(np.radians(np.arange(0.0, 18.05, 0.1)), holes)


def test_a_sweep_point_with_a_tiny_time_step_is_estimated_and_refused_like_a_run(tmp_path, capsys):
    """One point of many at dynamic.time_step = 1e-13 (ten million steps per microsecond of
    the run): the sampled steps of the others would miss it."""
    points = "".join(f'[[points]]\n"dynamic.speed" = {50.0 + i}\n' + ('"dynamic.time_step" = 1e-13\n' if i == 2 else "")
                     for i in range(9))
    path = tmp_path / "p.toml"
    path.write_text(Path("study/scenes/example_study.toml").read_text().split("[grid]")[0] + points
                    + '[outputs]\nscalars = ["dte_rms"]\n')
    code, _, err = run_cli(capsys, "sweep", path, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "--max-time: the run is estimated at" in err and "dt down to 1e-13 s" in err
    assert "dynamic.time_step (1e-13 s given)" in err and not (tmp_path / ".s.nc.parts").exists()


def test_a_load_too_small_to_resolve_is_refused_before_the_fe_naming_the_torque(tmp_path, capsys, private_fe_cache):
    code, _, err = run_cli(capsys, "run", "small_pair", "--set", "dynamic.torque=1e-6", "-o", tmp_path / "r.nc")
    assert code == 2 and "dynamic.torque: a load too small to resolve: 1e-06 N*m" in err
    assert "damping_ratio" not in err and not FE_CACHE.folder.exists()      # no FE body made
    from study.plausibility import MIN_APPROACH_MM, approach_estimate_mm, smallest_torque
    from tests.helpers import small_scene
    t = smallest_torque(small_scene())
    assert approach_estimate_mm(small_scene(), t) == pytest.approx(MIN_APPROACH_MM, rel=1e-6)
    small_scene(**{"dynamic.torque": 1.01 * t, "dynamic.torque_change_time": 0.1, "dynamic.torque_after": 0.0})


# ---------------------------------------------------------------- messages

def test_a_study_given_to_run_and_a_scene_given_to_sweep_are_told_apart(tmp_path, capsys):
    code, _, err = run_cli(capsys, "run", "example_study", "-o", tmp_path / "r.nc")
    assert code == 2 and "example_study is a study" in err and "lightgear sweep" in err and "unknown key" not in err
    code, _, err = run_cli(capsys, "run", "study/scenes/tolerance.toml", "-o", tmp_path / "r.nc")
    assert code == 2 and "is a study" in err
    code, _, err = run_cli(capsys, "sweep", "paper", "-o", tmp_path / "s.nc")
    assert code == 2 and "this file is a scene" in err and "lightgear run" in err and "unknown study key" not in err


def test_an_output_folder_is_not_made_at_the_root_of_the_file_system(tmp_path, capsys):
    missing = Path("/nonexistent-lightgear") / "dir"
    code, _, err = run_cli(capsys, "run", "-o", missing / "x.nc")
    assert code == 2 and "-o: the folder /nonexistent-lightgear does not exist" in err and not missing.parent.exists()
    # one new folder in an existing one is made, as is any folder under the working directory
    from study.cli import checked_output
    assert checked_output(tmp_path / "new" / "x.nc").parent.is_dir()


def test_the_documented_default_mesh_size_is_the_codes():
    from solver.fe.mesh import default_mesh_size
    assert default_mesh_size(1.0) == 0.25 and "default module/4" in Path("docs/cli.md").read_text()


def test_a_field_prefix_cut_short_suggests_the_fields_it_begins(capsys):
    code, _, err = run_cli(capsys, "fields", "gear2.bod")
    assert code == 2 and "did you mean 'gear2.body'?" in err
    code, out, _ = run_cli(capsys, "fields", "gear2.body")
    assert code == 0 and "gear2.body.holes" in out
    code, _, err = run_cli(capsys, "fields", "gear2.body.hol")
    assert code == 2 and "'gear2.body.holes' or 'gear2.body.hole_radius'" in err


def test_the_study_tables_render_writes_are_an_archive_export_takes(tmp_path, capsys):
    """(and the example study's DTE RMS is defined at each speed: its steady part covers more
    than a mesh period at 50 rad/s)"""
    import xarray as xr
    code, _, err = run_cli(capsys, "sweep", "example_study", "-o", tmp_path / "s.nc", "--workers", 0, "--no-progress")
    assert code == 0, err
    with xr.open_dataset(tmp_path / "s.nc") as ds:
        assert np.isfinite(ds["dte_rms"].values).all()
    code, _, err = run_cli(capsys, "render", tmp_path / "s.nc", "-o", tmp_path / "fig", "--no-renders")
    assert code == 0 and (tmp_path / "fig" / "s_study_tables.nc").is_file(), err      # named after the archive
    code, out, err = run_cli(capsys, "export", tmp_path / "fig" / "s_study_tables.nc", "-o", tmp_path / "csv")
    assert code == 0 and "csv:" in out, err


def test_a_full_disk_is_said_as_such(tmp_path, capsys, monkeypatch):
    """HDF5 reports a full disk as 'NetCDF: HDF error': the free space tells it."""
    import shutil
    from collections import namedtuple

    import xarray as xr

    from study.archive.netcdf import write_netcdf
    from study.cli import guarded

    def hdf_error(self, *a, **k):
        raise RuntimeError("NetCDF: HDF error")
    monkeypatch.setattr(xr.Dataset, "to_netcdf", hdf_error)
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1e9, 1e9, 1000))
    ds = xr.Dataset({"x": ("n", np.arange(10.0))})
    assert guarded("lightgear run", lambda: write_netcdf(ds, tmp_path / "r.nc")) == 1
    err = capsys.readouterr().err
    assert "no space left on device: 0.0 MiB free" in err and "HDF error" not in err
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1e12, 0, 1e12))     # room: the error as it is
    with pytest.raises(RuntimeError, match="HDF error"):
        write_netcdf(ds, tmp_path / "r.nc")


def test_an_override_that_invalidates_another_field_is_named(capsys):
    code, _, err = run_cli(capsys, "run", "--set", "gear2.module=2", "--set", "dynamic.speed=50")
    assert code == 2 and "invalid scene: gear2.module: 2 makes gear2.body.hole_radius invalid" in err
    assert "holes cut the hub" in err
    # an override that is itself at fault is named as before
    code, _, err = run_cli(capsys, "run", "--set", "gear2.body.hole_radius=30")
    assert code == 2 and "invalid scene: gear2.body.hole_radius: holes cut the rim" in err


def test_a_run_up_whose_teeth_lose_contact_says_its_critical_speeds_are_linear(capsys, tmp_path):
    from study.plan import RunOptions
    from study.report.summary import print_summary
    from study.run import run_fields

    def runup(speed_end):
        scene = paper_pair(**{"dynamic.speed_end": speed_end, "dynamic.torque": 20.0, "dynamic.ramp_time": 0.002,
                              "dynamic.duration": 0.1})      # (the tracked speeds from some 430 rad/s)
        return run_fields(scene, {"dynamic", "modes", "gear"}, RunOptions(warn=False)).dataset()
    rattles = runup(1500.0)         # through 2Z and 1Z (about 250 and 495 rad/s) at 20 N·m: the teeth separate
    lo, hi = rattles.attrs["contact_lost_speed_rad_s"]
    z1 = float(rattles["critical_speed"].sel(excitation="1Z", mode=0))
    assert rattles.attrs["contact_lost_fraction"] > 0 and 0 < lo <= hi < 1500.0
    capsys.readouterr()
    print_summary(rattles, tmp_path / "r.nc", 1.0)
    out = capsys.readouterr().out
    assert f"the teeth lost contact between {lo:.0f} and {hi:.0f} rad/s" in out and "linear estimates" in out
    assert "1Z measured" in out and f"modal {z1:.0f}" in out
    steady = dynamic_fields(paper_pair())       # 100 rad/s, far below the resonances: always in contact
    assert steady.attrs["contact_lost_fraction"] == 0.0 and "contact_lost_speed_rad_s" not in steady.attrs


def test_fe_bodies_beyond_the_memory_are_refused_before_any_fe_work(tmp_path, capsys, monkeypatch, private_fe_cache):
    """A 10000-tooth driven gear: some 1.9e6 elements, tens of GiB (`study.estimate.body_bytes`,
    22 kB an element measured), refused naming the lever in run, sweep and reference alike,
    whatever --max-time; a body over half the memory is warned of."""
    from study import estimate
    monkeypatch.setattr(estimate, "available_memory", lambda: 16.0 * 2 ** 30)
    code, _, err = run_cli(capsys, "run", "small_pair", "--set", "gear2.teeth=10000", "--max-time", "1e9",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "fe.mesh_size: the FE bodies need about" in err and "GiB" in err
    assert "a coarser fe.mesh_size" in err and not FE_CACHE.folder.exists()
    code, _, err = run_cli(capsys, "reference", "small_pair", "--set", "gear2.teeth=10000", "--max-time", "1e9",
                           "-o", tmp_path / "f.nc")
    assert code == 2 and "fe.mesh_size: the FE bodies need about" in err
    st = tmp_path / "big.toml"
    st.write_text('scene = "small_pair"\n[grid]\n"gear2.teeth" = [24, 10000]\n[outputs]\nscalars = ["ste_p2p"]\n')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--max-time", "1e9")
    assert code == 2 and "fe.mesh_size: the FE bodies need about" in err and not FE_CACHE.folder.exists()
    # the small pair's bodies (some 80 MB each) pass; with 200 MB available they are warned of
    from study.inputs.gearsetup import gear_setups
    from tests.helpers import small_scene
    setups = gear_setups(small_scene())
    assert estimate.check_fe_memory(setups) is None
    monkeypatch.setattr(estimate, "available_memory", lambda: 250e6)
    assert "more than half of" in estimate.check_fe_memory(setups)


def test_precision_outputs_beyond_the_memory_are_refused_naming_its_option(tmp_path, capsys):
    code, out, err = run_cli(capsys, "precision", "--duration", "1e7", "-o", tmp_path / "p.nc")
    assert code == 2 and "--duration: the run's outputs need about" in err and "TiB" in err and "study ..." not in out
    code, _, err = run_cli(capsys, "precision", "--only", "static", "--rotation", "1e12", "-o", tmp_path / "p.nc")
    assert code == 2 and "--rotation: the static analysis needs about" in err

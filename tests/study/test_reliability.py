"""What a careless user or script meets: every bad input is exit 2 with the field or option
named, before any work; every refusal names the lever that helps."""
from pathlib import Path

import numpy as np
import pytest

from study.cli import main


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

def write_study(tmp_path, grid: str, outputs: str = 'scalars = ["dte_rms"]') -> str:
    text = (Path("study/scenes/example_study.toml").read_text().split("[grid]")[0]
            + f"[grid]\n{grid}\n[outputs]\n{outputs}\n")
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
    """With per-tooth laws (k_con, k_phi scaled by 'fe-ratio' or 'uniform'), a 0.1 mm face gives
    exactly the STE of 17 mm: the run says so and names the lever ('fe' springs)."""
    import study
    from study.plausibility import face_width_note
    assert face_width_note(small_scene()) is None
    thin = small_scene(**{"gear1.face_width": 0.1, "gear2.face_width": 0.1, "gear1.body.web_thickness": 0.1,
                          "gear2.body.web_thickness": 0.1})
    note = face_width_note(thin)
    assert "masses and inertias only" in note and "'fe'" in note
    assert face_width_note(thin.replace(**{"gear1.spring.stiffness": "fe", "gear2.spring.stiffness": "fe"})) is None
    a = study.run_scene(small_scene(), static=True, dynamic=False)
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

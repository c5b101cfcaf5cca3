"""What a careless user or script meets: results that would pass as ok, run-ups, geometry and
physics bounds, what reaches the terminal, outputs a run cannot support."""
from pathlib import Path

import numpy as np
import pytest
from reliability_cases import dynamic_fields, paper_pair, run_cli, small_scene, write_study

# ---------------------------------------------------------------- results that would pass as ok

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

"""Runs refused by their estimate before any work, progress of long runs, and the solver
guards that flag results not to be trusted (inaccurate energy balance, statics beyond the
deflection bound, the integrator `auto` picks)."""
import numpy as np
import pytest

import study
from study import estimate
from study.cli import main

STUDY = "study/scenes/example_study.toml"


@pytest.fixture(scope="module")
def small_model():
    from study.scene_model import build_scene_model
    return build_scene_model(study.load_study(STUDY).base_scene())


def test_a_run_whose_outputs_do_not_fit_in_memory_is_refused_at_once(example_scene_file, tmp_path, capsys):
    out = tmp_path / "x.nc"
    assert main(["run", str(example_scene_file), "-o", str(out), "--set", "dynamic.duration=1e6"]) == 2
    err = capsys.readouterr().err
    # 1e11 records of 11 float64 columns: terabytes, named with the field to change
    assert "dynamic.duration" in err and "TiB" in err and "1e+11 records" in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("args, words", [
    (["run", "{small}", "--set", "dynamic.duration=100", "--max-time", "5"], "dynamics (explicit"),
    (["stiffness", "--set", "fe.mesh_size=0.005"], "FE bodies"),
    (["reference", "--set", "fe.mesh_size=0.01"], "gear 2 FE body"),
    (["run", "--set", "gear2.teeth=10000", "--set", "gear2.body.holes=0", "--max-time", "1000"], "FE bodies"),
])
def test_runs_estimated_beyond_max_time_are_refused_with_the_estimate(args, words, example_scene_file, tmp_path, capsys):
    out = tmp_path / "x.nc"
    args = [a.replace("{small}", str(example_scene_file)) for a in args]
    assert main(args + ["-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--max-time" in err and "estimated at" in err and words in err and "Traceback" not in err
    assert not out.exists()


def test_max_time_must_be_positive_and_is_in_the_help(example_scene_file, tmp_path, capsys):
    assert main(["run", str(example_scene_file), "-o", str(tmp_path / "x.nc"), "--max-time", "0"]) == 2
    assert "--max-time: must be a positive" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["stiffness", "--help"])
    assert "--max-time" in capsys.readouterr().out


def test_estimates_scale_with_the_work():
    sc = study.default_scene()
    from study.inputs.gearsetup import gear_setups
    s2 = gear_setups(sc)[1]
    fine = gear_setups(sc.replace(**{"fe.mesh_size": s2.mesh_size * 1e3 / 2}))[1]
    ungraded = gear_setups(sc.replace(**{"fe.mesh_grading": "fine"}))[1]
    # the paper body has 21 200 triangles graded, 39 700 fine (gmsh); halving the size quadruples them
    assert estimate.body_elements(s2) == pytest.approx(21200, rel=0.25)
    assert estimate.body_elements(ungraded) == pytest.approx(39700, rel=0.25)
    assert estimate.body_elements(fine) == pytest.approx(4 * estimate.body_elements(s2), rel=1e-9)
    assert estimate.dynamic_records(sc) == 20001


def test_progress_reports_the_time_reached_and_leaves_the_result_unchanged(small_model):
    from solver.mbs.dynamics import simulate
    args = (small_model, 100.0, 0.002, 50.0, 0.002, 0.01)
    seen = []
    plain = simulate(*args)
    watched = simulate(*args, progress=seen.append)
    assert plain.status == watched.status == 0
    np.testing.assert_array_equal(plain.te, watched.te)
    assert seen and seen[-1] == pytest.approx(0.01) and np.all(np.diff(seen) >= 0)


def test_a_contact_too_stiff_for_its_step_is_flagged_inaccurate(paper_solid_model):
    """k_con x 1000: the explicit run completes, but at the step of the static linearisation
    it misses the contact events (force spikes of ~30 x the static force) and the energy
    balance error grows to the size of the mesh's potential energy: flagged, not silent.
    (Lightly damped, with the raw coefficients: the default damping ratio makes the step
    small enough to follow these contacts.) The default step (0.9 of the bound with the
    tooth-root dampers implicit) does not stay there: its guards see the force spikes and the
    energy balance, and the run is repeated at a smaller step, which completes."""
    from helpers import RAW_DAMPING, solid_scene

    from solver.mbs.dynamics import INACCURATE, simulate
    from solver.mbs.stability import stable_time_step
    from study.scene_model import build_scene_model
    stiff = build_scene_model(solid_scene(**RAW_DAMPING, **{"contact.k_con": 5.64e9}))
    dt_static, _w = stable_time_step(stiff, 50.0)
    r = simulate(stiff, 100.0, 0.01, 50.0, 0.01, 0.02, dt=dt_static)
    assert r.status == INACCURATE and r.message.startswith("inaccurate: energy balance error")
    assert np.max(r.force_max) > 10 * 50.0 / stiff.base_radii[1]
    guarded = simulate(stiff, 100.0, 0.01, 50.0, 0.01, 0.02)
    assert guarded.status == 0 and guarded.dt < stable_time_step(stiff, 50.0, implicit_dampers=True)[0]
    # the paper model at its default step (0.9 of the bound, tooth-root dampers implicit) reads
    # 0.16 of its potential energy (0.009 at half the bound, 0.0005 all-explicit at half the
    # damped bound): near the bound the energy Verlet reads at the step instants of the
    # tooth-on-contact mode exceeds its conserved one by up to a/(1 - a), a = (w dt/2)² = 0.81:
    # 4x that mode's share; TE stays within 0.002 um of a tight reference
    ok = simulate(paper_solid_model, 100.0, 0.01, 50.0, 0.01, 0.02)
    assert ok.status == 0 and np.max(np.abs(ok.energy_error)) < 0.25 * np.max(ok.potential)


def test_auto_takes_the_explicit_integrator(small_model):
    from solver.mbs.method import choose_method
    # 10 s of the small pair: millions of steps, still explicit (an implicit step costs ~20)
    ch = choose_method(small_model, 50.0, 10.0, "auto")
    assert ch.method == "explicit" and 10.0 / ch.dt > 2e6 and "auto: explicit" in ch.reason


def test_statics_beyond_the_deflection_bound_are_not_a_result(small_model):
    from solver.mbs.statics import StaticSolveError, solve_static
    angles = np.radians(np.arange(0.0, 6.0, 0.5))
    ok = solve_static(small_model, angles, 1000.0)            # 0.26 mm approach: inside 0.3 mm
    assert ok.converged.all() and ok.message == "ok"
    deep = solve_static(small_model, angles, 2000.0, raise_on_failure=False)   # Newton converges at 0.49 mm
    assert not deep.converged.any() and "beyond 0.2 x module = 0.3 mm" in deep.message
    with pytest.raises(StaticSolveError, match="flanks approach by up to 0.488 mm"):
        solve_static(small_model, angles, 2000.0)


def test_unconverged_statics_exit_3_with_the_count(example_scene_file, tmp_path, capsys, monkeypatch):
    """A run past the scene checks whose statics fail: the archive is written, the count and
    cause are on stderr, exit 3 (the load bound of the scene check is lifted for the test, and
    the damping and modes, which a static-only run takes at the STE's torque and which would
    refuse 2000 N·m before the statics, are taken at 50 N·m)."""
    from study import plan, plausibility, scene_model
    monkeypatch.setattr(plausibility, "DEFLECTION_FRACTION", 10.0)
    for module in (plan, scene_model):
        monkeypatch.setattr(module, "mean_load", lambda scene: 50.0)
    out = tmp_path / "x.nc"
    assert main(["run", str(example_scene_file), "-o", str(out), "--no-dynamic", "--set", "quasi_static.torque=2000"]) == 3
    err = capsys.readouterr().err
    assert "static equilibrium not reached at 37 of 37 angles" in err and "beyond 0.2 x module" in err
    assert out.exists()


def test_an_inaccurate_sweep_status_is_a_cf_flag():
    from study.sweep.outputs import STATUS
    assert STATUS[:5] == ("pending", "ok", "diverged", "invalid", "failed") and STATUS[5] == "inaccurate"


def test_a_coarse_implicit_run_of_a_rattling_150_tooth_pair_is_flagged():
    """150/150 teeth (solid): the pair rattles across the backlash with forces of 10-20 x the
    static one. HHT at 2.5 us completes with a wrong DTE and an energy balance error ten times
    the potential energy of the mesh; flagged, not ok. (Lightly damped: the raw coefficients.)"""
    from solver.mbs.dynamics import INACCURATE
    from solver.mbs.implicit import simulate_implicit
    from study.scene_model import build_scene_model
    sc = study.load_scene(None, ["gear1.teeth=150", "gear2.teeth=150", "gear2.body.holes=0",
                                 "gear2.body.web_thickness=17", "contact.c_con=3640",
                                 "gear1.spring.c_phi=0.062", "gear2.spring.c_phi=0.062", "coupling.model=paper"])
    m = build_scene_model(sc)
    r = simulate_implicit(m, 100.0, 0.01, 50.0, 0.01, 0.025, dt=2.5e-6)
    assert r.status == INACCURATE and np.max(r.force_max) > 10 * 50.0 / m.base_radii[1]


@pytest.mark.parametrize("k_phi", ["10600", "1060"])
def test_soft_tooth_springs_are_refused_before_the_statics(k_phi, example_scene_file, tmp_path, capsys):
    # 100 x and 1000 x softer than the paper's springs: the paper torque bends a pair by 0.8 / 6.6 mm
    # (k_phi is the paper model's spring; the coupled models take theirs from the FE body)
    out = tmp_path / "x.nc"
    assert main(["run", "-o", str(out), "--no-dynamic", "--set", "coupling.model=paper", "--set", f"gear1.spring.k_phi={k_phi}",
                 "--set", f"gear2.spring.k_phi={k_phi}"]) == 2
    err = capsys.readouterr().err
    assert "quasi_static.torque: implausible load" in err and "Traceback" not in err and not out.exists()


def test_a_sweep_point_whose_run_is_inaccurate_keeps_its_scalars_flagged():
    from helpers import RAW_DAMPING, solid_scene

    from solver.mbs.stability import stable_time_step
    from study.scene_model import build_scene_model
    from study.sweep.engine import run_point
    from study.sweep.outputs import Outputs
    sc = solid_scene(**RAW_DAMPING, **{"contact.k_con": 5.64e9, "dynamic.duration": 0.021})
    # the step of the static linearisation, given (the default step's load guard would repair it)
    sc = sc.replace(**{"dynamic.time_step": stable_time_step(build_scene_model(sc), 50.0)[0]})
    r = run_point(sc, Outputs(scalars=("dte_rms", "tooth_force_max")))
    assert r["status"] == "inaccurate" and r["message"].startswith("inaccurate: energy balance error")
    assert np.isfinite(r["scalars"]["dte_rms"]) and r["scalars"]["tooth_force_max"] > 10 * 1062.0

"""Reliability after the mesher and of the estimates: a sweep in one process stops on SIGTERM
once gmsh has run in it, the FE reference's time and memory are estimated before its work and
refused or warned of, and outputs a run cannot support are left undefined with their reason."""
import math
import signal

import numpy as np
import pytest

from tests.study.test_interrupt import SMALL, STEP, STOP_WITHIN_S, cli, stop_after

# ---------------------------------------------------------------- SIGTERM after the mesher, in a sweep

def fe_study(folder, step: str):
    """The interrupt tests' 20-tooth pair with the driven gear's springs from its FE body (gmsh
    runs for it), one speed (6 ms after the ramps: 1.5 mesh periods), at dynamic time step ``step`` [s]."""
    scene = SMALL.replace('"gear2.spring.stiffness" = "uniform"', '"gear2.spring.stiffness" = "fe-ratio"')
    path = folder / "fe.toml"
    path.write_text(f'title = "fe"\n[scene]\n{scene}"dynamic" = {{duration = 0.01, ramp_time = 0.002, time_step = {step}}}\n'
                    '[grid]\n"dynamic.speed" = [80.0]\n[outputs]\nscalars = ["ste_p2p", "dte_rms"]\n')
    return path


def test_a_sweep_in_process_stops_on_sigterm_after_its_first_fe_body_and_resumes(tmp_path, monkeypatch, capsys):
    """gmsh's C library puts its own signal handlers in place at every initialize: ``sweep
    --workers 0`` meshes its first point's FE body in its own process, and SIGTERM during the
    next task must still give the one "interrupted" line and exit 130 (143 and no line before
    the handlers were installed again after gmsh), and the same command resume."""
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "cache"))      # an empty FE cache: gmsh runs
    study = fe_study(tmp_path, STEP)
    out, parts = tmp_path / "s.nc", tmp_path / ".s.nc.parts"
    proc = cli(["sweep", study, "-o", out, "--workers", 0, "--no-progress", "--max-time", "1e9"], tmp_path)
    # the static task (FE body, then the STE) is stored first; the dynamic one runs for hours at this step
    code, took = stop_after(proc, lambda: parts.is_dir() and any(parts.glob("*.pkl")), signal.SIGTERM)
    err = (tmp_path / "err.txt").read_text()
    assert any((tmp_path / "cache" / "fe").glob("*.nc")), "no FE body was meshed in the sweep's process"
    assert code == 130 and took < STOP_WITHIN_S, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines[-1] == (f"lightgear sweep: interrupted: 1 finished analysis kept in {parts}; the same command "
                         "resumes from them"), err
    assert not out.exists() and len(list(parts.glob("*.pkl"))) == 1
    # resumable: the same study at a sane step reuses the stored static task (run here, in this
    # process: the resumption, not a signal, is checked, and a process start costs some 3 s of CPU)
    from study.cli import main
    fast = tmp_path / "fast"
    fast.mkdir()
    capsys.readouterr()
    assert main(["sweep", str(fe_study(fast, "0.0")), "-o", str(out), "--workers", "0", "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "computed 1, reused 1" in text and "ok 1" in text
    import xarray as xr
    with xr.open_dataset(out) as ds:
        assert np.isfinite(ds["ste_p2p"].values).all() and np.isfinite(ds["dte_rms"].values).all()


# ---------------------------------------------------------------- K_v of a driver at standstill

def test_a_run_at_standstill_archives_no_dynamic_factor_and_says_why(tmp_path, capsys, example_scene_file):
    """dynamic.speed = 0: no mesh period to take the forces over. K_v used to come out about 0.6
    (with numpy's "All-NaN slice" warning on the terminal); it is NaN with its reason in the
    archive and the summary, and the strength's safety factors are the static ones, said as
    such (not "no dynamic run": the run was made)."""
    import xarray as xr

    from study.cli import main
    out = tmp_path / "r.nc"
    code = main(["run", str(example_scene_file), "--set", "dynamic.speed=0", "-o", str(out)])
    printed, err = capsys.readouterr()
    assert code == 0, err
    assert "RuntimeWarning" not in err and "All-NaN" not in err
    why = "the driver stands still (dynamic.speed = 0)"
    assert f"dynamic factor K_v undefined: {why}" in printed
    with xr.open_dataset(out) as ds:
        assert np.isnan(float(ds["dynamic_factor"])) and why in ds["dynamic_factor"].attrs["comment"]
        assert why in ds.attrs["steady_window_note"]          # the DTE RMS and peak-to-peak likewise
        assert ds["bending_safety"].attrs["loads"] == "static (K_v undefined)"
        np.testing.assert_array_equal(ds["bending_safety"].values, ds["bending_safety_static"].values)
    assert "S_F (18CrNiMo7-6, sigma_FG 1000 MPa, static (K_v undefined))" in printed


# ---------------------------------------------------------------- ligaments the FE cannot hold

@pytest.mark.parametrize("overrides, field, between", [
    # 17 holes of the paper's web leaving 3e-5 mm between neighbours (the STE levelled off, no word)
    ({"gear2.body.holes": 17, "gear2.body.hole_radius": 32.36 * math.sin(math.pi / 17) - 1.5e-5},
     "gear2.body.holes", "between neighbouring openings is 3e-05 mm"),
    # a 6 mm hole exactly touching the rim (42.3 mm inside) and the hub (19.05 mm): a zero ligament
    ({"gear2.body.hole_circle_radius": 36.3}, "gear2.body.hole_circle_radius", "between the openings and the rim"),
    ({"gear2.body.hole_circle_radius": 25.05}, "gear2.body.hole_circle_radius", "between the openings and the hub"),
])
def test_a_ligament_the_fe_cannot_hold_is_refused_naming_the_field_and_its_width(overrides, field, between):
    from study.scene import SceneError, load_scene
    with pytest.raises(SceneError) as e:
        load_scene(None, [f"{k}={v!r}" for k, v in overrides.items()])
    assert e.value.field == field and between in str(e.value) and "thinner than the FE mesh can hold" in str(e.value)


# ---------------------------------------------------------------- the FE reference's memory and time

def thin_rim_fine(mesh_size: float = 0.15, grading: str = "fine"):
    """The paper pair with a 2.5 mm rim (the web taking up the rest) on a fine mesh: the kind of
    reference that took 332 s and 12.5 GB against an estimate of 86 s and no memory."""
    from study.scene import load_scene
    return load_scene("paper", ["gear2.body.rim_height=2.5", "gear2.body.web_height=26.825",
                                f"fe.mesh_size={mesh_size}", f"fe.mesh_grading={grading!r}"])


def test_the_references_memory_is_estimated_refused_and_warned_of_before_any_fe_work(monkeypatch, private_fe_cache, capsys):
    import study
    from study import estimate
    from study.errors import BudgetError
    from study.inputs.cache import FE_CACHE
    from study.scene_model import static_angles
    from study.verify import fe_reference
    scene = thin_rim_fine()
    est = fe_reference.reference_cost(scene, static_angles(scene))
    need = sum(est.memory.values())
    assert est.memory["gear 1 FE body"] > 0 and est.memory["gear 2 FE body"] > 0 and need > 4 * 2 ** 30
    ran = []
    monkeypatch.setattr(fe_reference, "reference_dataset", lambda *a, **k: ran.append(1) or "ran")
    monkeypatch.setattr(estimate, "available_memory", lambda: need / 0.9)
    with pytest.raises(BudgetError) as e:
        study.reference(scene, max_time=1e9)
    assert e.value.field == "fe.mesh_size" and "for the reference" in str(e.value) and "more than the" in str(e.value)
    assert not ran and not FE_CACHE.folder.exists()          # before any FE work
    monkeypatch.setattr(estimate, "available_memory", lambda: need / 0.6)
    assert study.reference(scene, max_time=1e9) == "ran"
    assert "lightgear: warning: fe.mesh_size: the FE bodies need about" in capsys.readouterr().err
    monkeypatch.setattr(estimate, "available_memory", lambda: need / 0.3)
    assert study.reference(scene, max_time=1e9) == "ran" and "warning" not in capsys.readouterr().err


def test_the_references_estimate_grows_with_the_fine_gradings_elements(private_fe_cache):
    """At one outline size the fine grading keeps small elements through the teeth and the rim:
    measured 1.6-1.9 x the graded mesh's CPU time and memory (benchmarks/bench_reference_cost.py),
    which the estimate follows; a cached body costs neither."""
    from study.scene_model import static_angles
    from study.verify.fe_reference import reference_cost
    graded, fine = (reference_cost(s, static_angles(s)) for s in (thin_rim_fine(0.25, "graded"), thin_rim_fine(0.25)))
    for part in ("gear 1 FE body", "gear 2 FE body"):
        assert 1.5 < fine.seconds[part] / graded.seconds[part] < 4.0
        assert 1.5 < fine.memory[part] / graded.memory[part] < 4.0


# ---------------------------------------------------------------- a study whose scene is a number

def test_a_study_whose_scene_is_a_number_is_named_through_every_door(tmp_path, capsys):
    """``scene = 5``: the sweep named it already; the tolerance workflow's --set (which makes
    the scene a table with its file) and a [scene] table's ``file = 5`` ended in
    "TypeError: expected str, bytes or os.PathLike object" (exit 1)."""
    import study
    from study.scene import SceneError
    from workflows.tolerance import main as tolerance
    st = tmp_path / "s.toml"
    st.write_text('scene = 5\n[sample]\nsize = 2\n"gear2.body.hole_radius" = {uniform = [1.0, 1.5]}\n')
    assert tolerance([str(st), "--set", "dynamic.speed=60", "-o", str(tmp_path / "t"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "scene.file: must be a scene file or an embedded scene's name, got 5" in err and "TypeError" not in err
    with pytest.raises(SceneError) as e:
        study.study_from_dict({"scene": {"file": 5, "dynamic.speed": 60.0}, "grid": {"dynamic.speed": [50.0]}})
    assert e.value.field == "scene.file"


def test_the_contact_peers_deck_memory_is_estimated_and_refused_before_ccx_runs(monkeypatch, capsys):
    """A CalculiX deck's ccx process: 37 kB a node measured (0.68 GB at 18 000 nodes, 1.38 GB at
    38 000 on the small pair), its nodes growing as 1/flank_size; refused naming --flank-size."""
    import study
    from study import estimate
    from study.errors import BudgetError
    from study.verify import calculix_reference as peer
    from tests.helpers import small_scene
    scene = small_scene(**{"quasi_static.rotation": 1.0, "quasi_static.angle_step": 0.5})
    coarse, fine = (peer.peer_estimate(1, peer.settings_for(scene, f), 3e-3) for f in (0.4, 0.1))
    assert fine.memory["CalculiX deck"] == pytest.approx(4 * coarse.memory["CalculiX deck"])
    assert 0.34e9 < coarse.memory["CalculiX deck"] < 1.36e9          # within 2 x of the 0.68 GB measured
    ran = []
    monkeypatch.setattr(peer, "calculix_dataset", lambda *a, **k: ran.append(1) or "ran")
    monkeypatch.setattr(estimate, "available_memory", lambda: 1.5e9)
    with pytest.raises(BudgetError) as e:
        study.reference(scene, solver="calculix", max_time=1e9)          # module/30: some 3.7 GB a deck
    assert e.value.field == "--flank-size" and "a CalculiX deck needs about" in str(e.value) and not ran
    assert study.reference(scene, solver="calculix", flank_size=0.4, max_time=1e9) == "ran"
    assert "warning: --flank-size" in capsys.readouterr().err            # 0.9 GB: over half of 1.5 GB

"""A study's worker keeps a scene's model for the points that differ only in the dynamic run:
the same model, the same numbers as one built afresh."""
import numpy as np
from helpers import solid_scene

from solver.mbs.kernels import layout as L
from study import scene_model
from study.run import run_scene
from study.scene_model import build_scene_model, kept_scene_model, model_key

SHORT = {"quasi_static.rotation": 4.0, "quasi_static.angle_step": 1.0, "dynamic.duration": 0.003,
         "dynamic.ramp_time": 0.001}


def test_points_that_differ_only_in_speed_share_the_model_and_the_rest_do_not():
    base = solid_scene(**SHORT)
    faster = base.replace(**{"dynamic.speed": 2 * base.dynamic.speed})
    assert model_key(base, None, True) == model_key(faster, None, True)
    assert kept_scene_model(faster) is kept_scene_model(base)
    # the mean load the damping ratios are converted at, a gear, the contact: another model
    for other in ({"dynamic.torque": 2 * base.dynamic.torque}, {"gear2.body.rim_height": 5.0},
                  {"contact.damping_ratio": 0.03}):
        assert model_key(base.replace(**other), None, True) != model_key(base, None, True), other
    springs = ((np.full(20, 1e5), np.ones(20)), (np.full(20, 1e5), np.ones(20)))
    assert model_key(base, springs, True) != model_key(base, None, True)
    assert model_key(base, None, False) != model_key(base, None, True)


def test_the_kept_model_equals_one_built_afresh_and_gives_the_same_run():
    scene_model.MODELS.clear()
    a = solid_scene(**SHORT)
    b = a.replace(**{"dynamic.speed": 1.5 * a.dynamic.speed})
    kept = kept_scene_model(a)
    fresh = build_scene_model(b)
    assert kept is not fresh
    for name in ("gear_par", "pair_par", "law_par", "k_phi"):
        np.testing.assert_array_equal(getattr(kept, name), getattr(fresh, name))
    # a run after one at another speed: its model kept from that run, its numbers unchanged
    scene_model.MODELS.clear()
    run_scene(a, warn=False, keep_model=True)
    ds_kept = run_scene(b, warn=False, keep_model=True)
    assert len(scene_model.MODELS) == 1
    ds_fresh = run_scene(b, warn=False)
    for name in ("ste", "dte"):
        np.testing.assert_array_equal(ds_kept[name].values, ds_fresh[name].values)


# a tolerance study's builds: drawn pitch deviations, runout and tip relief on one pair
SAMPLED = {"size": 3, "method": "sobol", "seed": 1,
           "gear1.errors.seed": {"integers": [0, 999999]},
           "gear1.errors.eccentricity": {"uniform": [0.0, 5.0]},                      # um
           "gear1.modification.tip_relief": {"normal": [2.0, 0.5], "bounds": [1.0, 3.0]}}    # um
RELIEF = {"gear1.modification.tip_relief": 2.0, "gear1.modification.tip_shape": "linear",
          "gear1.modification.tip_length": 3.55}


def _clear():
    scene_model.MODELS.clear()
    scene_model.FLANKLESS.clear()


def test_a_build_with_other_flanks_is_the_kept_flankless_model_with_its_own_written_in():
    _clear()
    a = solid_scene(**SHORT, **RELIEF, **{"gear1.errors.grade": 5, "gear1.errors.seed": 1})
    b = a.replace(**{"gear1.errors.grade": 7, "gear1.errors.seed": 2, "gear1.errors.eccentricity": 3.0,
                     "gear1.modification.tip_relief": 2.5})
    model_a = build_scene_model(a)
    flankless = scene_model.flankless_model(b)
    kept_par = flankless.gear_par.copy(), flankless.pair_par.copy()
    model_b = build_scene_model(b)
    assert len(scene_model.FLANKLESS) == 1          # b's model came from a's flankless one
    scene_model.FLANKLESS.clear()
    fresh_b = build_scene_model(b)
    for name in ("gear_par", "pair_par", "law_par", "k_phi"):
        np.testing.assert_array_equal(getattr(model_b, name), getattr(fresh_b, name))
    # the builds differ where their flanks do (and so do their converted dampers), and the kept
    # model was not written into: no deviation, no errors block
    assert not np.array_equal(model_a.pair_par, model_b.pair_par)
    assert not np.array_equal(model_a.gear_par[0], model_b.gear_par[0])
    np.testing.assert_array_equal(flankless.gear_par, kept_par[0])
    np.testing.assert_array_equal(flankless.pair_par, kept_par[1])
    assert flankless.pair_par.size == L.N_PAIR_PAR and not np.any(flankless.gear_par[:, L.DEV_ON])
    assert model_b.inputs[0].errors == b.errors_spec(1) and model_b.inputs[0].modification == b.modification_spec(1)


def test_a_tolerance_study_builds_its_model_once_and_archives_what_a_model_per_build_gives(tmp_path, monkeypatch):
    import dataclasses

    import xarray as xr

    from study.sweep.engine import run_sweep
    from study.sweep.grid import dumps_study, loads_study
    raw = {"title": "builds", "scene": dataclasses.asdict(solid_scene(**SHORT, **RELIEF)),
           "grid": {"gear1.errors.grade": [5, 7]}, "sample": SAMPLED,
           "outputs": {"scalars": ["ste_p2p", "dte_rms", "amp_mesh_order"]}}
    st = loads_study(dumps_study(raw))
    built = []
    real = scene_model._build_flankless
    monkeypatch.setattr(scene_model, "_build_flankless", lambda *a: built.append(1) or real(*a))
    _clear()
    once = run_sweep(st, tmp_path / "once.nc", workers=0, progress=False).dataset
    assert len(built) == 1 and int((once["status"] == 1).sum()) == 6
    monkeypatch.setattr(scene_model.FLANKLESS, "kept", lambda key, make: make())      # every build makes its own
    _clear()
    built.clear()
    each = run_sweep(st, tmp_path / "each.nc", workers=0, progress=False).dataset
    assert len(built) == 6       # once a build: its statics and dynamic run follow each other (`by_model`)
    # the builds differ, and the archives are the same to the bit
    assert np.unique(once["ste_p2p"].values).size == 6
    drop = ["wall_time"]
    xr.testing.assert_identical(once.drop_vars(drop).load().assign_attrs(created="", history=""),
                                each.drop_vars(drop).load().assign_attrs(created="", history=""))


def test_a_model_changed_in_place_leaves_the_kept_flankless_one_and_the_next_build_alone():
    _clear()
    a = solid_scene(**SHORT, **RELIEF)
    first = build_scene_model(a)
    for name in ("gear_par", "pair_par", "law_par", "k_phi"):
        getattr(first, name)[...] *= 2.0
    again = build_scene_model(a)
    scene_model.FLANKLESS.clear()
    fresh = build_scene_model(a)
    for name in ("gear_par", "pair_par", "law_par", "k_phi"):
        np.testing.assert_array_equal(getattr(again, name), getattr(fresh, name))

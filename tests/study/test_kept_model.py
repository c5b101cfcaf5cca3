"""A study's worker keeps a scene's model for the points that differ only in the dynamic run:
the same model, the same numbers as one built afresh."""
import numpy as np
from helpers import solid_scene

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

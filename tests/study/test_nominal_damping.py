"""A study's points with flank deviations take the dampers of their nominal flanks: the mesh
ratio converted once, at the pair with perfect involutes and no pitch errors, gives that pair's
mesh mode the requested ratio; every build of the study runs with those coefficients, whatever
its drawn deviations; a single run of such a scene carries the same dampers as its study point."""
import dataclasses

import numpy as np
from helpers import solid_scene

from solver.mbs.kernels import layout as L
from solver.mbs.modes import modal_analysis
from study import scene_model
from study.run import run_scene
from study.scene_model import NOMINAL_NOTE, build_scene_model, converted_damping, flankless_model, mean_load, nominal_dampers

SHORT = {"quasi_static.rotation": 4.0, "quasi_static.angle_step": 1.0, "dynamic.duration": 0.003,
         "dynamic.ramp_time": 0.001}
RELIEF = {"gear1.modification.tip_relief": 2.0, "gear1.modification.tip_shape": "linear",
          "gear1.modification.tip_length": 3.55}
FLANKED = {**RELIEF, "gear1.errors.grade": 7, "gear1.errors.seed": 4, "gear1.errors.eccentricity": 4.0}


def _clear():
    for shelf in (scene_model.MODELS, scene_model.FLANKLESS, scene_model.NOMINAL):
        shelf.clear()


def _mesh_ratio(model, load):
    """The mesh mode's ratio of critical [1], mean over the 12 loaded equilibria."""
    return float(np.nanmean(modal_analysis(model, load).damping[0]))


def test_the_nominal_dampers_give_the_nominal_mesh_mode_its_ratio_and_a_build_keeps_them():
    _clear()
    scene = solid_scene(**SHORT, **FLANKED)
    zeta, load = scene.contact.damping_ratio, mean_load(scene)
    c_phi, c_con, _c_body = nominal_dampers(scene)
    assert c_con == 0.0 and min(c_phi) > 0.0
    nominal = flankless_model(scene)
    from solver.mbs.modes import with_damping
    assert abs(_mesh_ratio(with_damping(nominal, c_phi=c_phi), load) - zeta) < 1e-6 * zeta
    # converted at the build's own flanks, its dampers would differ (each build its own)
    own = converted_damping(scene, build_scene_model(scene, convert_damping=False))[0]
    assert abs(_mesh_ratio(own, load) - zeta) < 1e-6 * zeta
    assert not np.allclose(own.gear_par[:, L.C_PHI], c_phi, rtol=1e-3)
    # a single run's model takes the nominal ones, as the study's point does
    np.testing.assert_array_equal(build_scene_model(scene).gear_par[:, L.C_PHI], c_phi)
    # a study's build: its own flanks, the nominal dampers, and not the mesh ratio exactly
    kept = scene_model.kept_scene_model(scene)
    np.testing.assert_array_equal(kept.gear_par[:, L.C_PHI], c_phi)
    np.testing.assert_array_equal(kept.gear_par[:, L.DEV0:], own.gear_par[:, L.DEV0:])
    np.testing.assert_array_equal(kept.pair_par, own.pair_par)
    assert 0.0 < abs(_mesh_ratio(kept, load) / zeta - 1.0) < 0.2


def test_a_study_converts_once_and_says_where(tmp_path, monkeypatch):
    from study.sweep.engine import run_sweep
    from study.sweep.grid import dumps_study, loads_study
    raw = {"title": "builds", "scene": dataclasses.asdict(solid_scene(**SHORT, **RELIEF)),
           "grid": {"gear1.errors.grade": [5, 7]},
           "sample": {"size": 2, "method": "sobol", "seed": 1, "gear1.errors.seed": {"integers": [0, 999999]},
                      "gear1.errors.eccentricity": {"uniform": [0.0, 5.0]},
                      "gear1.modification.tip_relief": {"normal": [2.0, 0.5], "bounds": [1.0, 3.0]}},
           "outputs": {"scalars": ["ste_p2p", "dte_rms"]}}
    st = loads_study(dumps_study(raw))
    conversions = []
    real = scene_model._converted
    monkeypatch.setattr(scene_model, "_converted", lambda *a: conversions.append(1) or real(*a))
    _clear()
    ds = run_sweep(st, tmp_path / "builds.nc", workers=0, progress=False).dataset
    assert int((ds["status"] == 1).sum()) == ds["status"].size == 4
    assert np.isfinite(ds["dte_rms"].values).all() and np.unique(ds["dte_rms"].values).size == 4
    assert len(conversions) == 1
    assert ds.attrs["damping_conversion"] == NOMINAL_NOTE
    # every build's kept model carries the one conversion's dampers
    c_phi = nominal_dampers(st.points()[0].scene)[0]
    for p in st.points():
        np.testing.assert_array_equal(scene_model.kept_scene_model(p.scene).gear_par[:, L.C_PHI], c_phi)


def test_a_run_archive_says_where_its_dampers_were_converted():
    _clear()
    ds = run_scene(solid_scene(**SHORT, **RELIEF), dynamic=False, warn=False)
    assert ds.attrs["damping_conversion"] == NOMINAL_NOTE
    assert run_scene(solid_scene(**SHORT), dynamic=False, warn=False).attrs["damping_conversion"].startswith(
        "at the scene's own loaded equilibria")
    given = solid_scene(**SHORT, **{"contact.c_con": 3640.0, "gear1.spring.c_phi": 0.1, "gear2.spring.c_phi": 0.1})
    assert run_scene(given, dynamic=False, warn=False).attrs["damping_conversion"].startswith("none")

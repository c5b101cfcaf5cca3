"""The mesh damping ratio of a body-coupled pair whose tooth-root joints alone cannot give it:
the body dampers take part, and the modal analysis of the model built reads the ratio asked for."""
import numpy as np
import pytest

from study.scene import load_scene


def test_body_dampers_join_the_joints_where_they_cannot_reach_the_mesh_ratio(private_fe_cache):
    from solver.mbs.equilibria import loaded_equilibria
    from solver.mbs.kernels import layout as L
    from solver.mbs.model import body_critical_damping
    from solver.mbs.modes import joint_damping_for_ratio, modal_analysis
    from study.scene_model import build_scene_model, mean_load

    # joints alone: at most about 5.3 % of critical on the mesh mode
    scene = load_scene("small_lightened").replace(**{"contact.damping_ratio": 0.08})
    assert scene.coupling_model == "compliance"
    raw = build_scene_model(scene, convert_damping=False)
    eqs = loaded_equilibria(raw, mean_load(scene))
    with pytest.raises(ValueError, match="cannot damp the mesh mode"):
        joint_damping_for_ratio(raw, eqs, 0.08)
    model = build_scene_model(scene)
    modes = modal_analysis(model, mean_load(scene))
    assert float(np.nanmean(modes.damping[0])) == pytest.approx(0.08, rel=1e-6)
    # joints and bodies at one ratio of their own modes, above the 2 % the bodies had
    gp = model.gear_par
    ratio = [gp[i, L.C_BODY] / body_critical_damping(gp, i) for i in (0, 1)]
    assert ratio[0] == pytest.approx(ratio[1], rel=1e-9) and ratio[0] > 0.02

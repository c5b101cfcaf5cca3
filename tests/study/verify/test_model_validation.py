"""The default model against the FE reference: STE figures on a small lightened pair, the
tip relief that minimises the STE, and the default's name in scenes, studies and archives."""
import numpy as np
import pytest

from study.scene import SceneError, default_scene, load_scene
from study.scene_model import build_scene_model
from study.verify import model_validation as mv

LIGHT = {"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4, "gear2.body.hole_radius": 3.0,
         "gear2.body.hole_circle_radius": 19.5, "quasi_static.torque": 100.0}


def small_light(**kw):
    """The small 24-tooth pair (the small_pair scene), the driven gear with a web of 8 mm and 4 holes."""
    return load_scene("small_pair").replace(**{**LIGHT, **kw})


def test_the_default_model_of_a_lightened_pair_agrees_with_the_fe_reference():
    scene = small_light()
    assert scene.coupling.model == "auto" and scene.coupling_model == "compliance"
    angles = np.radians(np.arange(0.0, 90.0001, 0.25))          # one revolution of the 4 holes' period
    f = mv.ste_figures(scene, angles, ("fe-reference", "paper", "compliance"))
    ref = f["fe-reference"]
    assert ref["hole"] > 0.02 * ref["p2p"]                        # the holes are visible in the STE
    err = {m: {k: f[m][k] / ref[k] - 1 for k in ("elastic_mean", "p2p", "hole")} for m in ("paper", "compliance")}
    c = err["compliance"]
    assert abs(c["elastic_mean"]) < mv.TARGETS["elastic_mean"]
    assert abs(c["p2p"]) < mv.TARGETS["p2p"]
    assert abs(c["hole"]) < mv.TARGETS["hole"]
    # and the paper's plain model does not: it misses the ripple, which is why it is not the default
    assert abs(err["paper"]["p2p"]) > mv.TARGETS["p2p"]


def test_the_relief_that_minimises_the_ste_agrees_with_the_fe_reference():
    """At a light and a heavy load: the compliance model's optimum relief within the target of
    the FE reference's, its STE within the targets without relief (the local tooth compliance
    in series with the contact is what gets the heavy load's optimum right)."""
    scene = load_scene("small_pair").solid()
    ds = mv.relief_dataset({"small": scene}, reliefs=(0.0, 2.0, 4.0, 6.0, 8.0, 10.0), torques=(25.0, 100.0),
                           rotations={"small": 15.0}, step=0.25, models=("fe-reference", "compliance"))
    for torque in (25.0, 100.0):
        opt = ds["optimum_relief"].sel(pair="small", torque=torque)
        p2p = ds["ste_p2p"].sel(pair="small", torque=torque, model="fe-reference").values
        assert p2p.min() < 0.7 * p2p[0]                           # the relief matters at this load
        assert 0.0 < float(opt.sel(model="fe-reference")) < 10.0  # an optimum inside the grid, refined
        assert abs(float(opt.sel(model="compliance") - opt.sel(model="fe-reference"))) < mv.TARGETS["relief_um"]
    assert mv.check_targets(ds.isel(relief=[0]), "compliance") == []


def test_the_paper_model_is_one_key_away_and_none_still_reads():
    scene = small_light()
    paper = scene.replace(**{"coupling.model": "paper"})
    assert paper.coupling_model == "none" and paper.coupling_model_name == "paper"
    assert scene.replace(**{"coupling.model": "none"}).coupling_model_name == "paper"
    assert not build_scene_model(paper).teeth_coupled
    # a pair of solid bodies runs the compliance model too: the plain model misses its STE ripple
    solid = default_scene().solid()
    assert solid.coupling.model == "auto" and solid.coupling_model == "compliance"
    # springs that ignore the body on both gears ask for no FE: the paper's model
    uniform = {"gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform"}
    assert solid.replace(**uniform).coupling_model == "none"
    assert scene.replace(**uniform).coupling_model == "none"
    # one gear's FE springs are enough for the coupled model
    assert scene.replace(**{"gear2.spring.stiffness": "uniform"}).coupling_model == "compliance"
    with pytest.raises(SceneError, match="coupling.model"):
        scene.replace(**{"coupling.model": "plain-ish"})


def test_a_study_over_solid_and_lightened_bodies_runs_one_model():
    from study.sweep.grid import coupling_models, make_study
    base = default_scene().replace(**{"gear2.body.web_thickness": 17.0})
    pts = make_study(base, {"gear2.body.holes": [0, 6]}, outputs={"scalars": ["ste_p2p"]}).points()
    assert [p.scene.coupling_model for p in pts] == ["compliance", "compliance"]
    assert coupling_models(pts) == "compliance"
    # a grid that switches the FE springs off on some points still runs one model
    uni = base.replace(**{"gear1.spring.stiffness": "uniform"})
    pts = make_study(uni, {"gear2.spring.stiffness": ["uniform", "fe-ratio"]}, outputs={"scalars": ["ste_p2p"]}).points()
    assert [p.scene.coupling_model for p in pts] == ["compliance", "compliance"]
    pts = make_study(base.replace(**{"coupling.model": "paper"}), {"gear2.body.holes": [0, 6]},
                     outputs={"scalars": ["ste_p2p"]}).points()
    assert coupling_models(pts) == "paper"


def test_the_run_archive_names_the_model_it_ran():
    from study.run import run_scene
    scene = load_scene("small_pair").replace(**{"quasi_static.rotation": 15.0, "quasi_static.angle_step": 0.5,
                                                "gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform"}).solid()
    ds = run_scene(scene, static=True, dynamic=False)
    assert ds.attrs["coupling_model"] == "paper" and ds.attrs["coupling_model_setting"] == "auto"
    lite = small_light(**{"quasi_static.rotation": 15.0, "quasi_static.angle_step": 0.5})
    ds = run_scene(lite, static=True, dynamic=False)
    assert ds.attrs["coupling_model"] == "compliance" and ds.attrs["coupling_model_setting"] == "auto"
    assert ds.attrs["teeth_coupled"] == 1


def test_the_implicit_integrator_with_a_coupled_model_is_refused_before_any_work():
    """HHT-alpha carries the paper's model only: the default resolved to the compliance model
    with dynamic.method = 'implicit' is a SceneError naming both fields and the ways out; the
    paper's model named, the scene is valid; 'auto' picks the explicit integrator."""
    solid = default_scene().solid()
    with pytest.raises(SceneError, match=r"dynamic.method.*coupling.model = 'auto' runs the compliance model.*"
                                         r"coupling.model = 'paper'.*dynamic.method = 'explicit'"):
        solid.replace(**{"dynamic.method": "implicit"})
    with pytest.raises(SceneError, match=r"dynamic.method.*'body-torsion' is a coupled model"):
        solid.replace(**{"dynamic.method": "implicit", "coupling.model": "body-torsion"})
    ok = solid.replace(**{"dynamic.method": "implicit", "coupling.model": "paper"})
    assert ok.coupling_model == "none"
    # no dynamic run, no integrator: nothing to refuse
    assert solid.replace(**{"dynamic.method": "implicit", "dynamic.enabled": False}).coupling_model == "compliance"
    assert solid.replace(**{"dynamic.method": "auto"}).coupling_model == "compliance"

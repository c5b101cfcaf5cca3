"""Scene fields of the profile modification: conversions to roll angles, the table, errors."""
import math

import numpy as np
import pytest

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.gearmesh import flank_deviation
from study.scene import SceneError, default_scene, loads_scene
from study.scene_model import geometry_model

M = "gear1.modification."


def _geo(scene, g=1):
    return scene.geometry(g)


def test_three_ways_to_start_a_tip_relief_give_the_same_roll():
    """A start by roll angle, by diameter and by length along the path of contact name the same
    flank point: u = sqrt((d/2/rb)^2 - 1), length = rb*(u_tip - u)."""
    s0 = default_scene()
    g = _geo(s0)
    u = 0.5 * (g.u_form + g.u_tip)
    d = 2.0 * g.base_radius * math.sqrt(1.0 + u * u) * 1e3
    length = g.base_radius * (g.u_tip - u) * 1e3
    starts = [s0.replace(**{M + "tip_relief": 15.0, M + key: v}).modification_spec(1).tip.start
              for key, v in (("tip_start_roll", math.degrees(u)), ("tip_start_diameter", d), ("tip_length", length))]
    np.testing.assert_allclose(starts, u, rtol=1e-12)


def test_relief_amount_and_shape_at_the_flank_ends():
    """Linear tip relief: the amount at the tip, half of it halfway, none below its start;
    parabolic: a quarter halfway. Root relief: the amount at the form circle."""
    s0 = default_scene()
    g = _geo(s0)
    u_s = g.u_tip - 0.1
    for shape, half in (("linear", 0.5), ("parabolic", 0.25)):
        mod = s0.replace(**{M + "tip_relief": 20.0, M + "tip_shape": shape,
                            M + "tip_start_roll": math.degrees(u_s)}).modification_spec(1)
        dev = mod.deviation([u_s - 0.01, u_s + 0.05, g.u_tip], g.u_form, g.u_tip)
        np.testing.assert_allclose(dev, [0.0, half * 20e-6, 20e-6], atol=1e-15)
    mod = s0.replace(**{M + "root_relief": 8.0, M + "root_length": 1.0}).modification_spec(1)
    u_r = g.u_form + 1e-3 / g.base_radius
    np.testing.assert_allclose(mod.deviation([g.u_form, u_r, g.u_tip], g.u_form, g.u_tip), [8e-6, 0, 0], atol=1e-15)


def test_the_model_table_interpolates_the_deviation():
    """The kernel's table holds the deviation on its grid: linear parts are exact, between
    the nodes the table is linear, beyond the flank it is constant; zero modification: DEV_ON 0."""
    s0 = default_scene()
    assert not geometry_model(s0).gear_par[:, L.DEV_ON].any()
    s = s0.replace(**{"gear2.modification.profile_roll": [16.0, 20.0, 24.0],
                      "gear2.modification.profile_deviation": [4.0, -2.0, 6.0]})
    gp = geometry_model(s).gear_par
    assert gp[1, L.DEV_ON] == 1.0 and gp[0, L.DEV_ON] == 0.0
    h = gp[1, L.DEV_DU]
    slope = 8e-6 / math.radians(4.0)                              # the steeper segment [m/rad]
    assert gp[1, L.DEV_NEG] == pytest.approx(2e-6, abs=slope * h)  # the sampled low point (a kink between nodes)
    for deg, um in ((16.0, 4.0), (18.0, 1.0), (22.0, 2.0), (24.0, 6.0), (5.0, 4.0), (40.0, 6.0)):
        dev, _ = flank_deviation(gp, 1, math.radians(deg))
        assert dev == pytest.approx(um * 1e-6, abs=slope * h / 4 + 1e-12), deg


def test_scene_round_trip_keeps_the_table():
    s = default_scene().replace(**{M + "profile_diameter": [98.0, 101.0, 103.0], M + "profile_deviation": [1.0, 0.0, 3.5],
                                   M + "tip_relief": 10.0, M + "tip_shape": "parabolic", M + "tip_length": 1.5})
    back = loads_scene(s.to_toml())
    assert back == s
    assert back.gear1.modification.profile_diameter == (98.0, 101.0, 103.0)


@pytest.mark.parametrize("over, field, words", [
    ({M + "tip_relief": 10.0}, M + "tip_relief", "needs its start"),
    ({M + "tip_relief": 10.0, M + "tip_length": 1.0, M + "tip_start_roll": 20.0}, M + "tip_length", "not both"),
    ({M + "tip_relief": 10.0, M + "tip_length": 30.0}, M + "tip_length", "off the flank"),
    ({M + "root_relief": 10.0, M + "root_start_diameter": 110.0}, M + "root_start_diameter", "off the flank"),
    ({M + "tip_relief": -1.0}, M + "tip_relief", ">= 0"),
    ({M + "tip_shape": "cubic"}, M + "tip_shape", "one of"),
    ({M + "profile_deviation": [1.0, 2.0]}, M + "profile_deviation", "one per position"),
    ({M + "profile_roll": [20.0, 18.0], M + "profile_deviation": [1.0, 2.0]}, M + "profile_roll", "increasing"),
    ({M + "profile_roll": [18.0, "x"]}, M + "profile_roll", "a number"),
    ({M + "profile_roll": 18.0}, M + "profile_roll", "a list"),
])
def test_bad_modifications_name_the_field(over, field, words):
    with pytest.raises(SceneError) as e:
        default_scene().replace(**over)
    assert e.value.field == field and words in e.value.reason


def test_relief_scene_and_study_load():
    """The embedded relief scene relieves both tips by its stated amount over the double-contact
    stretch of the path of contact; its study builds its 48 points without error."""
    from pathlib import Path

    from study.scene import load_scene
    from study.sweep.grid import load_study
    here = Path(__file__).resolve().parents[2] / "study" / "scenes"
    s = load_scene(here / "paper_relief.toml")
    m = geometry_model(s)
    length = (m.pair.contact_ratio - 1.0) * m.pair.base_pitch * 1e3
    for g in (1, 2):
        mod = s.gear(g).modification
        assert mod.tip_relief == 2.0 and mod.tip_length == pytest.approx(length, abs=0.01)
    st = load_study(here / "relief_study.toml")
    assert len(st.points()) == 48 and all(p.scene is not None for p in st.points())

"""The small and solid pairs the tests run are embedded scenes: each is the paper example with the
changes its header states, field for field, and loads by name."""
import dataclasses

import pytest
from helpers import scene_overrides

import study
from study.scene import default_scene, load_scene


def same_but_title(a, b) -> bool:
    """Every field equal but the free-text title (repr: the unset dampers are NaN)."""
    return repr(dataclasses.replace(a, title="")) == repr(dataclasses.replace(b, title=""))


def small_pair_fields() -> dict:
    fields = {"pair.backlash": 0.1}
    for g in (1, 2):
        fields |= {f"gear{g}.module": 3.0, f"gear{g}.teeth": 24, f"gear{g}.fillet_radius": 0.9,
                   f"gear{g}.face_width": 20.0, f"gear{g}.body.rim_height": 4.0, f"gear{g}.body.web_height": 14.0,
                   f"gear{g}.body.hub_height": 6.0, f"gear{g}.body.web_thickness": 20.0, f"gear{g}.body.holes": 0}
    return fields


SMALL_LIGHTENED = {
    "gear1.module": 2.0, "gear1.teeth": 24, "gear2.module": 2.0, "gear2.teeth": 24, "fe.mesh_size": 1.0,
    "gear1.body.rim_height": 3.0, "gear1.body.web_height": 12.0, "gear1.body.hub_height": 3.0,
    "gear1.body.web_thickness": 17.0, "gear1.body.holes": 0, "gear2.body.rim_height": 3.0,
    "gear2.body.web_height": 12.0, "gear2.body.hub_height": 3.0, "gear2.body.web_thickness": 8.0,
    "gear2.body.holes": 8, "gear2.body.hole_radius": 3.0, "gear2.body.hole_circle_radius": 12.5,
}


@pytest.mark.parametrize("name, expected", [
    ("small_pair", lambda: default_scene().replace(**small_pair_fields())),
    ("small_lightened", lambda: default_scene().replace(**SMALL_LIGHTENED)),
    ("paper_solid", lambda: study.solid_scene(default_scene(), gears=(2,))),
], ids=["small_pair", "small_lightened", "paper_solid"])
def test_a_test_scene_is_the_paper_example_with_the_changes_it_states(name, expected):
    scene = load_scene(name)
    assert same_but_title(scene, expected())
    assert study.scenes()[name][1:] == ("scene", scene.title)       # listed by `lightgear scenes`
    # the same fields set over the paper example by dotted path (as --set or a study's [scene] table)
    assert same_but_title(default_scene().replace(**scene_overrides(name)), scene)


def test_only_the_lightened_pair_has_a_lightened_gear_and_every_pair_the_compliance_model():
    """As their headers say: one lightened gear in the small lightened pair, none in the solid
    pairs; all three run the default compliance model (the solid ones too: its FE is their
    body's), the paper's plain model one key away."""
    scenes = {n: load_scene(n) for n in ("small_pair", "paper_solid", "small_lightened")}
    assert {n: (s.is_lightened(1), s.is_lightened(2), s.coupling_model) for n, s in scenes.items()} == {
        "small_pair": (False, False, "compliance"), "paper_solid": (False, False, "compliance"),
        "small_lightened": (False, True, "compliance")}
    assert all(s.replace(**{"coupling.model": "paper"}).coupling_model == "none" for s in scenes.values())

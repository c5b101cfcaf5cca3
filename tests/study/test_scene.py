"""Scenes: field checks that name the field, dotted-path overrides, metadata and TOML round trip."""
import pytest

from study.scene import SceneError, default_scene, field_doc, field_unit, get_dotted, load_scene, loads_scene, parse_override


@pytest.mark.parametrize("text, field, reason", [
    ("[gear2]\nteeth = 4", "gear2.teeth", "must be >= 6"),
    ("[gear2.body]\nholez = 3", "gear2.body.holez", "unknown key"),
    ("[gear2.body]\nholes = 2.5", "gear2.body.holes", "must be an integer"),
    ("[gear2.body]\nrim_height = -1.0", "gear2.body.rim_height", "must be >= 0"),
    ("[gear2.body]\nholes = 6\nhole_radius = 12.0", "gear2.body.hole_radius", "cut the rim"),
    ("[dynamic]\nmethod = 'rk4'", "dynamic.method", "must be one of"),
    ("[dynamic]\nenabled = 1", "dynamic.enabled", "must be true or false"),
    ("[dynamic]\nspeed = true", "dynamic.speed", "must be a number"),
    ("[dynamic]\nspeed = inf", "dynamic.speed", "must be finite"),
    ("[gear2]\nteeth = inf", "gear2.teeth", "must be an integer"),
    ("[dynamic]\nmethod = 3", "dynamic.method", "must be a string"),
    ("title = 'x'\n[material]\npoisson_ratio = 0.6", "material.poisson_ratio", "must be <= 0.499"),
    ("[material]\ndensity = 0.0", "material.density", "must be > 0"),
])
def test_scene_errors_name_the_field(text, field, reason):
    with pytest.raises(SceneError) as e:
        loads_scene(text)
    assert e.value.field == field and reason in str(e.value), str(e.value)


def test_overrides_and_replace_are_checked_like_the_file():
    paper = default_scene()
    sc = load_scene(None, ["gear2.body.holes=3", "dynamic.speed=150"])
    assert sc == paper.replace(**{"gear2.body.holes": 3, "dynamic.speed": 150.0})
    assert sc.gear2.body.holes == 3 and isinstance(sc.dynamic.speed, float)
    assert parse_override("title=two words") == ("title", "two words")   # not TOML: kept as text
    with pytest.raises(SceneError, match="cut the rim"):
        paper.replace(**{"gear2.body.hole_radius": 12.0})
    with pytest.raises(SceneError, match="no such file"):
        load_scene("no/such/scene.toml")


def test_metadata_and_toml_round_trip():
    paper = default_scene()
    assert field_unit("gear2.body.hole_radius") == "mm" and field_unit("dynamic.speed") == "rad/s"
    assert field_unit("gear2.body") == "" and field_doc("gear2.body") == "body"
    assert "lightening holes" in field_doc("gear2.body.holes")
    assert get_dotted(paper, "gear2.body.holes") == paper.gear2.body.holes
    for bad in ("gear2.body.holez", "gear2.teeth.x", "replace"):
        with pytest.raises(SceneError, match="no such scene field"):
            get_dotted(paper, bad)
    assert loads_scene(paper.to_toml()) == paper


def test_solid_variant_and_geometry_of_a_scene():
    """`Scene.solid` makes only the named gears' bodies solid (no holes, web as thick as the
    face) and keeps everything else; `Scene.geometry` is the SI geometry of the scene's teeth."""
    paper = default_scene()
    assert paper.is_lightened(2) and not paper.is_lightened(1)
    solid = paper.solid(gears=(2,))
    assert not solid.is_lightened(2) and solid.gear2.body.web_thickness == paper.gear2.face_width
    assert solid.gear1 == paper.gear1 and solid.dynamic == paper.dynamic
    assert solid.replace(**{"gear2.body.holes": paper.gear2.body.holes,
                            "gear2.body.web_thickness": paper.gear2.body.web_thickness}) == paper
    assert paper.solid() == solid         # the driver was solid already
    geo = paper.geometry(2)
    assert geo.teeth == paper.gear2.teeth
    assert geo.pitch_radius == pytest.approx(0.5 * paper.gear2.module * paper.gear2.teeth * 1e-3, rel=1e-12)
    assert geo.root_radius == paper.pivot_radius(2)       # the pivot defaults to the root circle

"""The field and output reference: generated from the declarations the validation uses, and the
committed copy in docs/ is the generated one."""
import dataclasses
import math
import tomllib

import pytest

import study
from study import docs
from study.scene import Scene, field_paths, scene_field
from study.sweep.outputs import CURVES, SCALARS


def test_the_committed_reference_matches_the_declarations():
    assert docs.stale_blocks() == [], "run python -m study.docs"


def test_every_field_is_listed_with_its_declared_unit_default_and_range():
    rows = {r.path: r for r in study.fields()}
    assert list(rows) == field_paths()
    for path, row in rows.items():
        f = scene_field(path)
        md = f.metadata
        assert row.unit == ("" if md["unit"] == "1" else md["unit"]) and row.doc == md["doc"]
        if md.get("optional") and isinstance(f.default, float) and math.isnan(f.default):
            assert row.default == "not given"
        else:   # the listed default read back as TOML is the declared one
            value = tomllib.loads(f"v = {row.default}")["v"]
            assert (tuple(value) if isinstance(value, list) else value) == f.default, path
    assert rows["gear2.body.hole_radius"].unit == "mm" and rows["gear2.body.hole_radius"].range == ">= 0"
    assert rows["material.poisson_ratio"].range == "[0, 0.499]"
    assert rows["contact.friction"].range == "[0, 0.5)"
    assert "'fe-ratio'" in rows["gear2.spring.stiffness"].range
    # a field the docs list is one the scene accepts, with the listed default
    scene = Scene()
    for path in rows:
        node = scene
        for p in path.split("."):
            node = getattr(node, p)
        assert dataclasses.is_dataclass(node) is False


def test_a_prefix_selects_a_section_and_a_misspelled_one_names_the_closest():
    assert [r.path for r in study.fields("gear2.body")][0] == "gear2.body.rim_height"
    assert all(r.path.startswith("dynamic.") for r in study.fields("dynamic"))
    with pytest.raises(study.SceneError, match="did you mean 'gear2.body.holes'"):
        study.fields("gear2.body.hols")


def test_every_output_is_listed_with_its_units():
    rows = {r[0]: r for r in study.outputs()}
    assert set(rows) == set(SCALARS) | set(CURVES)
    for name, s in SCALARS.items():
        assert rows[name][1:4] == ("scalar", s.units, s.analysis)
    assert rows["dte"][1] == "curve over time" and rows["dte"][2] == "um"
    md = docs.outputs_markdown()
    assert all(f"| `{k}` |" in md for k in rows)


def test_a_changed_declaration_makes_the_committed_reference_stale(tmp_path, monkeypatch):
    for file in docs.GENERATED.values():
        (tmp_path / file).write_text((docs.DOCS / file).read_text())
    assert docs.stale_blocks(tmp_path) == []
    monkeypatch.setitem(SCALARS, "ste_p2p", dataclasses.replace(SCALARS["ste_p2p"], units="mm"))
    assert docs.stale_blocks(tmp_path) == ["numbers.md: outputs"]
    assert docs.write_blocks(tmp_path) == [tmp_path / "numbers.md"] and docs.stale_blocks(tmp_path) == []

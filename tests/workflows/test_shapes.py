"""The shapes workflow: the embedded study's bodies weigh the same, and a small pair's round holes,
slots and windows at equal mass give one table and one figure."""
import math

import pytest

import study
from workflows.shapes import main


def test_the_embedded_study_compares_the_three_shapes_at_equal_mass():
    from study.mass_match import gear_mass_kg
    points = study.load_study("shapes").points()
    assert [p.scene.gear2.body.opening for p in points] == ["round", "slot", "window"]
    masses = [gear_mass_kg(p.scene, 2) for p in points]
    assert max(masses) - min(masses) < 1e-5 * masses[0]
    assert len({p.scene.gear2.body.holes for p in points}) == 1
    # the sizes are what equal_mass gives, to the 1e-4 mm they are written with
    for p in points[1:]:
        exact = study.equal_mass(p.scene, points[0].scene)
        field = "slot_width" if p.scene.gear2.body.opening == "slot" else "spoke_width"
        assert getattr(exact.gear2.body, field) == pytest.approx(getattr(p.scene.gear2.body, field), abs=1e-4)


def test_a_small_pair_gives_the_table_and_the_figure(tmp_path, capsys, private_fe_cache):
    base = study.load_scene("small_pair").replace(**{
        "gear2.body.web_thickness": 8.0, "gear2.body.holes": 4, "gear2.body.hole_radius": 5.0,
        "gear2.body.hole_circle_radius": 21.25, "gear2.body.window_height": 6.0, "gear2.body.corner_radius": 1.0,
        "gear2.body.slot_angle": 40.0,
        "fe.mesh_size": 1.5, "quasi_static.rotation": 90.0, "quasi_static.angle_step": 1.0,
        "dynamic.duration": 0.02, "dynamic.ramp_time": 0.002})
    slot = study.equal_mass(base.replace(**{"gear2.body.opening": "slot"}), base)
    window = study.equal_mass(base.replace(**{"gear2.body.opening": "window"}), base)
    points = [{"gear2.body.opening": "round"},
              {"gear2.body.opening": "slot", "gear2.body.slot_width": slot.gear2.body.slot_width},
              {"gear2.body.opening": "window", "gear2.body.spoke_width": window.gear2.body.spoke_width}]
    st = study.make_study(base, points=points, outputs={"scalars": ["ste_p2p", "dte_rms", "amp_hole_order",
                                                                    "root_stress_max_gear2", "mass_gear2"],
                                                        "curves": ["ste"]}, title="small shapes")
    path = tmp_path / "small_shapes.toml"
    path.write_text(st.text)
    out = tmp_path / "out"
    assert main([str(path), "-o", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    table = (out / "shapes.txt").read_text().splitlines()
    assert len(table) == 2 + 3 and table[2].startswith("4 holes of R_h 5 mm")
    assert table[3].startswith("4 slots") and table[4].startswith("4 windows")
    masses = {float(line.split()[-7]) for line in table[2:]}
    assert len(masses) == 1                                          # equal mass, to the table's 1e-4 kg
    ste_order = [float(line.split()[-5]) for line in table[2:]]
    assert all(x > 0 and math.isfinite(x) for x in ste_order)       # every shape shows at its order N
    assert (out / "shapes.png").stat().st_size > 20_000 and "figure:" in text

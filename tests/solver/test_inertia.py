"""Mass properties of a gear against closed forms, a polygon integral and the FE body mesh."""
import math

import numpy as np
import pytest

from solver.geometry import BodySpec, ToothSpec, gear_geometry, hole_angles, solid_body
from solver.inertia import body_inertia, gear_inertia, gear_mass, polygon_properties

RHO = 7850.0


def small_gear():
    """24 teeth, m = 3 mm, 20 mm face; web 8 mm thick with 5 holes of 4 mm on 21 mm (SI)."""
    g = gear_geometry(ToothSpec(3e-3, 24, math.radians(20.0), fillet_radius=0.9e-3, face_width=20e-3))
    body = BodySpec(4e-3, 14e-3, 6e-3, 8e-3, holes=5, hole_radius=4e-3, hole_circle_radius=21e-3, hole_phase=0.3)
    return g, body


def test_solid_body_is_an_annulus():
    g, body = small_gear()
    solid = solid_body(body, g.spec.face_width)
    r_out, r_in, b = g.root_radius, g.root_radius - 24e-3, g.spec.face_width
    m, i = body_inertia(g, solid, RHO)
    m_ref = RHO * math.pi * (r_out**2 - r_in**2) * b
    assert m == pytest.approx(m_ref, rel=1e-12)
    assert i == pytest.approx(0.5 * m_ref * (r_out**2 + r_in**2), rel=1e-12)


def test_holed_web_against_a_polygon_integral_of_each_hole():
    """The holes' share: each hole a fine polygon at its place, integrated about the gear axis
    (no parallel-axis formula involved)."""
    g, body = small_gear()
    no_holes = BodySpec(body.rim_height, body.web_height, body.hub_height, body.web_thickness)
    m0, i0 = body_inertia(g, no_holes, RHO)
    m, i = body_inertia(g, body, RHO)
    s = np.linspace(0.0, 2 * math.pi, 4001)[:-1]
    dm = di = 0.0
    for c in hole_angles(body.holes, body.hole_phase):
        x = body.hole_circle_radius * math.cos(c) + body.hole_radius * np.cos(s)
        y = body.hole_circle_radius * math.sin(c) + body.hole_radius * np.sin(s)
        area, _, _, j0 = polygon_properties(x, y)
        dm += RHO * body.web_thickness * area
        di += RHO * body.web_thickness * j0
    assert m0 - m == pytest.approx(dm, rel=1e-5)
    assert i0 - i == pytest.approx(di, rel=1e-5)


def test_mass_saving_is_the_thinned_web_and_the_holes():
    g, body = small_gear()
    mp = gear_mass(g, body, RHO)
    r_rim = g.root_radius - body.rim_height
    r_hub = r_rim - body.web_height
    removed = RHO * (math.pi * (r_rim**2 - r_hub**2) * (g.spec.face_width - body.web_thickness)
                     + body.holes * math.pi * body.hole_radius**2 * body.web_thickness)
    assert mp.mass_solid - mp.mass == pytest.approx(removed, rel=1e-12)
    assert mp.mass_saving == pytest.approx(100 * removed / mp.mass_solid, rel=1e-12)
    assert gear_mass(g, solid_body(body, g.spec.face_width), RHO).mass_saving == 0.0
    assert 0 < mp.inertia_saving < 100 and mp.inertia < mp.inertia_solid


def test_mass_and_inertia_match_the_fe_body_mesh_integral():
    """The gmsh body mesh with the FE thickness field (face width on teeth, rim and hub, web
    thickness in the web), integrated exactly triangle by triangle: the same body to the
    chords of its curves."""
    from solver.fe.mesh import REGION_WEB, mesh_body
    g, body = small_gear()
    mesh = mesh_body(g, body, g.spec.module / 4)
    p = mesh.points[mesh.triangles]
    x, y = p[..., 0], p[..., 1]
    area = 0.5 * ((x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0]))
    sq = lambda v: (v**2).sum(1) + v[:, 0] * v[:, 1] + v[:, 1] * v[:, 2] + v[:, 0] * v[:, 2]  # noqa: E731
    j0 = area / 6 * (sq(x) + sq(y))                       # polar moment of a triangle about the origin
    t = np.where(mesh.region == REGION_WEB, body.web_thickness, g.spec.face_width)
    m, i = gear_inertia(g, body, RHO)
    assert (RHO * t * area).sum() == pytest.approx(m, rel=3e-3)
    assert (RHO * t * j0).sum() == pytest.approx(i, rel=3e-3)


def test_gear_inertia_is_the_models_total_inertia():
    """One formula: the archive's inertia is the I_TOT the dynamics integrate (lightened gear)."""
    import study
    from study.inputs.gearsetup import gear_setups
    from study.scene_model import geometry_model
    scene = study.default_scene()
    model = geometry_model(scene)
    for s, i_tot in zip(gear_setups(scene), model.inertia_total):
        assert gear_inertia(s.geometry, s.body, s.material.density)[1] == pytest.approx(i_tot, rel=1e-12)

"""Gear geometry against closed forms (Table 1) and clear errors on invalid gears."""
import math

import numpy as np
import pytest

from solver.geometry import (
    BodySpec,
    GeometryError,
    ToothSpec,
    gear_geometry,
    hole_angles,
    involute,
    pair_geometry,
    solid_body,
    validate_body,
)
from solver.inertia import body_inertia, hole_inertia, polygon_properties, tooth_inertia

TABLE1 = ToothSpec(module=1.5e-3, teeth=67, pressure_angle=math.radians(20), addendum_coef=1.0,
                   dedendum_coef=1.25, fillet_radius=0.45e-3, face_width=17e-3, thinning=0.035e-3)


def test_table1_radii_and_contact_ratio():
    g = gear_geometry(TABLE1)
    assert g.pitch_radius == pytest.approx(50.25e-3)
    assert g.base_radius == pytest.approx(47.2196e-3, abs=1e-7)
    assert g.tip_radius == pytest.approx(51.75e-3)
    assert g.root_radius == pytest.approx(48.375e-3)
    p = pair_geometry(g, g)
    assert p.contact_ratio == pytest.approx(1.801, abs=5e-4)
    # path of contact = 2*sqrt(ra^2 - rb^2) - a*sin(alpha), closed form
    path = 2 * math.sqrt(g.tip_radius**2 - g.base_radius**2) - 100.5e-3 * math.sin(math.radians(20))
    assert p.path_of_contact == pytest.approx(path, rel=1e-12)
    # normal backlash = circumferential backlash * cos(alpha)
    assert p.normal_backlash == pytest.approx(0.07e-3 * math.cos(math.radians(20)), rel=1e-12)
    # the mating tip reaches above the form circle (no interference)
    assert g.form_radius < p.sap_radius[0] < g.pitch_radius


def test_flank_is_an_involute_with_the_thinned_tooth_thickness():
    g = gear_geometry(TABLE1)
    u = np.linspace(g.u_form, g.u_tip, 50)
    x, y = g.flank_point(u)
    r = np.hypot(x, y)
    np.testing.assert_allclose(r, g.base_radius * np.sqrt(1 + u**2), rtol=1e-12)
    # polar angle = psi_b - inv(alpha_r)
    alpha_r = np.arccos(g.base_radius / r)
    np.testing.assert_allclose(np.arctan2(y, x), g.psi_base - (np.tan(alpha_r) - alpha_r), atol=1e-12)
    # circular tooth thickness on the pitch circle = pi*m/2 - thinning
    up = math.tan(math.radians(20))
    xp, yp = g.flank_point(up)
    s = 2 * g.pitch_radius * math.atan2(yp, xp)
    assert s == pytest.approx(math.pi * 1.5e-3 / 2 - 0.035e-3, rel=1e-10)


def test_fillet_is_tangent_to_root_circle_and_flank():
    g = gear_geometry(TABLE1)
    cx, cy = g.fillet_center
    rho = TABLE1.fillet_radius
    assert math.hypot(cx, cy) == pytest.approx(g.root_radius + rho, rel=1e-12)
    fx, fy = g.flank_point(g.u_form)
    assert math.hypot(fx - cx, fy - cy) == pytest.approx(rho, rel=1e-9)
    # tangency: the flank's normal at the form point passes through the fillet centre
    t = g.psi_base - g.u_form
    n = np.array([-math.sin(t), math.cos(t)])
    assert n[0] * (cy - fy) - n[1] * (cx - fx) == pytest.approx(0.0, abs=1e-12)


def test_tooth_mass_and_inertia_against_numerical_integration():
    g = gear_geometry(TABLE1)
    ti = tooth_inertia(g, 7850.0, g.root_radius)
    # about 1 g, I about the root pivot about 3.7e-9 kg m^2 (design figures)
    assert ti.mass == pytest.approx(1.08e-3, rel=0.02)
    assert ti.inertia_pivot == pytest.approx(3.7e-9, rel=0.03)
    # polygon formulas against a rectangle and a triangle
    a, cx, cy, j = polygon_properties(np.array([0, 2.0, 2.0, 0]), np.array([0, 0, 1.0, 1.0]))
    assert (a, cx, cy) == pytest.approx((2.0, 1.0, 0.5))
    assert j == pytest.approx(2.0 * (4 + 1) / 12 + 2.0 * (1 + 0.25))
    # tooth area by Monte-Carlo-free grid integration of the outline
    x, y = g.tooth_polygon()
    from matplotlib.path import Path
    poly = Path(np.c_[x, y])
    xs = np.linspace(x.min(), x.max(), 600)
    ys = np.linspace(y.min(), y.max(), 600)
    X, Y = np.meshgrid(xs, ys)
    inside = poly.contains_points(np.c_[X.ravel(), Y.ravel()])
    area_grid = inside.mean() * (xs[-1] - xs[0]) * (ys[-1] - ys[0])
    assert polygon_properties(x, y)[0] == pytest.approx(area_grid, rel=0.01)


def test_body_inertia_closed_form_and_holes():
    g = gear_geometry(TABLE1)
    solid = BodySpec(6.075e-3, 23.25e-3, 7.425e-3, 17e-3)
    m, i = body_inertia(g, solid, 7850.0)
    rb = g.root_radius - 36.75e-3
    assert rb == pytest.approx(11.625e-3)
    i_disc = 0.5 * 7850 * math.pi * 17e-3 * (g.root_radius**4 - rb**4)
    assert i == pytest.approx(i_disc, rel=1e-12)
    light = BodySpec(6.075e-3, 23.25e-3, 7.425e-3, 10e-3, 6, 6e-3, 32.36e-3)
    ml, il = body_inertia(g, light, 7850.0)
    assert ml < m and il < i


def test_holes_and_the_solid_variant_of_a_body():
    """Each hole takes out a disc of the web thickness on the hole circle (parallel axes);
    the solid variant of a lightened body is the full disc, whatever its hole fields were."""
    g = gear_geometry(TABLE1)
    light = BodySpec(6.075e-3, 23.25e-3, 7.425e-3, 10e-3, 6, 6e-3, 32.36e-3, 0.3)
    webbed = BodySpec(6.075e-3, 23.25e-3, 7.425e-3, 10e-3)
    disc = 7850 * math.pi * 6e-3**2 * 10e-3
    m_h, i_h = hole_inertia(light, 7850.0)
    assert (m_h, i_h) == pytest.approx((6 * disc, 6 * disc * (0.5 * 6e-3**2 + 32.36e-3**2)), rel=1e-12)
    assert body_inertia(g, light, 7850.0) == pytest.approx(np.subtract(body_inertia(g, webbed, 7850.0), (m_h, i_h)), rel=1e-12)
    assert hole_inertia(webbed, 7850.0) == (0.0, 0.0)
    solid = solid_body(light, TABLE1.face_width)
    assert solid == BodySpec(6.075e-3, 23.25e-3, 7.425e-3, TABLE1.face_width)
    assert body_inertia(g, solid, 7850.0) == body_inertia(g, BodySpec(6.075e-3, 23.25e-3, 7.425e-3, 17e-3), 7850.0)


@pytest.mark.parametrize("spec, field", [
    (dict(teeth=12), "gear.teeth"),                 # undercut
    (dict(module=-1.0), "gear.module"),
    (dict(fillet_radius=2e-3), "gear.fillet_radius"),
    (dict(addendum_coef=2.5), "gear.addendum"),     # pointed tooth
])
def test_invalid_gears_name_the_field(spec, field):
    params = {**TABLE1.__dict__, **spec}
    with pytest.raises(GeometryError) as e:
        gear_geometry(ToothSpec(**params))
    assert e.value.field == field


@pytest.mark.parametrize("body, field, words", [
    (BodySpec(6e-3, 23e-3, 7e-3, 10e-3, 6, 12e-3, 32.36e-3), "b.hole_radius", "cut the rim"),
    (BodySpec(6e-3, 23e-3, 7e-3, 10e-3, 6, 6e-3, 24e-3), "b.hole_radius", "cut the hub"),
    (BodySpec(6e-3, 23e-3, 7e-3, 10e-3, 20, 6e-3, 32.36e-3), "b.holes", "each other"),
    (BodySpec(-1e-3, 23e-3, 7e-3, 10e-3), "b.rim_height", ">= 0"),
    (BodySpec(6e-3, 23e-3, 30e-3, 10e-3), "b.hub_height", "centre"),
    (BodySpec(6e-3, 23e-3, 7e-3, 20e-3), "b.web_thickness", "face_width"),
])
def test_invalid_bodies_name_the_field(body, field, words):
    g = gear_geometry(TABLE1)
    with pytest.raises(GeometryError) as e:
        validate_body(g, body, prefix="b")
    assert e.value.field == field and words in str(e.value)


def test_small_gear_with_root_inside_base_circle():
    g = gear_geometry(ToothSpec(3e-3, 20, math.radians(20), 1, 1.25, 0.5e-3, 20e-3))
    assert g.root_radius < g.base_radius and g.radial_flank
    x, y = g.outline()
    assert np.all(np.hypot(x, y) >= g.root_radius * (1 - 1e-12))
    assert involute(math.radians(20)) == pytest.approx(0.014904383867336446)


def test_hole_angles_are_equally_spaced_from_the_phase_in_either_unit():
    rad = hole_angles(6, 0.3)
    assert rad.shape == (6,) and rad[0] == 0.3
    assert np.allclose(np.diff(rad), 2 * math.pi / 6, rtol=0, atol=1e-15)
    deg = hole_angles(6, math.degrees(0.3), 360.0)
    assert np.allclose(np.radians(deg), rad, rtol=0, atol=1e-14)
    # every hole the same distance from its neighbours round the full turn, the last to the first too
    gaps = np.diff(np.concatenate([rad, [rad[0] + 2 * math.pi]]))
    assert np.ptp(gaps) < 1e-14
    assert hole_angles(0, 0.3).size == 0

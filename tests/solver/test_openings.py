"""Openings beyond round holes (arc slots, windows between spokes): their exact outline against
closed forms of area and polar moment, the zero-size limits, the body mass through them, the
mesh of a slot of no span, and the checks that refuse a shape that does not fit."""
import dataclasses
import math

import numpy as np
import pytest

from solver.geometry import BodySpec, GeometryError, ToothSpec, body_settings, gear_geometry, validate_body
from solver.inertia import body_inertia, polygon_properties
from solver.openings import (
    Line,
    OpeningShape,
    between_openings,
    local_outline,
    opening_area_moment,
    outline_moments,
    polygon,
    slot_area,
    window_corners,
)

RHO = 7850.0
MM, DEG = 1e-3, math.pi / 180


def paper_gear():
    """The paper's gear (67 teeth, m 1.5 mm, 17 mm face) and its body with a 10 mm web (SI)."""
    g = gear_geometry(ToothSpec(1.5e-3, 67, 20 * DEG, fillet_radius=0.45e-3, face_width=17e-3))
    return g, BodySpec(6.075e-3, 23.25e-3, 7.425e-3, 10e-3, hole_circle_radius=32.36e-3)


def slot(n=6, w=8.0, theta=30.0, rc=32.36):
    return OpeningShape("slot", n, rc * MM, slot_width=w * MM, slot_angle=theta * DEG)


def window(n=5, ws=8.0, rho=2.0, height=12.0, rc=32.36):
    return OpeningShape("window", n, rc * MM, spoke_width=ws * MM, corner_radius=rho * MM, window_height=height * MM)


def test_slot_area_and_polar_moment_are_the_closed_forms():
    """Annular sector theta/2 (Ro²-Ri²) = w Rc theta plus two half discs; the polar moment
    theta/4 (Ro⁴-Ri⁴) plus each half disc's pi r⁴/4 + (pi r²/2) Rc² (its centroid lies 4r/(3 pi)
    off the end centre, tangentially)."""
    for theta in (0.0, 10.0, 30.0, 55.0):
        s = slot(theta=theta)
        rc, r, t = s.centre_radius, 0.5 * s.slot_width, s.slot_angle
        a, j = opening_area_moment(s)
        assert a / 6 == pytest.approx(w_rc_theta := s.slot_width * rc * t + math.pi * r * r, rel=1e-13)
        assert w_rc_theta == pytest.approx(slot_area(s.slot_width, rc, t), rel=1e-15)
        j_ref = t / 4 * ((rc + r) ** 4 - (rc - r) ** 4) + 2 * (math.pi * r**4 / 4 + math.pi * r * r / 2 * rc * rc)
        assert j / 6 == pytest.approx(j_ref, rel=1e-13)


def test_a_slot_of_no_span_is_a_round_hole_of_its_width():
    g, body = paper_gear()
    round_ = dataclasses.replace(body, holes=6, hole_radius=4e-3)
    slot0 = dataclasses.replace(body, holes=6, opening="slot", slot_width=8e-3, slot_angle=0.0)
    m_r, i_r = body_inertia(g, round_, RHO)
    m_s, i_s = body_inertia(g, slot0, RHO)
    assert m_s == pytest.approx(m_r, rel=1e-13) and i_s == pytest.approx(i_r, rel=1e-13)


def _sharp_window_closed_form(s: OpeningShape):
    """Area and polar moment of a window with sharp corners as the signed sum of what each of its
    four pieces spans with the gear centre: the sectors of the arcs (area R² a / 2, moment
    R⁴ a / 4) and the triangles of the straight sides (the polygon formulas of one edge)."""
    _, _, g_out, g_in, _, _ = window_corners(s)
    r_out, r_in = s.centre_radius + s.window_height / 2, s.centre_radius - s.window_height / 2

    def arc(r, a0, a1):
        return 0.5 * r * r * (a1 - a0), 0.25 * r**4 * (a1 - a0)

    def edge(p, q):
        cr = p[0] * q[1] - q[0] * p[1]
        return 0.5 * cr, (p[0] ** 2 + p[0] * q[0] + q[0] ** 2 + p[1] ** 2 + p[1] * q[1] + q[1] ** 2) * cr / 12

    po = (r_out * math.cos(g_out), r_out * math.sin(g_out))
    pi = (r_in * math.cos(g_in), r_in * math.sin(g_in))
    parts = [arc(r_out, -g_out, g_out), edge(po, pi), arc(r_in, g_in, -g_in),
             edge((pi[0], -pi[1]), (po[0], -po[1]))]
    return sum(p[0] for p in parts), sum(p[1] for p in parts)


def test_window_with_sharp_corners_is_its_closed_form():
    s = window(rho=0.0)
    a, j = opening_area_moment(s)
    a_ref, j_ref = _sharp_window_closed_form(s)
    assert a / 5 == pytest.approx(a_ref, rel=1e-13) and j / 5 == pytest.approx(j_ref, rel=1e-13)
    # the spokes' sides are straight and spoke_width apart: the window is the sector less two strips
    sector = 0.5 * (2 * math.pi / 5) * ((s.centre_radius + 6e-3) ** 2 - (s.centre_radius - 6e-3) ** 2)
    assert a_ref < sector


def test_window_with_fillets_against_a_fine_polygon_and_the_sharp_window():
    """The filleted outline integrated exactly against the same outline sampled every 0.5 um
    (shoelace, an independent integral); the fillets take material back from the sharp window,
    and more for larger ones."""
    areas = []
    for rho in (0.0, 1.0, 2.0, 4.0):
        s = window(rho=rho)
        a, j = opening_area_moment(s)
        x, y = polygon(local_outline(s), 0.5e-6)
        a_p, _, _, j_p = polygon_properties(x, y)
        assert a / 5 == pytest.approx(a_p, rel=2e-8) and j / 5 == pytest.approx(j_p, rel=2e-8)
        areas.append(a)
    assert all(np.diff(areas) < 0)
    # the 2 mm fillets give back some material, at most the square of side rho at each of the four corners
    lost = (areas[0] - areas[2]) / 5
    assert 0 < lost < 4 * (2e-3) ** 2


def test_outline_is_closed_counter_clockwise_and_continuous():
    for s in (slot(), slot(theta=0.0), window(), window(rho=0.0), window(n=2, ws=5.0, rho=3.0)):
        pieces = local_outline(s)
        for p, q in zip(pieces, pieces[1:] + pieces[:1]):
            assert np.allclose(p.end, q.start, atol=1e-15)
        assert outline_moments(pieces)[0] > 0            # counter-clockwise: positive area
    assert any(isinstance(p, Line) for p in local_outline(window()))
    # corners of half the height meet: no zero-length side is left (the mesher would make a
    # degenerate element on it), and the ends are half circles of the window's height
    full = local_outline(window(n=3, rho=6.0))
    assert not any(isinstance(p, Line) for p in full)
    for p, q in zip(full, full[1:] + full[:1]):
        assert np.allclose(p.end, q.start, atol=1e-15)
    x, y = polygon(full, 0.5e-6)
    assert opening_area_moment(window(n=3, rho=6.0))[0] / 3 == pytest.approx(polygon_properties(x, y)[0], rel=2e-8)


def test_a_window_of_no_size_is_the_solid_web():
    g, body = paper_gear()
    web = body_inertia(g, body, RHO)
    for h in (0.0, 1e-6, 1e-4):
        b = dataclasses.replace(body, holes=5, opening="window", spoke_width=8e-3, corner_radius=0.0, window_height=h)
        m, i = body_inertia(g, b, RHO)
        # the window's area is at most the sector of its height, 5 of them: to zero with the height
        bound = RHO * body.web_thickness * 2 * math.pi * body.hole_circle_radius * h
        assert 0 <= web[0] - m <= bound + 1e-18
        assert 0 <= web[1] - i <= bound * (body.hole_circle_radius + h) ** 2 + 1e-24
    assert body_inertia(g, dataclasses.replace(body, holes=5, opening="window", spoke_width=8e-3, window_height=0.0),
                        RHO) == web


def test_body_mass_of_slots_and_windows_is_the_web_less_the_openings():
    g, body = paper_gear()
    m0, i0 = body_inertia(g, body, RHO)
    for kind, s in (("slot", slot()), ("window", window())):
        b = dataclasses.replace(body, holes=s.count, opening=kind, slot_width=s.slot_width, slot_angle=s.slot_angle,
                                spoke_width=s.spoke_width, corner_radius=s.corner_radius, window_height=s.window_height)
        m, i = body_inertia(g, b, RHO)
        a, j = opening_area_moment(s)
        assert m0 - m == pytest.approx(RHO * body.web_thickness * a, rel=1e-12)
        assert i0 - i == pytest.approx(RHO * body.web_thickness * j, rel=1e-12)


def _refused(body, field):
    g, _ = paper_gear()
    with pytest.raises(GeometryError) as e:
        validate_body(g, body, "gear2.body")
    assert e.value.field == f"gear2.body.{field}", str(e.value)
    return str(e.value)


def test_shapes_that_do_not_fit_are_refused_naming_the_field():
    _, body = paper_gear()
    sl = dataclasses.replace(body, holes=6, opening="slot", slot_width=8e-3, slot_angle=30 * DEG)
    wi = dataclasses.replace(body, holes=5, opening="window", spoke_width=8e-3, corner_radius=2e-3, window_height=12e-3)
    g, _ = paper_gear()
    validate_body(g, sl, "gear2.body")
    validate_body(g, wi, "gear2.body")
    assert "cut each other" in _refused(dataclasses.replace(sl, slot_angle=50 * DEG), "slot_angle")
    assert "ends meet" in _refused(dataclasses.replace(sl, holes=1, slot_angle=350 * DEG), "slot_angle")
    assert "cut the rim" in _refused(dataclasses.replace(sl, slot_width=21e-3), "slot_width")
    assert "cut the hub" in _refused(dataclasses.replace(sl, hole_circle_radius=22e-3), "slot_width")
    _refused(dataclasses.replace(sl, slot_width=0.0), "slot_width")
    _refused(dataclasses.replace(sl, slot_angle=2 * math.pi), "slot_angle")
    assert "cut the rim" in _refused(dataclasses.replace(wi, window_height=20e-3), "window_height")
    assert "no window is left" in _refused(dataclasses.replace(wi, spoke_width=40e-3), "spoke_width")
    assert "half the window height" in _refused(dataclasses.replace(wi, corner_radius=6.5e-3), "corner_radius")
    # a fillet that fits the height but not the inner arc between wide spokes
    tight = dataclasses.replace(wi, holes=10, spoke_width=12e-3, window_height=12e-3)
    assert window_corners(OpeningShape("window", 10, tight.hole_circle_radius, spoke_width=12e-3, window_height=12e-3))[3] > 0
    assert "inner corners overlap" in _refused(dataclasses.replace(tight, corner_radius=5.9e-3), "corner_radius")
    _refused(dataclasses.replace(wi, holes=1), "holes")
    _refused(dataclasses.replace(wi, corner_radius=-1e-3), "corner_radius")
    _refused(dataclasses.replace(wi, opening="star"), "opening")


def test_between_openings():
    """Neighbouring slots leave the chord between their end centres less the width; windows the spoke."""
    s = slot(n=6, theta=30.0)
    assert between_openings(s) == pytest.approx(2 * s.centre_radius * math.sin(math.radians(15.0)) - s.slot_width)
    assert between_openings(window(ws=5.0)) == pytest.approx(5e-3)
    assert between_openings(slot(n=1, theta=100.0)) == math.inf


def test_cache_settings_of_round_holes_are_unchanged_and_shapes_are_told_apart():
    _, body = paper_gear()
    r = dataclasses.replace(body, holes=6, hole_radius=6e-3, slot_width=1e-3, spoke_width=2e-3)
    old = dict(rim_height=body.rim_height, web_height=body.web_height, hub_height=body.hub_height,
               web_thickness=body.web_thickness, holes=6, hole_radius=6e-3, hole_circle_radius=body.hole_circle_radius,
               hole_phase=0.0)
    assert body_settings(r) == old                           # the keys round holes had before the shapes
    none = dataclasses.replace(body, holes=0, opening="window")
    assert body_settings(none) == {**old, "holes": 0, "hole_radius": 0.0, "hole_circle_radius": 0.0}
    sl = dataclasses.replace(r, opening="slot", slot_width=8e-3, slot_angle=0.5)
    wi = dataclasses.replace(r, opening="window", spoke_width=8e-3, corner_radius=2e-3, window_height=12e-3)
    keys = [body_settings(b) for b in (r, sl, wi, dataclasses.replace(wi, corner_radius=1e-3),
                                       dataclasses.replace(sl, slot_angle=0.6))]
    assert len({str(sorted(k.items())) for k in keys}) == len(keys)
    assert body_settings(dataclasses.replace(sl, hole_radius=1e-3, spoke_width=9e-3)) == body_settings(sl)

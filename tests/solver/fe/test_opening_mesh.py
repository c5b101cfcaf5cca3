"""The body mesh of slots and windows: a slot of no span meshes as the round hole of its width (to
the bit), the web's mesh area is the exact outline's, and the corners of a window get their finer size."""
import dataclasses
import math

import numpy as np
import pytest

from solver.fe.mesh import REGION_WEB, mesh_body, opening_edge_sizes
from solver.geometry import BodySpec, ToothSpec, gear_geometry
from solver.openings import opening_area_moment, shape_of

MM = 1e-3


def small():
    """24 teeth, m 2 mm (the small lightened pair's driven gear): web from 6.5 to 18.5 mm, 8 mm thick."""
    g = gear_geometry(ToothSpec(2 * MM, 24, math.radians(20.0), fillet_radius=0.6 * MM, face_width=17 * MM))
    return g, BodySpec(3 * MM, 12 * MM, 3 * MM, 8 * MM, holes=4, hole_circle_radius=12.5 * MM)


def _areas(m):
    a = m.points[m.triangles]
    return 0.5 * ((a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1]) - (a[:, 2, 0] - a[:, 0, 0]) * (a[:, 1, 1] - a[:, 0, 1]))


def test_a_slot_of_no_span_meshes_as_the_round_hole_of_its_width():
    g, body = small()
    holes = mesh_body(g, dataclasses.replace(body, hole_radius=3 * MM), 1 * MM)
    slot = mesh_body(g, dataclasses.replace(body, opening="slot", slot_width=6 * MM, slot_angle=0.0), 1 * MM)
    assert np.array_equal(holes.points, slot.points) and np.array_equal(holes.triangles, slot.triangles)


@pytest.mark.parametrize("shape", [dict(opening="slot", slot_width=4 * MM, slot_angle=math.radians(40.0)),
                                   dict(opening="window", spoke_width=3 * MM, window_height=8 * MM, corner_radius=1 * MM),
                                   dict(opening="window", spoke_width=3 * MM, window_height=8 * MM, corner_radius=0.0)],
                         ids=["slot", "window", "sharp window"])
def test_the_web_mesh_covers_the_exact_outline(shape):
    """The web's elements miss the area of the web without openings by the openings' exact area
    (the straight element edges cut the arcs: a chord error within 0.5 %), no element is
    degenerate, and the corners of a window are meshed finer than its edges."""
    g, body = small()
    b = dataclasses.replace(body, **shape)
    m = mesh_body(g, b, 0.5 * MM)
    area = _areas(m)
    assert area.min() > 1e-3 * (0.5 * MM) ** 2
    plain = _areas(m0 := mesh_body(g, dataclasses.replace(b, holes=0), 0.5 * MM))[m0.region == REGION_WEB].sum()
    removed = plain - area[m.region == REGION_WEB].sum()
    assert removed == pytest.approx(opening_area_moment(shape_of(b))[0], rel=5e-3)
    edge, corner = opening_edge_sizes(b, 0.5 * MM)
    if b.opening == "window":
        assert corner < edge
        # the smallest web elements sit at the corners, about the corner size
        web = m.region == REGION_WEB
        small_el = np.sqrt(2 * area[web].min())
        assert small_el < 1.5 * corner

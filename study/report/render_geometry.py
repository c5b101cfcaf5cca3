"""Gear bodies as render geometry: triangulated 2D bodies [mm] (from the outline of a solid
gear or the FE mesh of a lightened one), their placement in mesh and their extrusion to
thickness (pyvista surface). Pure geometry: nothing here solves or draws.

Geometry is in mm, gear 1 at the origin, gear 2 at the centre distance on +x, both at the
nominal conjugate position (tooth 0 of gear 1 on +x inside the space of gear 2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver import units
from solver.geometry import bore_radius, gear_outline, pair_geometry


@dataclass
class Body2D:
    """Triangulated gear body in its own frame [mm]: per-triangle thickness [mm] and tooth index
    (-1 below the root circle)."""

    points: np.ndarray      # (n, 2)
    triangles: np.ndarray   # (m, 3), counter-clockwise
    thickness: np.ndarray   # (m,)
    tooth: np.ndarray       # (m,) int


def _tooth_of(points_mm, triangles, root_mm: float, z: int) -> np.ndarray:
    """Tooth index of each triangle (by its centroid's angle), -1 below the root circle [mm]."""
    c = points_mm[triangles].mean(axis=1)
    r = np.hypot(c[:, 0], c[:, 1])
    ang = np.arctan2(c[:, 1], c[:, 0])
    k = np.round(ang / (2 * math.pi / z)).astype(int) % z
    return np.where(r > root_mm * (1 - 1e-6), k, -1)


def outline_body(scene, g: int) -> Body2D:
    """Body of a gear without holes from its outline: strips between the outline, the root
    circle, the rim/web/hub radii and the bore, each point at the outline point's polar angle
    (the outline is star-shaped about the centre, so the strips never overlap)."""
    geo = scene.geometry(g)
    body = scene.body_spec(g)
    x, y = gear_outline(geo)
    ang = np.arctan2(y, x)
    n = ang.size
    rf = geo.root_radius
    r_rim = rf - body.rim_height
    r_hub = r_rim - body.web_height
    radii = [rf, r_rim, r_hub, bore_radius(geo, body)]
    thick = [geo.spec.face_width, body.web_thickness, geo.spec.face_width]
    rings = [np.column_stack([x, y])] + [np.column_stack([r * np.cos(ang), r * np.sin(ang)]) for r in radii]
    pts = np.vstack(rings) / units.MM
    tris, tk = [], []
    i = np.arange(n)
    j = (i + 1) % n
    for level in range(len(rings) - 1):
        o, q = level * n, (level + 1) * n      # outer ring, inner ring
        t = np.vstack([np.column_stack([q + i, o + j, o + i]), np.column_stack([q + i, q + j, o + j])])
        t = t[:, ::-1]                           # counter-clockwise
        tris.append(t)
        tk.append(np.full(len(t), (geo.spec.face_width if level == 0 else thick[level - 1]) / units.MM))
    tris = np.vstack(tris)
    thickness = np.concatenate(tk)
    keep = thickness > 0
    # drop zero-height rings (e.g. no web) and degenerate triangles
    p = pts[tris]
    area = 0.5 * ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    keep &= np.abs(area) > 1e-12
    tris, thickness = tris[keep], thickness[keep]
    return Body2D(pts, tris, thickness, _tooth_of(pts, tris, rf / units.MM, geo.teeth))


def fe_body(field_) -> Body2D:
    """Body of a lightened gear from its FE mesh (`solver.fe.body.BodyField`)."""
    pts = field_.points / units.MM
    return Body2D(pts, field_.triangles, field_.thickness / units.MM, np.full(len(field_.triangles), -1))


def with_teeth(b: Body2D, scene, g: int) -> Body2D:
    """The body with each triangle's tooth index of gear g (an FE body comes without)."""
    geo = scene.geometry(g)
    return Body2D(b.points, b.triangles, b.thickness, _tooth_of(b.points, b.triangles, geo.root_radius / units.MM, geo.teeth))


def placement(scene, g: int) -> tuple[float, np.ndarray]:
    """Rotation [rad] and centre [mm] of gear g at the nominal conjugate position."""
    geo2 = scene.geometry(2)
    if g == 1:
        return 0.0, np.zeros(2)
    a = pair_geometry(scene.geometry(1), geo2).center_distance / units.MM
    return math.pi + math.pi / geo2.teeth, np.array([a, 0.0])


def transform(p2, rot, centre):
    """Points (n, 2) turned by ``rot`` [rad] about the origin, then moved to ``centre``."""
    c, s = math.cos(rot), math.sin(rot)
    return np.column_stack([c * p2[:, 0] - s * p2[:, 1], s * p2[:, 0] + c * p2[:, 1]]) + centre


def extrude(b: Body2D, rot: float = 0.0, centre=(0.0, 0.0), cell_scalar=None, name: str = "scalar"):
    """Wedge cells of each triangle, symmetric about z = 0 with its thickness [mm]; the surface
    (pyvista PolyData) with ``cell_scalar`` (per triangle) as cell data ``name``."""
    import pyvista as pv
    p2 = transform(b.points, rot, np.asarray(centre, float))
    n = len(p2)
    levels, inv = np.unique(np.round(b.thickness, 9), return_inverse=True)
    pts, cells = [], []
    for li, t in enumerate(levels):
        off = 2 * n * li
        pts += [np.column_stack([p2, np.full(n, -t / 2)]), np.column_stack([p2, np.full(n, t / 2)])]
        tri = b.triangles[inv == li]
        # VTK wedge: base (0,1,2) with its normal pointing away from the top face
        w = np.column_stack([off + tri[:, 0], off + tri[:, 2], off + tri[:, 1],
                             off + n + tri[:, 0], off + n + tri[:, 2], off + n + tri[:, 1]])
        cells.append((np.flatnonzero(inv == li), w))
    order = np.concatenate([c[0] for c in cells])
    w = np.vstack([c[1] for c in cells])
    conn = np.hstack([np.full((len(w), 1), 6), w]).ravel()
    grid = pv.UnstructuredGrid(conn, np.full(len(w), pv.CellType.WEDGE, dtype=np.uint8), np.vstack(pts))
    if cell_scalar is not None:
        grid.cell_data[name] = np.asarray(cell_scalar, float)[order]
    surf = grid.extract_surface(pass_pointid=False, pass_cellid=False, algorithm="dataset_surface")
    return surf.clean()



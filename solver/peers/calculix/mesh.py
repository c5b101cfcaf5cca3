"""Quadratic triangle mesh of one whole gear for the CalculiX contact peer, fine where it meshes.

The outline, rim, web, holes and hub are those of the FE body (`solver.fe.mesh.build_outline`,
with the flanks' profile modification); the sizes differ: ``flank_size`` on the flanks and tip
arcs of the teeth around the mesh (`fine_teeth`), ``fillet_size`` on their fillets, growing to
``body_size`` on the rest of the outline and to 5 ``body_size`` in the body. Elements are
6-node triangles whose mid-side nodes lie on the curves (the flank is the involute, not a chord).

Units: SI (m) in and out.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.fe.mesh import REGION_WEB, _collect, build_outline, generate, start_gmsh
from solver.geometry import BodySpec, GearGeometry, validate_body

# points of each flank's spline: the mesh nodes then lie within 0.01 um of the involute (12, the
# FE body's, leave deviations of up to 4 um: as large as the STE itself)
FLANK_POINTS = 150


@dataclass(frozen=True)
class MeshSizes:
    """Element sizes of the peer's mesh [m]."""

    flank: float        # on the flanks and tip arcs of the teeth around the mesh
    fillet: float       # on their fillets
    body: float         # on the rest of the outline (5 x in the web and hub)


@dataclass(frozen=True)
class GearMesh:
    """One gear meshed for the peer, gear frame (tooth k's axis at polar angle 2*pi*k/z)."""

    points: np.ndarray      # (n, 2) node coordinates [m]
    triangles: np.ndarray   # (m, 6) node indices, counter-clockwise, corners then mid-sides
    region: np.ndarray      # (m,) solver.fe.mesh.REGION_*
    bore: np.ndarray        # node indices on the bore circle
    contact_faces: np.ndarray  # (f, 2) element index, edge 0 (nodes 1-2), 1 (2-3), 2 (3-1) on a drive flank or tip arc
    web: bool               # whether REGION_WEB elements exist (their thickness is the web's)

    @property
    def n_nodes(self) -> int:
        return self.points.shape[0]

    @property
    def n_elements(self) -> int:
        return self.triangles.shape[0]


def teeth_near(pitch: float, axis0: float, target: float, angles, half_width: int) -> list[int]:
    """Indices of the teeth whose axis (tooth k at polar angle ``axis0 + angle + k*pitch`` [rad])
    comes within ``half_width`` pitches of the polar angle ``target`` [rad] at any of ``angles``."""
    z = round(2 * math.pi / pitch)
    out = set()
    for a in np.atleast_1d(angles):
        for k in range(z):
            d = (axis0 + a + k * pitch - target + math.pi) % (2 * math.pi) - math.pi
            if abs(d) <= half_width * pitch + 1e-12:
                out.add(k)
    return sorted(out)


def mesh_gear(g: GearGeometry, body: BodySpec, sizes: MeshSizes, fine_teeth, contact_teeth,
              deviation=None, prefix: str = "gear.body", edge_radius: float = 0.0) -> GearMesh:
    """Mesh the whole gear: ``fine_teeth`` get the flank and fillet sizes, the drive (+) flanks
    and tip arcs of ``contact_teeth`` become contact faces; ``deviation`` is the flanks' profile
    modification u -> m (`solver.fe.mesh.tooth_pieces`); ``edge_radius`` [m] > 0: every tooth's
    tip corners rounded to it (`solver.tip_edge`), the rounds of the fine teeth meshed at
    `round_size`, graded into the flank size."""
    validate_body(g, body, prefix)
    gmsh = start_gmsh()     # the process's SIGINT/SIGTERM handlers kept (gmsh's library replaces them)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("gear_peer")
        outline = build_outline(gmsh, g, body, sizes.body, deviation=deviation, n_flank=FLANK_POINTS,
                                edge_radius=edge_radius)
        n_pieces = len(outline.pieces)
        tip = (n_pieces - 1) // 2          # the pieces run -side, (round,) tip arc, (round,) +side
        near = 2 if edge_radius > 0 else 1
        fine_flanks, fine_fillets, rounds = [], [], []
        for k in fine_teeth:
            c = outline.curves[k * n_pieces:(k + 1) * n_pieces]
            fine_flanks += c[tip - near:tip + near + 1]
            fine_fillets += [t for t, (_, f) in zip(c, outline.pieces) if f]
            if edge_radius > 0:
                rounds += [c[tip - 1], c[tip + 1]]
        _size_field(gmsh, g, outline.curves, fine_flanks, fine_fillets, sizes, rounds, edge_radius)
        generate(gmsh, order=2)
        bm = _collect(gmsh, outline.surfaces, outline.bore_radius, sizes.flank, order=2)
    finally:
        gmsh.finalize()
    bore = np.flatnonzero(np.abs(np.hypot(bm.points[:, 0], bm.points[:, 1]) - bm.bore_radius) < 1e-3 * sizes.body)
    faces = contact_faces(g, bm.points, bm.triangles, contact_teeth, deviation)
    return GearMesh(bm.points, bm.triangles, bm.region, bore, faces, bool(np.any(bm.region == REGION_WEB)))


def round_size(edge_radius: float, flank_size: float) -> float:
    """Element size [m] on a rounded tip edge of radius ``edge_radius`` [m]: a quarter of the
    radius (the arc, a quarter turn or less, spans at least two quadratic elements and its contact
    patch several nodes), never coarser than the flanks."""
    return min(0.25 * edge_radius, flank_size)


def _size_field(gmsh, g: GearGeometry, curves, flanks, fillets, sizes: MeshSizes, rounds=(),
                edge_radius: float = 0.0) -> None:
    """``flank`` within a quarter module of the fine flanks, growing to ``body`` over a module;
    ``fillet`` within two of its sizes of their fillets, growing to ``body`` over a module;
    ``body`` at the outline growing to 5 ``body`` over 4 modules inside; on the ``rounds`` (tip
    edges of radius ``edge_radius`` [m]) `round_size` within a quarter radius, growing by half
    the distance beyond."""
    m = g.spec.module
    f = gmsh.model.mesh.field

    def threshold(curve_list, size_min, size_max, d_min, d_max, sampling):
        d = f.add("Distance")
        f.setNumbers(d, "CurvesList", curve_list)
        f.setNumber(d, "Sampling", sampling)
        t = f.add("Threshold")
        f.setNumber(t, "InField", d)
        f.setNumber(t, "SizeMin", size_min)
        f.setNumber(t, "SizeMax", size_max)
        f.setNumber(t, "DistMin", d_min)
        f.setNumber(t, "DistMax", d_max)
        return t

    h_body = 5.0 * sizes.body

    def graded(curve_list, size_min, d_min, d_body, sampling):
        # size_min within d_min, sizes.body at d_body, on to h_body (the thresholds' SizeMax
        # holds everywhere beyond DistMax, so it must be the largest size)
        d_max = d_min + (d_body - d_min) * (h_body - size_min) / (sizes.body - size_min)
        return threshold(curve_list, size_min, h_body, d_min, d_max, sampling)

    fields = [threshold(curves, sizes.body, h_body, 0.5 * m, 4.0 * m, 30)]
    if flanks:
        fields.append(graded(flanks, sizes.flank, 0.25 * m, 1.25 * m, max(200, int(8 * m / sizes.flank))))
    if fillets:
        fields.append(graded(fillets, sizes.fillet, 2 * sizes.fillet, 1.0 * m, max(50, int(4 * m / sizes.fillet))))
    if rounds:
        h_r = round_size(edge_radius, sizes.flank)
        d_min = 0.25 * edge_radius
        fields.append(threshold(rounds, h_r, h_body, d_min, d_min + 2.0 * (h_body - h_r), 40))
    fm = f.add("Min")
    f.setNumbers(fm, "FieldsList", fields)
    f.setAsBackgroundMesh(fm)


# edges of a 6-node triangle: (corner, corner, mid-side), CalculiX face labels S1, S2, S3
EDGES = np.array([[0, 1, 3], [1, 2, 4], [2, 0, 5]])


def boundary_edges(triangles: np.ndarray) -> np.ndarray:
    """(b, 2) element index and local edge (0..2) of the edges that belong to one element only."""
    corner = triangles[:, EDGES[:, :2]]                     # (m, 3, 2)
    key = np.sort(corner, axis=2).reshape(-1, 2)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = count[inv.ravel()] == 1
    idx = np.flatnonzero(once)
    return np.column_stack([idx // 3, idx % 3])


def contact_faces(g: GearGeometry, points: np.ndarray, triangles: np.ndarray, teeth, deviation=None) -> np.ndarray:
    """Boundary edges on the drive (+) flank from the form circle up, and on the tip arc, of
    ``teeth``: (f, 2) element index and local edge."""
    b = boundary_edges(triangles)
    mid = points[triangles[b[:, 0], EDGES[b[:, 1], 2]]]       # mid-side node of each edge
    r = np.hypot(mid[:, 0], mid[:, 1])
    pitch = g.pitch_angle
    rel = np.arctan2(mid[:, 1], mid[:, 0])
    k = np.rint(rel / pitch).astype(int) % g.teeth
    rel = (rel - k * pitch + math.pi) % (2 * math.pi) - math.pi   # polar angle from the tooth's axis
    tol = 1e-6 * g.spec.module
    tip = r > g.tip_radius - 0.02 * g.spec.module
    flank = (r > g.form_radius - tol) & (rel > 0)
    keep = (tip | flank) & np.isin(k, np.asarray(list(teeth), int)) & (r < g.tip_radius + tol)
    return b[keep]

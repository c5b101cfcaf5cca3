"""2D triangle mesh of a whole gear body (all teeth, rim, web with holes, hub) with gmsh.

The outline is built from the exact pieces of each tooth (root arcs, fillets, involutes, tip
arc) as splines, so the mesh follows the curves whatever the element size. Three regions:
teeth + rim (down to ``root - rim_height``), web (down to the hub, pierced by the holes) and hub
(down to the bore). Sizes: ``h`` at the outline, ``h/2`` on the fillets (the stress
concentrates there), growing to ``h_body`` (about 5 h) in the web and hub; how fast they grow
away from the outline is the grading (`GRADINGS`: 'fine', the reference, or 'graded').

Units: SI (m) in and out. Triangles are linear (3 nodes); the FE raises the order itself.
"""
from __future__ import annotations

import math
import signal
import threading
from dataclasses import dataclass

import numpy as np

from solver.geometry import BodySpec, GearGeometry, bore_radius, hole_angles, validate_body
from solver.openings import Line, local_outline, place, shape_of

REGION_RIM, REGION_WEB, REGION_HUB = 0, 1, 2
KEPT_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def start_gmsh():
    """The gmsh module, initialised, with the process's own handlers of SIGINT and SIGTERM
    kept. interruptible=False: gmsh's Python layer must not install its SIGINT handler (that
    fails outside the main thread, e.g. in dask workers). Its C library still puts its own
    handlers in place at every initialize, and Python's handlers (a command's exit 130 with
    its "interrupted" line, the compiled loops' stop) were then never called again in the
    process: they are installed again here, from the main thread (only it may)."""
    import gmsh
    gmsh.initialize(interruptible=False)
    if threading.current_thread() is threading.main_thread():
        for sig in KEPT_SIGNALS:
            handler = signal.getsignal(sig)
            if handler is not None:         # (None: a handler not installed from Python)
                signal.signal(sig, handler)
    return gmsh
REGION_NAMES = ("teeth and rim", "web", "hub")

# How fast the elements grow away from the outline (sizes in modules m and outline sizes h):
# "fine", the reference: h through 1.5 m into the body (all of the teeth and the rim under them),
# growing to 5 h over 20 h further. "graded": h only within 0.1 m of the outline, growing to
# 5 h over 2 m (the tooth cores and the rim under the roots coarser); the fillets keep h/2 in
# both. Graded against fine (paper pair, Table 1 driven gear, a 12-hole 6 mm web on a 5 mm rim,
# a hole-free web, the solid body): every tooth's stiffness within 0.12 %, the stiffness ratio to
# the solid body within 0.1 %, the largest fillet stress within 1 %, with about half the elements
# (tests/solver/fe/test_grading.py).
GRADINGS = {
    "fine": dict(outline_fine_m=1.5, outline_growth_m=0.0, outline_growth_h=20.0, fillet_fine_h=1.0, fillet_growth_h=6.0),
    "graded": dict(outline_fine_m=0.1, outline_growth_m=2.0, outline_growth_h=0.0, fillet_fine_h=1.0, fillet_growth_h=6.0),
}


@dataclass(frozen=True)
class BodyMesh:
    """Triangle mesh of a gear body, gear frame (tooth k's axis at polar angle 2*pi*k/z)."""

    points: np.ndarray      # (n, 2) node coordinates [m]
    triangles: np.ndarray   # (m, 3) node indices, counter-clockwise ((m, 6) quadratic: `_collect`)
    region: np.ndarray      # (m,) REGION_RIM / REGION_WEB / REGION_HUB
    bore_radius: float      # m
    size: float             # element size at the outline [m]

    @property
    def n_elements(self) -> int:
        return self.triangles.shape[0]


def default_mesh_size(module: float) -> float:
    """Element size at the outline [m]: a quarter of the module (about 6 quadratic elements
    across a tooth; the per-tooth stiffness ratio then changes < 0.5 % on refinement)."""
    return module / 4.0


def _arc(r: float, a0: float, a1: float, n: int):
    a = np.linspace(a0, a1, n)
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


def tooth_pieces(g: GearGeometry, n: int = 12, deviation=None, edge_radius: float = 0.0) -> list[tuple[np.ndarray, bool]]:
    """One tooth's outline as pieces from mid-space -pi/z to +pi/z, counter-clockwise.

    Returns a list of (points (k, 2) [m], is_fillet). Consecutive pieces share end points; the
    last point of a tooth is the first of the next tooth rotated by the pitch angle.
    ``deviation``: None (perfect involutes) or a function of the roll parameter u [-] giving the
    flank's deviation along its normal [m], positive where material is removed (a profile
    modification, `solver.modification.ProfileModification.deviation`); the tip arc then ends at
    the modified tip corners. ``edge_radius`` [m] > 0: each tip corner rounded by an arc of that
    radius tangent to the flank and the tip circle (`solver.tip_edge.tip_round`), a piece of its
    own between the flank and the tip arc (two pieces more a tooth, 17 points each).
    """
    rf, ra = g.root_radius, g.tip_radius
    half_pitch = math.pi / g.teeth
    plus = []  # + half from the tip corner down to mid-space, as (points, is_fillet)
    u_top = g.u_tip
    if edge_radius > 0:
        from solver.tip_edge import tip_round
        rnd = tip_round(g, edge_radius, deviation)
        plus.append((rnd.points(17), False))
        u_top = rnd.u_flank
    u = np.linspace(u_top, g.u_form, n)
    flank = np.column_stack(g.flank_point(u, 1))
    if deviation is not None:
        t = g.psi_base - u   # the + flank's outward normal is (-sin t, cos t)
        d = np.asarray(deviation(u), float)
        flank = flank - d[:, None] * np.column_stack([-np.sin(t), np.cos(t)])
    if plus:
        flank[0] = plus[0][0][-1]       # the round's tangent point, exactly
    plus.append((flank, False))
    if g.radial_flank:
        rho = g.spec.fillet_radius
        r_tan = math.sqrt((rf + rho) ** 2 - rho**2)
        r = np.linspace(g.base_radius, r_tan, 3)
        plus.append((np.column_stack([r * math.cos(g.psi_base), r * math.sin(g.psi_base)]), False))
    start = plus[-1][0][-1]
    rho = g.spec.fillet_radius
    if rho > 0:
        cx, cy = g.fillet_center
        a0 = math.atan2(start[1] - cy, start[0] - cx)
        a1 = g.fillet_root_angle + math.pi
        da = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi
        a = a0 + da * np.linspace(0.0, 1.0, max(n // 2, 4))
        plus.append((np.column_stack([cx + rho * np.cos(a), cy + rho * np.sin(a)]), True))
    plus.append((_arc(rf, g.fillet_root_angle, half_pitch, 4), False))
    minus = [(p[::-1] * np.array([1.0, -1.0]), f) for p, f in reversed(plus)]
    a_tip = g.tip_half_angle if edge_radius <= 0 else math.atan2(plus[0][0][0, 1], plus[0][0][0, 0])
    tip = _arc(ra, -a_tip, a_tip, 5)
    tip[0], tip[-1] = minus[-1][0][-1], plus[0][0][0]   # the (modified) tip corners, or the rounds' ends
    return minus + [(tip, False)] + plus


def _rotate(p: np.ndarray, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return p @ np.array([[c, s], [-s, c]])


def mesh_body(g: GearGeometry, body: BodySpec, size: float | None = None, prefix: str = "gear.body",
              grading: str = "fine", rim: bool = True) -> BodyMesh:
    """Mesh the gear body. ``size`` = element size at the outline [m] (default from the module);
    ``grading``: one of `GRADINGS` (how fast the elements grow away from the outline).
    ``rim=False``: only the web and hub (a body with neither: an error), by the same size
    field, so that their boundary nodes are those of the whole body's (gmsh meshes each region
    from its own boundary; inside, the triangles may differ from the whole body's, whose other
    node numbers steer gmsh's Delaunay otherwise: stiffness and stress within 1e-6): the part
    that differs between bodies of one rim height, to be joined to their common teeth and rim
    (`solver.fe.condense.join_rim`)."""
    validate_body(g, body, prefix)
    if grading not in GRADINGS:
        raise ValueError(f"fe.mesh_grading: one of {', '.join(GRADINGS)}, got {grading!r}")
    h = float(size) if size else default_mesh_size(g.spec.module)
    if not (h > 0) or h > g.spec.module:
        raise ValueError(f"fe.mesh_size: must lie in (0, module = {g.spec.module * 1e3:.4g} mm], got {h * 1e3:.4g} mm")
    gmsh = start_gmsh()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("gear_body")
        return _build(gmsh, g, body, h, grading, rim)
    finally:
        gmsh.finalize()


def _build(gmsh, g: GearGeometry, body: BodySpec, h: float, grading: str, rim: bool = True) -> BodyMesh:
    outline = build_outline(gmsh, g, body, h, rim)
    if not rim:
        # The size field measures from the outline's curves (sampled, not their mesh), but gmsh
        # meshes every curve of the model: without the rim the outline bounds no surface, and
        # its 1D mesh (two thirds of a web's meshing time) is left out, one element a curve.
        for c in outline.curves:
            gmsh.model.mesh.setTransfiniteCurve(c, 2)
    corner_size = opening_edge_sizes(body, h)[1] if any(outline.corners) else None
    _size_field(gmsh, g, outline, h, GRADINGS[grading], corner_size)
    generate(gmsh)
    return _collect(gmsh, outline.surfaces, outline.bore_radius, h)


@dataclass(frozen=True)
class Outline:
    """The gmsh geometry of a gear body (`build_outline`): the tags of its surfaces and curves."""

    surfaces: dict          # REGION_* -> plane surface tag
    curves: list            # outline curve tags, ``pieces`` per tooth, tooth by tooth
    fillets: list           # the fillet curves among them
    pieces: list            # (points [m], is_fillet) of one tooth in its frame (`tooth_pieces`)
    bore_radius: float      # m
    corners: tuple = ((), ())   # a window's fillet curves and sharp corner points (refined by the size field)


def build_outline(gmsh, g: GearGeometry, body: BodySpec, h: float, rim: bool = True, deviation=None,
                  n_flank: int = 12, edge_radius: float = 0.0) -> Outline:
    """Add the gear body to the current gmsh model (gear frame, tooth k's axis at 2*pi*k/z):
    the outline of all teeth with points of size ``h`` [m] (``h/2`` on the fillets), the
    rim, web (pierced by the holes) and hub as plane surfaces; ``rim=False``: web and hub only
    (see `mesh_body`); ``deviation``: the flanks' profile modification (`tooth_pieces`);
    ``n_flank``: points of each flank's spline (12: the involute within a few um, enough for a
    body loaded at given points; a contact analysis needs ~150, within 0.01 um); ``edge_radius``
    [m]: the tip corners rounded (`tooth_pieces`)."""
    geo = gmsh.model.geo
    h_body = 5.0 * h
    pieces = tooth_pieces(g, n=n_flank, deviation=deviation, edge_radius=edge_radius)
    # ---- outline: one spline per piece, shared end points between pieces and teeth
    first_tag = None
    prev_tag = None
    curves, fillets = [], []
    for k in range(g.teeth):
        a = k * g.pitch_angle
        for p, is_fillet in pieces:
            q = _rotate(p, a)
            lc = h / 2 if is_fillet else h
            if prev_tag is None:
                prev_tag = geo.addPoint(q[0, 0], q[0, 1], 0.0, h)
                first_tag = prev_tag
            last = k == g.teeth - 1 and p is pieces[-1][0]
            end_tag = first_tag if last else geo.addPoint(q[-1, 0], q[-1, 1], 0.0, lc)
            inner = [geo.addPoint(x, y, 0.0, lc) for x, y in q[1:-1]]
            c = geo.addSpline([prev_tag, *inner, end_tag]) if inner else geo.addLine(prev_tag, end_tag)
            curves.append(c)
            if is_fillet:
                fillets.append(c)
            prev_tag = end_tag
    outline = geo.addCurveLoop(curves)

    r_rim = g.root_radius - body.rim_height
    r_hub = r_rim - body.web_height
    r_bore = bore_radius(g, body)
    centre = geo.addPoint(0.0, 0.0, 0.0, h_body)

    def circle(cx, cy, r, lc):
        c0 = geo.addPoint(cx, cy, 0.0, lc) if (cx, cy) != (0.0, 0.0) else centre
        pts = [geo.addPoint(cx + r * math.cos(t), cy + r * math.sin(t), 0.0, lc) for t in np.arange(4) * math.pi / 2]
        arcs = [geo.addCircleArc(pts[i], c0, pts[(i + 1) % 4]) for i in range(4)]
        return geo.addCurveLoop(arcs)

    surfaces = {}
    has_web = body.web_height > 0
    has_hub = body.hub_height > 0
    rim_in = circle(0.0, 0.0, r_rim, min(2 * h, h_body)) if (has_web or has_hub) else None
    hub_out = circle(0.0, 0.0, r_hub, h_body) if (has_web and has_hub) else None
    bore = circle(0.0, 0.0, r_bore, h_body)
    if not (rim or has_web or has_hub):
        raise ValueError("mesh_body: a body without web and hub has nothing below its rim to mesh")
    # rim (with the teeth); the outline is defined either way: the size field measures from it
    if rim:
        surfaces[REGION_RIM] = geo.addPlaneSurface([outline, rim_in if rim_in is not None else bore])
    corners = ([], [])      # window fillets (curves) and sharp corners (points): refined by the size field
    if has_web:
        holes = []
        if body.holes and body.opening != "round" and not _is_round_slot(body):
            h_edge, _ = opening_edge_sizes(body, h)
            for t in hole_angles(body.holes, body.hole_phase):
                holes.append(_opening_loop(geo, place(local_outline(shape_of(body)), t), h_edge,
                                           corners if body.opening == "window" else None, body.corner_radius))
        else:   # round holes, and slots of no span: round holes of the slot's width
            r_hole = 0.5 * body.slot_width if _is_round_slot(body) else body.hole_radius
            h_hole = min(h_body, 2 * math.pi * r_hole / 24) if body.holes else h_body
            for t in hole_angles(body.holes, body.hole_phase):
                holes.append(circle(body.hole_circle_radius * math.cos(t), body.hole_circle_radius * math.sin(t),
                                    r_hole, h_hole))
        surfaces[REGION_WEB] = geo.addPlaneSurface([rim_in, *holes, hub_out if hub_out is not None else bore])
    if has_hub:
        surfaces[REGION_HUB] = geo.addPlaneSurface([hub_out if hub_out is not None else rim_in, bore])
    geo.synchronize()
    return Outline(surfaces, curves, fillets, pieces, r_bore, corners)


def generate(gmsh, order: int = 1) -> None:
    """Mesh the current gmsh model's surfaces by its size field and point sizes (``order`` 2:
    6-node triangles whose mid-side nodes lie on the curves)."""
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 1)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 5)  # Delaunay: fast and robust for large planar meshes
    gmsh.model.mesh.generate(2)
    if order > 1:
        gmsh.model.mesh.setOrder(order)


def _is_round_slot(body: BodySpec) -> bool:
    """A slot of no angular span: a round hole of the slot's width, meshed as one."""
    return body.opening == "slot" and body.slot_angle == 0.0


# Elements along a full turn of an opening's arc (round holes: 24 on the circle) and a window's
# corner fillets (6 on a quarter turn); the size field grows from a corner's size to the web's
# over CORNER_GROWTH times their difference (a growth rate of 1/3).
ARC_ELEMENTS = 24
CORNER_GROWTH = 3.0


def opening_edge_sizes(body: BodySpec, h: float) -> tuple[float, float]:
    """(element size along an opening's edges, at a window's corners) [m] of the body mesh for
    the outline size ``h`` [m]: at most the web's 5 h, ARC_ELEMENTS on the circle of a round hole
    (of a slot's end circle, of a circle as high as a window); a window's corners ARC_ELEMENTS
    on the circle of their fillet, at least h/2 (as the tooth fillets; sharp corners h/2)."""
    h_body = 5.0 * h
    if body.opening == "window":
        edge = min(h_body, 2 * math.pi * 0.5 * body.window_height / ARC_ELEMENTS)
        return edge, min(edge, max(2 * math.pi * body.corner_radius / ARC_ELEMENTS, h / 2))
    r = 0.5 * body.slot_width if body.opening == "slot" else body.hole_radius
    edge = min(h_body, 2 * math.pi * r / ARC_ELEMENTS)
    return edge, edge


def _opening_loop(geo, pieces: list, size: float, corners: tuple | None, corner_radius: float = 0.0) -> int:
    """A closed curve loop of gmsh geo lines and circle arcs (each arc in pieces of at most a
    quarter turn: gmsh draws arcs below half a turn) of an opening's outline, points of ``size``
    [m]. With ``corners`` (a window's): its fillet arcs (of ``corner_radius`` [m]) go to
    corners[0], its sharp corners (``corner_radius`` = 0) to corners[1]."""
    first = geo.addPoint(*pieces[0].start, 0.0, size)
    prev, tags = first, []
    for i, p in enumerate(pieces):
        end = first if i == len(pieces) - 1 else geo.addPoint(*p.end, 0.0, size)
        if isinstance(p, Line):
            tags.append(geo.addLine(prev, end))
            if corners is not None and corner_radius == 0.0:
                corners[1].extend([prev, end])
        else:
            k = max(1, math.ceil(abs(p.a1 - p.a0) / (0.5 * math.pi) - 1e-9))
            c = geo.addPoint(*p.centre, 0.0, size)
            a = np.linspace(p.a0, p.a1, k + 1)
            chain = [prev, *[geo.addPoint(*p.point(x), 0.0, size) for x in a[1:-1]], end]
            arcs = [geo.addCircleArc(chain[j], c, chain[j + 1]) for j in range(k)]
            tags += arcs
            if corners is not None and corner_radius > 0.0 and p.radius == corner_radius:
                corners[0].extend(arcs)
        prev = end
    return geo.addCurveLoop(tags)


def _size_field(gmsh, g: GearGeometry, outline: Outline, h: float, grade: dict, corner_size: float | None = None) -> None:
    """Background size field [m] of a `GRADINGS` entry, with h_body = 5 h: ``h`` within
    ``outline_fine_m`` modules of the outline's curves, growing linearly to ``h_body`` over
    ``outline_growth_m`` modules plus ``outline_growth_h`` h; ``h/2`` within ``fillet_fine_h`` h
    of its fillets, growing to ``h_body`` at ``fillet_growth_h`` h; ``corner_size`` within that
    size of a window's corners (``outline.corners``: its fillet curves and sharp corner points),
    growing to ``h_body`` over CORNER_GROWTH times the difference."""
    curves, fillets, corners = outline.curves, outline.fillets, outline.corners
    h_body = 5.0 * h
    m = g.spec.module
    f = gmsh.model.mesh.field
    d_out = f.add("Distance")
    f.setNumbers(d_out, "CurvesList", curves)
    f.setNumber(d_out, "Sampling", 30)
    th = f.add("Threshold")
    f.setNumber(th, "InField", d_out)
    f.setNumber(th, "SizeMin", h)
    f.setNumber(th, "SizeMax", h_body)
    f.setNumber(th, "DistMin", grade["outline_fine_m"] * m)
    f.setNumber(th, "DistMax", (grade["outline_fine_m"] + grade["outline_growth_m"]) * m + grade["outline_growth_h"] * h)
    fields = [th]
    if fillets:
        d_f = f.add("Distance")
        f.setNumbers(d_f, "CurvesList", fillets)
        f.setNumber(d_f, "Sampling", 10)
        tf = f.add("Threshold")
        f.setNumber(tf, "InField", d_f)
        f.setNumber(tf, "SizeMin", h / 2)
        f.setNumber(tf, "SizeMax", h_body)
        f.setNumber(tf, "DistMin", grade["fillet_fine_h"] * h)
        f.setNumber(tf, "DistMax", grade["fillet_growth_h"] * h)
        fields.append(tf)
    if corner_size is not None:
        d_c = f.add("Distance")
        if corners[0]:
            f.setNumbers(d_c, "CurvesList", corners[0])
            f.setNumber(d_c, "Sampling", 20)
        if corners[1]:
            f.setNumbers(d_c, "PointsList", corners[1])
        tc = f.add("Threshold")
        f.setNumber(tc, "InField", d_c)
        f.setNumber(tc, "SizeMin", corner_size)
        f.setNumber(tc, "SizeMax", h_body)
        f.setNumber(tc, "DistMin", corner_size)
        f.setNumber(tc, "DistMax", corner_size + CORNER_GROWTH * (h_body - corner_size))
        fields.append(tc)
    fm = f.add("Min")
    f.setNumbers(fm, "FieldsList", fields)
    f.setAsBackgroundMesh(fm)


def _collect(gmsh, surfaces: dict, r_bore: float, h: float, order: int = 1) -> BodyMesh:
    """Nodes and triangles (``order`` 1: 3 nodes; 2: 6 nodes, corners then the mid-sides of
    edges 1-2, 2-3, 3-1) of the meshed surfaces, tagged by region, counter-clockwise."""
    gmsh_type, nodes_per = {1: (2, 3), 2: (9, 6)}[order]
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(tags.size)
    points = xyz.reshape(-1, 3)[:, :2].copy()
    tris, regions = [], []
    for reg, s in surfaces.items():
        types, _, nodes = gmsh.model.mesh.getElements(2, s)
        for ty, nd in zip(types, nodes):
            if ty != gmsh_type:
                raise RuntimeError(f"gmsh returned element type {ty}, expected {nodes_per}-node triangles")
            t = index[nd.astype(np.int64)].reshape(-1, nodes_per)
            tris.append(t)
            regions.append(np.full(t.shape[0], reg, dtype=np.int8))
    tri = np.concatenate(tris)
    region = np.concatenate(regions)
    # drop nodes not used by any triangle (geometry construction points, the centre)
    used = np.zeros(points.shape[0], bool)
    used[tri.ravel()] = True
    remap = np.cumsum(used) - 1
    points, tri = points[used], remap[tri]
    # counter-clockwise orientation
    a = points[tri]
    area2 = (a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1]) - (a[:, 2, 0] - a[:, 0, 0]) * (a[:, 1, 1] - a[:, 0, 1])
    flip = area2 < 0
    tri[flip] = tri[flip][:, [0, 2, 1, 5, 4, 3][:nodes_per]]
    return BodyMesh(points, tri, region, r_bore, h)


def mesh_annulus(r_in: float, r_split: float, r_out: float, size: float) -> BodyMesh:
    """Annulus r_in..r_out [m] meshed with element size ``size`` [m]; elements inside r_split are
    tagged as web, outside as rim. An analytic check case for the FE (torsion of a thick ring)."""
    if not 0 < r_in < r_split < r_out:
        raise ValueError("mesh_annulus: need 0 < r_in < r_split < r_out")
    gmsh = start_gmsh()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("annulus")
        geo = gmsh.model.geo
        c = geo.addPoint(0.0, 0.0, 0.0, size)

        def circle(r):
            pts = [geo.addPoint(r * math.cos(t), r * math.sin(t), 0.0, size) for t in np.arange(4) * math.pi / 2]
            return geo.addCurveLoop([geo.addCircleArc(pts[i], c, pts[(i + 1) % 4]) for i in range(4)])

        lo, mid, hi = circle(r_in), circle(r_split), circle(r_out)
        surfaces = {REGION_RIM: geo.addPlaneSurface([hi, mid]), REGION_WEB: geo.addPlaneSurface([mid, lo])}
        geo.synchronize()
        gmsh.model.mesh.generate(2)
        return _collect(gmsh, surfaces, r_in, size)
    finally:
        gmsh.finalize()

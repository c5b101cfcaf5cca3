"""Off-screen 3D renders (pyvista/VTK, PNG) of a run archive's gear pair and FE body field.

  gear_pair_render    both gears in mesh, extruded to their thickness (face width on teeth, rim
                      and hub; web thickness in the web; holes as voids), teeth coloured by their
                      spring stiffness k_phi [N·mm/rad]. Top row: perspective view (lit); bottom
                      row: the same map seen from above, unlit, so colours read exactly against
                      the colour bar.
  fe_stress_render    von Mises stress [MPa] and displacement [um] of a lightened body under
                      the FE tooth load on the stiffest and on the softest tooth, one colour
                      scale per quantity for both.

Both read the archive only (``tooth_stiffness`` and the scene TOML in ``ds.attrs['scene']``); a
lightened body's mesh and fields come from `study.inputs.springs` (cached FE), a solid gear is drawn
from its outline without FE. Geometry is drawn in mm, gear 1 at the origin, gear 2 at the
centre distance on +x, both at the nominal conjugate position (tooth 0 of gear 1 on +x inside
the space of gear 2). Off-screen: VTK is told to use EGL unless a window type is already set,
so no X display is needed and none is looked for.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from solver import units  # noqa: E402
from solver.geometry import bore_radius, gear_geometry, gear_outline, pair_geometry  # noqa: E402

STIFFNESS_CMAP = "viridis"
STRESS_CMAP = "turbo"
DISPLACEMENT_CMAP = "cividis"
NAN_COLOR = "#c8c8c8"
WINDOW = (1600, 1400)


@dataclass
class RenderResult:
    """What a render drew: the PNG, the colour range, and for checks the image pixel (row,
    column) of given world points with the scalar value there."""

    path: Path
    clim: tuple
    scalar: str
    unit: str
    probes: list = field(default_factory=list)   # (row, col, value) in the written image


@dataclass
class Body2D:
    """Triangulated gear body in its own frame [mm]: per-triangle thickness [mm] and tooth index
    (-1 below the root circle)."""

    points: np.ndarray      # (n, 2)
    triangles: np.ndarray   # (m, 3), counter-clockwise
    thickness: np.ndarray   # (m,)
    tooth: np.ndarray       # (m,) int


# ------------------------------------------------------------------ geometry

def _tooth_of(points_mm, triangles, root_mm: float, z: int) -> np.ndarray:
    c = points_mm[triangles].mean(axis=1)
    r = np.hypot(c[:, 0], c[:, 1])
    ang = np.arctan2(c[:, 1], c[:, 0])
    k = np.round(ang / (2 * math.pi / z)).astype(int) % z
    return np.where(r > root_mm * (1 - 1e-6), k, -1)


def outline_body(scene, g: int) -> Body2D:
    """Body of a gear without holes from its outline: strips between the outline, the root
    circle, the rim/web/hub radii and the bore, each point at the outline point's polar angle
    (the outline is star-shaped about the centre, so the strips never overlap)."""
    geo = gear_geometry(scene.tooth_spec(g))
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


def _with_teeth(b: Body2D, scene, g: int) -> Body2D:
    geo = gear_geometry(scene.tooth_spec(g))
    return Body2D(b.points, b.triangles, b.thickness, _tooth_of(b.points, b.triangles, geo.root_radius / units.MM, geo.teeth))


def placement(scene, g: int) -> tuple[float, np.ndarray]:
    """Rotation [rad] and centre [mm] of gear g at the nominal conjugate position."""
    geo2 = gear_geometry(scene.tooth_spec(2))
    if g == 1:
        return 0.0, np.zeros(2)
    a = pair_geometry(gear_geometry(scene.tooth_spec(1)), geo2).center_distance / units.MM
    return math.pi + math.pi / geo2.teeth, np.array([a, 0.0])


def _transform(p2, rot, centre):
    c, s = math.cos(rot), math.sin(rot)
    return np.column_stack([c * p2[:, 0] - s * p2[:, 1], s * p2[:, 0] + c * p2[:, 1]]) + centre


def extrude(b: Body2D, rot: float = 0.0, centre=(0.0, 0.0), cell_scalar=None, name: str = "scalar"):
    """Wedge cells of each triangle, symmetric about z = 0 with its thickness [mm]; the surface
    (pyvista PolyData) with ``cell_scalar`` (per triangle) as cell data ``name``."""
    import pyvista as pv
    p2 = _transform(b.points, rot, np.asarray(centre, float))
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


# ------------------------------------------------------------------ data from the archive

def _scene(ds: xr.Dataset):
    if "scene" not in ds.attrs:
        raise KeyError("archive has no 'scene' attribute: renders need the scene")
    from study.scene import loads_scene
    return loads_scene(ds.attrs["scene"], "archive attribute 'scene'")


def tooth_stiffness(ds: xr.Dataset, g: int) -> np.ndarray:
    """k_phi [N·mm/rad^n_k] of gear g's teeth from the archive."""
    k = ds["tooth_stiffness"].sel(gear=g).values
    return k[np.isfinite(k)]


def fe_fields(scene, g: int, teeth) -> list:
    """`solver.fe.body.BodyField` of gear g under the load on each of ``teeth`` (one FE solve)."""
    from study.inputs.gearsetup import gear_setup
    from study.inputs.springs import body_fields
    return body_fields(gear_setup(scene, g), teeth)


def pair_bodies(ds: xr.Dataset, fields: dict | None = None) -> dict:
    """Body2D of both gears: FE mesh for a lightened gear (from ``fields[g]`` or a new FE
    solve), outline for a solid one."""
    sc = _scene(ds)
    out = {}
    for g in (1, 2):
        if sc.is_lightened(g):
            f = (fields or {}).get(g) or fe_fields(sc, g, [0])[0]
            out[g] = _with_teeth(fe_body(f), sc, g)
        else:
            out[g] = outline_body(sc, g)
    return out


def stiffness_range(ds: xr.Dataset) -> tuple[tuple, list]:
    """Colour range [N·mm/rad] of the tooth map and the gears coloured by it: the range of the
    gears whose teeth differ (the lightened ones); a gear with one value for all teeth outside
    that range is drawn grey and named in the caption."""
    ks = {g: tooth_stiffness(ds, g) for g in (1, 2)}
    varying = [g for g, k in ks.items() if np.ptp(k) > 1e-9 * abs(k).max()]
    base = varying or [1, 2]
    lo = min(float(ks[g].min()) for g in base)
    hi = max(float(ks[g].max()) for g in base)
    coloured = [g for g in (1, 2) if g in base or (lo <= ks[g].min() and ks[g].max() <= hi)]
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        lo, hi = lo * (1 - 1e-3), hi * (1 + 1e-3)
    return (lo, hi), coloured


# ------------------------------------------------------------------ renders

def _plotter(shape=(1, 1), size=WINDOW):
    import pyvista as pv
    p = pv.Plotter(off_screen=True, shape=shape, window_size=size, border=False)
    p.set_background("white")
    return p


def _project(p, subplot, xyz) -> tuple[int, int]:
    """Image (row, column) of a world point in subplot ``subplot``."""
    import vtk
    p.subplot(*subplot)
    c = vtk.vtkCoordinate()
    c.SetCoordinateSystemToWorld()
    c.SetValue(*map(float, xyz))
    x, y = c.GetComputedDisplayValue(p.renderer)
    h = p.window_size[1]
    return int(h - 1 - y), int(x)


def _fit_parallel(p, pts, vp_w: float, vp_h: float, margin: float = 1.04, bottom_margin: float = 0.0,
                  top_margin: float = 0.0) -> None:
    """Top view, parallel projection, framing the points' x-y box in a vp_w x vp_h viewport,
    leaving ``bottom_margin`` (colour bar) and ``top_margin`` (caption) of the height free."""
    p.camera_position = "xy"
    p.enable_parallel_projection()
    p.reset_camera()
    lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
    c = 0.5 * (lo + hi)
    w, h = (hi - lo) * margin
    usable = vp_h * (1 - bottom_margin - top_margin)
    scale = max(h / 2, w / 2 * usable / vp_w) * vp_h / usable
    cam = p.camera
    shift = scale * (bottom_margin - top_margin)   # box centre at the middle of the free band
    z = cam.position[2]
    cam.focal_point = (c[0], c[1] - shift, 0.0)
    cam.position = (c[0], c[1] - shift, z)
    cam.view_up = (0.0, 1.0, 0.0)
    cam.parallel_scale = scale


def gear_pair_render(ds: xr.Dataset, path, fields: dict | None = None) -> RenderResult:
    """Both gears in mesh, teeth coloured by k_phi, holes and web thickness visible."""
    sc = _scene(ds)
    (lo, hi), coloured = stiffness_range(ds)
    bodies = pair_bodies(ds, fields)
    p = _plotter(shape=(2, 1))
    meshes = {}
    for g in (1, 2):
        b = bodies[g]
        k = tooth_stiffness(ds, g)
        val = np.where(b.tooth >= 0, k[np.clip(b.tooth, 0, None)], np.nan) if g in coloured else np.full(len(b.tooth), np.nan)
        rot, centre = placement(sc, g)
        meshes[g] = extrude(b, rot, centre, val, "k_phi")
    title = "tooth spring stiffness k_phi [N·mm/rad]"
    bar = dict(title=title, n_labels=5, fmt="%.4g", color="black", vertical=False, width=0.6, height=0.07,
               position_x=0.2, position_y=0.04, title_font_size=22, label_font_size=18)
    for row, lit in ((0, True), (1, False)):
        p.subplot(row, 0)
        for g in (1, 2):
            p.add_mesh(meshes[g].copy(), scalars="k_phi", cmap=STIFFNESS_CMAP, clim=(lo, hi), nan_color=NAN_COLOR,
                       lighting=lit, show_scalar_bar=(row == 1), scalar_bar_args=bar if row == 1 else None,
                       smooth_shading=False)
        if row == 0:
            p.camera_position = "xy"
            p.camera.elevation = -35
            p.reset_camera()
            p.camera.zoom(2.1)
            p.add_text(_pair_caption(ds, sc, coloured), position="upper_left", font_size=11, color="black")
        else:
            _fit_parallel(p, np.vstack([m.points for m in meshes.values()]), WINDOW[0], WINDOW[1] / 2,
                          bottom_margin=0.17, top_margin=0.05)
            p.add_text("seen from above (unlit: colours match the bar)", position="upper_left", font_size=10, color="black")
    p.render()
    probes = []
    for g in coloured:
        geo = gear_geometry(sc.tooth_spec(g))
        r_mid = 0.5 * (geo.root_radius + geo.pitch_radius) / units.MM
        rot, centre = placement(sc, g)
        k = tooth_stiffness(ds, g)
        for t in range(geo.teeth):
            a = rot + t * geo.pitch_angle
            xy = centre + r_mid * np.array([math.cos(a), math.sin(a)])
            zt = sc.gear(g).face_width / 2
            probes.append((*_project(p, (1, 0), (xy[0], xy[1], zt)), float(k[t])))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    p.screenshot(str(path))
    p.close()
    return RenderResult(path, (lo, hi), "k_phi", "N mm rad-1", probes)


def _pair_caption(ds, sc, coloured) -> str:
    lines = [ds.attrs.get("title", "gear pair")[:90], "gear 1 (driver) left, gear 2 (driven) right; grey: body below the teeth"]
    for g in (1, 2):
        b = sc.gear(g).body
        k = tooth_stiffness(ds, g)
        desc = f"{b.holes} holes R {b.hole_radius:g} mm, web {b.web_thickness:g} mm" if sc.is_lightened(g) else "solid"
        kk = f"k_phi {k.min():.4g} .. {k.max():.4g}" if np.ptp(k) > 0 else f"every tooth k_phi {k[0]:.4g}"
        grey = "" if g in coloured else " (outside the colour range: grey)"
        lines.append(f"gear {g}: {sc.gear(g).teeth} teeth, {desc}; {kk} N·mm/rad{grey}")
    return "\n".join(lines)


def _fillet_peak(f, geo, tooth: int) -> float:
    """Largest element von Mises stress [Pa] in the root/fillet band of the loaded tooth
    (radius within one module of the root circle, within one pitch of the tooth axis)."""
    c = f.points[f.triangles].mean(axis=1)
    r = np.hypot(c[:, 0], c[:, 1])
    a = np.arctan2(c[:, 1], c[:, 0]) - tooth * geo.pitch_angle
    a = (a + math.pi) % (2 * math.pi) - math.pi
    m = geo.spec.module
    sel = (np.abs(r - geo.root_radius) < m) & (np.abs(a) < geo.pitch_angle)
    return float(f.von_mises[sel].max()) if sel.any() else float("nan")


def fe_stress_render(ds: xr.Dataset, path, g: int = 2, teeth=None, fields=None) -> RenderResult:
    """FE response of gear g's body to the tooth load on the stiffest and on the softest tooth
    (or ``teeth``), one row each, the loaded tooth turned to point up, the view on the teeth and
    rim around it (with the top of the hole below it):

    left, von Mises stress [MPa] on one linear scale for both rows (0 .. the larger peak fillet
    stress; the contact spot under the load goes beyond and is clipped); right, displacement
    magnitude [um] on the shape magnified so the largest displacement in view reads 0.5 mm,
    undeformed outline in grey. The arrow is the load on the drive flank at the pitch circle."""
    import pyvista as pv
    sc = _scene(ds)
    geo = gear_geometry(sc.tooth_spec(g))
    body = sc.body_spec(g)
    k = tooth_stiffness(ds, g)
    if teeth is None:
        teeth = [int(np.argmax(k)), int(np.argmin(k))]
    fields = fields or fe_fields(sc, g, teeth)
    from study.inputs.springs import hole_offset
    off = hole_offset(sc, g)
    n_holes = body.holes
    r_tip = geo.tip_radius / units.MM
    # view: from just above the hole circle's outer edge (or mid-web) to the tip, +-3.5 pitches
    if n_holes:
        r_in = (body.hole_circle_radius + 0.6 * body.hole_radius) / units.MM
    else:
        r_in = (geo.root_radius - body.rim_height - 0.5 * body.web_height) / units.MM
    r_in = min(r_in, (geo.root_radius - 2 * geo.spec.module) / units.MM)
    half = 3.5 * geo.pitch_angle
    peaks = [_fillet_peak(f, geo, f.tooth) / units.MPA for f in fields]
    lo, hi = 0.0, float(max(peaks))
    n = len(fields)
    vw, vh = 1000, 560
    p = _plotter(shape=(n, 2), size=(2 * vw, vh * n))
    bar = dict(title="von Mises stress [MPa]", n_labels=5, fmt="%.0f", color="black", vertical=False,
               width=0.7, height=0.1, position_x=0.15, position_y=0.02, title_font_size=20, label_font_size=16)
    crops, views = [], []
    for f in fields:
        b = fe_body(f)
        c = b.points[b.triangles].mean(axis=1)
        a = (np.arctan2(c[:, 1], c[:, 0]) - f.tooth * geo.pitch_angle + math.pi) % (2 * math.pi) - math.pi
        r = np.hypot(c[:, 0], c[:, 1])
        # crop well outside the view (ragged cell edges stay out of the picture)
        crops.append((b, (np.abs(a) <= 3 * half) & (r >= 0.5 * r_in)))
        views.append((np.abs(a) <= half) & (r >= r_in))
    u_mag = [np.hypot(*f.displacement.T) / units.UM for f in fields]              # um per vertex
    u_cell = [um[f.triangles].mean(axis=1) for um, f in zip(u_mag, fields)]
    u_hi = float(max(uc[v].max() for uc, v in zip(u_cell, views)))
    magnify = 0.5 / (u_hi * units.UM / units.MM)                                   # largest -> 0.5 mm
    ubar = dict(title=f"displacement [um] (shape magnified x{magnify:.0f})", n_labels=5, fmt="%.2f", color="black",
                vertical=False, width=0.7, height=0.1, position_x=0.15, position_y=0.02, title_font_size=20,
                label_font_size=16)
    corners = np.array([[r_tip * math.sin(t), r_tip * math.cos(t)] for t in np.linspace(-half, half, 9)]
                       + [[r_in * math.sin(t), r_in * math.cos(t)] for t in np.linspace(-half, half, 9)])
    for j, f in enumerate(fields):
        b, keep = crops[j]
        rot = math.pi / 2 - f.tooth * geo.pitch_angle
        sub = Body2D(b.points, b.triangles[keep], b.thickness[keep], b.tooth[keep])
        last = j == n - 1
        # stress
        p.subplot(j, 0)
        mesh = extrude(sub, rot, (0.0, 0.0), f.von_mises[keep] / units.MPA, "von_mises")
        p.add_mesh(mesh, scalars="von_mises", cmap=STRESS_CMAP, clim=(lo, hi), lighting=False,
                   show_scalar_bar=last, scalar_bar_args=bar)
        lp = _transform(np.asarray(f.load_point)[None, :] / units.MM, rot, np.zeros(2))[0]
        d = _transform(np.asarray(f.load_direction)[None, :], rot, np.zeros(2))[0]
        L = 3 * geo.spec.module / units.MM
        z = sc.gear(g).face_width
        p.add_mesh(pv.Arrow(start=(lp[0] - L * d[0], lp[1] - L * d[1], z), direction=(d[0], d[1], 0), scale=L,
                            tip_length=0.3, tip_radius=0.12, shaft_radius=0.04), color="#00b4ff", lighting=False)
        _fit_parallel(p, corners, vw, vh, margin=1.03, bottom_margin=0.2 if last else 0.0, top_margin=0.12)
        where = ""
        if n_holes:
            where = (" (over a hole" if abs(off[f.tooth]) < 0.5 * _hole_half_pitches(sc, g) else " (between holes") + \
                f", {off[f.tooth]:+.1f} pitches from a hole centre)"
        p.add_text(f"gear {g}: {f.load_N:.0f} N on tooth {f.tooth}{where}\n"
                   f"k_phi {k[f.tooth]:.4g} N·mm/rad; peak fillet stress {peaks[j]:.0f} MPa",
                   position="upper_left", font_size=10, color="black")
        # displacement on the magnified shape, undeformed outline in grey
        p.subplot(j, 1)
        moved = Body2D(b.points + magnify * f.displacement / units.MM, sub.triangles, sub.thickness, sub.tooth)
        mesh = extrude(moved, rot, (0.0, 0.0), u_cell[j][keep], "displacement")
        p.add_mesh(mesh, scalars="displacement", cmap=DISPLACEMENT_CMAP, clim=(0.0, u_hi), lighting=False,
                   show_scalar_bar=last, scalar_bar_args=ubar)
        p2 = _transform(sub.points, rot, np.zeros(2))
        flat = pv.PolyData(np.column_stack([p2, np.full(len(p2), z)]),
                           np.hstack([np.full((len(sub.triangles), 1), 3), sub.triangles]).ravel())
        ref = flat.extract_feature_edges(boundary_edges=True, feature_edges=False, manifold_edges=False,
                                         non_manifold_edges=False)
        p.add_mesh(ref, color="#606060", line_width=1.0, lighting=False)
        _fit_parallel(p, corners, vw, vh, margin=1.03, bottom_margin=0.2 if last else 0.0, top_margin=0.12)
        p.add_text(f"tooth {f.tooth}: displacement, largest in view {u_cell[j][views[j]].max():.2f} um",
                   position="upper_left", font_size=10, color="black")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    p.screenshot(str(path))
    p.close()
    return RenderResult(path, (lo, hi), "von_mises", "MPa")


def _hole_half_pitches(sc, g) -> float:
    b = sc.gear(g).body
    if not b.holes:
        return 0.0
    return 2 * math.degrees(math.asin(min(1.0, b.hole_radius / b.hole_circle_radius))) / (360.0 / sc.gear(g).teeth)

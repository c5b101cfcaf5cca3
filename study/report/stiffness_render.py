"""Stiffness map render (pyvista/VTK, off-screen PNG) of a run archive's gear pair.

  gear_pair_render    both gears in mesh, extruded to their thickness (face width on teeth, rim
                      and hub; web thickness in the web; holes as voids), teeth coloured by their
                      spring stiffness k_phi [N·mm/rad]. Top row: perspective view (lit); bottom
                      row: the same map seen from above, unlit, so colours read exactly against
                      the colour bar.

It reads the archive (``tooth_stiffness`` and the scene TOML in ``ds.attrs['scene']``); a
lightened body's mesh comes from the FE body fields its caller gives (`study.report.render_inputs`),
a solid gear is drawn from its outline without FE.
"""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from solver import units
from study.report.plot_style import archive_title
from study.report.render_canvas import NAN_COLOR, WINDOW, RenderResult, fit_parallel, plotter, project, write_png
from study.report.render_geometry import extrude, placement
from study.report.render_inputs import pair_bodies, required_scene, tooth_stiffness
from study.scene import opening_text

STIFFNESS_CMAP = "viridis"


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


def gear_pair_render(ds: xr.Dataset, path, fields: dict | None = None) -> RenderResult:
    """Both gears in mesh, teeth coloured by k_phi, holes and web thickness visible; ``fields``
    {gear: BodyField} of each lightened gear (`study.report.render_inputs.pair_bodies`)."""
    sc = required_scene(ds)
    (lo, hi), coloured = stiffness_range(ds)
    bodies = pair_bodies(ds, fields)
    p = plotter(shape=(2, 1))
    meshes = {}
    for g in (1, 2):
        b = bodies[g]
        k = tooth_stiffness(ds, g)
        val = np.where(b.tooth >= 0, k[np.clip(b.tooth, 0, None)], np.nan) if g in coloured else np.full(len(b.tooth), np.nan)
        rot, centre = placement(sc, g)
        meshes[g] = extrude(b, rot, centre, val, "k_phi")
    title = "tooth spring stiffness k_phi [N·mm/rad^n_k]"
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
            fit_parallel(p, np.vstack([m.points for m in meshes.values()]), WINDOW[0], WINDOW[1] / 2,
                          bottom_margin=0.17, top_margin=0.05)
            p.add_text("seen from above (unlit: colours match the bar)", position="upper_left", font_size=10, color="black")
    p.render()
    probes = []
    for g in coloured:
        geo = sc.geometry(g)
        r_mid = 0.5 * (geo.root_radius + geo.pitch_radius) / units.MM
        rot, centre = placement(sc, g)
        k = tooth_stiffness(ds, g)
        for t in range(geo.teeth):
            a = rot + t * geo.pitch_angle
            xy = centre + r_mid * np.array([math.cos(a), math.sin(a)])
            zt = sc.gear(g).face_width / 2
            probes.append((*project(p, (1, 0), (xy[0], xy[1], zt)), float(k[t])))
    png_title = f"Gear pair, teeth coloured by spring stiffness / {archive_title(ds)}"
    return RenderResult(write_png(p, path, png_title), (lo, hi), "k_phi", "N mm", probes)


def _pair_caption(ds, sc, coloured) -> str:
    lines = [(archive_title(ds) or "gear pair"), "gear 1 (driver) left, gear 2 (driven) right; grey: body below the teeth"]
    for g in (1, 2):
        b = sc.gear(g).body
        k = tooth_stiffness(ds, g)
        holes = f"{b.holes} holes R {b.hole_radius:g} mm" if b.opening == "round" or not b.holes else opening_text(b)
        desc = f"{holes}, web {b.web_thickness:g} mm" if sc.is_lightened(g) else "solid"
        kk = f"k_phi {k.min():.4g} .. {k.max():.4g}" if np.ptp(k) > 0 else f"every tooth k_phi {k[0]:.4g}"
        grey = "" if g in coloured else " (outside the colour range: grey)"
        lines.append(f"gear {g}: {sc.gear(g).teeth} teeth, {desc}; {kk} N·mm/rad^{sc.gear(g).spring.n_k:g}{grey}")
    return "\n".join(lines)



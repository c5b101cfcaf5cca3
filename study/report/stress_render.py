"""FE stress render (pyvista/VTK, off-screen PNG) of a lightened gear body of a run archive.

  fe_stress_render    von Mises stress [MPa] and displacement [um] of a lightened body under
                      the FE tooth load on the stiffest and on the softest tooth, one colour
                      scale per quantity for both.

It reads the archive (``tooth_stiffness`` and the scene TOML in ``ds.attrs['scene']``); the
body's mesh and fields are given by the caller (`study.inputs.springs.archive_body_fields`: FE cache).
"""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from solver import units
from solver.geometry import opening_half_angle, opening_radii
from study.report.plot_style import archive_title
from study.report.render_canvas import RenderResult, fit_parallel, plotter, write_png
from study.report.render_geometry import Body2D, extrude, fe_body, transform
from study.report.render_inputs import required_scene, tooth_stiffness

STRESS_CMAP = "turbo"
DISPLACEMENT_CMAP = "cividis"


def fillet_peak(f, geo, tooth: int) -> float:
    """Largest element von Mises stress [Pa] in the root/fillet band of the loaded tooth
    (`solver.geometry.fillet_band`: radius within one module of the root circle, within one pitch
    of the tooth axis)."""
    from solver.geometry import fillet_band
    sel = fillet_band(f.points[f.triangles].mean(axis=1), geo, tooth)
    return float(f.von_mises[sel].max()) if sel.any() else float("nan")


def fe_stress_render(ds: xr.Dataset, path, g: int, fields: list) -> RenderResult:
    """FE response of gear g's body to the tooth loads of ``fields`` (BodyField each: the
    stiffest and the softest tooth, `study.inputs.springs.archive_body_fields`), one row each,
    the loaded tooth turned to point up, the view on the teeth and rim around it (with the top
    of the hole below it):

    left, von Mises stress [MPa] (element means) on one linear scale for both rows (0 .. the
    larger peak fillet stress of the element means; the contact spot under the load goes
    beyond and is clipped), with the archive's fillet stress ``root_stress`` of the tooth (the
    largest at the fillet vertices: above the element means) in the text; right, displacement
    magnitude [um] on the shape magnified so the largest displacement in view reads 0.5 mm,
    undeformed outline in grey. The arrow is the load on the drive flank at the pitch circle."""
    view = _StressView(ds, g, fields)
    n = len(fields)
    p = plotter(shape=(n, 2), size=(2 * VIEW_W, VIEW_H * n))
    for j, f in enumerate(fields):
        view.stress_panel(p, j, f)
        view.displacement_panel(p, j, f)
    title = f"FE stress and displacement of gear {g} under a tooth load / {archive_title(ds)}"
    return RenderResult(write_png(p, path, title), (view.lo, view.hi), "von_mises", "MPa")


VIEW_W, VIEW_H = 1000, 560      # pixels of one panel
# the bars sit in a band below the image (bottom margin of the last row) with their labels;
# what they show is said in the panel's text (a VTK bar title overlaps its tick labels)
STRESS_BAR = dict(title=" ", n_labels=5, fmt="%.0f", color="black", vertical=False,
                  width=0.7, height=0.08, position_x=0.15, position_y=0.03, label_font_size=16)
DISPLACEMENT_BAR = dict(title="  ", n_labels=5, fmt="%.2f", color="black",
                        vertical=False, width=0.7, height=0.08, position_x=0.15, position_y=0.03, label_font_size=16)


class _StressView:
    """What the rows of `fe_stress_render` share: gear g's scene, geometry and springs, the
    view (inner radius r_in [mm], half angle [rad], its corners [mm] and lower edge y_cut [mm]),
    the stress scale lo..hi [MPa], each field's crop and view masks, its displacement per cell
    [um] and the magnification of the shapes."""

    def __init__(self, ds: xr.Dataset, g: int, fields: list):
        self.ds, self.g, self.n = ds, g, len(fields)
        self.sc = sc = required_scene(ds)
        self.geo = geo = sc.geometry(g)
        body = sc.body_spec(g)
        self.k = tooth_stiffness(ds, g)
        from solver.geometry import hole_offset
        b = sc.gear(g).body
        self.off = hole_offset(sc.gear(g).teeth, b.holes, b.hole_phase)
        self.n_holes = body.holes
        r_tip = geo.tip_radius / units.MM
        # view: from just above the hole circle's outer edge (or mid-web) to the tip, +-3.5 pitches
        if self.n_holes:
            r_in = (body.hole_circle_radius + 0.6 * (opening_radii(body)[1] - body.hole_circle_radius)) / units.MM
        else:
            r_in = (geo.root_radius - body.rim_height - 0.5 * body.web_height) / units.MM
        r_in = min(r_in, (geo.root_radius - 2 * geo.spec.module) / units.MM)
        self.half = half = 3.5 * geo.pitch_angle
        self.peaks = [fillet_peak(f, geo, f.tooth) / units.MPA for f in fields]
        self.lo, self.hi = 0.0, float(max(self.peaks))
        self.stress = archive_root_stress(ds, g)
        self.crops, self.views = [], []
        for f in fields:
            b = fe_body(f)
            c = b.points[b.triangles].mean(axis=1)
            a = (np.arctan2(c[:, 1], c[:, 0]) - f.tooth * geo.pitch_angle + math.pi) % (2 * math.pi) - math.pi
            r = np.hypot(c[:, 0], c[:, 1])
            # crop well outside the view (ragged cell edges stay out of the picture)
            self.crops.append((b, (np.abs(a) <= 3 * half) & (r >= 0.5 * r_in)))
            self.views.append((np.abs(a) <= half) & (r >= r_in))
        u_mag = [np.hypot(*f.displacement.T) / units.UM for f in fields]              # um per vertex
        self.u_cell = [um[f.triangles].mean(axis=1) for um, f in zip(u_mag, fields)]
        self.u_hi = float(max(uc[v].max() for uc, v in zip(self.u_cell, self.views)))
        self.magnify = 0.5 / (self.u_hi * units.UM / units.MM)                        # largest -> 0.5 mm
        self.corners = np.array([[r_tip * math.sin(t), r_tip * math.cos(t)] for t in np.linspace(-half, half, 9)]
                                + [[r_in * math.sin(t), r_in * math.cos(t)] for t in np.linspace(-half, half, 9)])
        self.y_cut = float(self.corners[:, 1].min())     # the view's lower edge: below it the colour bars, on white

    def _row(self, j: int, f):
        """(cropped body, kept cells, the turn [rad] that points the loaded tooth up, the cropped
        Body2D, whether the row is the last) of row j."""
        b, keep = self.crops[j]
        rot = math.pi / 2 - f.tooth * self.geo.pitch_angle
        sub = Body2D(b.points, b.triangles[keep], b.thickness[keep], b.tooth[keep])
        return b, keep, rot, sub, j == self.n - 1

    def stress_panel(self, p, j: int, f) -> None:
        """Row j, left: von Mises stress [MPa], the load arrow, the hot spots and the text."""
        import pyvista as pv
        ds, g, sc, geo = self.ds, self.g, self.sc, self.geo
        b, keep, rot, sub, last = self._row(j, f)
        p.subplot(j, 0)
        mesh = below_cut(extrude(sub, rot, (0.0, 0.0), f.von_mises[keep] / units.MPA, "von_mises"), self.y_cut)
        p.add_mesh(mesh, scalars="von_mises", cmap=STRESS_CMAP, clim=(self.lo, self.hi), lighting=False,
                   show_scalar_bar=last, scalar_bar_args=STRESS_BAR)
        lp = transform(np.asarray(f.load_point)[None, :] / units.MM, rot, np.zeros(2))[0]
        d = transform(np.asarray(f.load_direction)[None, :], rot, np.zeros(2))[0]
        L = 3 * geo.spec.module / units.MM
        z = sc.gear(g).face_width
        p.add_mesh(pv.Arrow(start=(lp[0] - L * d[0], lp[1] - L * d[1], z), direction=(d[0], d[1], 0), scale=L,
                            tip_length=0.3, tip_radius=0.12, shaft_radius=0.04), color="#00b4ff", lighting=False)
        hot = hot_spots(ds, g, rot, self.corners, z)
        for name, xy, _ in hot:
            p.add_mesh(pv.Sphere(radius=0.5 * geo.spec.module / units.MM, center=(xy[0], xy[1], z + 0.1)),
                       color=HOT_COLOURS[name], lighting=False)
        fit_parallel(p, self.corners, VIEW_W, VIEW_H, margin=1.03, bottom_margin=0.3 if last else 0.0, top_margin=0.16)
        where = ""
        off = self.off
        if self.n_holes:
            where = (" (over a hole" if abs(off[f.tooth]) < 0.5 * _hole_half_pitches(sc, g) else " (between holes") + \
                f", {off[f.tooth]:+.1f} pitches from a hole centre)"
        stress = self.stress
        archived = f"{stress[f.tooth]:.1f} MPa" if np.isfinite(stress[f.tooth]) else "not in the archive"
        p.add_text(f"gear {g}: {f.load_N:.0f} N on tooth {f.tooth}{where}\n"
                   f"k_phi {self.k[f.tooth]:.4g} N·mm/rad^{sc.gear(g).spring.n_k:g}; fillet stress (root_stress, largest at "
                   f"the fillet vertices) {archived}\n"
                   f"colour: von Mises stress [MPa], element means (largest in the fillet {self.peaks[j]:.0f} MPa)"
                   + ("\nhot spots under the run's loads (strength.png), in view: "
                      + ", ".join(f"{name} ({HOT_NAMES[name]}) {v:.1f} MPa" for name, _, v in hot) if hot else ""),
                   position="upper_left", font_size=10, color="black")

    def displacement_panel(self, p, j: int, f) -> None:
        """Row j, right: displacement on the magnified shape, undeformed outline in grey."""
        import pyvista as pv
        b, keep, rot, sub, last = self._row(j, f)
        z = self.sc.gear(self.g).face_width
        p.subplot(j, 1)
        moved = Body2D(b.points + self.magnify * f.displacement / units.MM, sub.triangles, sub.thickness, sub.tooth)
        mesh = below_cut(extrude(moved, rot, (0.0, 0.0), self.u_cell[j][keep], "displacement"), self.y_cut)
        p.add_mesh(mesh, scalars="displacement", cmap=DISPLACEMENT_CMAP, clim=(0.0, self.u_hi), lighting=False,
                   show_scalar_bar=last, scalar_bar_args=DISPLACEMENT_BAR)
        p2 = transform(sub.points, rot, np.zeros(2))
        flat = pv.PolyData(np.column_stack([p2, np.full(len(p2), z)]),
                           np.hstack([np.full((len(sub.triangles), 1), 3), sub.triangles]).ravel())
        ref = flat.extract_feature_edges(boundary_edges=True, feature_edges=False, manifold_edges=False,
                                         non_manifold_edges=False)
        p.add_mesh(below_cut(ref, self.y_cut), color="#606060", line_width=1.0, lighting=False)
        fit_parallel(p, self.corners, VIEW_W, VIEW_H, margin=1.03, bottom_margin=0.3 if last else 0.0, top_margin=0.16)
        p.add_text(f"tooth {f.tooth}: displacement, largest in view {self.u_cell[j][self.views[j]].max():.2f} um\n"
                   f"colour: displacement magnitude [um] on the shape magnified x{self.magnify:.0f} (grey: undeformed)",
                   position="upper_left", font_size=10, color="black")


HOT_COLOURS = {"root": "#ff2d2d", "rim": "#b44bff", "web": "#ffffff"}
HOT_NAMES = {"root": "red dot", "rim": "violet dot", "web": "white dot"}


def hot_spots(ds: xr.Dataset, g: int, rot: float, corners: np.ndarray, z: float) -> list:
    """[(location, (x, y) [mm] in the view's frame, largest tensile stress [MPa])] of the
    archive's strength hot spots of gear g (``stress_position``, ``bending_stress``) that lie in
    the view (the box of ``corners``); [] without them."""
    if "stress_position" not in ds or "bending_stress" not in ds:
        return []
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    out = []
    for k, name in enumerate(ds["location"].values):
        v = float(ds["bending_stress"].sel(gear=g).values[k])
        xy = ds["stress_position"].sel(gear=g).values[k]
        if not (np.isfinite(v) and np.isfinite(xy).all()):
            continue
        q = transform(np.asarray(xy, float)[None, :], rot, np.zeros(2))[0]
        if np.all(q >= lo) and np.all(q <= hi):
            out.append((str(name), q, v))
    return out


def below_cut(mesh, y_cut: float):
    """``mesh`` with what lies below y = y_cut [mm] (the view's lower edge) cut away, so that
    the colour bars below the last row sit on white."""
    return mesh.clip(normal=(0.0, 1.0, 0.0), origin=(0.0, y_cut, 0.0), invert=False)


def archive_root_stress(ds: xr.Dataset, g: int) -> np.ndarray:
    """The archive's fillet stress ``root_stress`` [MPa] of gear g's teeth (NaN without it)."""
    z = int(np.isfinite(tooth_stiffness(ds, g)).sum())
    if "root_stress" not in ds:
        return np.full(z, np.nan)
    return np.asarray(ds["root_stress"].sel(gear=g).values[:z], float)


def _hole_half_pitches(sc, g) -> float:
    b = sc.gear(g).body
    if not b.holes:
        return 0.0
    return 2 * math.degrees(opening_half_angle(sc.body_spec(g))) / (360.0 / sc.gear(g).teeth)

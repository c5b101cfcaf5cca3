"""The off-screen VTK canvas of the renders (pyvista): plotter, camera framing, world-to-image
projection, PNG writing, and what a render returns.

Off-screen: VTK is told to use EGL unless a window type is already set, so no X display is
needed and none is looked for (set here, before any plotter is made).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

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


def plotter(shape=(1, 1), size=WINDOW):
    """Off-screen pyvista plotter, white background, ``shape`` subplots, ``size`` pixels."""
    import pyvista as pv
    p = pv.Plotter(off_screen=True, shape=shape, window_size=size, border=False)
    p.set_background("white")
    return p


def project(p, subplot, xyz) -> tuple[int, int]:
    """Image (row, column) of a world point in subplot ``subplot``."""
    import vtk
    p.subplot(*subplot)
    c = vtk.vtkCoordinate()
    c.SetCoordinateSystemToWorld()
    c.SetValue(*map(float, xyz))
    x, y = c.GetComputedDisplayValue(p.renderer)
    h = p.window_size[1]
    return int(h - 1 - y), int(x)


def fit_parallel(p, pts, vp_w: float, vp_h: float, margin: float = 1.04, bottom_margin: float = 0.0,
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


def write_png(p, path, title: str = "") -> Path:
    """Screenshot of plotter ``p`` to ``path`` (parent folders made); closes the plotter. A
    ``title`` goes into the PNG's ``Title`` text field (as the plots' titles do)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    p.screenshot(str(path))
    p.close()
    if title:
        from PIL import Image, PngImagePlugin
        info = PngImagePlugin.PngInfo()
        info.add_text("Title", title)
        with Image.open(path) as im:
            im.load()
            im.save(path, pnginfo=info)
    return path

"""What the renders take from a run archive: its scene, the per-tooth spring stiffness, and
the FE body fields of a lightened gear (`study.inputs.springs`: cached springs, one FE
factorisation, the displacement under each loaded tooth), made into render bodies.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from study.report.render_geometry import fe_body, outline_body, with_teeth


def required_scene(ds: xr.Dataset):
    """The scene stored in the archive's ``scene`` attribute; ``KeyError`` without one."""
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
    sc = required_scene(ds)
    out = {}
    for g in (1, 2):
        if sc.is_lightened(g):
            f = (fields or {}).get(g) or fe_fields(sc, g, [0])[0]
            out[g] = with_teeth(fe_body(f), sc, g)
        else:
            out[g] = outline_body(sc, g)
    return out



"""What the renders take: the run archive's scene and per-tooth spring stiffness, and the FE
body fields of its lightened gears, given by the caller (`study.inputs.springs.archive_body_fields`
reads them from the FE cache or solves them; `study.render` does so before it draws). The
pictures start no FE solve: a lightened gear without its fields is not rendered, and
`missing_fields` says which.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from study.report.plot_style import archive_scene
from study.report.render_geometry import fe_body, outline_body, with_teeth


def required_scene(ds: xr.Dataset):
    """The scene stored in the archive's ``scene`` attribute; ``KeyError`` without one."""
    sc = archive_scene(ds)
    if sc is None:
        raise KeyError("archive has no 'scene' attribute: renders need the scene")
    return sc


def tooth_stiffness(ds: xr.Dataset, g: int) -> np.ndarray:
    """k_phi [N·mm/rad^n_k] of gear g's teeth from the archive."""
    k = ds["tooth_stiffness"].sel(gear=g).values
    return k[np.isfinite(k)]


def missing_fields(ds: xr.Dataset, fields: dict | None) -> list[int]:
    """The lightened gears of the archive's scene that have no FE body fields in ``fields``."""
    sc = required_scene(ds)
    return [g for g in (1, 2) if sc.is_lightened(g) and not (fields or {}).get(g)]


def pair_bodies(ds: xr.Dataset, fields: dict | None = None) -> dict:
    """Body2D of both gears: the FE mesh of a lightened gear (from ``fields[g]``: a BodyField,
    or a list of them whose first is taken), the outline of a solid one. ``ValueError`` naming
    the lightened gears without fields."""
    missing = missing_fields(ds, fields)
    if missing:
        raise ValueError(f"no FE body fields of lightened gear {', '.join(map(str, missing))} "
                         "(study.inputs.springs.archive_body_fields gives them)")
    sc = required_scene(ds)
    out = {}
    for g in (1, 2):
        if sc.is_lightened(g):
            f = fields[g]
            out[g] = with_teeth(fe_body(f[0] if isinstance(f, list | tuple) else f), sc, g)
        else:
            out[g] = outline_body(sc, g)
    return out

"""Body-torsion coupling of a scene's gears, identified from the FE body (cached).

`body_torsion(scene, g)` loads every tooth of gear g's FE body at the pitch point (one tooth
for a solid body, by symmetry) and reads each tooth's and its neighbours' deflection along
the line of action at the tooth centreline (`solver.ltca` influence coefficients, same mesh
and load patch as the FE tooth springs), then splits the body wind-up off the tooth springs
(`solver.coupling.body_torsion_fit`). Used by `study.run` when ``coupling.model =
"body-torsion"``.
"""
from __future__ import annotations

import math

import numpy as np

from solver.coupling import BodyTorsionFit, body_torsion_fit
from solver.fe import load_case
from solver.geometry import gear_geometry

from .reference import body_compliance_cached
from .scene import Scene


def body_torsion(scene: Scene, g: int) -> BodyTorsionFit:
    """Body spring [N·m/rad] and tooth springs without the body wind-up of gear g, about the
    pivot of `tooth_pivot` (so `BodyTorsionFit.k_total` is the plain FE spring about it)."""
    geo = gear_geometry(scene.tooth_spec(g), f"gear{g}")
    z = geo.teeth
    u = np.array([math.tan(geo.spec.pressure_angle)])
    if scene.is_lightened(g):
        c, _ = body_compliance_cached(scene, g, list(range(z)), 1, u=u)
        G = c.g[:, 0, :, 0]                        # read tooth, load tooth
        a = np.arange(z)
        c_tot = G[a, a]
        c_adj = 0.5 * (G[a, (a - 1) % z] + G[a, (a + 1) % z])
    else:
        c, _ = body_compliance_cached(scene, g, [0], 1, u=u)
        G = c.g[:, 0, 0, 0]                        # read offsets -1, 0, 1
        c_tot = np.full(z, G[1])
        c_adj = np.full(z, 0.5 * (G[0] + G[2]))
    r_q, k_q = tooth_pivot(scene, g, float(np.mean(c_adj)))
    return body_torsion_fit(c_tot, c_adj, load_case(geo, 0, r_q).lever, geo.base_radius, r_q, k_q)


def tooth_pivot(scene: Scene, g: int, c_body: float) -> tuple[float, float]:
    """(pivot radius [m], spring [N·m/rad]) of gear g's tooth 0 refitted to its FE compliance
    along the profile less the body compliance c_body [m/N] (see `solver.coupling`)."""
    from solver.identify import fit_pivot
    from .reference import PROFILE_POINTS
    geo = gear_geometry(scene.tooth_spec(g), f"gear{g}")
    if scene.is_lightened(g):
        c, _ = body_compliance_cached(scene, g, [0], 0, PROFILE_POINTS)
        off = 0
    else:
        c, _ = body_compliance_cached(scene, g, [0], 1, PROFILE_POINTS)
        off = 1
    diag = np.array([c.g[off, i, 0, i] for i in range(c.u.size)])
    r_q, k, _err = fit_pivot(geo.base_radius, geo.psi_base - c.u, diag - c_body)
    return r_q, k


def plain_fe_springs(scene: Scene, g: int) -> np.ndarray:
    """Per-tooth FE springs [N·m/rad] of the plain model about the scene's pivot, from the same
    influence coefficients (lever**2 / c_total: body wind-up included in every tooth)."""
    geo = gear_geometry(scene.tooth_spec(g), f"gear{g}")
    lever = load_case(geo, 0, scene.pivot_radius(g)).lever
    return lever**2 / body_torsion(scene, g).c_total

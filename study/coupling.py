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
    """Body spring [N·m/rad] and tooth springs without the body wind-up of gear g."""
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
    lever = load_case(geo, 0, scene.pivot_radius(g)).lever
    return body_torsion_fit(c_tot, c_adj, lever, geo.base_radius)

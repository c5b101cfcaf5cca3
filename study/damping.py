"""Damping in a scene: a damper given as a coefficient or as a ratio of critical damping.

The contact (``c_con`` or ``damping_ratio`` of the mesh mode) and each gear's tooth springs
(``c_phi`` or ``damping_ratio`` of the tooth's own mode) take exactly one of the two; a field
left out is NaN (``NOT_GIVEN``, written as ``nan`` when a scene is saved). The conversion of
ratios to coefficients is in `study.scene_model.damping_from_ratios`.
"""
from __future__ import annotations

import math

from study.errors import SceneError

NOT_GIVEN = math.nan   # an optional field left out (written as ``nan`` when a scene is saved)

# Damping defaults, as ratios of critical (see docs/numbers.md, "Damping"). Mesh: measured spur-gear mesh
# damping ratios are a few percent of critical: 0.03-0.17 (the range Kasuba & Evans 1981, ASME
# J. Mech. Des. 103, report for the mesh), about 0.05-0.10 (Gerber 1984, measurements on an
# FZG back-to-back rig), and a few percent from the EHL film of the mesh interface (Li &
# Kahraman 2011, Int. J. Powertrains 1, a mesh damping model). 0.05 sits at the low end.
# Teeth: 0.02, the structural damping of a steel cantilever with its root joint (no value in
# the paper; the coefficient the scenes used before, c_phi = 0.062 N·mm·s/rad, is 2 %).
MESH_DAMPING_RATIO = 0.05
TOOTH_DAMPING_RATIO = 0.02


def resolve_exclusive(cls, kwargs: dict, path: str) -> None:
    """A damper given as a coefficient or as a ratio of critical, exactly one of them: both is
    a SceneError, neither takes the default ratio; a ratio needs a linear damper (exponent 1)."""
    coef, ratio, default, exponent = getattr(cls, "EXCLUSIVE", (None,) * 4)
    if coef is None:
        return
    if coef in kwargs and ratio in kwargs:
        raise SceneError(f"{path}.{ratio}", f"give either {path}.{coef} (a coefficient) or {path}.{ratio} "
                                            "(a ratio of critical damping), not both")
    if coef not in kwargs and default is not None:
        kwargs.setdefault(ratio, default)
    if ratio in kwargs and exponent is not None:
        if kwargs.get(exponent, 1.0) != 1.0:
            raise SceneError(f"{path}.{exponent}", f"a damping ratio ({path}.{ratio} = {kwargs[ratio]}) needs a linear "
                                                   f"damper ({exponent} = 1); give {path}.{coef} for {exponent} = "
                                                   f"{kwargs[exponent]}")


def check_damping(scene) -> None:
    """A mesh damping ratio (contact.damping_ratio, the default) is carried by the tooth-root
    joint dampers (`study.scene_model.damping_from_ratios`): the springs then give no damper of their
    own and have linear dampers (n_c = 1). Raises SceneError naming the field."""
    if not math.isnan(scene.contact.c_con):
        return
    for g in (1, 2):
        sp = scene.gear(g).spring
        for name in ("c_phi", "damping_ratio"):
            if not math.isnan(getattr(sp, name)):
                raise SceneError(f"gear{g}.spring.{name}", "the mesh damping ratio (contact.damping_ratio, default "
                                 f"{MESH_DAMPING_RATIO}) sets the tooth-root joint dampers: give no spring damper with "
                                 "it, or give contact.c_con instead of the ratio")
        if sp.n_c != 1.0:
            raise SceneError(f"gear{g}.spring.n_c", "the mesh damping ratio (contact.damping_ratio) is carried by the "
                             "tooth-root joint dampers, which needs n_c = 1; give contact.c_con and c_phi instead")


def damping_partner(parts: list[str]) -> str | None:
    """The other way to give the same damper ('c_con' <-> 'damping_ratio' in ``contact``,
    'c_phi' <-> 'damping_ratio' in ``gearN.spring``), or None."""
    pairs = {"contact": ("c_con", "damping_ratio"), "spring": ("c_phi", "damping_ratio")}
    if len(parts) < 2 or parts[-2] not in pairs or parts[-1] not in pairs[parts[-2]]:
        return None
    a, b = pairs[parts[-2]]
    return b if parts[-1] == a else a

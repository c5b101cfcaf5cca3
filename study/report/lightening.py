"""What a lightening buys and what it costs, per gear of a run archive:

  mass(gear)                 mass of the gear, body and teeth [kg]            (geometry)
  mass_saving(gear)          mass saved against the same gear solid [%]       (geometry)
  inertia(gear)              polar inertia about the gear axis [kg mm2]       (geometry)
  root_stress(gear, tooth)   largest fillet stress of each tooth [MPa]        (FE body)
  root_stress_max(gear)      the largest of them [MPa]                        (FE body)
  root_stress_ratio(gear)    root_stress_max over the solid gear's value [1]  (FE body; 1 for a solid gear)

Mass and inertia are cheap geometry (`solver.inertia.gear_mass`: the body rings at their
thickness less the holes, plus the teeth from their outline; the solid gear is
`solver.geometry.solid_body`) and are always computed. The root stress comes from the FE solve
of the stiffness map (`study.inputs.springs.root_stress`, cached with it), so it is given only
for a gear whose springs come from the FE (a lightened gear, springs not 'uniform'); the solid
reference's value is the same FE of the solid body that the stiffness ratio uses. Other gears
get NaN and the reason in the attributes: no FE is started for this output alone.

A solid gear is its own stress reference: its ``root_stress_ratio`` is 1 by definition (no FE
needed), while its ``root_stress_max`` stays NaN unless its springs ran the FE (never: a solid
gear's springs need none). So every point of a study that keeps a gear solid has a ratio, and a
stress limit on the ratio applies to it without special cases.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from solver import units
from solver.inertia import gear_mass

GEOMETRY_SOURCE = ("geometry: body rings (rim and hub at the face width, web at its thickness) less the holes, "
                   "plus the teeth from their outline polygon (solver.inertia.gear_mass)")
FE_SOURCE = ("FE plane-stress body (gmsh mesh, scikit-fem quadratic triangles, thickness field, clamped at the bore), "
             "the solve of the stiffness map: each tooth loaded alone by F = T/rb on its drive flank at the pitch point; "
             "von Mises stress at the element vertices of the tooth's fillet band (both fillets), "
             "solver.fe.body.fillet_stress")


def _var(dims, data, unit, long_name, **attrs):
    return xr.Variable(dims, data, {"units": unit, "long_name": long_name, **attrs})


def lightening_variables(setups, stress: bool = True) -> tuple[dict, dict]:
    """Coordinates and variables (see the module) of both gears of a scene, from its gear setups
    (`study.inputs.gearsetup.gear_setups`). ``stress``: read the root stress of the gears whose
    springs use the FE (False: NaN for every gear, e.g. when the caller needs no stress)."""
    from study.inputs.springs import root_stress, uses_fe_springs

    zmax = max(s.teeth for s in setups)
    mass, saving, inertia = (np.empty(2) for _ in range(3))
    sigma = np.full((2, zmax), np.nan)
    sigma_max, ratio = np.full(2, np.nan), np.full(2, np.nan)
    reasons = []
    for i, s in enumerate(setups):
        mp = gear_mass(s.geometry, s.body, s.material.density)
        mass[i], saving[i], inertia[i] = mp.mass, mp.mass_saving, mp.inertia * units.MM_PER_M**2
        if not s.lightened:
            ratio[i] = 1.0          # the solid gear is the reference of the ratio: 1 by definition
        if not stress:
            reasons.append(f"gear {s.gear}: not requested")
        elif not uses_fe_springs(s):
            why = "solid body" if not s.lightened else "springs 'uniform'"
            reasons.append(f"gear {s.gear}: {why}, its springs need no FE (none is run for this output alone)")
        else:
            sigma[i, : s.teeth] = root_stress(s) / units.MPA
            sigma_max[i] = np.max(sigma[i, : s.teeth])
            ratio[i] = sigma_max[i] / (float(root_stress(s.solid(), teeth=[0])[0]) / units.MPA)
    load = ", ".join(f"gear {s.gear}: {s.force:.4g} N" for s in setups)
    nan_reason = "; ".join(reasons) if reasons else "none"
    coords = {"gear": _var("gear", np.array([1, 2]), "1", "gear (1 driver, 2 driven)"),
              "tooth": _var("tooth", np.arange(zmax), "1", "tooth index (counter-clockwise from tooth 0)")}
    data = {
        "mass": _var("gear", mass, "kg", "mass of the gear (body and teeth)", source=GEOMETRY_SOURCE),
        "mass_saving": _var("gear", saving, "%", "mass saved against the same gear solid (no holes, web as thick as the face)",
                            source=GEOMETRY_SOURCE),
        "inertia": _var("gear", inertia, "kg mm2", "polar moment of inertia about the gear axis (body and teeth)",
                        source=GEOMETRY_SOURCE),
        "root_stress": _var(("gear", "tooth"), sigma, "MPa", "largest fillet (root) stress of each tooth under its reference load",
                            source=FE_SOURCE, load=load, not_computed=nan_reason),
        "root_stress_max": _var("gear", sigma_max, "MPa", "largest fillet (root) stress over the teeth",
                                source=FE_SOURCE, load=load, not_computed=nan_reason,
                                comment="NaN for a gear whose springs need no FE, a solid gear included: its stress "
                                        "is the reference of root_stress_ratio (1 for it), computed by the FE of a "
                                        "lightened gear only"),
        "root_stress_ratio": _var("gear", ratio, "1", "largest fillet stress relative to the same gear solid",
                                  source=FE_SOURCE + "; the solid body's tooth 0 with the same mesh settings and load "
                                  "(the reference of the stiffness ratio)", not_computed=nan_reason,
                                  comment="1 by definition for a solid gear (no holes, web as thick as the face: "
                                          "its own reference, no FE needed); NaN for a lightened gear whose "
                                          "springs need no FE"),
    }
    return coords, data


def lightening_dataset(scene, stress: bool = True) -> xr.Dataset:
    """The variables of `lightening_variables` for a scene, alone (no solve: the FE runs only
    for a gear whose springs need it and whose map is not cached)."""
    from study.inputs.gearsetup import gear_setups
    coords, data = lightening_variables(gear_setups(scene), stress)
    return xr.Dataset(data, coords=coords)

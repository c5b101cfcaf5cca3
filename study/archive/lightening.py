"""What a lightening buys and what it costs, per gear of a run archive:

  mass(gear)                 mass of the gear, body and teeth [kg]            (geometry)
  mass_saving(gear)          mass saved against the same gear solid [%]       (geometry)
  inertia(gear)              polar inertia about the gear axis [kg mm2]       (geometry)
  root_stress(gear, tooth)   largest fillet stress of each tooth [MPa]        (FE body)
  root_stress_max(gear)      the largest of them [MPa]                        (FE body)
  root_stress_ratio(gear)    root_stress_max over the solid gear's value [1]  (FE body; 1 for a solid gear)

Mass and inertia are cheap geometry (`solver.inertia.gear_mass`: the body rings at their
thickness less the holes, plus the teeth from their outline; the solid gear is
`solver.geometry.solid_body`), computed by the run's gear stage (`study.stages.gear_stage`) and
always given. The root stress comes from the FE solve
of the stiffness map (`study.inputs.springs.root_stresses`, cached with it), so it is given only
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

from solver import units
from study.archive.schema import variable


def lightening_variables(setups, masses, stresses: dict) -> tuple[dict, dict]:
    """Coordinates and variables (see the module) of both gears of a scene, from its gear setups
    (`study.inputs.gearsetup.gear_setups`), their mass properties ``masses``
    (`solver.inertia.gear_mass`, SI) and ``stresses`` {gear: (root stress of each tooth [Pa], of
    the solid body's tooth 0 [Pa]) or the reason it is not computed}
    (`study.inputs.springs.root_stresses`)."""
    zmax = max(s.teeth for s in setups)
    mass, saving, inertia = (np.empty(2) for _ in range(3))
    sigma = np.full((2, zmax), np.nan)
    sigma_max, ratio = np.full(2, np.nan), np.full(2, np.nan)
    reasons = []
    for i, (s, mp) in enumerate(zip(setups, masses)):
        mass[i], saving[i], inertia[i] = mp.mass, mp.mass_saving, mp.inertia * units.MM_PER_M**2
        if not s.lightened:
            ratio[i] = 1.0          # the solid gear is the reference of the ratio: 1 by definition
        got = stresses[s.gear]
        if isinstance(got, str):
            reasons.append(f"gear {s.gear}: {got}")
        else:
            teeth, solid = got
            sigma[i, : s.teeth] = teeth / units.MPA
            sigma_max[i] = np.max(sigma[i, : s.teeth])
            ratio[i] = sigma_max[i] / (float(solid) / units.MPA)
    load = ", ".join(f"gear {s.gear}: {s.force:.4g} N" for s in setups)
    nan_reason = "; ".join(reasons) if reasons else "none"
    coords = {"gear": variable("gear", np.array([1, 2])), "tooth": variable("tooth", np.arange(zmax))}
    data = {
        "mass": variable("mass", mass),
        "mass_saving": variable("mass_saving", saving),
        "inertia": variable("inertia", inertia),
        "root_stress": variable("root_stress", sigma, load=load, not_computed=nan_reason),
        "root_stress_max": variable("root_stress_max", sigma_max, load=load, not_computed=nan_reason),
        "root_stress_ratio": variable("root_stress_ratio", ratio, not_computed=nan_reason),
    }
    return coords, data

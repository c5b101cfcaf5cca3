"""The strength of each gear under the loads a run computes, as run-archive variables:

  bending_stress(gear, location)          largest tensile stress at the root, in the rim, in the web [MPa]
  bending_stress_static(gear, location)   the same under the static loads alone [MPa]
  von_mises_max(gear, location)           largest von Mises stress there [MPa]
  stress_position(gear, location, axis)   where the largest tensile stress is, x and y in the gear frame [mm]
  web_stress_max, rim_stress_max (gear)   bending_stress in the web, in the rim [MPa]
  web_stress_site(gear)                   the opening edge or the ligament the web's largest stress is at
  ligament_width, ligament_stress_max (gear, ligament)   narrowest ligament of each kind and its largest stress
  rim_thickness, backup_ratio, rim_thickness_factor_iso6336 (gear)   s_R [mm], m_B, Y_B (= AGMA K_B)
  root_stress_hpstc, root_stress_iso6336 (gear)   FE and ISO 6336-3 root stress, one tooth loaded at the HPSTC [MPa]
  failure_mode(gear)                      'tooth', 'rim' or 'web' (`solver.strength.failure_mode`)
  bending_safety(gear, location), bending_safety_static(gear, location)   S_F against the gear's material

The stresses come from `study.inputs.strength` (FE body, load cases superposed with the STE's
contact forces, K_v with a dynamic run), the ratings from `study.inputs.rating` (both made by the
run's strength stage, `study.stages.strength_stage`); this module packs them.
"""
from __future__ import annotations

import math

import numpy as np

from solver.fe.stress import LIGAMENT_KINDS
from solver.strength import LOCATIONS
from study.archive.schema import variable

WEB_SITES = ("opening edge", *(f"{k} ligament" for k in LIGAMENT_KINDS))


def strength_variables(ratings, dynamic_scale: float, dynamic_note: str) -> tuple[dict, dict]:
    """Coordinates and variables (see the module) of both gears from their ratings
    (`study.inputs.rating.GearRating`), whose stresses are the static torque's scaled by
    ``dynamic_scale`` [1] (the dynamic torque over the static one times K_v, ``dynamic_note``
    saying so; NaN without a dynamic run)."""
    n_site = max((r.site_stress.size for r in ratings), default=0)
    site_s, site_p = np.full((2, n_site), np.nan), np.full((2, n_site, 2), np.nan)
    site_loc = np.full((2, n_site), -1, np.int8)
    for i, r in enumerate(ratings):
        n = r.site_stress.size
        site_s[i, :n], site_p[i, :n], site_loc[i, :n] = r.site_stress, r.site_position, r.site_location
    stress, static, vm = (np.array([getattr(r, k) for r in ratings]) for k in ("stress", "static", "von_mises"))
    pos = np.array([r.position for r in ratings])
    notes = [f"gear {r.gear}: not computed ({r.reason})" if r.reason is not None else r.note for r in ratings]
    notes = [n for n in notes if n]
    done = [r for r in ratings if r.reason is None]
    yb_notes, iso_notes = [r.rim_note for r in done], [r.iso_note for r in done]
    mode_notes, mat_notes = "; ".join(r.mode_note for r in done), "; ".join(r.material_note for r in done)

    def per_gear(name):
        return np.array([getattr(r, name) for r in ratings])
    load = (f"the STE's static contact forces superposed on the FE load cases ({', '.join(str(r.steps) for r in done)} "
            f"angles)" + (f", times {dynamic_scale:.4f} for the dynamic run ({dynamic_note})"
                          if math.isfinite(dynamic_scale) else f" ({dynamic_note or 'no dynamic run'})"))
    stress_kind = "largest principal stress (tensile)"
    how = ("FE plane-stress body (study.inputs.strength): stress per unit load at the site nodes (element vertex stress "
           "averaged over the elements of the location's region) for a load on each loaded tooth at five roll parameters, "
           f"superposed with {load}")
    coords = {"location": variable("location", np.array(LOCATIONS)), "ligament": variable("ligament", np.array(LIGAMENT_KINDS)),
              "axis": variable("axis", np.array(["x", "y"])), "site": variable("site", np.arange(n_site))}
    nan_reason = "; ".join(notes) if notes else "none"
    rim = "; ".join(yb_notes)
    data = {
        "bending_stress": variable("bending_stress", stress, stress=stress_kind, source=how, not_computed=nan_reason),
        "bending_stress_static": variable("bending_stress_static", static, stress=stress_kind, source=how,
                                          not_computed=nan_reason),
        "von_mises_max": variable("von_mises_max", vm, source=how, not_computed=nan_reason),
        "stress_position": variable("stress_position", pos),
        "site_stress": variable("site_stress", site_s, stress=stress_kind, source=how),
        "site_position": variable("site_position", site_p),
        "site_location": variable("site_location", site_loc, flag_values=np.array([0, 1, 2, -1], np.int8),
                                  flag_meanings="root rim web none"),
        "web_stress_max": variable("web_stress_max", stress[:, 2], stress=stress_kind, source=how, not_computed=nan_reason),
        "rim_stress_max": variable("rim_stress_max", stress[:, 1], stress=stress_kind, source=how, not_computed=nan_reason),
        "web_stress_site": variable("web_stress_site", np.array([r.site for r in ratings])),
        "ligament_width": variable("ligament_width", per_gear("ligament_width")),
        "ligament_stress_max": variable("ligament_stress_max", per_gear("ligament_stress"), stress=stress_kind, source=how),
        "rim_thickness": variable("rim_thickness", per_gear("rim_thickness"), comment=rim),
        "backup_ratio": variable("backup_ratio", per_gear("backup_ratio"), comment=rim),
        "rim_thickness_factor_iso6336": variable("rim_thickness_factor_iso6336", per_gear("rim_factor"), comment=rim),
        "root_stress_hpstc": variable("root_stress_hpstc", per_gear("hpstc"), stress=stress_kind),
        "root_stress_iso6336": variable("root_stress_iso6336", per_gear("iso"), comment="; ".join(iso_notes)),
        "tooth_form_factor_iso6336": variable("tooth_form_factor_iso6336", per_gear("form_factor")),
        "stress_correction_factor_iso6336": variable("stress_correction_factor_iso6336", per_gear("correction_factor")),
        "failure_mode": variable("failure_mode", np.array([r.mode for r in ratings]), comment=mode_notes),
        "gear_material": variable("gear_material", np.array([r.material for r in ratings]), comment=mat_notes),
        "bending_limit_stress": variable("bending_limit_stress", per_gear("limit"), material=mat_notes),
        "bending_safety": variable("bending_safety", per_gear("safety"), material=mat_notes,
                                   loads="with K_v" if math.isfinite(dynamic_scale)
                                   else f"static ({dynamic_note or 'no dynamic run'})"),
        "bending_safety_static": variable("bending_safety_static", per_gear("safety_static"), material=mat_notes),
    }
    return coords, data

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
contact forces, K_v with a dynamic run).
"""
from __future__ import annotations

import math

import numpy as np

from solver import units
from solver.fe.stress import LIGAMENT_KINDS
from solver.materials import gear_material
from solver.peers import iso6336
from solver.peers.iso6336_strength import backup_ratio, crack_path, nominal_root_stress, rim_thickness_factor
from solver.strength import LOCATIONS, bending_safety, failure_mode
from study.archive.schema import variable

WEB_SITES = ("opening edge", *(f"{k} ligament" for k in LIGAMENT_KINDS))


def rim_thickness(setup, bs) -> tuple[float, str]:
    """(s_R [m], how it was read) of a gear: the rim's height where the web is thinner than the
    face; with a web as thick as the face, down to its openings' outermost edge, or to the bore
    without openings (the body is solid there)."""
    g, b = setup.geometry, setup.body
    if b.web_height > 0 and b.web_thickness < setup.tooth.face_width:
        return b.rim_height, "rim height (the web is thinner than the face)"
    if bs.openings:
        return g.root_radius - bs.opening_outer_radius, "root circle to the outermost edge of the web openings (web as thick as the face)"
    from solver.geometry import bore_radius
    return g.root_radius - bore_radius(g, b), "root circle to the bore (a solid body)"


def strength_variables(setups, pair, results, scene, dynamic_scale: float, dynamic_note: str) -> tuple[dict, dict]:
    """Coordinates and variables (see the module) of both gears from their
    `study.inputs.strength.GearStrength` ``results`` (a text: why not computed), the static torque's
    results scaled by ``dynamic_scale`` [1] (the dynamic torque over the static one times K_v;
    NaN without a dynamic run, or where its K_v is undefined: ``dynamic_note`` then says so) for the
    stresses with K_v."""
    nl, nk = len(LOCATIONS), len(LIGAMENT_KINDS)
    stress, static, vm = (np.full((2, nl), np.nan) for _ in range(3))
    pos = np.full((2, nl, 2), np.nan)
    site = ["", ""]
    lig_w, lig_s = np.full((2, nk), np.nan), np.full((2, nk), np.nan)
    s_r, m_b, y_b, hp, iso, y_f, y_s = (np.full(2, np.nan) for _ in range(7))
    mode, names, limits = ["", ""], ["", ""], np.full(2, np.nan)
    reasons = list(results)
    results = [r if hasattr(r, "body") else None for r in reasons]
    n_site = max((r.body.points.shape[0] for r in results if r is not None), default=0)
    site_s, site_p = np.full((2, n_site), np.nan), np.full((2, n_site, 2), np.nan)
    site_loc = np.full((2, n_site), -1, np.int8)
    safety, safety_static = np.full((2, nl), np.nan), np.full((2, nl), np.nan)
    notes, iso_notes, yb_notes, mode_notes, mat_notes = [], [], [], [], []
    scale = dynamic_scale if math.isfinite(dynamic_scale) else 1.0
    for i, (s, res) in enumerate(zip(setups, results)):
        if res is None:
            notes.append(f"gear {s.gear}: not computed ({reasons[i] if isinstance(reasons[i], str) else 'no static analysis'})")
            continue
        bs, peak = res.body, res.peak
        mp = peak["max_principal"]
        n = mp.size
        site_s[i, :n], site_p[i, :n], site_loc[i, :n] = mp / units.MPA * max(scale, 1.0), bs.points * units.MM_PER_M, bs.location
        for k in range(nl):
            sel = bs.location == k
            if not sel.any():
                continue
            j = np.flatnonzero(sel)[np.argmax(mp[sel])]
            static[i, k] = mp[j] / units.MPA
            stress[i, k] = static[i, k] * max(scale, 1.0)
            vm[i, k] = float(peak["von_mises"][sel].max()) / units.MPA * max(scale, 1.0)
            pos[i, k] = bs.points[j] * units.MM_PER_M
            if k == 2:
                on = [lk for lk in range(bs.lig_kind.size) if bs.lig_node[lk, j]]
                site[i] = f"{LIGAMENT_KINDS[bs.lig_kind[on[0]]]} ligament" if on else "opening edge"
        for lk in range(bs.lig_kind.size):
            kind = bs.lig_kind[lk]
            w = bs.lig_width[lk] * units.MM_PER_M
            if np.isnan(lig_w[i, kind]) or w < lig_w[i, kind] - 1e-9:
                lig_w[i, kind] = w
            if bs.lig_node[lk].any():
                v = float(mp[bs.lig_node[lk]].max()) / units.MPA * max(scale, 1.0)
                lig_s[i, kind] = np.fmax(lig_s[i, kind], v)
        g = s.geometry
        if not bs.openings:
            notes.append(f"gear {s.gear}: web {'without openings' if s.body.web_height > 0 else 'absent'}: "
                         "no web stress (NaN)")
        sr, how = rim_thickness(s, bs)
        h_t = g.tip_radius - g.root_radius
        s_r[i], m_b[i] = sr * units.MM_PER_M, backup_ratio(sr, h_t)
        y_b[i], inside = rim_thickness_factor(m_b[i])
        yb_notes.append(f"gear {s.gear}: s_R {s_r[i]:.3f} mm ({how}), h_t {h_t * units.MM_PER_M:.3f} mm, m_B {m_b[i]:.3f}, "
                        f"Y_B {y_b[i]:.3f}" + ("" if inside else " (m_B < 0.5: outside ISO 6336-3 and AGMA 2001, "
                                                                 "the curve extrapolated)"))
        # ISO 6336-3 Method B beside the FE at the same load: one tooth, F_n at the HPSTC
        m, z, a, b = g.spec.module, g.teeth, g.spec.pressure_angle, g.spec.face_width
        d = iso6336.single_contact_diameter(z, m, a, g.tip_radius, pair.contact_ratio)
        f = iso6336.root_form_factors(z, m, a, g.spec.dedendum_coef, g.spec.fillet_radius, d)
        f_t = res.force * math.cos(a)
        iso[i] = nominal_root_stress(f_t, b, m, f["Y_F"], f["Y_S"], y_b[i]) / units.MPA
        hp[i] = res.hpstc / units.MPA
        iso_notes.append(f"gear {s.gear}: F_t {f_t:.1f} N, b {b * 1e3:g} mm, m {m * 1e3:g} mm, d_HPSTC {d * 1e3:.3f} mm, "
                         f"Y_F {f['Y_F']:.3f}, Y_S {f['Y_S']:.3f}, Y_B {y_b[i]:.3f}, FE/ISO {hp[i] / iso[i]:.3f}")
        y_f[i], y_s[i] = f["Y_F"], f["Y_S"]
        rim_ratio = static[i, 1] / static[i, 0] if static[i, 0] > 0 else math.nan
        web_ratio = static[i, 2] / static[i, 0] if static[i, 0] > 0 else math.nan
        mode[i] = failure_mode(m_b[i], rim_ratio, web_ratio) if math.isfinite(rim_ratio) else ""
        mode_notes.append(f"gear {s.gear}: m_B {m_b[i]:.3f} (Lewicki & Ballarini: {crack_path(m_b[i])}), rim/root "
                          f"{rim_ratio:.3f}, web/root {web_ratio:.3f} -> {mode[i]}")
        mat = gear_material(scene.gear(s.gear).material)
        limit = mat.limit_stress() / units.MPA
        names[i], limits[i] = mat.name, limit
        mat_notes.append(f"gear {s.gear}: {mat.name} ({mat.treatment}), sigma_Flim {mat.sigma_f_lim / units.MPA:g} MPa "
                         f"({mat.source}), sigma_FG {limit:g} MPa")
        for k in range(nl):
            safety[i, k] = bending_safety(limit, stress[i, k])
            safety_static[i, k] = bending_safety(limit, static[i, k])
    load = (f"the STE's static contact forces superposed on the FE load cases ({', '.join(str(r.steps) for r in results if r)} "
            f"angles)" + (f", times {scale:.4f} for the dynamic run ({dynamic_note})" if math.isfinite(dynamic_scale) else
                          f" ({dynamic_note or 'no dynamic run'})"))
    stress_kind = "largest principal stress (tensile)"
    how = ("FE plane-stress body (study.inputs.strength): stress per unit load at the site nodes (element vertex stress "
           "averaged over the elements of the location's region) for a load on each loaded tooth at five roll parameters, "
           f"superposed with {load}")
    coords = {"location": variable("location", np.array(LOCATIONS)), "ligament": variable("ligament", np.array(LIGAMENT_KINDS)),
              "axis": variable("axis", np.array(["x", "y"])), "site": variable("site", np.arange(n_site))}
    nan_reason = "; ".join(notes) if notes else "none"
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
        "web_stress_site": variable("web_stress_site", np.array(site)),
        "ligament_width": variable("ligament_width", lig_w),
        "ligament_stress_max": variable("ligament_stress_max", lig_s, stress=stress_kind, source=how),
        "rim_thickness": variable("rim_thickness", s_r, comment="; ".join(yb_notes)),
        "backup_ratio": variable("backup_ratio", m_b, comment="; ".join(yb_notes)),
        "rim_thickness_factor_iso6336": variable("rim_thickness_factor_iso6336", y_b, comment="; ".join(yb_notes)),
        "root_stress_hpstc": variable("root_stress_hpstc", hp, stress=stress_kind),
        "root_stress_iso6336": variable("root_stress_iso6336", iso, comment="; ".join(iso_notes)),
        "tooth_form_factor_iso6336": variable("tooth_form_factor_iso6336", y_f),
        "stress_correction_factor_iso6336": variable("stress_correction_factor_iso6336", y_s),
        "failure_mode": variable("failure_mode", np.array(mode), comment="; ".join(mode_notes)),
        "gear_material": variable("gear_material", np.array(names), comment="; ".join(mat_notes)),
        "bending_limit_stress": variable("bending_limit_stress", limits, material="; ".join(mat_notes)),
        "bending_safety": variable("bending_safety", safety, material="; ".join(mat_notes),
                                   loads="with K_v" if math.isfinite(dynamic_scale) else f"static ({dynamic_note or 'no dynamic run'})"),
        "bending_safety_static": variable("bending_safety_static", safety_static, material="; ".join(mat_notes)),
    }
    return coords, data

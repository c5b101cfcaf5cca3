"""The bending rating of one gear from its strength under a run's loads
(`study.inputs.strength.GearStrength`): the largest stresses at root, rim and web (with K_v
scaled), where they are, the ligaments, the rim thickness and backup ratio with ISO 6336-3's
Y_B, ISO 6336-3's nominal root stress beside the FE at the HPSTC, the expected failure mode and
the safety factors against the gear's material. `study.archive.strength` packs the ratings of
both gears into run-archive variables.

Units as the archive gives them: MPa, mm.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from solver import units
from solver.fe.stress import LIGAMENT_KINDS
from solver.materials import gear_material
from solver.peers import iso6336
from solver.peers.iso6336_strength import backup_ratio, crack_path, nominal_root_stress, rim_thickness_factor
from solver.strength import LOCATIONS, bending_safety, failure_mode


def _nan(n: int) -> np.ndarray:
    return np.full(n, np.nan)


@dataclass
class GearRating:
    """One gear's rating (see the module); NaN and empty texts where not computed (``reason``)."""
    gear: int
    reason: str | None = None               # why it is not computed (None: it is)
    steps: int | None = None                # STE angles superposed
    static: np.ndarray = field(default_factory=lambda: _nan(len(LOCATIONS)))   # largest tensile stress, static [MPa]
    stress: np.ndarray = field(default_factory=lambda: _nan(len(LOCATIONS)))   # the same with K_v [MPa]
    von_mises: np.ndarray = field(default_factory=lambda: _nan(len(LOCATIONS)))  # [MPa]
    position: np.ndarray = field(default_factory=lambda: np.full((len(LOCATIONS), 2), np.nan))  # [mm]
    site: str = ""                          # the web's largest stress: opening edge or ligament
    site_stress: np.ndarray = field(default_factory=lambda: _nan(0))            # every site node [MPa]
    site_position: np.ndarray = field(default_factory=lambda: np.full((0, 2), np.nan))  # [mm]
    site_location: np.ndarray = field(default_factory=lambda: np.full(0, -1, np.int8))
    ligament_width: np.ndarray = field(default_factory=lambda: _nan(len(LIGAMENT_KINDS)))   # [mm]
    ligament_stress: np.ndarray = field(default_factory=lambda: _nan(len(LIGAMENT_KINDS)))  # [MPa]
    note: str | None = None                 # why a location has no stress
    rim_thickness: float = math.nan         # s_R [mm]
    backup_ratio: float = math.nan          # m_B [1]
    rim_factor: float = math.nan            # Y_B [1]
    rim_note: str = ""
    hpstc: float = math.nan                 # FE root stress at the HPSTC [MPa]
    iso: float = math.nan                   # ISO 6336-3 sigma_F0 [MPa]
    form_factor: float = math.nan           # Y_F [1]
    correction_factor: float = math.nan     # Y_S [1]
    iso_note: str = ""
    mode: str = ""                          # failure mode
    mode_note: str = ""
    material: str = ""
    limit: float = math.nan                 # sigma_FG [MPa]
    material_note: str = ""
    safety: np.ndarray = field(default_factory=lambda: _nan(len(LOCATIONS)))         # with K_v [1]
    safety_static: np.ndarray = field(default_factory=lambda: _nan(len(LOCATIONS)))  # [1]


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


def gear_rating(setup, pair, res, material, dynamic_scale: float) -> GearRating:
    """The rating of gear ``setup`` of ``pair`` from its `study.inputs.strength.GearStrength`
    ``res`` (a text: why not computed), its material (the scene's ``gearN.material`` name) and
    ``dynamic_scale`` [1] (the dynamic torque over the static one times K_v; NaN without a
    dynamic run: the static stresses)."""
    if not hasattr(res, "body"):
        return GearRating(setup.gear, reason=res if isinstance(res, str) else "no static analysis")
    r = GearRating(setup.gear, steps=res.steps)
    _stresses(r, res, max(dynamic_scale if math.isfinite(dynamic_scale) else 1.0, 1.0))
    if not res.body.openings:
        r.note = (f"gear {setup.gear}: web {'without openings' if setup.body.web_height > 0 else 'absent'}: "
                  "no web stress (NaN)")
    g = setup.geometry
    sr, how = rim_thickness(setup, res.body)
    h_t = g.tip_radius - g.root_radius
    r.rim_thickness, r.backup_ratio = sr * units.MM_PER_M, backup_ratio(sr, h_t)
    r.rim_factor, inside = rim_thickness_factor(r.backup_ratio)
    r.rim_note = (f"gear {setup.gear}: s_R {r.rim_thickness:.3f} mm ({how}), h_t {h_t * units.MM_PER_M:.3f} mm, "
                  f"m_B {r.backup_ratio:.3f}, Y_B {r.rim_factor:.3f}"
                  + ("" if inside else " (m_B < 0.5: outside ISO 6336-3 and AGMA 2001, the curve extrapolated)"))
    _iso_root(r, res, g, pair)
    rim_ratio = r.static[1] / r.static[0] if r.static[0] > 0 else math.nan
    web_ratio = r.static[2] / r.static[0] if r.static[0] > 0 else math.nan
    r.mode = failure_mode(r.backup_ratio, rim_ratio, web_ratio) if math.isfinite(rim_ratio) else ""
    r.mode_note = (f"gear {setup.gear}: m_B {r.backup_ratio:.3f} (Lewicki & Ballarini: {crack_path(r.backup_ratio)}), "
                   f"rim/root {rim_ratio:.3f}, web/root {web_ratio:.3f} -> {r.mode}")
    mat = gear_material(material)
    r.material, r.limit = mat.name, mat.limit_stress() / units.MPA
    r.material_note = (f"gear {setup.gear}: {mat.name} ({mat.treatment}), sigma_Flim {mat.sigma_f_lim / units.MPA:g} MPa "
                       f"({mat.source}), sigma_FG {r.limit:g} MPa")
    for k in range(len(LOCATIONS)):
        r.safety[k] = bending_safety(r.limit, r.stress[k])
        r.safety_static[k] = bending_safety(r.limit, r.static[k])
    return r


def _stresses(r: GearRating, res, scale: float) -> None:
    """The stresses of ``r`` from the body's peak stresses, times ``scale`` (>= 1) for K_v."""
    bs, peak = res.body, res.peak
    mp = peak["max_principal"]
    r.site_stress, r.site_position, r.site_location = mp / units.MPA * scale, bs.points * units.MM_PER_M, bs.location
    for k in range(len(LOCATIONS)):
        sel = bs.location == k
        if not sel.any():
            continue
        j = np.flatnonzero(sel)[np.argmax(mp[sel])]
        r.static[k] = mp[j] / units.MPA
        r.stress[k] = r.static[k] * scale
        r.von_mises[k] = float(peak["von_mises"][sel].max()) / units.MPA * scale
        r.position[k] = bs.points[j] * units.MM_PER_M
        if k == 2:
            on = [lk for lk in range(bs.lig_kind.size) if bs.lig_node[lk, j]]
            r.site = f"{LIGAMENT_KINDS[bs.lig_kind[on[0]]]} ligament" if on else "opening edge"
    for lk in range(bs.lig_kind.size):
        kind = bs.lig_kind[lk]
        w = bs.lig_width[lk] * units.MM_PER_M
        if np.isnan(r.ligament_width[kind]) or w < r.ligament_width[kind] - 1e-9:
            r.ligament_width[kind] = w
        if bs.lig_node[lk].any():
            v = float(mp[bs.lig_node[lk]].max()) / units.MPA * scale
            r.ligament_stress[kind] = np.fmax(r.ligament_stress[kind], v)


def _iso_root(r: GearRating, res, g, pair) -> None:
    """ISO 6336-3 Method B beside the FE at the same load: one tooth, F_n at the HPSTC."""
    m, z, a, b = g.spec.module, g.teeth, g.spec.pressure_angle, g.spec.face_width
    d = iso6336.single_contact_diameter(z, m, a, g.tip_radius, pair.contact_ratio)
    f = iso6336.root_form_factors(z, m, a, g.spec.dedendum_coef, g.spec.fillet_radius, d)
    f_t = res.force * math.cos(a)
    r.iso = nominal_root_stress(f_t, b, m, f["Y_F"], f["Y_S"], r.rim_factor) / units.MPA
    r.hpstc = res.hpstc / units.MPA
    r.iso_note = (f"gear {r.gear}: F_t {f_t:.1f} N, b {b * 1e3:g} mm, m {m * 1e3:g} mm, d_HPSTC {d * 1e3:.3f} mm, "
                  f"Y_F {f['Y_F']:.3f}, Y_S {f['Y_S']:.3f}, Y_B {r.rim_factor:.3f}, FE/ISO {r.hpstc / r.iso:.3f}")
    r.form_factor, r.correction_factor = f["Y_F"], f["Y_S"]

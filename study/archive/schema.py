"""The run archive's variables, declared once: name -> dimensions, CF unit, long name and the
attributes that do not depend on the run. `variable` builds each from this table; the attributes
that do (a load, a resolution, a comment with the run's numbers) are given where it is built.

A run archive (`study.run.run_scene`) holds the groups below; which are present depends on the
analyses the scene asks for (a static run has no ``dte``, a solid gear's root stress is NaN, ...).
`python -m study.archive.schema` prints the table.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field

from study.archive.spectra import WINDOW


@dataclass(frozen=True)
class Var:
    """One archive variable (or coordinate): its dimensions, CF unit, long name, fixed attributes."""
    dims: tuple
    units: str
    long_name: str
    attrs: dict = field(default_factory=dict)


GEOMETRY_SOURCE = ("geometry: body rings (rim and hub at the face width, web at its thickness) less the holes, "
                   "plus the teeth from their outline polygon (solver.inertia.gear_mass)")
FE_SOURCE = ("FE plane-stress body (gmsh mesh, scikit-fem quadratic triangles, thickness field, clamped at the bore), "
             "the solve of the stiffness map: each tooth loaded alone by F = T/rb on its drive flank at the pitch point; "
             "von Mises stress at the element vertices of the tooth's fillet band (both fillets), "
             "solver.fe.body.fillet_stress")
MODAL_SOURCE = ("pair linearised at static equilibrium under {torque:g} N·m; state-space eigenvalues lambda: "
                "f = |lambda|/2pi, zeta = -Re(lambda)/|lambda|")
PEAK_NAMES = ("peak name: N hole order, Z mesh order, kZ+-N sidebands, R1 and R2 the driver's and the driven "
              "gear's once-per-revolution orders (gears with errors), other k = k-th largest unexplained peak")

# per-gear scalars a study archives as ``{name}_gear{g}`` (`study.sweep.outputs`)
GEAR_VARIABLES = ("mass", "mass_saving", "inertia", "root_stress_max", "root_stress_ratio")
# per-gear strength scalars a study archives as ``{name}_gear{g}`` (`study.archive.strength`); besides
# them ``failure_mode_gear{g}`` (its index in solver.strength.FAILURE_MODES) and ``bending_safety_gear{g}``
# (the smallest over the locations) with ``bending_safety_{location}_gear{g}``
STRENGTH_VARIABLES = ("web_stress_max", "rim_stress_max", "backup_ratio", "rim_thickness_factor_iso6336",
                      "root_stress_hpstc", "root_stress_iso6336")
STRENGTH_SOURCE = ("FE plane-stress body (study.inputs.strength): its stress per unit load at the strength sites "
                   "(solver.fe.stress.strength_sites) for a load on each loaded tooth at five roll parameters, superposed "
                   "with the STE's static contact forces at every angle; with a dynamic run, times the dynamic torque over "
                   "the static torque times K_v when that is larger")


def _peaks(prefix: str, frequency: bool) -> dict:
    """The named-peak table of the STE or DTE spectrum along ``{prefix}_peak`` (``frequency``:
    with each peak's frequency, for a spectrum over time)."""
    dim, what = (f"{prefix}_peak",), prefix.upper()
    return {
        f"{prefix}_peak": Var(dim, "1", PEAK_NAMES),
        f"{prefix}_peak_nominal_order": Var(dim, "1", f"nominal order of the named {what} peak (driven-gear revolutions)"),
        f"{prefix}_peak_order": Var(dim, "1", f"order where the {what} peak was found (driven-gear revolutions)"),
        f"{prefix}_peak_amplitude": Var(dim, "um", f"{what} amplitude at the peak"),
        **({f"{prefix}_peak_frequency": Var(dim, "Hz", f"frequency of the {what} peak")} if frequency else {}),
    }


RUN_VARIABLES: dict[str, Var] = {
    # ---- tooth springs (always): `study.archive.run_variables.stiffness_variables`
    "gear": Var(("gear",), "1", "gear (1 driver, 2 driven)"),
    "tooth": Var(("tooth",), "1", "tooth index (counter-clockwise from tooth 0)"),
    "tooth_stiffness": Var(("gear", "tooth"), "N mm", "torsion spring stiffness k_phi of each tooth", {
        "unit_symbol": "N·mm/rad^n_k",
        "comment": "T = k_phi |phi|^n_k: k_phi is in N·mm/rad^n_k (n_k of each gear in its scene section; the radian "
                   "is dimensionless, so the CF unit reads N mm); tooth_stiffness_pitch gives the linear stiffness in N/um"}),
    "stiffness_ratio": Var(("gear", "tooth"), "1", "tooth stiffness relative to the solid gear (FE)"),
    # ---- what a lightening buys and costs (always): `study.archive.lightening`
    "mass": Var(("gear",), "kg", "mass of the gear (body and teeth)", {"source": GEOMETRY_SOURCE}),
    "mass_saving": Var(("gear",), "%", "mass saved against the same gear solid (no holes, web as thick as the face)",
                       {"source": GEOMETRY_SOURCE}),
    "inertia": Var(("gear",), "kg mm2", "polar moment of inertia about the gear axis (body and teeth)",
                   {"source": GEOMETRY_SOURCE}),
    "root_stress": Var(("gear", "tooth"), "MPa", "largest fillet (root) stress of each tooth under its reference load",
                       {"source": FE_SOURCE}),
    "root_stress_max": Var(("gear",), "MPa", "largest fillet (root) stress over the teeth", {
        "source": FE_SOURCE,
        "comment": "NaN for a gear whose springs need no FE, a solid gear included: its stress is the reference of "
                   "root_stress_ratio (1 for it), computed by the FE of a lightened gear only"}),
    "root_stress_ratio": Var(("gear",), "1", "largest fillet stress relative to the same gear solid", {
        "source": FE_SOURCE + "; the solid body's tooth 0 with the same mesh settings and load (the reference of the "
                              "stiffness ratio)",
        "comment": "1 by definition for a solid gear (no holes, web as thick as the face: its own reference, no FE "
                   "needed); NaN for a lightened gear whose springs need no FE"}),
    # ---- strength under the run's loads: `study.archive.strength`
    "location": Var(("location",), "1", "where a gear's strength is read: root (fillets and root lands), rim (inner half "
                                        "of the rim under the roots), web (edges of its openings and its ligaments)"),
    "ligament": Var(("ligament",), "1", "ligament of the web: between an opening and the rim, the next opening, the hub "
                                        "(the bore without a hub)"),
    "axis": Var(("axis",), "1", "coordinate in the gear frame: x along tooth 0's axis, y 90 degrees ahead"),
    "site": Var(("site",), "1", "a mesh node where a gear's strength is read (root, rim or web; padded per gear)"),
    "site_stress": Var(("gear", "site"), "MPa", "largest tensile (max principal) stress at each strength site under the "
                       "run's loads", {"comment": "the field the location maxima are read from; NaN past a gear's sites"}),
    "site_position": Var(("gear", "site", "axis"), "mm", "position of each strength site (gear frame)"),
    "site_location": Var(("gear", "site"), "1", "location of each strength site: 0 root, 1 rim, 2 web, -1 none"),
    "bending_stress": Var(("gear", "location"), "MPa", "largest tensile (max principal) stress at the location under the "
                          "run's loads", {"comment": "the stress S_F divides; static, or with K_v when that is larger"}),
    "bending_stress_static": Var(("gear", "location"), "MPa", "largest tensile (max principal) stress at the location "
                                 "under the STE's static contact forces"),
    "von_mises_max": Var(("gear", "location"), "MPa", "largest von Mises stress at the location under the run's loads"),
    "stress_position": Var(("gear", "location", "axis"), "mm", "position of the largest tensile stress of the location "
                           "(gear frame)", {"source": STRENGTH_SOURCE}),
    "web_stress_max": Var(("gear",), "MPa", "largest tensile stress at the web's opening edges and ligaments under the "
                          "run's loads", {"comment": "bending_stress at the web; NaN for a web without openings"}),
    "rim_stress_max": Var(("gear",), "MPa", "largest tensile stress in the inner half of the rim under the run's loads",
                          {"comment": "bending_stress in the rim"}),
    "web_stress_site": Var(("gear",), "1", "where the web's largest tensile stress is: an opening's edge or a ligament "
                           "(hole-rim, hole-hole, hole-hub)"),
    "ligament_width": Var(("gear", "ligament"), "mm", "width of the narrowest ligament of each kind (from the mesh: "
                          "opening edge to the rim circle, to the next opening, to the hub circle)"),
    "ligament_stress_max": Var(("gear", "ligament"), "MPa", "largest tensile stress on the ligaments of each kind under "
                               "the run's loads"),
    "rim_thickness": Var(("gear",), "mm", "rim thickness s_R under the root circle"),
    "backup_ratio": Var(("gear",), "1", "backup ratio m_B = s_R / h_t (rim thickness over tooth height)",
                        {"source": "ISO 6336-3:2019, AGMA 2001-D04"}),
    "rim_thickness_factor_iso6336": Var(("gear",), "1", "rim thickness factor Y_B of ISO 6336-3 (= K_B of AGMA 2001)", {
        "source": "Y_B = 1.6 ln(2.242 / m_B) for 0.5 <= m_B < 1.2, 1 for m_B >= 1.2 (solver.peers.iso6336_strength)"}),
    "root_stress_hpstc": Var(("gear",), "MPa", "FE root stress (largest max principal on the tooth's root) with the tooth "
                             "loaded alone by F = T/rb at the outer point of single tooth contact (HPSTC)", {
                                 "comment": "largest over the loaded teeth; the load position and the load of "
                                            "root_stress_iso6336, for their comparison"}),
    "root_stress_iso6336": Var(("gear",), "MPa", "nominal tooth root stress sigma_F0 = F_t/(b m) Y_F Y_S Y_B of ISO 6336-3 "
                               "Method B at the HPSTC", {"source": "solver.peers.iso6336 (Y_F, Y_S of the basic rack "
                                                                   "generating a fillet of the tool tip radius), "
                                                                   "solver.peers.iso6336_strength (Y_B)"}),
    "tooth_form_factor_iso6336": Var(("gear",), "1", "tooth form factor Y_F of ISO 6336-3 Method B, load at the HPSTC",
                                     {"source": "solver.peers.iso6336.root_form_factors"}),
    "stress_correction_factor_iso6336": Var(("gear",), "1", "stress correction factor Y_S of ISO 6336-3 Method B, load at "
                                            "the HPSTC", {"source": "solver.peers.iso6336.root_form_factors"}),
    "failure_mode": Var(("gear",), "1", "where the first crack is expected: 'tooth', 'rim' or 'web'", {
        "source": "solver.strength.failure_mode: m_B with the thresholds of Lewicki & Ballarini 1997 (1.0 tooth, "
                  "0.5 mixed, 0.3 rim fracture) and the FE's rim-to-root and web-to-root ratios of bending_stress_static"}),
    "gear_material": Var(("gear",), "1", "gear steel of the bending rating (scene gearN.material; solver.materials)"),
    "bending_limit_stress": Var(("gear",), "MPa", "tooth-root limit stress sigma_FG = sigma_Flim Y_ST Y_NT Y_delta_rel_T "
                                "Y_R_rel_T Y_X", {"comment": "Y_ST = 2, Y_NT = Y_delta_rel_T = Y_R_rel_T = Y_X = 1; sigma_Flim "
                                                             "of ISO 6336-5 grade MQ (solver.materials)"}),
    "bending_safety": Var(("gear", "location"), "1", "bending safety factor S_F = sigma_FG / bending_stress", {
        "comment": "sigma_FG = sigma_Flim Y_ST Y_NT Y_delta_rel_T Y_R_rel_T Y_X with Y_ST = 2 and the others 1 "
                   "(solver.materials); the rim and web of a surface-hardened gear are core material, weaker than the "
                   "root's case: their S_F is optimistic for those"}),
    "bending_safety_static": Var(("gear", "location"), "1", "bending safety factor S_F under the static loads alone"),
    # ---- modes and critical speeds: `study.archive.modes`
    "mode": Var(("mode",), "1", "mode number: 0 the mesh mode, then the tooth modes by frequency"),
    "mode_kind": Var(("mode",), "1", "what the mode is: the mesh mode (largest share of kinetic energy on the driven "
                                     "hub) or a tooth mode of the gear whose teeth carry most of its energy"),
    "mesh_position": Var(("mesh_position",), "degree", "driver angle over one mesh period"),
    "excitation": Var(("excitation",), "1", "excitation: kZ mesh orders, N hole order, kZ+-N sidebands"),
    "excitation_order": Var(("excitation",), "1", "order of the driven gear's rotation"),
    "mode_frequency": Var(("mode", "mesh_position"), "Hz", "natural frequency"),     # source: MODAL_SOURCE
    "mode_damping": Var(("mode", "mesh_position"), "1", "damping ratio (of critical)"),  # source: MODAL_SOURCE
    "critical_speed": Var(("excitation", "mode"), "rad/s",
                          "driver speed at which the excitation order meets the mode's mean frequency"),
    # ---- static TE: `study.archive.run_variables.static_variables`
    "angle": Var(("angle",), "degree", "driver rotation from the nominal position"),
    "driver_tooth": Var(("driver_tooth",), "1", "driver tooth index"),
    "ste": Var(("angle",), "um", "static transmission error rb1*theta1 + rb2*theta2"),
    "ste_contacts": Var(("angle",), "1", "loaded tooth contacts"),
    "ste_tooth_force": Var(("angle", "driver_tooth"), "N", "normal contact force on each driver tooth"),
    "ste_converged": Var(("angle",), "1", "static equilibrium reached (1) or not (0)"),
    "ste_order": Var(("ste_order",), "1", "order of the driven gear's rotation (STE spectrum)"),
    "ste_amplitude": Var(("ste_order",), "um", "one-sided amplitude spectrum of STE over driven-gear orders",
                         {"window": WINDOW}),
    **_peaks("ste", frequency=False),
    # ---- the mesh under load: `study.archive.mesh.mesh_variables`
    "driven_tooth": Var(("driven_tooth",), "1", "driven tooth index (counter-clockwise from tooth 0)"),
    "mesh_stiffness": Var(("angle",), "N um-1", "tangent mesh stiffness of the pair along the line of action, "
                                                "the bodies' wind-up from the bore included"),
    "mesh_stiffness_mean": Var((), "N um-1", "mean tangent mesh stiffness of the pair over whole mesh periods of the STE, "
                                             "the bodies' wind-up from the bore included"),
    "mesh_stiffness_p2p": Var((), "N um-1", "peak-to-peak of the tangent mesh stiffness of the pair over the STE"),
    "c_prime": Var((), "N mm-1 um-1", "single stiffness c' of a tooth pair per face width (largest over the STE), the "
                                      "bodies' wind-up from the bore included"),
    "c_gamma_alpha": Var((), "N mm-1 um-1", "mesh stiffness c_gamma_alpha per face width (mean over the STE), the bodies' "
                                            "wind-up from the bore included"),
    "mesh_stiffness_mesh_mean": Var((), "N um-1", "mean tangent stiffness of the mesh alone (the bodies' wind-up from "
                                                  "the bore taken out) over whole mesh periods of the STE"),
    "c_prime_mesh": Var((), "N mm-1 um-1", "single stiffness c' of a tooth pair per face width of the mesh alone (the "
                                           "bodies' wind-up from the bore taken out; largest over the STE)"),
    "c_gamma_alpha_mesh": Var((), "N mm-1 um-1", "mesh stiffness c_gamma_alpha per face width of the mesh alone (the "
                                                 "bodies' wind-up from the bore taken out; mean over the STE)"),
    "c_prime_iso6336": Var((), "N mm-1 um-1", "single stiffness c' by ISO 6336-1 Method B with its low-load factor"),
    "c_gamma_alpha_iso6336": Var((), "N mm-1 um-1", "mesh stiffness c_gamma_alpha by ISO 6336-1 Method B with its "
                                                    "low-load factor"),
    "loaded_contact_ratio": Var((), "1", "loaded contact ratio: mean number of loaded tooth pairs"),
    "ste_tooth_force_gear2": Var(("angle", "driven_tooth"), "N", "normal contact force on each driven tooth"),
    "ste_mate_tooth": Var(("driver_tooth",), "1", "driven tooth that each driver tooth meets in the STE (-1: none)"),
    "tooth_stiffness_pitch": Var(("gear", "tooth"), "N um-1", "tooth stiffness at the pitch point along the line of "
                                                              "action, the body rigid below the rim (no wind-up from the bore)"),
    "tooth_stiffness_pitch_bore": Var(("gear", "tooth"), "N um-1", "tooth stiffness at the pitch point along the line of "
                                                                   "action with the body's wind-up from the bore in series"),
    # ---- dynamic TE: `study.archive.run_variables.dynamic_variables`, `efficiency_variable`
    "time": Var(("time",), "s", "time", {"comment": "elapsed time from the start of the run, not a calendar time"}),
    "dte": Var(("time",), "um", "dynamic transmission error rb1*theta1 + rb2*theta2"),
    "contact_force_max": Var(("time",), "N", "largest tooth contact force over the output interval"),
    "dte_contacts": Var(("time",), "1", "loaded tooth contacts"),
    "driver_torque": Var(("time",), "N m", "torque applied by the driver"),
    "energy_balance_error": Var(("time",), "J", "work in - change of kinetic and potential energy - dissipated energy "
                                                "- energy taken out by the coupled set's switches"),
    "frequency": Var(("frequency",), "Hz", "frequency"),
    "order": Var(("frequency",), "1", "order of the driven gear's rotation"),
    "dte_amplitude": Var(("frequency",), "um", "one-sided amplitude spectrum of DTE after the ramp", {"window": WINDOW}),
    **_peaks("dte", frequency=True),
    "mesh_efficiency": Var((), "1", "mesh efficiency: work out over work in after the ramp", {
        "comment": "driven torque times driven rotation over driver speed times the integral of the driver torque; "
                   "its loss is the flank friction's plus the dampers'"}),
    # ---- dynamic tooth forces: `study.archive.mesh.dynamic_force_variables`
    "contact_slot": Var(("contact_slot",), "1", "slot of a loaded contact at an instant"),
    "dte_contact_tooth1": Var(("time", "contact_slot"), "1", "driver tooth of each loaded contact (-1: empty slot)"),
    "dte_contact_tooth2": Var(("time", "contact_slot"), "1", "driven tooth of each loaded contact (-1: empty slot)"),
    "dte_contact_force": Var(("time", "contact_slot"), "N", "normal force of each loaded contact", {
        "comment": "at the output instant; a tooth's force is the sum over the slots naming it"}),
    "dte_tooth_force_max": Var(("gear", "tooth"), "N", "largest dynamic force on each tooth"),
    "dynamic_factor": Var((), "1", "dynamic factor K_v: largest dynamic over largest static tooth force"),
    # ---- run-up order tracking: `study.archive.order_tracking`
    "runup_speed": Var(("runup_speed",), "rad/s", "driver speed (mean over the block)"),
    "tracked_order": Var(("tracked_order",), "1", "order of the driven gear's rotation"),
    "order_amplitude": Var(("runup_speed", "tracked_order"), "um",
                           "DTE amplitude by order over the run-up (computed order tracking)", {
                               "window": WINDOW, "comment": "DTE resampled to the driven gear's angle; one spectrum per "
                                                            "block of whole driven revolutions"}),
}


def variable(name: str, data, **attrs):
    """The run archive's variable ``name`` (`RUN_VARIABLES`: dimensions, units, long name, fixed
    attributes) holding ``data``, with the run's own ``attrs`` after the fixed ones -> xarray.Variable."""
    import xarray as xr  # here: the table itself is read without xarray (`study.sweep.outputs`)
    v = RUN_VARIABLES[name]
    return xr.Variable(v.dims, data, {"units": v.units, "long_name": v.long_name, **v.attrs, **attrs})


def table() -> str:
    """The declared variables as text: name, dimensions, unit, long name."""
    width = max(len(n) for n in RUN_VARIABLES)
    return "\n".join(f"{n:{width}s}  ({', '.join(v.dims)})  [{v.units}]  {v.long_name}"
                     for n, v in RUN_VARIABLES.items())


if __name__ == "__main__":
    sys.stdout.write(table() + "\n")

"""What the mesh does under load, as archive variables: tangent mesh stiffness over the STE
angle with ISO 6336-1 Method B beside it, each tooth's stiffness at the pitch point, the
loaded contact ratio, the static tooth forces of both gears and which teeth meet, and the
dynamic tooth forces with the dynamic factor.

Units as gear engineers quote them: stiffness in N/um (per face width N/(mm·um)), forces in N.
"""
from __future__ import annotations

import math

import numpy as np

from solver import units
from solver.peers import iso6336
from study.archive.schema import variable


def iso_stiffness(scene, contact_ratio: float, torque: float) -> dict:
    """ISO 6336-1 Method B stiffness of the scene's pair at ``torque`` [N·m] on the driven gear:
    no profile shift, C_M 0.8, the basic-rack factor of gear 1, the gear-blank factor C_R of
    each gear's web (mean of the two; the standard has no holes), the low-load factor
    (F_t/b / 100 N/mm)^0.25 below 100 N/mm (F_t = |torque| / r2 at the driven gear's reference
    circle, K_A = 1, b the smaller face width), c_gamma_alpha = c' (0.75 eps_alpha + 0.25) with
    the geometric transverse contact ratio eps_alpha. Returns c_prime, c_gamma_alpha
    [N/(mm·um)] with the factor, the same without it (``*_full_load``) and without C_M either
    (``*_elastic``: the theoretical stiffness of the elastic pair, c'_th C_R C_B), c_r,
    load_per_width [N/mm] and low_load_factor [1]."""
    g1, g2 = scene.gear1, scene.gear2
    c_r = 0.5 * sum(iso6336.blank_factor(g.body.web_thickness, g.face_width, g.body.rim_height, g.module)
                    for g in (g1, g2))
    c_full = iso6336.single_stiffness(g1.teeth, g2.teeth, g1.dedendum, g1.pressure_angle, c_r)
    r2 = 0.5 * g2.teeth * g2.module * units.MM          # scene mm -> m
    w = abs(torque) / r2 / (min(g1.face_width, g2.face_width))   # N / mm
    f = iso6336.low_load_factor(w)
    ratio = 0.75 * contact_ratio + 0.25
    return {"c_prime": c_full * f, "c_gamma_alpha": c_full * f * ratio, "c_prime_full_load": c_full,
            "c_gamma_alpha_full_load": c_full * ratio, "c_prime_elastic": c_full / iso6336.C_M,
            "c_gamma_alpha_elastic": c_full / iso6336.C_M * ratio, "c_r": c_r, "load_per_width": w, "low_load_factor": f}


def whole_periods(angle_deg, z1: int) -> np.ndarray:
    """Mask of the angles within the largest whole number of mesh periods (360/z1 deg) from
    the first angle (all of them when the range is shorter than one period)."""
    a = np.asarray(angle_deg, float)
    period = 360.0 / z1
    span = a[-1] - a[0] + (a[1] - a[0] if a.size > 1 else 0.0)
    n = math.floor(span / period + 1e-9)
    return a < a[0] + n * period - 1e-9 if n >= 1 else np.ones(a.size, bool)


def mesh_variables(states, model, scene, torque: float, windup=None) -> tuple[dict, dict]:
    """Archive variables of `solver.mbs.mesh_stiffness.mesh_states` over the STE angles
    (``states`` at ``torque`` [N·m]) for the pair ``model`` of ``scene``: the pair's stiffness
    (at the hubs, both bodies' wind-up from the bore in it), the mesh alone (without it) and
    ISO 6336-1 Method B beside them. ``windup``: (gear 1, gear 2) [m/N] the body wind-up the
    plain model's tooth springs hold (`study.inputs.coupling.plain_windup`; the one given to
    `mesh_states`), None for a body-coupled model."""
    from solver.mbs.mesh_stiffness import body_windup_compliance, pitch_point_stiffness
    z1, z2 = model.teeth
    angle = np.degrees(states.angle)
    width = min(g.spec.face_width for g in model.geometry)
    k = units.stiffness_n_per_um(states.stiffness)
    sel = whole_periods(angle, z1) & np.isfinite(k)
    loaded = states.loaded_pairs()
    eps_loaded = float(np.mean(loaded[sel & states.converged])) if (sel & states.converged).any() else float("nan")
    mean, p2p, c1, cga = _stiffness_scalars(k, states.pair_stiffness, sel, width)
    k_mesh = units.stiffness_n_per_um(states.stiffness_mesh)
    mean_m, _p2p_m, c1_m, cga_m = _stiffness_scalars(k_mesh, states.pair_stiffness_mesh, sel, width)
    eps = model.pair.contact_ratio
    load = torque if abs(torque) > 1e-9 else 1.0        # the load mesh_states linearises at
    iso = iso_stiffness(scene, eps, load)
    cw = body_windup_compliance(model, windup)
    cw_um = [c * units.UM_PER_M for c in cw]
    load_note = f"at static equilibrium under {torque:g} N·m"
    both = "includes both bodies' wind-up from the bore (the hubs' TE)"
    if model.coupled:
        how = ("the bodies rigid below the rim: the tangent matrix of mesh_stiffness without the body springs "
               "(hub -> rim), condensed onto the driven rim with the driver rim prescribed; the body springs are in "
               "series with it: 1/k_pair = 1/k_mesh + rb1^2/k_body1 + rb2^2/k_body2 wherever the contacts act along "
               "the line of action (a tip corner's other lever aside)")
    elif windup is not None:
        how = ("the plain model lumps the body wind-up into every tooth spring: each loaded spring's tangent k with "
               "the wind-up c_w of its body taken out at the pitch point, 1/(1/k - c_w/h^2), h the pitch lever; "
               "c_w from the bore-clamped FE body (study.inputs.coupling.plain_windup: mean compliance of a tooth "
               "under its neighbours' pitch-point loads, of the solid body for springs that are not the FE's)")
    else:
        how = "unknown: a plain model given no body wind-up"
    windup_attrs = {"body_windup_um_per_N": np.array(cw_um), "comment": how}
    iso_attrs = {"low_load_factor": iso["low_load_factor"], "load_per_width_N_per_mm": iso["load_per_width"],
                 "K_A": 1.0}
    coords = {"driven_tooth": variable("driven_tooth", np.arange(z2))}
    data = {
        "mesh_stiffness": variable("mesh_stiffness", k,
                                   comment=f"dF/dTE {load_note}, the pair linearised as for the modes "
                                       "(solver.mbs.mesh_stiffness): the driver hub prescribed, every tooth at its "
                                       f"static response; F = driven torque / rb2; {both}"),
        "mesh_stiffness_mean": variable("mesh_stiffness_mean", mean, comment=both),
        "mesh_stiffness_p2p": variable("mesh_stiffness_p2p", p2p, comment=both),
        "c_prime": variable("c_prime", c1,
                            comment="each loaded pair's share of the tangent mesh stiffness (the pair as if alone in mesh), "
                                f"its largest value over the STE angles, over the face width {width * 1e3:g} mm; {both}"),
        "c_gamma_alpha": variable("c_gamma_alpha", cga, comment=f"mesh_stiffness_mean / b; {both}"),
        "mesh_stiffness_mesh_mean": variable("mesh_stiffness_mesh_mean", mean_m, **windup_attrs),
        "c_prime_mesh": variable("c_prime_mesh", c1_m, **windup_attrs),
        "c_gamma_alpha_mesh": variable("c_gamma_alpha_mesh", cga_m, **windup_attrs),
        "c_prime_iso6336": variable("c_prime_iso6336", iso["c_prime"], **iso_attrs,
                                    value_without_low_load_factor=iso["c_prime_full_load"],
                                    value_without_C_M_and_low_load_factor=iso["c_prime_elastic"],
                                    comment=f"c'_th C_M C_R C_B (F_t/b / 100 N/mm)^0.25 (the low-load factor "
                                        f"{iso['low_load_factor']:.4f} at F_t/b = {iso['load_per_width']:.4g} N/mm, "
                                        f"1 from 100 N/mm; F_t = |T| / r2 at the reference circle, K_A = 1): "
                                        f"C_M 0.8, C_R {iso['c_r']:.4f} (mean of the two webs; holes are not in the "
                                        "standard), C_B of the basic rack, no profile shift; the mesh alone, no body "
                                        "wind-up from the bore: compare with c_prime_mesh. C_M (measured over "
                                        "theoretical) and the low-load factor are the standard's corrections for real, "
                                        "measured gears; the model's elastic pair of perfect involutes compares with "
                                        "value_without_C_M_and_low_load_factor (docs/outputs.md); the standard states "
                                        "a spread of about 20 %"),
        "c_gamma_alpha_iso6336": variable("c_gamma_alpha_iso6336", iso["c_gamma_alpha"], **iso_attrs,
                                          value_without_low_load_factor=iso["c_gamma_alpha_full_load"],
                                          value_without_C_M_and_low_load_factor=iso["c_gamma_alpha_elastic"],
                                          comment=f"c_prime_iso6336 (0.75 eps_alpha + 0.25), eps_alpha = {eps:.4f} "
                                              "(geometric); compare with c_gamma_alpha_mesh"),
        "loaded_contact_ratio": variable("loaded_contact_ratio", eps_loaded,
                                         comment=f"{load_note}, over whole mesh periods of the STE, tip-corner contacts "
                                             f"included; the geometric transverse contact ratio is {eps:.4f}"),
        "ste_tooth_force_gear2": variable("ste_tooth_force_gear2", states.tooth_force[:, z1:], comment=load_note),
        "ste_mate_tooth": variable("ste_mate_tooth", _mates(states.mate, z1)),
    }
    force = load / model.base_radii[1]
    try:
        alone = units.stiffness_n_per_um(pitch_point_stiffness(model, force, (0.0, 0.0) if model.coupled else cw))
    except ValueError:      # a plain spring stiffer than its body's wind-up alone: it cannot hold it
        alone = np.full(z1 + z2, np.nan)
    bore = 1.0 / (1.0 / alone + np.repeat([c * units.UM_PER_M for c in cw], (z1, z2)))
    spring = "k_phi n_k phi^(n_k-1) / h^2, h the lever arm of the line of action about the pivot"
    for name, kt, what in (
            ("tooth_stiffness_pitch", alone,
             f"the tooth alone, its body rigid below the rim: {spring}"
             + (", in series with the local compliance c_loc at the pitch point" if model.teeth_coupled else "")
             + ("" if model.coupled else ", with the body wind-up c_w the plain model's spring holds taken out: "
                "1/(1/k - c_w)")),
            ("tooth_stiffness_pitch_bore", bore,
             "tooth_stiffness_pitch in series with its body's wind-up from the bore c_w (body_windup_um_per_N): what "
             "a tooth of the bore-clamped body reads" + ("" if model.coupled else " (the plain model's spring itself)"))):
        K = np.full((2, max(z1, z2)), np.nan)
        K[0, :z1], K[1, :z2] = kt[:z1], kt[z1:]
        data[name] = variable(name, K, comment=f"the tangent under the whole load {torque:g} N·m / rb at the pitch point; "
                                               f"{what} (solver.mbs.mesh_stiffness.pitch_point_stiffness)",
                              body_windup_um_per_N=np.array(cw_um))
    return coords, data


def _stiffness_scalars(k: np.ndarray, pair: np.ndarray, sel: np.ndarray, width: float) -> tuple:
    """(mean [N/um], peak-to-peak [N/um], c' [N/(mm·um)], c_gamma_alpha [N/(mm·um)]) of a mesh
    stiffness ``k`` [N/um] over the angles ``sel`` and its pair shares ``pair`` [N/m]."""
    ok = sel & np.isfinite(k)
    mean = float(np.mean(k[ok])) if ok.any() else float("nan")
    p2p = float(np.ptp(k[ok])) if ok.any() else float("nan")
    shares = pair[np.isfinite(k)]
    c1 = float(units.stiffness_per_width(np.nanmax(shares), width)) if shares.size else float("nan")
    return mean, p2p, c1, float(units.stiffness_per_width(mean / units.UM, width))


def _mates(mate: np.ndarray, z1: int) -> np.ndarray:
    """The driven tooth each driver tooth meets most often over the angles (-1: never)."""
    out = np.full(z1, -1, dtype=np.int32)
    for a in range(z1):
        m = mate[:, a]
        m = m[m >= 0]
        if m.size:
            out[a] = int(np.bincount(m).argmax())
    return out


# a load below this [N·m] gives no static tooth force to divide by: K_v is undefined
NO_LOAD_TORQUE = 1e-9


def steady_window(scene, start: float, to_load_change: bool = True) -> tuple[float, float, str | None]:
    """(end [s], mesh periods covered, reason or None) of the steady part of a dynamic run
    from ``start`` [s] that its dynamic factor K_v and DTE RMS / peak-to-peak are taken over:
    to the end of the run, or for K_v (``to_load_change``) with a load change to its start (the
    forces are then compared at the torque of `static_force_max`, dynamic.torque). The reason, when there is one, says
    why the window cannot support them: no static load, the driver standing still, or fewer
    than one mesh period (every tooth pair's whole passage) after the ramp."""
    d = scene.dynamic
    z1 = scene.gear1.teeth
    end = d.duration if d.torque_change_time <= 0 or not to_load_change else min(d.duration, d.torque_change_time)
    speed = d.speed_end if d.speed_end > 0 else d.speed
    periods = max(end - start, 0.0) * speed * z1 / (2 * math.pi)
    if d.speed_end <= 0 and d.speed <= 0:
        return end, periods, "the driver stands still (dynamic.speed = 0): no mesh period to take the forces over"
    if periods < 1.0 - 1e-9:
        load = f" up to the load change at {d.torque_change_time:g} s" if end < d.duration else ""
        return end, periods, (f"the steady part after the ramp ({start:g} to {end:g} s{load}) covers {periods:.3g} of a "
                              f"mesh period ({2 * math.pi / (z1 * speed) if speed > 0 else math.inf:.3g} s at "
                              f"{speed:g} rad/s): lengthen dynamic.duration")
    return end, periods, None


def dynamic_factor_reason(scene, start: float) -> str | None:
    """Why the dynamic factor K_v of the scene's dynamic run from ``start`` [s] is undefined
    (archived as NaN with this reason), or None: no static load to divide by, or a steady
    part that misses a mesh period (`steady_window`)."""
    if abs(scene.dynamic.torque) < NO_LOAD_TORQUE:
        return f"no static load (dynamic.torque = {scene.dynamic.torque:g} N·m): no static tooth force to divide by"
    return steady_window(scene, start)[2]


def dynamic_force_variables(res, start: float, z1: int, z2: int, static_force_max: float,
                            end: float = math.inf, undefined: str | None = None) -> tuple[dict, dict]:
    """The loaded contacts of a dynamic run over ``time`` (slots: teeth, force), each tooth's
    largest force from ``start`` to ``end`` [s] on both gears, and the dynamic factor K_v: the
    largest dynamic tooth force over the largest static one (``static_force_max`` [N], at the
    same torque over a whole revolution, `study.run.static_force_max`); NaN with the reason
    ``undefined`` in its comment where the run cannot support it (`dynamic_factor_reason`)."""
    from solver.mbs.kernels import layout as L
    c = res.contacts
    if c is None:
        return {}, {}
    t1 = c[:, :, L.OC_TOOTH1].astype(np.int32)
    t2 = c[:, :, L.OC_TOOTH2].astype(np.int32)
    f = c[:, :, L.OC_FORCE]
    coords = {"contact_slot": variable("contact_slot", np.arange(c.shape[1]))}
    data = {
        "dte_contact_tooth1": variable("dte_contact_tooth1", t1),
        "dte_contact_tooth2": variable("dte_contact_tooth2", t2),
        "dte_contact_force": variable("dte_contact_force", f),
    }
    sel = (res.time >= start) & (res.time <= end + 1e-12)
    fmax = np.full((2, max(z1, z2)), np.nan)
    for g, (t, z) in enumerate(((t1, z1), (t2, z2))):
        per = np.zeros((int(sel.sum()), z))
        rows = np.nonzero(sel)[0]
        for s in range(c.shape[1]):
            ok = t[rows, s] >= 0
            np.add.at(per, (np.nonzero(ok)[0], t[rows, s][ok]), f[rows, s][ok])
        fmax[g, :z] = per.max(axis=0) if per.shape[0] else np.nan
    until = f" to {end:g} s" if math.isfinite(end) else ""
    data["dte_tooth_force_max"] = variable("dte_tooth_force_max", fmax,
                                           comment=f"over the steady part from {start:g} s{until} (output instants)",
                                           start_s=float(start))
    fdyn = float(np.nanmax(fmax)) if np.isfinite(fmax).any() else float("nan")
    if undefined is None and not static_force_max > 0:
        undefined = "no static tooth force to divide by (the statics over a revolution did not converge)"
    if undefined is not None:
        data["dynamic_factor"] = variable("dynamic_factor", float("nan"), comment=f"undefined: {undefined}")
    else:
        data["dynamic_factor"] = variable("dynamic_factor", fdyn / static_force_max,
                                          comment=f"largest dynamic tooth force {fdyn:.1f} N from {start:g}{until or ' s on'}, "
                                              f"largest static {static_force_max:.1f} N (static, the same torque, over a "
                                              "whole revolution)")
    return coords, data

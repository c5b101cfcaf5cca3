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


def iso_stiffness(scene, contact_ratio: float) -> tuple[float, float, float]:
    """(c', c_gamma_alpha [N/(mm·um)], C_R [1]) of the scene's pair by ISO 6336-1 Method B:
    no profile shift, C_M 0.8, the basic-rack factor of gear 1, the gear-blank factor C_R of
    each gear's web (mean of the two; the standard has no holes), c_gamma_alpha = c'
    (0.75 eps_alpha + 0.25) with the geometric transverse contact ratio eps_alpha."""
    g1, g2 = scene.gear1, scene.gear2
    c_r = 0.5 * sum(iso6336.blank_factor(g.body.web_thickness, g.face_width, g.body.rim_height, g.module)
                    for g in (g1, g2))
    c1 = iso6336.single_stiffness(g1.teeth, g2.teeth, g1.dedendum, g1.pressure_angle, c_r)
    return c1, c1 * (0.75 * contact_ratio + 0.25), c_r


def whole_periods(angle_deg, z1: int) -> np.ndarray:
    """Mask of the angles within the largest whole number of mesh periods (360/z1 deg) from
    the first angle (all of them when the range is shorter than one period)."""
    a = np.asarray(angle_deg, float)
    period = 360.0 / z1
    span = a[-1] - a[0] + (a[1] - a[0] if a.size > 1 else 0.0)
    n = math.floor(span / period + 1e-9)
    return a < a[0] + n * period - 1e-9 if n >= 1 else np.ones(a.size, bool)


def mesh_variables(states, model, scene, torque: float) -> tuple[dict, dict]:
    """Archive variables of `solver.mbs.mesh_stiffness.mesh_states` over the STE angles
    (``states`` at ``torque`` [N·m]) for the pair ``model`` of ``scene``."""
    from solver.mbs.mesh_stiffness import pitch_point_stiffness
    z1, z2 = model.teeth
    angle = np.degrees(states.angle)
    width = min(g.spec.face_width for g in model.geometry)
    k = units.stiffness_n_per_um(states.stiffness)
    sel = whole_periods(angle, z1) & np.isfinite(k)
    mean = float(np.mean(k[sel])) if sel.any() else float("nan")
    p2p = float(np.ptp(k[sel])) if sel.any() else float("nan")
    loaded = states.loaded_pairs()
    eps_loaded = float(np.mean(loaded[sel & states.converged])) if (sel & states.converged).any() else float("nan")
    c1 = float(units.stiffness_per_width(np.nanmax(states.pair_stiffness), width)) if states.converged.any() else float("nan")
    cga = float(units.stiffness_per_width(mean / units.UM, width))
    eps = model.pair.contact_ratio
    c1_iso, cga_iso, c_r = iso_stiffness(scene, eps)
    load_note = f"at static equilibrium under {torque:g} N·m"
    coords = {"driven_tooth": variable("driven_tooth", np.arange(z2))}
    data = {
        "mesh_stiffness": variable("mesh_stiffness", k,
                                   comment=f"dF/dTE {load_note}, the pair linearised as for the modes "
                                       "(solver.mbs.mesh_stiffness): the driver hub prescribed, every tooth at its "
                                       "static response; F = driven torque / rb2"),
        "mesh_stiffness_mean": variable("mesh_stiffness_mean", mean),
        "mesh_stiffness_p2p": variable("mesh_stiffness_p2p", p2p),
        "c_prime": variable("c_prime", c1,
                            comment="each loaded pair's share of the tangent mesh stiffness (the pair as if alone in mesh), "
                                f"its largest value over the STE angles, over the face width {width * 1e3:g} mm"),
        "c_gamma_alpha": variable("c_gamma_alpha", cga),
        "c_prime_iso6336": variable("c_prime_iso6336", c1_iso,
                                    comment=f"C_M 0.8, C_R {c_r:.4f} (mean of the two webs; holes are not in the standard), "
                                        "C_B of the basic rack, no profile shift; the standard states a spread of about 20 %"),
        "c_gamma_alpha_iso6336": variable("c_gamma_alpha_iso6336", cga_iso,
                                          comment=f"c' (0.75 eps_alpha + 0.25), eps_alpha = {eps:.4f} (geometric)"),
        "loaded_contact_ratio": variable("loaded_contact_ratio", eps_loaded,
                                         comment=f"{load_note}, over whole mesh periods of the STE, tip-corner contacts "
                                             f"included; the geometric transverse contact ratio is {eps:.4f}"),
        "ste_tooth_force_gear2": variable("ste_tooth_force_gear2", states.tooth_force[:, z1:], comment=load_note),
        "ste_mate_tooth": variable("ste_mate_tooth", _mates(states.mate, z1)),
    }
    kt = units.stiffness_n_per_um(pitch_point_stiffness(model, torque / model.base_radii[1]))
    zmax = max(z1, z2)
    K = np.full((2, zmax), np.nan)
    K[0, :z1], K[1, :z2] = kt[:z1], kt[z1:]
    data["tooth_stiffness_pitch"] = variable("tooth_stiffness_pitch", K,
                                             comment=f"tangent of the tooth's spring under the whole load {torque:g} N·m / rb "
                                                 "at the pitch point, n_k k_phi phi^(n_k-1) / h^2, h the lever arm of "
                                                 "the line of action about the pivot (solver.mbs.mesh_stiffness)")
    return coords, data


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

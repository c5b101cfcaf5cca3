"""What the mesh does under load, as archive variables: tangent mesh stiffness over the STE
angle with ISO 6336-1 Method B beside it, each tooth's stiffness at the pitch point, the
loaded contact ratio, the static tooth forces of both gears and which teeth meet, and the
dynamic tooth forces with the dynamic factor.

Units as gear engineers quote them: stiffness in N/um (per face width N/(mm·um)), forces in N.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver import units
from study.archive.schema import variable


def whole_periods(angle_deg, z1: int) -> np.ndarray:
    """Mask of the angles within the largest whole number of mesh periods (360/z1 deg) from
    the first angle (all of them when the range is shorter than one period)."""
    a = np.asarray(angle_deg, float)
    period = 360.0 / z1
    span = a[-1] - a[0] + (a[1] - a[0] if a.size > 1 else 0.0)
    n = math.floor(span / period + 1e-9)
    return a < a[0] + n * period - 1e-9 if n >= 1 else np.ones(a.size, bool)


@dataclass(frozen=True)
class MeshNumbers:
    """What the mesh stage computed beside the linearised states (`study.stages.mesh_stage`)."""
    torque: float               # the static torque [N·m] the states are at
    plain_windup: bool          # the plain model's springs hold the bodies' wind-up (taken out for the mesh alone)
    windup: tuple               # (gear 1, gear 2) body wind-up compliance from the bore [m/N]
    alone: np.ndarray           # each tooth's tangent stiffness at the pitch point, its body rigid [N/um]
    iso: dict                   # ISO 6336-1 Method B (`study.stages.iso_stiffness`)


def mesh_variables(states, model, numbers: MeshNumbers) -> tuple[dict, dict]:
    """Archive variables of `solver.mbs.mesh_stiffness.mesh_states` over the STE angles
    (``states`` at ``numbers.torque`` [N·m]) for the pair ``model``: the pair's stiffness
    (at the hubs, both bodies' wind-up from the bore in it), the mesh alone (without it) and
    ISO 6336-1 Method B beside them (`MeshNumbers`)."""
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
    torque, iso, cw = numbers.torque, numbers.iso, numbers.windup
    cw_um = [c * units.UM_PER_M for c in cw]
    load_note = f"at static equilibrium under {torque:g} N·m"
    both = "includes both bodies' wind-up from the bore (the hubs' TE)"
    if model.coupled:
        how = ("the bodies rigid below the rim: the tangent matrix of mesh_stiffness without the body springs "
               "(hub -> rim), condensed onto the driven rim with the driver rim prescribed; the body springs are in "
               "series with it: 1/k_pair = 1/k_mesh + rb1^2/k_body1 + rb2^2/k_body2 wherever the contacts act along "
               "the line of action (a tip corner's other lever aside)")
    elif numbers.plain_windup:
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
    data.update(pitch_variables(model, numbers, cw_um))
    return coords, data


def pitch_variables(model, numbers: MeshNumbers, cw_um: list) -> dict:
    """Each tooth's tangent stiffness at the pitch point, alone (its body rigid below the rim)
    and with its body's wind-up from the bore ``cw_um`` [um/N] in series, over (gear, tooth)."""
    z1, z2 = model.teeth
    torque = numbers.torque
    data = {}
    alone = numbers.alone
    bore = 1.0 / (1.0 / alone + np.repeat(cw_um, (z1, z2)))
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
    return data


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


@dataclass(frozen=True)
class ToothForces:
    """The loaded contacts of a dynamic run and what the dynamic stage made of them
    (`study.stages.tooth_forces`)."""
    tooth1: np.ndarray          # (time, slot) driver tooth of each loaded contact (-1: none)
    tooth2: np.ndarray          # (time, slot) driven tooth
    force: np.ndarray           # (time, slot) contact force [N]
    start: float                # the steady part's start [s]
    end: float                  # and end [s] (inf: to the end of the run)
    force_max: np.ndarray       # (gear, tooth) each tooth's largest force over it [N]
    dynamic_max: float          # the largest of them [N]
    static_max: float           # the largest static tooth force at the same torque over a revolution [N]
    dynamic_factor: float       # K_v [1] (NaN: undefined)
    undefined: str | None       # why K_v is undefined, or None


def dynamic_force_variables(tf: ToothForces) -> tuple[dict, dict]:
    """The loaded contacts of a dynamic run over ``time`` (slots: teeth, force), each tooth's
    largest force over the steady part on both gears, and the dynamic factor K_v: the
    largest dynamic tooth force over the largest static one (at the same torque over a whole
    revolution, `study.stages.static_force_max`); NaN with the reason in its comment where the
    run cannot support it (`study.stages.dynamic_factor_reason`)."""
    coords = {"contact_slot": variable("contact_slot", np.arange(tf.force.shape[1]))}
    data = {
        "dte_contact_tooth1": variable("dte_contact_tooth1", tf.tooth1),
        "dte_contact_tooth2": variable("dte_contact_tooth2", tf.tooth2),
        "dte_contact_force": variable("dte_contact_force", tf.force),
    }
    until = f" to {tf.end:g} s" if math.isfinite(tf.end) else ""
    data["dte_tooth_force_max"] = variable("dte_tooth_force_max", tf.force_max,
                                           comment=f"over the steady part from {tf.start:g} s{until} (output instants)",
                                           start_s=float(tf.start))
    if tf.undefined is not None:
        data["dynamic_factor"] = variable("dynamic_factor", float("nan"), comment=f"undefined: {tf.undefined}")
    else:
        data["dynamic_factor"] = variable("dynamic_factor", tf.dynamic_factor,
                                          comment=f"largest dynamic tooth force {tf.dynamic_max:.1f} N from "
                                              f"{tf.start:g}{until or ' s on'}, largest static {tf.static_max:.1f} N "
                                              "(static, the same torque, over a whole revolution)")
    return coords, data

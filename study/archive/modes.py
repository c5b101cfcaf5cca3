"""Modes of the loaded pair, their damping, the free decay and the critical speeds -> run
archive variables (the modal analysis `solver.mbs.modes` and the free decay `solver.mbs.ringdown`
as the run's modes stage, `study.stages.modes_stage`, made them).

  mode_frequency(mode, mesh_position)   natural frequency [Hz]
  mode_damping(mode, mesh_position)     damping ratio [1] (mode 0: the mesh mode)
  mode_kind(mode)                       'mesh', 'tooth gear1', 'tooth gear2' (largest share of kinetic energy)
  critical_speed(excitation, mode)      driver speed [rad/s] at which an excitation order meets the
                                        mode's mean frequency; excitation: 1Z..5Z, N, 2N, kZ-N, kZ+N
Attributes: the damping coefficients the run has (scene units), the mesh mode's frequency and
damping ratio from the modal analysis (mean over the mesh period, and at the mesh position
whose ratio is nearest that mean) and from the simulated free decay there.
"""
from __future__ import annotations

import math

import numpy as np

from solver import units
from solver.mbs.kernels import layout as L
from solver.mbs.model import Model
from study.archive.schema import MODAL_SOURCE, variable


def excitation_orders(z2: int, holes: int) -> list[tuple[str, float]]:
    """(label, order of the driven gear's rotation) of the Campbell lines: kZ (k = 1..5), and
    with holes N, 2N and kZ +- N."""
    out = [(f"{k}Z", float(k * z2)) for k in range(1, 6)]
    if holes:
        out += [("N", float(holes)), ("2N", 2.0 * holes)]
        out += [(f"{k}Z{s}N", float(k * z2 + (holes if s == "+" else -holes))) for k in range(1, 6) for s in "-+"]
    return out


def critical_speeds(freq_hz: np.ndarray, orders: np.ndarray, z1: int, z2: int) -> np.ndarray:
    """Driver speeds [rad/s] (order, mode) at which order x driven rotation frequency equals each
    mode's frequency: omega1 = 2 pi f z2 / (z1 order)."""
    return 2 * math.pi * freq_hz[None, :] * z2 / (z1 * orders[:, None])


def modal_variables(md, decay, model: Model, torque: float, holes: int) -> tuple[dict, dict, dict]:
    """Coordinates, variables and attributes (see the module) of the modal analysis ``md``
    (`solver.mbs.modes.Modes`) of ``model`` under ``torque`` [N·m] on a driven gear with
    ``holes`` openings, and of the free decay ``decay``: (mesh position index, its
    `solver.mbs.ringdown.RingDown`), or None without one."""
    z1, z2 = model.teeth
    exc = excitation_orders(z2, holes)
    coords = {
        "mode": variable("mode", np.arange(md.frequency.shape[0])),
        "mode_kind": variable("mode_kind", np.array(md.kind, dtype=object)),
        "mesh_position": variable("mesh_position", np.degrees(md.position)),
        "excitation": variable("excitation", np.array([e[0] for e in exc], dtype=object)),
        "excitation_order": variable("excitation_order", np.array([e[1] for e in exc])),
    }
    src = MODAL_SOURCE.format(torque=torque)
    fmean = np.nanmean(md.frequency, axis=1)
    data = {
        "mode_frequency": variable("mode_frequency", md.frequency, source=src),
        "mode_damping": variable("mode_damping", md.damping, source=src),
        "critical_speed": variable("critical_speed", critical_speeds(fmean, coords["excitation_order"].values, z1, z2)),
    }
    attrs = {
        "mesh_mode_frequency_hz": float(fmean[0]),
        "mesh_mode_damping": float(np.nanmean(md.damping[0])),
        "mesh_mode_damping_range": np.array([np.nanmin(md.damping[0]), np.nanmax(md.damping[0])]),
        "modal_torque_N_m": float(torque),
        "c_con_used": float(model.law_par[L.C_CON] / units.contact_damping_to_si(1.0, model.law_par[L.M2], model.law_par[L.M3])),
        "c_phi_used_N_mm_s_rad": model.gear_par[:, L.C_PHI] / units.spring_damping_to_si(1.0),
    }
    if decay is not None:
        j, rd = decay
        attrs.update(mesh_mode_frequency_decay_hz=rd.frequency, mesh_mode_damping_decay=rd.damping,
                     mesh_mode_damping_at_decay=float(md.damping[0, j]),
                     mesh_mode_decay_angle_deg=float(np.degrees(md.position[j])),
                     mesh_mode_decay_method="free decay after a 10 % load step with the driver held at "
                                            "mesh_mode_decay_angle_deg, the mesh position whose modal ratio is "
                                            "nearest the mean (solver.mbs.ringdown): damped cosine fitted to TE")
    return coords, data, attrs

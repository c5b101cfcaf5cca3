"""The one place where engineering units meet the internal SI system.

Inside `solver` every quantity is SI: m, kg, s, N, rad (N·m, N/m, kg·m²).
Scene files, command lines and reports use the units gear engineers use: mm, deg, N·m,
rad/s, N/mm, N·mm/rad, um for transmission error. Convert only with these factors.

Power laws need care: a law F = k * delta**m with k in N/mm**m and delta in mm becomes
F = k_si * delta_si**m with k_si = k * MM_PER_M**m (see `power_law_to_si`).
"""
from __future__ import annotations

import math

MM = 1e-3          # m per mm
UM = 1e-6          # m per um
MM_PER_M = 1e3
UM_PER_M = 1e6
DEG = math.pi / 180.0  # rad per degree
NMM = 1e-3         # N·m per N·mm
MPA = 1e6          # Pa per MPa (N/mm²)


def power_law_to_si(k_mm: float, exponent_mm: float, scale_out: float = 1.0) -> float:
    """Coefficient of ``y = k * x**e`` with x in mm converted to x in m.

    ``scale_out`` converts the output (1 for N, NMM for N·mm -> N·m).
    """
    return k_mm * scale_out * MM_PER_M ** exponent_mm


def contact_stiffness_to_si(k_con_n_per_mm_m1: float, m1: float) -> float:
    """k_con [N/mm^m1] -> [N/m^m1] for F = k_con * delta**m1."""
    return power_law_to_si(k_con_n_per_mm_m1, m1)


def contact_damping_to_si(c_con: float, m2: float, m3: float) -> float:
    """c_con [N/((mm/s)^m2 mm^m3)] -> SI for F = c_con * |v|**m2 * delta**m3."""
    return c_con * MM_PER_M ** (m2 + m3)


def spring_stiffness_to_si(k_phi_nmm: float) -> float:
    """k_phi [N·mm/rad^n] -> [N·m/rad^n]; the angle is already in rad."""
    return k_phi_nmm * NMM


def spring_damping_to_si(c_phi_nmm: float) -> float:
    """c_phi [N·mm/(rad/s)^n_c] -> [N·m/(rad/s)^n_c]."""
    return c_phi_nmm * NMM


def stiffness_n_per_um(k_n_per_m):
    """Stiffness N/m -> N/um (a mesh or tooth stiffness as gear engineers quote it)."""
    return k_n_per_m * UM


def stiffness_per_width(k_n_per_m, width_m):
    """Stiffness N/m over a face width [m] -> N/(mm·um) (ISO 6336-1's c' and c_gamma_alpha)."""
    return k_n_per_m * UM / (width_m * MM_PER_M)

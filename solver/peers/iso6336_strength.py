"""ISO 6336-3:2019 and AGMA 2001-D04 rim and root bending factors of a spur gear, kept apart
from the stiffness peer (`solver.peers.iso6336`, whose Y_F and Y_S it uses).

Backup ratio m_B = s_R / h_t: the rim thickness under the root s_R over the tooth height h_t.
Rim thickness factor (ISO 6336-3 Y_B, AGMA 2001 K_B: the same curve)

    Y_B = 1.6 ln(2.242 / m_B)   for 0.5 <= m_B < 1.2,      Y_B = 1   for m_B >= 1.2;

below m_B = 0.5 the standards give no value (ISO: such rims should be avoided; AGMA: not
recommended): `rim_thickness_factor` extrapolates the curve and says so.

Nominal root stress at the outer point of single tooth contact (Method B):

    sigma_F0 = F_t / (b m_n) Y_F Y_S Y_B       (Y_beta = Y_DT = 1 for a spur gear, eps_alpha < 2).

Crack path of thin-rim gears (Lewicki & Ballarini 1997, J. Mech. Des. 119, tests and FE crack
propagation): m_B 3.3 and 1.0 tooth fracture, 0.5 tooth or rim fracture depending on where
the crack starts, 0.3 rim fracture: `LEWICKI_TOOTH`, `LEWICKI_RIM`.
"""
from __future__ import annotations

import math

from solver.peers import iso6336

RIM_FACTOR_LOW = 0.5      # smallest m_B the standards give Y_B for
_TOL = 1e-9               # relative: an m_B from lengths in metres, 0.5 within rounding, is 0.5
RIM_FACTOR_ONE = 1.2      # m_B from which Y_B = 1
LEWICKI_TOOTH = 1.0       # m_B at and above which the tests and FE give tooth fracture
LEWICKI_RIM = 0.5         # m_B below which they give rim fracture (0.5: either; 0.3: rim)


def backup_ratio(rim_thickness: float, tooth_height: float) -> float:
    """m_B = s_R / h_t [1] (lengths in one unit)."""
    if not tooth_height > 0:
        raise ValueError(f"tooth height must be > 0, got {tooth_height}")
    return rim_thickness / tooth_height


def rim_thickness_factor(m_b: float) -> tuple[float, bool]:
    """(Y_B = K_B [1], within the standard) of backup ratio ``m_b``: 1.6 ln(2.242/m_B) below
    1.2, 1 above; below 0.5 the curve extrapolated and False; NaN for m_B <= 0."""
    if not m_b > 0:
        return float("nan"), False
    if m_b >= RIM_FACTOR_ONE * (1 - _TOL):
        return 1.0, True
    return 1.6 * math.log(2.242 / m_b), m_b >= RIM_FACTOR_LOW * (1 - _TOL)


def single_contact_roll(tip_radius: float, base_radius: float, base_pitch: float, contact_ratio: float) -> float:
    """Roll parameter [rad] of the outer point of single tooth contact (HPSTC) of a gear:
    sqrt(ra^2 - rb^2) - p_b (eps_alpha - 1), over rb (`solver.peers.iso6336.single_contact_diameter`)."""
    return (math.sqrt(tip_radius**2 - base_radius**2) - base_pitch * (contact_ratio - 1.0)) / base_radius


def inner_single_contact_roll(tip_radius: float, base_radius: float, base_pitch: float) -> float:
    """Roll parameter [rad] of the inner point of single tooth contact (LPSTC) of a gear, one
    base pitch below its tip contact: (sqrt(ra^2 - rb^2) - p_b) / rb."""
    return (math.sqrt(tip_radius**2 - base_radius**2) - base_pitch) / base_radius


def nominal_root_stress(tangential_force: float, face_width: float, module: float, y_f: float, y_s: float,
                        y_b: float = 1.0) -> float:
    """sigma_F0 = F_t / (b m) Y_F Y_S Y_B [Pa with N and m] (`solver.peers.iso6336.nominal_root_stress` times Y_B)."""
    return iso6336.nominal_root_stress(tangential_force, face_width, module, y_f, y_s) * y_b


def crack_path(m_b: float) -> str:
    """What Lewicki & Ballarini's tests and FE give at backup ratio ``m_b``: 'tooth' (m_B >= 1),
    'rim' (m_B < 0.5) or 'mixed' (between: tooth or rim, by where the crack starts)."""
    if m_b >= LEWICKI_TOOTH * (1 - _TOL):
        return "tooth"
    return "rim" if m_b < LEWICKI_RIM * (1 - _TOL) else "mixed"

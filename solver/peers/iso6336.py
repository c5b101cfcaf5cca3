"""ISO 6336-1:2019 Method B tooth stiffness of a spur pair (independent check of the FE springs).

Single stiffness c' [N/(mm·um)]: the maximum stiffness of one tooth pair per unit face width,
    c' = c'_th * C_M * C_R * C_B * cos(beta),  c'_th = 1 / q',
q' from the standard polynomial in the virtual tooth numbers and profile shift (x = 0 here),
C_M = 0.8 (theoretical-to-measured correction), C_B the basic-rack factor and C_R the gear-blank
factor of a webbed body, C_R = 1 + ln(b_s/b) / (5 exp(s_R / (5 m))) (b_s web thickness, s_R rim
thickness), clipped to the standard's validity range 0.2 <= b_s/b <= 1.2, s_R/m >= 1.
The standard quotes a spread of about +-20 % against measurements and FE.
"""
from __future__ import annotations

import math

Q_COEF = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188, 0.00529, 0.00182)
C_M = 0.8


def q_prime(z1: float, z2: float, x1: float = 0.0, x2: float = 0.0) -> float:
    """Minimum flexibility q' [mm·um/N] of a pair (spur: virtual = actual tooth numbers)."""
    c = Q_COEF
    return c[0] + c[1] / z1 + c[2] / z2 + c[3] * x1 + c[4] * x1 / z1 + c[5] * x2 + c[6] * x2 / z2 + c[7] * x1**2 + c[8] * x2**2


def basic_rack_factor(dedendum_coef: float, pressure_angle_deg: float) -> float:
    """C_B for one gear's basic rack (dedendum h_fP/m, pressure angle alpha_Pn)."""
    return (1 + 0.5 * (1.2 - dedendum_coef)) * (1 - 0.02 * (20.0 - pressure_angle_deg))


def blank_factor(web_thickness: float, face_width: float, rim_thickness: float, module: float) -> float:
    """C_R of a webbed gear blank (1 for a solid blank). Lengths in any one unit."""
    ratio = min(max(web_thickness / face_width, 0.2), 1.2)
    if ratio >= 1.0:
        return 1.0
    s = max(rim_thickness / module, 1.0)
    return 1 + math.log(ratio) / (5 * math.exp(s / 5))


def single_stiffness(z1: int, z2: int, dedendum_coef: float = 1.25, pressure_angle_deg: float = 20.0,
                     c_r: float = 1.0) -> float:
    """c' [N/(mm·um)] of a spur pair without profile shift."""
    return C_M * c_r * basic_rack_factor(dedendum_coef, pressure_angle_deg) / q_prime(z1, z2)

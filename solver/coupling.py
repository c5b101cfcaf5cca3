"""Foundation coupling of the pseudo-rigid model: a body-torsion spring per gear.

The per-tooth spring fitted to a bore-clamped FE body holds the wind-up of the whole body,
which all loaded teeth share. Put into every tooth spring, it is counted once per tooth, so
in double contact the body is effectively twice as stiff as it is. The body-torsion model
splits it off: hub -> body torsion spring k_body -> rigid rim -> tooth springs k_tooth.

Identification from the FE influence coefficients at the pitch point (`solver.ltca`,
displacement along the line of action read at the tooth centreline, [m/N]):

* c_total[a]: a tooth's own compliance (the plain model's spring: k_fe = lever**2 / c_total);
* c_adjacent[a]: the mean compliance of tooth a under a load on its two neighbours. In
  double contact the two loaded teeth are neighbours, so this is the compliance they share;
  c_body = mean over the teeth of c_adjacent, k_body = rb**2 / c_body [N·m/rad];
* k_tooth[a] = lever**2 / (c_total[a] - c_body) [N·m/rad]: the tooth spring without the
  body wind-up.

The body wind-up is a rotation about the gear centre (lever rb whatever the contact point),
the tooth's own deflection a rotation about a point low in the tooth. So once the body part is
split off, the tooth's pivot is refitted to the remaining compliance along the profile
(`solver.identify.fit_pivot`; about 1 mm below the root circle for Table 1): the fit's
stiffness is tooth 0's spring, the other teeth scale it by their pitch-point tooth compliance.
Against the FE reference (Table 1, 50 N·m) this halves the STE error of a root-circle pivot.

With k_body -> infinity and k_tooth = k_fe the coupled model is the plain one.
Units: SI.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BodyTorsionFit:
    k_body: float            # body torsion stiffness hub -> rim [N·m/rad]
    c_body: float            # the same as a compliance along the line of action [m/N]
    k_tooth: np.ndarray      # (Z,) tooth springs without the body wind-up [N·m/rad]
    k_total: np.ndarray      # (Z,) tooth springs with it (the plain model's FE springs) [N·m/rad]
    c_total: np.ndarray      # (Z,) own compliance at the pitch point [m/N]
    c_adjacent: np.ndarray   # (Z,) compliance under the neighbours' loads [m/N]
    pivot_radius: float      # tooth pivot the levers are taken about [m]


def body_torsion_fit(c_total, c_adjacent, lever: float, base_radius: float,
                     pivot_radius: float = float("nan"), k_profile: float | None = None) -> BodyTorsionFit:
    """Body and tooth springs from the own and adjacent pitch-point compliances [m/N] of every
    tooth, the pitch-point load lever about the tooth pivot [m] (at ``pivot_radius`` [m]) and the
    base radius [m]. ``k_profile`` [N·m/rad]: tooth 0's spring from the fit along its profile;
    the other teeth then scale it by their pitch-point tooth compliance (else each tooth's
    spring matches its pitch-point compliance exactly)."""
    c_total = np.asarray(c_total, float)
    c_adjacent = np.asarray(c_adjacent, float)
    if c_total.shape != c_adjacent.shape or c_total.ndim != 1:
        raise ValueError("c_total and c_adjacent: need one value per tooth")
    if not np.all(c_total > 0):
        raise ValueError("c_total: tooth compliance must be positive")
    c_body = float(np.mean(c_adjacent))
    if not 0 < c_body < c_total.min():
        raise ValueError(f"body compliance {c_body:.4g} m/N is not between 0 and the smallest tooth compliance {c_total.min():.4g} m/N")
    c_tooth = c_total - c_body
    k_tooth = lever**2 / c_tooth if k_profile is None else k_profile * c_tooth[0] / c_tooth
    return BodyTorsionFit(base_radius**2 / c_body, c_body, k_tooth, lever**2 / c_total,
                          c_total, c_adjacent, pivot_radius)


def body_windup(torque: float, base_radii, k_body) -> float:
    """Static TE added by the body springs [m] under ``torque`` [N·m] on gear 2 (flank contact:
    the driver carries torque*rb1/rb2): rb1*M1/k_body1 + rb2*T/k_body2."""
    rb1, rb2 = base_radii
    return rb1 * (torque * rb1 / rb2) / k_body[0] + rb2 * torque / k_body[1]

"""Pitch errors and eccentricity of a gear (SI) and their place in the model arrays.

Pitch: single pitch deviations f_pt,k [m] (ISO 1328-1 sign: actual minus theoretical
transverse pitch on the reference circle between tooth k-1 and tooth k, k counted in the
gear's counter-clockwise sense, so f_pt,0 is the pitch from the last tooth to tooth 0). Their
sum is zero (a closed circle). The cumulative pitch deviation of tooth k from tooth 0,
F_p,k = f_pt,1 + ... + f_pt,k (F_p,0 = 0), turns tooth k rigidly about the teeth's centre by
eps_k = F_p,k / r (r the reference radius), counter-clockwise in the gear frame: both flanks
move, the tooth keeps its thickness. Along the line of action that is rb*eps_k =
F_p,k*cos(alpha). In this model's frame both gears' "+" flanks drive (gear 1 turns
counter-clockwise, gear 2 clockwise), so eps_k > 0 on either gear brings tooth k's drive flank
forward: it meets its mate earlier, carries more load and lowers the TE by rb*eps_k while it
is alone in the mesh; its coast flank gets the same amount more clearance.

Eccentricity: the teeth's centre sits e [m] from the bearing axis O, at the polar angle
``phase`` [rad] from tooth 0's axis in the gear frame, and turns with the gear about O. The
radial runout of the teeth is F_r ~ 2e. Along a contact normal n the offset moves the flank by
e*cos(theta + gamma0 + phase - psi_n) (psi_n the angle of n); the change of the centre
distance along the line of centres is second order for involutes.

ISO 1328-1:2013 tolerances of flank tolerance class A (1..11), d the reference diameter and m
the module in mm, results in um (the standard's clauses 5.3.2 and 5.3.3; values unrounded):

    f_pT = (0.001 d + 0.4 m + 5) * sqrt(2)**(A - 5)                 single pitch
    F_pT = (0.002 d + 0.55 sqrt(d) + 0.7 m + 12) * sqrt(2)**(A - 5) cumulative pitch (total)

`random_pitch` draws a closed set whose |f_pt| <= f_pT and whose cumulative deviations span
(max - min of F_p,k) at most F_pT.

Model arrays (`solver.mbs.model.error_block`, columns `solver.mbs.kernels.layout` E_*): when either gear has errors, ``pair_par`` is
extended by an errors block (a bound on the extra penetration, each gear's e and phase, and
every tooth's eps, gear-1 teeth first); without errors it keeps its plain length and the
kernels skip every step of this.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ISO_CLASSES = range(1, 12)


@dataclass(frozen=True)
class GearErrors:
    """One gear's pitch deviations and eccentricity (SI)."""

    pitch: tuple = ()               # f_pt,k per tooth [m]; () = none
    eccentricity: float = 0.0       # [m]
    eccentricity_phase: float = 0.0  # [rad] from tooth 0's axis, gear frame

    @property
    def is_zero(self) -> bool:
        return self.eccentricity == 0.0 and not any(self.pitch)

    def cumulative(self, teeth: int) -> np.ndarray:
        """F_p,k [m] of tooth k from tooth 0 (zeros without pitch deviations)."""
        if not len(self.pitch):
            return np.zeros(teeth)
        f = np.asarray(self.pitch, float)
        return np.concatenate([[0.0], np.cumsum(f[1:])])

    def check(self, teeth: int, module: float, name: str = "gear") -> None:
        """ValueError naming the field: wrong length, an open circle, a negative eccentricity."""
        if len(self.pitch):
            f = np.asarray(self.pitch, float)
            if f.size != teeth:
                raise ValueError(f"{name}.errors.pitch: {f.size} values for {teeth} teeth (one per tooth)")
            if not np.all(np.isfinite(f)):
                raise ValueError(f"{name}.errors.pitch: values must be finite")
            if abs(f.sum()) > closure_tolerance(f):
                raise ValueError(f"{name}.errors.pitch: the single pitch deviations must sum to zero (a closed "
                                 f"circle), they sum to {f.sum() * 1e6:.4g} um")
        if not (self.eccentricity >= 0.0 and math.isfinite(self.eccentricity)):
            raise ValueError(f"{name}.errors.eccentricity: must be finite and >= 0, got {self.eccentricity}")
        # the pre-search window and the rigid gap bound take the errors as small against a pitch
        if np.max(np.abs(self.cumulative(teeth)), initial=0.0) + self.eccentricity > 0.1 * module:
            raise ValueError(f"{name}.errors: cumulative pitch deviation plus eccentricity beyond 0.1 x module "
                             f"({0.1 * module * 1e6:.4g} um): outside the model's small-error range")


def closure_tolerance(f: np.ndarray) -> float:
    """Largest |sum f_pt| [m] taken as closed: rounding of the listed values (1e-3 um each) or
    1e-6 of their magnitude."""
    f = np.asarray(f, float)
    return max(1e-9 * f.size, 1e-6 * float(np.abs(f).sum()))


def iso1328_pitch_tolerances(d: float, m: float, grade: int) -> tuple[float, float]:
    """(f_pT, F_pT) [m] of ISO 1328-1:2013 flank tolerance class ``grade`` for reference
    diameter d [m] and module m [m] (formulas in the module docstring)."""
    if int(grade) != grade or grade not in ISO_CLASSES:
        raise ValueError(f"ISO 1328-1 flank tolerance class must be an integer 1..11, got {grade}")
    dm, mm = d * 1e3, m * 1e3
    step = math.sqrt(2.0) ** (grade - 5)
    f_pt = (0.001 * dm + 0.4 * mm + 5.0) * step
    f_p = (0.002 * dm + 0.55 * math.sqrt(dm) + 0.7 * mm + 12.0) * step
    return f_pt * 1e-6, f_p * 1e-6


def random_pitch(teeth: int, d: float, m: float, grade: int, seed: int) -> tuple:
    """A reproducible closed set of single pitch deviations f_pt,k [m] within class ``grade``.

    Cumulative deviations F_p,k are drawn as a smooth long-wave part (a once-per-revolution
    sine of random phase: the usual shape of a cumulative pitch curve) plus white tooth-to-tooth
    scatter, then scaled down (if needed) until |f_pt| <= f_pT and max(F_p) - min(F_p) <= F_pT.
    The same (teeth, d, m, grade, seed) gives the same set.
    """
    f_pt_tol, f_p_tol = iso1328_pitch_tolerances(d, m, grade)
    rng = np.random.default_rng(int(seed))
    k = np.arange(teeth)
    wave = np.sin(2.0 * math.pi * k / teeth + rng.uniform(0.0, 2.0 * math.pi))
    fp = f_p_tol * (0.35 * wave + 0.3 * rng.uniform(-0.5, 0.5, teeth))
    fp -= fp[0]
    f = np.diff(np.concatenate([fp, [fp[0]]]))           # f[k] = F_p,k+1 - F_p,k ...
    f = np.roll(f, 1)                                    # ... as f_pt,k = F_p,k - F_p,k-1
    scale = min(1.0, 0.95 * f_pt_tol / np.abs(f).max(), 0.95 * f_p_tol / max(np.ptp(fp), 1e-30))
    f = f * scale
    f -= f.mean()                                        # closed to rounding
    return tuple(float(x) for x in f)

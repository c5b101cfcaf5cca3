"""Scene fields of a gear's pitch errors and eccentricity (``gearN.errors.*``) and their
conversion to `solver.pitch_errors.GearErrors` (SI).

Pitch deviations come either as a list (``pitch``, one single pitch deviation f_pt per tooth
in um, ISO 1328-1 sign: actual minus theoretical pitch between tooth k-1 and tooth k) or as an
ISO 1328-1:2013 flank tolerance class (``grade``, 1..11) with a ``seed``: a reproducible
random set within that class's f_pT and F_pT for the gear's reference diameter and module
(`solver.pitch_errors.random_pitch`). The eccentricity is the offset of the teeth's centre from the
bearing axis (um; radial runout F_r ~ 2 x eccentricity) at ``eccentricity_phase`` (deg, gear
frame, from tooth 0's axis).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from solver import units
from solver.geometry import GearGeometry
from solver.pitch_errors import GearErrors, closure_tolerance, random_pitch
from study.errors import SceneError


def _f(default, unit: str, doc: str, lo=None, hi=None):
    return field(default=default, metadata=dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=False, choices=None,
                                                optional=False))


@dataclass(frozen=True)
class ErrorsSection:
    """Pitch deviations and eccentricity of the gear; all zero = a perfect gear."""
    pitch: tuple[float, ...] = _f((), "um", "single pitch deviations f_pt, one per tooth (tooth k: actual minus "
                                  "theoretical pitch from tooth k-1 to tooth k on the reference circle; they sum to 0)")
    grade: int = _f(0, "1", "or a random set of pitch deviations within this ISO 1328-1:2013 flank tolerance "
                    "class (1..11; 0 = none), drawn with seed", 0, 11)
    seed: int = _f(0, "1", "seed of the random pitch deviations of grade (the same seed gives the same set)", 0)
    eccentricity: float = _f(0.0, "um", "offset of the teeth's centre from the bearing axis (radial runout "
                             "F_r ~ 2 x eccentricity)", 0.0)
    eccentricity_phase: float = _f(0.0, "deg", "direction of that offset in the gear, from tooth 0's axis",
                                   -360.0, 360.0)

    @property
    def is_zero(self) -> bool:
        return self.eccentricity == 0.0 and self.grade == 0 and not any(self.pitch)


def errors_spec(e: ErrorsSection, g: GearGeometry, prefix: str) -> GearErrors | None:
    """The SI errors of a gear (None: a perfect gear); SceneError naming the field."""
    if e.is_zero:
        return None
    if e.pitch and e.grade:
        raise SceneError(f"{prefix}.grade", "give pitch (a list) or grade (a random set), not both")
    pitch = ()
    if e.pitch:
        if len(e.pitch) != g.teeth:
            raise SceneError(f"{prefix}.pitch", f"{len(e.pitch)} values for {g.teeth} teeth (one per tooth)")
        pitch = tuple(x * units.UM for x in e.pitch)
        total = sum(pitch)
        if abs(total) > closure_tolerance(pitch):
            raise SceneError(f"{prefix}.pitch", f"the single pitch deviations must sum to zero (a closed circle), "
                             f"they sum to {total / units.UM:.4g} um")
    elif e.grade:
        pitch = random_pitch(g.teeth, 2.0 * g.pitch_radius, g.spec.module, e.grade, e.seed)
    spec = GearErrors(pitch, e.eccentricity * units.UM, e.eccentricity_phase * units.DEG)
    try:
        spec.check(g.teeth, g.spec.module, prefix.rsplit(".errors", 1)[0])
    except ValueError as err:     # "gearN.errors.<field>: reason"
        where, reason = str(err).split(": ", 1)
        raise SceneError(where, reason) from None
    return spec

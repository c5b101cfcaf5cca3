"""Gear materials for the bending strength rating: the nominal bending stress limit
sigma_Flim of ISO 6336-5 and the factors that turn it into the tooth-root limit of ISO 6336-3.

sigma_Flim is the standard's endurance limit of the reference test gear (stress correction
Y_ST = 2, 10^6-10^7 cycles, 1 % failure probability) for the material, its heat treatment and
quality grade. The values below are ISO 6336-5:2016 quality grade MQ (the grade of normal
industrial practice) read from its charts for the stated hardness; the limit of a real part
comes from its own hardness and grade. Units: SI (Pa).

The limit stress of the part (ISO 6336-3), which the safety factor divides:

    sigma_FG = sigma_Flim * Y_ST * Y_NT * Y_delta_rel_T * Y_R_rel_T * Y_X

with Y_ST = 2, and at this stage Y_NT = 1 (long life), Y_delta_rel_T = 1 (relative notch
sensitivity), Y_R_rel_T = 1 (relative surface factor), Y_X = 1 (size, module <= 5 mm):
`GearMaterial.limit_stress`. S_F = sigma_FG / sigma; ISO 6336's usual minimum is 1.4 for
industrial gears (S_Fmin is the user's choice: `workflows.lightest_gear`).

The same limit is applied to the rim and the web (the FE's stress there against the tooth's
limit): a case-carburised or nitrided gear's web and rim below the case are core material,
weaker than the hardened root, so their safety is optimistic for those treatments.
"""
from __future__ import annotations

from dataclasses import dataclass

from solver import units

Y_ST = 2.0     # stress correction factor of the reference test gear (ISO 6336-3)


@dataclass(frozen=True)
class GearMaterial:
    """A gear steel for the bending rating."""

    name: str
    treatment: str
    sigma_f_lim: float        # nominal bending stress limit sigma_Flim [Pa] (ISO 6336-5)
    sigma_h_lim: float        # contact stress limit sigma_Hlim [Pa] (ISO 6336-5; for reference)
    hardness: str             # the surface hardness the limits hold for
    source: str

    def limit_stress(self, y_nt: float = 1.0, y_delta_rel: float = 1.0, y_r_rel: float = 1.0, y_x: float = 1.0) -> float:
        """Tooth-root limit stress sigma_FG [Pa] = sigma_Flim Y_ST Y_NT Y_delta_rel_T Y_R_rel_T Y_X."""
        return self.sigma_f_lim * Y_ST * y_nt * y_delta_rel * y_r_rel * y_x


_ISO = "ISO 6336-5:2016, quality grade MQ"
MATERIALS = {
    m.name: m for m in (
        GearMaterial("18CrNiMo7-6", "case-carburised", 500.0 * units.MPA, 1500.0 * units.MPA,
                     "58-62 HRC surface, core >= 30 HRC", f"{_ISO} (case-carburised wrought steel)"),
        GearMaterial("42CrMo4", "through-hardened (quenched and tempered)", 315.0 * units.MPA, 740.0 * units.MPA,
                     "300 HV10", f"{_ISO} (through-hardened wrought alloy steel, at 300 HV)"),
        GearMaterial("31CrMoV9", "gas-nitrided", 420.0 * units.MPA, 1250.0 * units.MPA,
                     "700-800 HV1 surface", f"{_ISO} (nitriding steel, nitrided)"),
    )
}
DEFAULT_MATERIAL = "18CrNiMo7-6"


def gear_material(name: str) -> GearMaterial:
    """The `MATERIALS` entry ``name``; a KeyError lists the known names."""
    try:
        return MATERIALS[name]
    except KeyError:
        raise KeyError(f"unknown gear material {name!r} (known: {', '.join(MATERIALS)})") from None

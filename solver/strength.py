"""Where a lightened gear is expected to crack first, and its bending safety factors.

`failure_mode` reads the backup ratio m_B = s_R/h_t and the FE's largest tensile (max
principal) stresses under the same loads at the root, in the rim and in the web:

* 'web'  when the web's largest tensile stress (an opening's edge or a ligament) reaches the
  root's and the rim's: the first crack starts in the web;
* 'rim'  when the rim's reaches the root's (the rim is the most stressed place), or where the
  published tests and crack-propagation FE put rim fracture (Lewicki & Ballarini 1997: m_B
  0.3 rim fracture; below 0.5 `solver.peers.iso6336_strength.crack_path` gives 'rim'), or in their
  mixed band 0.5 <= m_B < 1 when the rim's stress is at least `RIM_RATIO_MIXED` of the root's
  (a root crack then turns into the rim: its path follows the rim's bending, which this ratio
  measures);
* 'tooth' otherwise: the crack starts at the root fillet and runs through the tooth (m_B >= 1:
  the tests' tooth fracture at 1.0 and 3.3).

Bending safety S_F = sigma_FG / sigma at each location (`solver.materials`).
"""
from __future__ import annotations

import math

from solver.peers.iso6336_strength import crack_path

FAILURE_MODES = ("tooth", "rim", "web")
LOCATIONS = ("root", "rim", "web")      # where a gear's strength is read (solver.fe.stress.strength_sites)
RIM_RATIO_MIXED = 0.5   # rim-to-root stress ratio from which a mixed-band rim (0.5 <= m_B < 1) counts as 'rim'


def failure_mode(m_b: float, rim_ratio: float, web_ratio: float) -> str:
    """'tooth', 'rim' or 'web' (see the module) from the backup ratio ``m_b`` [1] and the FE's
    rim-to-root and web-to-root ratios of the largest tensile stress [1] (NaN web ratio: no
    openings)."""
    if not (math.isfinite(m_b) and math.isfinite(rim_ratio)):
        raise ValueError(f"failure_mode: needs a finite m_B and rim ratio, got {m_b}, {rim_ratio}")
    if math.isfinite(web_ratio) and web_ratio >= 1.0 and web_ratio >= rim_ratio:
        return "web"
    path = crack_path(m_b)
    if rim_ratio >= 1.0 or path == "rim" or (path == "mixed" and rim_ratio >= RIM_RATIO_MIXED):
        return "rim"
    return "tooth"


def bending_safety(limit_stress: float, stress: float) -> float:
    """S_F = sigma_FG / sigma [1] (inf for a stress <= 0: no tension; NaN stays NaN)."""
    if math.isnan(stress):
        return float("nan")
    return limit_stress / stress if stress > 0 else float("inf")

"""Rim thickness factor, crack path, failure mode and safety factors of the bending rating."""
import math

import pytest

from solver.materials import MATERIALS, Y_ST, gear_material
from solver.peers.iso6336_strength import (
    backup_ratio,
    crack_path,
    inner_single_contact_roll,
    nominal_root_stress,
    rim_thickness_factor,
    single_contact_roll,
)
from solver.strength import bending_safety, failure_mode


def test_rim_thickness_factor_is_the_standards_curve():
    """ISO 6336-3 Y_B = AGMA K_B = 1.6 ln(2.242/m_B): 1.29 at 1.0, 1.65 at 0.8, 2.40 at 0.5, 1 from 1.2;
    continuous at 1.2 within the standard's rounding; below 0.5 extrapolated and flagged."""
    assert rim_thickness_factor(1.0)[0] == pytest.approx(1.29, abs=0.005)
    assert rim_thickness_factor(0.8)[0] == pytest.approx(1.65, abs=0.005)
    assert rim_thickness_factor(0.5) == (pytest.approx(2.40, abs=0.005), True)
    assert rim_thickness_factor(1.2) == (1.0, True) and rim_thickness_factor(3.3) == (1.0, True)
    assert rim_thickness_factor(1.2 - 1e-6)[0] == pytest.approx(1.0, abs=0.002)
    y, inside = rim_thickness_factor(0.3)
    assert not inside and y == pytest.approx(1.6 * math.log(2.242 / 0.3))
    # an m_B of 0.5 from lengths in metres (rounding) is within the standard
    assert rim_thickness_factor(backup_ratio(0.5 * 3.375e-3, 51.75e-3 - 48.375e-3))[1]
    assert math.isnan(rim_thickness_factor(0.0)[0])
    with pytest.raises(ValueError):
        backup_ratio(1.0, 0.0)


def test_crack_path_follows_lewicki_and_ballarini():
    assert [crack_path(m) for m in (3.3, 1.0, 0.7, 0.5, 0.3)] == ["tooth", "tooth", "mixed", "mixed", "rim"]


def test_failure_mode_from_backup_ratio_and_stress_ratios():
    assert failure_mode(3.3, 0.1, float("nan")) == "tooth"          # thick rim, no openings
    assert failure_mode(3.3, 1.2, 0.3) == "rim"                     # the FE puts the largest stress in the rim
    assert failure_mode(0.3, 0.2, 0.1) == "rim"                     # tests: rim fracture at 0.3
    assert failure_mode(0.7, 0.6, 0.1) == "rim" and failure_mode(0.7, 0.2, 0.1) == "tooth"   # mixed band
    assert failure_mode(1.5, 0.1, 1.3) == "web" and failure_mode(0.3, 0.2, 1.1) == "web"
    assert failure_mode(1.5, 1.4, 1.3) == "rim"                     # the rim more stressed than the web
    with pytest.raises(ValueError):
        failure_mode(float("nan"), 0.1, 0.1)


def test_single_contact_points_bound_the_single_pair_zone():
    """Equal gears: the inner single contact point of one gear is one base pitch below its tip
    contact, the outer one a base pitch above its SAP; the pitch point lies between."""
    z, m, a = 67, 1.5e-3, math.radians(20.0)
    rb, ra = 0.5 * z * m * math.cos(a), 0.5 * z * m + m
    pb = math.pi * m * math.cos(a)
    eps = (2 * math.sqrt(ra**2 - rb**2) - z * m * math.sin(a)) / pb
    lo, hi = inner_single_contact_roll(ra, rb, pb), single_contact_roll(ra, rb, pb, eps)
    assert lo < math.tan(a) < hi
    u_tip = math.sqrt((ra / rb) ** 2 - 1)
    assert (u_tip - lo) * rb == pytest.approx(pb) and (hi - lo) * rb == pytest.approx(pb * (2 - eps))


def test_nominal_root_stress_carries_y_b_and_safety_divides_the_limit():
    assert nominal_root_stress(1000.0, 0.017, 0.0015, 1.2, 2.0, 1.29) == pytest.approx(1000 / (0.017 * 0.0015) * 2.4 * 1.29)
    mat = gear_material("18CrNiMo7-6")
    assert mat.limit_stress() == pytest.approx(Y_ST * 500e6)
    assert bending_safety(mat.limit_stress(), 250e6) == pytest.approx(4.0)
    assert bending_safety(1.0, -5.0) == math.inf and math.isnan(bending_safety(1.0, float("nan")))
    assert {"18CrNiMo7-6", "42CrMo4", "31CrMoV9"} <= set(MATERIALS)
    assert all("ISO 6336-5" in m.source and m.sigma_f_lim > 0 for m in MATERIALS.values())
    with pytest.raises(KeyError, match="known"):
        gear_material("unobtainium")

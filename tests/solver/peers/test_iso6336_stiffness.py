"""ISO 6336-1 Method B stiffness against hand calculations: the flexibility polynomial, the
basic-rack factor and the low-load factor below 100 N/mm."""
import math

import pytest

from solver.peers.iso6336 import basic_rack_factor, low_load_factor, q_prime, single_stiffness


def test_single_stiffness_of_the_paper_pair_by_hand():
    # q' = 0.04723 + 0.15551/67 + 0.25791/67 (spur, no profile shift) = 0.0534004 mm·um/N
    q = 0.04723 + (0.15551 + 0.25791) / 67
    assert q_prime(67, 67) == pytest.approx(q, rel=1e-14)
    # C_B for h_fP = 1.25 m, alpha 20 deg: 1 + 0.5 (1.2 - 1.25) = 0.975; C_M 0.8
    assert basic_rack_factor(1.25, 20.0) == pytest.approx(0.975, rel=1e-14)
    assert single_stiffness(67, 67, 1.25, 20.0) == pytest.approx(0.8 * 0.975 / q, rel=1e-14)
    assert single_stiffness(67, 67, 1.25, 20.0) == pytest.approx(14.607, abs=5e-4)


def test_low_load_factor_of_the_paper_pair_at_50_n_m_by_hand():
    # F_t = 50 N·m / r2 (67 x 1.5 mm / 2 = 50.25 mm) = 995.02 N; F_t / b = 995.02 / 17 = 58.531 N/mm;
    # (0.58531)^0.25 = sqrt(sqrt(0.58531)) = sqrt(0.765055) = 0.874674
    w = 50.0 / 0.05025 / 17.0
    assert w == pytest.approx(58.531, abs=1e-3)
    assert low_load_factor(w) == pytest.approx(0.874674, abs=2e-6)
    c = single_stiffness(67, 67, 1.25, 20.0)
    assert single_stiffness(67, 67, 1.25, 20.0, load_per_width=w) == pytest.approx(0.874674 * c, rel=3e-6)


def test_low_load_factor_is_one_from_100_n_per_mm_and_falls_as_the_fourth_root_below():
    assert low_load_factor(100.0) == 1.0 and low_load_factor(250.0) == 1.0
    assert low_load_factor(6.25) == pytest.approx(0.5, rel=1e-14)          # (1/16)^0.25
    assert low_load_factor(-58.5) == low_load_factor(58.5)                  # the coast flanks: by its size
    assert low_load_factor(0.0) == 0.0
    with pytest.raises(ValueError, match="load_per_width"):
        low_load_factor(math.nan)

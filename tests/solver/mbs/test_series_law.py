"""The series contact law (`laws.series_contact`, the compliance model) against a tight
reference solve: over the loads, the local compliances of both signs and the exponents a scene
may give, the law's share of the penetration, the force and the tangent agree with a
50-digit Newton solve of delta = delta_c + c_loc*k*delta_c^m1 to a few units in the last
place; and a negative compliance beyond the law's limit is clamped so that the force stays
single-valued with a finite tangent for every exponent up to the scene's bound of 3."""
from decimal import Decimal, localcontext

import numpy as np
import pytest

from solver.mbs.kernels.laws import SERIES_NEG_LIMIT, series_contact

K = 2.96e10      # N/m^m1: the paper's 5.64e6 N/mm^1.24 (the law is solved in ratios: k only scales)
EXPONENTS = (1.02, 1.24, 1.5, 2.0, 2.5, 3.0)     # m1: the scene allows 1 to 3


def _reference(delta, c_loc, k, m1):
    """(delta_c [m], F_e [N], dF_e/d delta [N/m]) by Newton's iteration in 50-digit decimals
    (`decimal` powers are correctly rounded), from delta_c = delta: monotone for either sign of
    c_loc, stopped at a relative step of 1e-40."""
    with localcontext() as ctx:
        ctx.prec = 50
        d, c, kk, m = Decimal(delta), Decimal(c_loc), Decimal(k), Decimal(m1)
        x = d
        for _ in range(200):
            p = x ** (m - 1)
            dx = (x + c * kk * p * x - d) / (1 + c * m * kk * p)
            x -= dx
            if abs(dx) <= Decimal("1e-40") * x:
                break
        else:
            raise AssertionError("reference solve did not converge")
        kx = m * kk * x ** (m - 1)
        return float(x), float(kk * x ** m), float(kx / (1 + c * kx))


def _limit_ratio(m1):
    """The most negative c_loc*k*delta^(m1-1) the law takes unclamped (SERIES_NEG_LIMIT: the
    series tangent at most 1/(1 - limit) times the law's own at its penetration)."""
    y = m1 / (m1 - SERIES_NEG_LIMIT)
    return -SERIES_NEG_LIMIT / (m1 * y ** (m1 - 1.0))


@pytest.mark.parametrize("m1", EXPONENTS)
def test_series_law_agrees_with_a_50_digit_solve(m1):
    """Penetrations of 1 nm to 20 um (forces of about 1e-2 to 1e5 N) and compliance ratios
    a = c_loc*k*delta^(m1-1) from just inside the negative limit to 1e6 (FE tooth data: -0.1 to
    2.2): relative differences below 4e-15 (a few units in the last place), in the compiled
    kernel and in its Python function alike."""
    a_min = _limit_ratio(m1)
    ratios = np.concatenate([np.linspace(0.98 * a_min, -1e-3, 7), [-1e-9, 1e-12, 1e-7],
                             np.linspace(1e-2, 3.0, 9), np.geomspace(5.0, 1e6, 6)])
    worst = 0.0
    for delta in (1e-9, 2.5e-6, 2e-5):
        kd = K * delta ** (m1 - 1.0)
        for a in ratios:
            c_loc = a / kd
            ref = np.array(_reference(delta, c_loc, K, m1))
            got = np.array(series_contact(delta, c_loc, K, m1))
            np.testing.assert_allclose(series_contact.py_func(delta, c_loc, K, m1), got, rtol=1e-15, atol=0)
            rel = np.abs(got - ref) / np.abs(ref)
            worst = max(worst, rel.max())
            assert np.all(rel < 4e-15), (delta, a, got, ref)
    assert worst > 0.0       # (a real comparison: some digits beyond the last differ)


def test_series_law_solves_its_own_equation():
    """At the returned share, delta_c + c_loc*F_e gives back delta and F_e = k*delta_c^m1, to
    rounding, for the load range of the paper pair's run with FE local compliances."""
    m1 = 1.24
    rng = np.random.default_rng(7)
    for delta, c_loc in zip(rng.uniform(1e-9, 2.7e-6, 300), rng.uniform(-9e-11, 1.6e-9, 300)):
        dc, f, kt = series_contact(delta, c_loc, K, m1)
        assert dc + c_loc * f == pytest.approx(delta, rel=4e-15)
        assert f == pytest.approx(K * dc ** m1, rel=4e-15)
        assert 0.0 < kt < 2.0 * m1 * K * dc ** (m1 - 1.0)
        assert (dc < delta) == (c_loc > 0)


@pytest.mark.parametrize("m1", (1.24, 2.0, 2.5, 3.0))
def test_a_negative_compliance_beyond_the_limit_is_clamped(m1):
    """c_loc far below the limit (ten times the law's compliance at delta, negative): the law
    takes the limit instead, where its tangent is 1/(1 - SERIES_NEG_LIMIT) times the contact
    law's own at delta_c, exactly; the force stays single-valued (increasing in delta) with a
    finite positive tangent. (For m1 >= 2 a limit taken at delta instead of delta_c left no
    root there: the iteration returned a force that solved nothing.)"""
    forces = []
    for delta in np.geomspace(1e-8, 1e-5, 25):
        kd = K * delta ** (m1 - 1.0)
        c_loc = -10.0 / (m1 * kd)
        dc, f, kt = series_contact(delta, c_loc, K, m1)
        assert np.isfinite([dc, f, kt]).all() and dc > delta and f > 0.0
        assert f == pytest.approx(K * dc ** m1, rel=1e-14)
        k_law = m1 * K * dc ** (m1 - 1.0)
        assert kt == pytest.approx(k_law / (1.0 - SERIES_NEG_LIMIT), rel=1e-14)
        # the clamped compliance is the limit's, and the root of the series equation with it
        c_lim = (delta - dc) / f
        assert c_loc < c_lim < 0.0
        assert 1.0 + c_lim * k_law == pytest.approx(1.0 - SERIES_NEG_LIMIT, rel=1e-12)
        forces.append(f)
    assert np.all(np.diff(forces) > 0.0)

"""Tooth-root dampers taken implicitly in the Verlet kicks (IMEX): same solution, second
order, no damping limit on the step; the step bound without them; the load guard."""
import math

import numpy as np
import pytest
from helpers import RAW_DAMPING, solid_scene

from solver.mbs.dynamics import simulate
from solver.mbs.kernels import layout as L
from solver.mbs.stability import (
    IMEX_SAFETY,
    implicit_dampers_apply,
    load_covered,
    stability_limit,
    stable_time_step,
    stiffening_exponent,
)
from study.scene_model import build_scene_model

RUN = (100.0, 0.002, 50.0, 0.002, 0.003)     # 0 -> 100 rad/s and 0 -> 50 N m in 2 ms, 3 ms


def test_applies_to_linear_tooth_dampers_only(paper_solid_model):
    m = paper_solid_model
    assert implicit_dampers_apply(m)           # the damping ratio: linear tooth-root dampers
    nonlinear = build_scene_model(solid_scene(**RAW_DAMPING, **{"gear1.spring.n_c": 1.2}))
    assert not implicit_dampers_apply(nonlinear)
    with pytest.raises(ValueError, match="implicit_dampers"):
        simulate(nonlinear, *RUN, implicit_dampers=True)


def test_converges_at_second_order_to_the_explicit_solution(paper_solid_model):
    """Every tooth free: the IMEX runs at dt, dt/2, dt/4 approach the all-explicit run at a
    tenth of its step, their differences falling about 4x per halved step (with the damper at
    each kick's end rate instead of the kick's mean rate, 2x: first order)."""
    m = paper_solid_model
    dt, _w = stable_time_step(m, 50.0, implicit_dampers=True)
    dt_ex, _w = stable_time_step(m, 50.0)
    ref = simulate(m, *RUN, dt=dt_ex / 10, all_teeth=True, implicit_dampers=False).te
    err = [np.max(np.abs(simulate(m, *RUN, dt=dt / f, all_teeth=True).te - ref)) for f in (1, 2, 4)]
    assert err[0] < 0.01e-6                     # m: 0.01 um at the default step
    assert 1.8 < math.log2(err[0] / err[1]) < 2.3 and 1.8 < math.log2(err[1] / err[2]) < 2.3


def test_step_no_longer_limited_by_the_dampers(paper_solid_model):
    """The damping ratio puts 5 % of the mesh mode in the tooth-root joints: the tooth mode is
    then damped at about 0.9 of critical, and the all-explicit Verlet bound
    2/w*(sqrt(1+4 zeta²)-2 zeta) falls far below 2/w. Between the two, the explicit kicks blow up
    and the implicit ones run, within 0.01 um of the tight reference."""
    m = paper_solid_model
    gp = m.gear_par
    zeta = gp[:, L.C_PHI] / (2.0 * np.sqrt(m.k_phi.max() * gp[:, L.I_P]))
    assert np.all(zeta > 0.5)
    dt_damped, w = stability_limit(m, 50.0)
    dt_free, w2 = stability_limit(m, 50.0, implicit_dampers=True)
    # no contact damper: the undamped bound (w of every tooth free, the all-explicit bound's, the same)
    assert w2 == pytest.approx(w, rel=1e-4) and dt_free == pytest.approx(2.0 / w2)
    assert dt_damped < 0.8 * dt_free
    dt = 1e-5 / math.ceil(1e-5 / (0.9 * dt_free))           # a divisor of the output step, below 0.9 dt_free
    assert dt > dt_damped
    ex = simulate(m, *RUN, dt=dt, implicit_dampers=False)
    assert ex.status != 0
    im = simulate(m, *RUN, dt=dt)
    assert im.status == 0 and im.dt == dt
    ref = simulate(m, *RUN, dt=dt_damped / 16, all_teeth=True, implicit_dampers=False)
    assert np.max(np.abs(im.te - ref.te)) < 0.01e-6
    # the dissipated energy is booked: the balance closes
    assert im.dissipated[-1] > 0 and np.max(np.abs(im.energy_error)) < 1e-3 * im.work[-1]


def test_load_guard_bounds_the_stiffening():
    """A step at s of the bound stays below it while s * r^(e/2) < 1, r the ratio of the
    largest contact force to the estimate's (about |torque|/r_b2), e the stiffening exponent of
    the laws: (m1 - 1)/m1 = 0.24/1.24 for the paper's contact."""
    m = build_scene_model(solid_scene())
    e = stiffening_exponent(m)
    assert e == pytest.approx(0.24 / 1.24)
    f0 = 50.0 / m.base_radii[1]
    r_max = IMEX_SAFETY ** (-2.0 / e)
    assert load_covered(m, 50.0, IMEX_SAFETY, 0.99 * r_max * f0)
    assert not load_covered(m, 50.0, IMEX_SAFETY, 1.01 * r_max * f0)
    assert load_covered(m, 50.0, 0.5, 100.0 * f0)


def test_zero_torque_rattle_takes_the_step_of_its_impacts(paper_solid_model):
    """Without load the estimate is made under 1 N m, but the rattle's impacts reach hundreds
    of newtons: the guard estimates again under the load of the largest impact, and the run it
    keeps is within the bound at the load of its largest impact."""
    m = paper_solid_model
    dt_1nm, _w = stable_time_step(m, 0.0, implicit_dampers=True)
    r = simulate(m, 100.0, 0.005, 0.0, 0.005, 0.02)
    assert r.status == 0, r.message
    peak = float(r.force_max.max())
    assert peak * m.base_radii[1] > 1.0        # far above the 1 N m of the first estimate
    assert r.dt < dt_1nm
    # the step kept is below the bound of the pair linearised under the load of its largest impact
    dt_crit, _w = stability_limit(m, peak * m.base_radii[1], implicit_dampers=True)
    assert r.dt < dt_crit

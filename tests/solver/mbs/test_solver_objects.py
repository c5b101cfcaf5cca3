"""The solvers as objects that hold their settings: the one-call fronts (`simulate`,
`simulate_implicit`, `simulate_scipy`, `solve_static`) are the objects' runs, bit for bit, a
load profile travels in the run's `Drive`, and a setting no solver has is refused by name."""
import dataclasses

import numpy as np
import pytest

from solver.mbs.dynamics import Drive, ExplicitIntegrator, simulate
from solver.mbs.implicit import ImplicitIntegrator, simulate_implicit
from solver.mbs.statics import StaticSolver, solve_static
from solver.peers.scipy_dynamics import ScipyIntegrator, simulate_scipy

RUN = (100.0, 0.001, 50.0, 0.001, 0.002)            # rad/s, s, N·m, s, s
# +50 N·m, then down to 25 N·m (rows of time [s], torque [N·m] from 0 N·m at t = 0)
TABLE = [[0.0, 0.0], [0.001, 50.0], [0.0015, 25.0]]


def same_result(a, b) -> None:
    """Every field of two results equal, arrays bit for bit (NaNs where they are)."""
    assert type(a) is type(b)
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        elif f.name != "wall_time":         # the scipy peer's measured time
            assert x == y or (x != x and y != y), f.name


def test_simulate_is_the_explicit_integrators_run_with_a_load_profile(paper_solid_model):
    m = paper_solid_model
    a = simulate(m, *RUN, output_step=1e-4, load_table=TABLE)
    b = ExplicitIntegrator(output_step=1e-4).run(m, Drive(*RUN, load_table=TABLE))
    same_result(a, b)
    ramp = ExplicitIntegrator(output_step=1e-4).run(m, Drive(*RUN))
    # the profile is the ramp up to 1 ms; after, its torque falls to 25 N·m and the TE parts
    assert a.status == 0 and ramp.status == 0
    up, after = a.time <= 0.001 + 1e-12, a.time >= 0.0015
    np.testing.assert_allclose(a.te[up], ramp.te[up], rtol=0, atol=1e-12)
    assert np.max(np.abs(a.te[after] - ramp.te[after])) > 1e-7
    with pytest.raises(TypeError, match="time_step"):
        simulate(m, *RUN, time_step=1e-7)


def test_simulate_implicit_is_the_implicit_integrators_run(paper_solid_model):
    m = paper_solid_model
    a = simulate_implicit(m, *RUN, dt=2e-6, output_step=1e-4, alpha=-0.1)
    b = ImplicitIntegrator(dt=2e-6, output_step=1e-4, alpha=-0.1).run(m, Drive(*RUN))
    same_result(a, b)
    assert a.alpha == -0.1 and a.newton_total > 0
    with pytest.raises(TypeError, match="safety"):
        simulate_implicit(m, *RUN, safety=0.5)      # an explicit setting the implicit integrator has not


def test_simulate_scipy_is_the_scipy_integrators_run(paper_solid_model):
    m = paper_solid_model
    short = (*RUN[:4], 0.0005)
    a = simulate_scipy(m, *short, method="LSODA", rtol=1e-5, output_step=1e-4)
    b = ScipyIntegrator(method="LSODA", rtol=1e-5, output_step=1e-4).run(m, Drive(*short))
    same_result(a, b)
    with pytest.raises(ValueError, match="method"):
        ScipyIntegrator(method="Euler").run(m, Drive(*short))


def test_solve_static_is_the_static_solvers_run(paper_solid_model):
    m = paper_solid_model
    angles = np.radians([0.0, 1.0, 2.0])
    a = solve_static(m, angles, 50.0, tol=1e-12)
    b = StaticSolver(tol=1e-12).run(m, angles, 50.0)
    np.testing.assert_array_equal(a.te, b.te)
    np.testing.assert_array_equal(a.phi_last, b.phi_last)
    # continued from the last equilibrium: the same answer from a start that is already there
    c = StaticSolver(tol=1e-12).run(m, angles[-1:], 50.0, phi0=b.phi_last, te0=float(b.te[-1]))
    assert c.te[0] == pytest.approx(b.te[-1], abs=1e-12)
    with pytest.raises(TypeError, match="dt"):
        solve_static(m, angles, 50.0, dt=1e-6)

"""scipy peer (`solver.peers.scipy_dynamics`): agrees with the numba explicit solver, between its own
methods, closes the energy balance, and reports failures by name."""
import numpy as np
import pytest
from helpers import solid_scene

from solver.mbs.dynamics import DivergenceError, simulate
from solver.peers.pair_equations import PairEquations
from solver.peers.scipy_dynamics import simulate_explicit_all_teeth, simulate_scipy
from study.scene_model import build_scene_model

# a short run of the paper pair: 100 rad/s and 50 N·m reached in 2 ms, 3 ms in all
RUN = (100.0, 0.002, 50.0, 0.002, 0.003)


@pytest.fixture(scope="module")
def model():
    return build_scene_model(solid_scene())


@pytest.fixture(scope="module")
def small_model():
    """A 30/30-tooth pair of module 3 (60 teeth in all): the stiff solvers' cost grows with
    the number of free teeth, and their agreement does not depend on it."""
    return build_scene_model(solid_scene(**{"gear1.module": 3.0, "gear1.teeth": 30,
                                            "gear2.module": 3.0, "gear2.teeth": 30}))


@pytest.fixture(scope="module")
def dop853(small_model):
    """The DOP853 reference of RUN on the 30/30 pair (about a third of the CPU time of the
    Table 1 pair's 134 free teeth)."""
    return simulate_scipy(small_model, *RUN, method="DOP853", rtol=1e-9, output_step=1e-4)


def test_agrees_with_the_numba_explicit_solver_on_the_same_model(small_model, dop853):
    """Verlet (all teeth free, dt = 0.31 and 0.078 us) converges onto the DOP853 solution at
    second order: the two implementations solve the same equations (on the 30/30 pair, in
    contact from 0.1 ms on, speed and load ramps included)."""
    errs = []
    for dt in (3.125e-7, 7.8125e-8):
        ex = simulate_explicit_all_teeth(small_model, *RUN, dt=dt, output_step=1e-4)
        assert ex.status == 0
        errs.append(np.max(np.abs(ex.te - dop853.te)))
    assert errs[1] < 1.5e-10                   # 1.5e-4 um on a TE of about 40 um
    assert 10 < errs[0] / errs[1] < 22         # 4x smaller step, error /16


def test_close_to_the_active_set_explicit_solver(model):
    """`simulate` freezes idle teeth rigid to their hub; on the Table 1 pair that model
    reduction moves TE by less than a tenth of a micrometre in this impact-rich ramp (the idle
    driver teeth, wound up by the speed ramp in the full model, enter the mesh pre-deflected),
    no more. The full model is the peer's all-teeth Verlet at the same step (it agrees with
    DOP853 to 1e-10 m here: test_agrees_with_the_numba_explicit_solver_on_the_same_model)."""
    ex = simulate(model, *RUN, dt=1.5625e-7, output_step=1e-4)
    full = simulate_explicit_all_teeth(model, *RUN, dt=1.5625e-7, output_step=1e-4)
    assert full.status == 0
    assert np.max(np.abs(ex.te - full.te)) < 0.3e-6
    np.testing.assert_allclose(ex.n_contacts, full.n_contacts)


@pytest.mark.parametrize("method, duration", [("Radau", 0.0003), ("LSODA", 0.001)])
def test_stiff_methods_agree_with_dop853(small_model, method, duration):
    """In loaded contact with the ramps still running, the stiff methods with their analytic
    Jacobian land on the DOP853 solution (Radau's implicit stages cost about 40 ms a step
    here, so it gets the shorter window)."""
    run = (*RUN[:4], duration)
    ref = simulate_scipy(small_model, *run, method="DOP853", rtol=1e-9, output_step=1e-4)
    r = simulate_scipy(small_model, *run, method=method, rtol=1e-7, output_step=1e-4)
    assert r.status == 0 and r.njev > 0
    assert r.n_contacts[-1] >= 1
    assert np.max(np.abs(r.te - ref.te)) < 0.01e-6


def test_energy_balance_closes(dop853):
    """Work in = kinetic + potential + dissipated energy, to a relative 1e-7 at rtol 1e-9 (the
    30/30 pair's DOP853 run)."""
    assert dop853.dissipated[-1] > 0
    assert np.max(np.abs(dop853.energy_error)) < 1e-7 * np.max(np.abs(dop853.work))


def test_jacobian_matches_finite_differences(model):
    """Analytic Jacobian = finite differences of the right-hand side (up to the geometric
    stiffness it leaves out, which is a relative 1e-3 here)."""
    eq = PairEquations(model, *RUN[:4])
    # rebuild a loaded state at t = 2.5 ms from a short explicit run of the same model (the
    # same equations as the scipy peer's: test_agrees_with_the_numba_explicit_solver...)
    ex = simulate_explicit_all_teeth(model, *RUN[:4], 0.0025, dt=3e-7, output_step=5e-4)
    assert ex.n_contacts[-1] >= 1                # in contact there
    t = 0.0025
    y = np.zeros(2 * eq.n + 2)
    y[0] = ex.theta2[-1]
    J = eq.jac(t, y)
    f0 = eq.rhs(t, y)
    n = eq.n
    for col in [0, n]:          # theta2 and its rate
        h = 1e-9 if col < n else 1e-6
        yp = y.copy(); yp[col] += h
        ym = y.copy(); ym[col] -= h
        fd = (eq.rhs(t, yp) - eq.rhs(t, ym)) / (2 * h)
        scale = np.max(np.abs(fd[n:2 * n])) + 1e-30
        assert np.max(np.abs(fd[n:2 * n] - J[n:2 * n, col])) < 2e-3 * scale
    assert np.all(np.isfinite(f0))


def test_bad_input_names_the_field(model):
    with pytest.raises(ValueError, match="method"):
        simulate_scipy(model, *RUN, method="Euler")
    with pytest.raises(ValueError, match="duration"):
        simulate_scipy(model, *RUN[:4], -1.0)


def test_failure_is_reported_not_silent(small_model):
    """A penetration bound below the loaded penetration stops the run: status != 0, a message
    naming the cause and the time, finite output up to there (the 30/30 pair: 0.1 s of CPU a run
    against 2.3 s on the Table 1 pair; without the bound the same run ends ok)."""
    short = (*RUN[:4], 0.0005)     # the load reaches 0.1 um of penetration after about 0.1 ms
    r = simulate_scipy(small_model, *short, method="LSODA", rtol=1e-6, output_step=1e-4, delta_max=0.1e-6)
    assert r.status == 2 and "penetration beyond the bound" in r.message and "t = " in r.message
    assert np.all(np.isfinite(r.te))
    with pytest.raises(DivergenceError, match="penetration"):
        simulate_scipy(small_model, *short, method="LSODA", rtol=1e-6, output_step=1e-4, delta_max=0.1e-6,
                       raise_on_failure=True)
    assert simulate_scipy(small_model, *short, method="LSODA", rtol=1e-6, output_step=1e-4).status == 0

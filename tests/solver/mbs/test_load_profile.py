"""A resisting torque that changes during the run: the profile, its checks, and a reversal
that carries the mesh across the backlash onto the coast flanks."""
import numpy as np
import pytest
from helpers import solid_scene

from solver.mbs.dynamics import load_profile, run_loads, simulate
from solver.mbs.kernels.mechanics import load_torque
from solver.mbs.statics import solve_static
from study.scene import SceneError

TABLE = np.array([[0.0, 0.0], [0.005, 50.0], [0.01, 50.0], [0.015, -50.0]])


@pytest.mark.parametrize("jit", [True, False])
def test_load_torque_follows_the_ramp_or_the_table(jit):
    f = load_torque if jit else load_torque.py_func
    empty = np.zeros((0, 2))
    assert f(0.002, 50.0, 0.004, empty) == pytest.approx(25.0)
    assert f(0.01, 50.0, 0.004, empty) == 50.0
    assert f(0.0025, 0.0, 1.0, TABLE) == pytest.approx(25.0)
    assert f(0.0075, 0.0, 1.0, TABLE) == 50.0
    assert f(0.0125, 0.0, 1.0, TABLE) == pytest.approx(0.0, abs=1e-12)
    assert f(0.014, 0.0, 1.0, TABLE) == pytest.approx(-30.0)
    assert f(1.0, 0.0, 1.0, TABLE) == -50.0             # held after the last point


def test_profiles_are_checked():
    assert load_profile(None).shape == (0, 2)
    assert load_profile([[0.001, 10.0], [0.002, 20.0]])[0].tolist() == [0.0, 0.0]   # from rest
    for bad, msg in (([[0.0, 0.0]], "at least two"), ([[0.0, 0.0], [0.0, 1.0]], "increase strictly"),
                     ([[0.0, 5.0], [1.0, 1.0]], "must be 0"), ([[0.0, 0.0], [1.0, np.nan]], "finite")):
        with pytest.raises(ValueError, match=msg):
            load_profile(bad)
    table, step_torque, side = run_loads(TABLE, 1.0)
    assert step_torque == 50.0 and side == 50.0
    assert run_loads(None, -20.0)[1:] == (-20.0, -20.0)


def test_scene_torque_change_is_validated():
    with pytest.raises(SceneError, match="dynamic.torque_change_time"):
        solid_scene(**{"dynamic.torque_change_time": 0.005, "dynamic.ramp_time": 0.01})
    with pytest.raises(SceneError, match="dynamic.torque_change_time"):
        solid_scene(**{"dynamic.torque_change_time": 0.5, "dynamic.duration": 0.2})
    from study.scene_model import load_table
    s = solid_scene(**{"dynamic.torque_change_time": 0.05, "dynamic.torque_change_duration": 0.002,
                       "dynamic.torque_after": -20.0})
    np.testing.assert_allclose(load_table(s), [[0.0, 0.0], [0.01, 50.0], [0.05, 50.0], [0.052, -20.0]])
    assert load_table(solid_scene()) is None


@pytest.fixture(scope="module")
def damped_pair():
    """The solid Table 1 pair with tooth dampers strong enough (c_phi = 2 N·mm·s/rad) that the
    impact on the coast flanks dies out within the run (with c_phi = 0.062 the 3 kHz mesh mode
    kept ringing for some 50 ms); the contact damper the scenes had before."""
    from study.scene_model import build_scene_model
    return build_scene_model(solid_scene(**{"gear1.spring.c_phi": 2.0, "gear2.spring.c_phi": 2.0, "contact.c_con": 3640.0}))


@pytest.mark.parametrize("method", ["explicit", "implicit"])
def test_torque_reversal_crosses_the_backlash_onto_the_coast_flanks(damped_pair, method):
    """+50 -> -50 N·m over 5 ms at 10 rad/s: the mesh leaves the drive flanks, crosses the
    backlash without contact and settles on the coast flanks at the static coast STE."""
    from solver.mbs.implicit import simulate_implicit
    m = damped_pair
    run = simulate if method == "explicit" else simulate_implicit
    r = run(m, 10.0, 0.005, 50.0, 0.005, 0.04, load_table=TABLE)
    assert r.status == 0
    t, te = r.time, r.te
    ang = np.radians(np.arange(0.0, 360 / 67, 0.05))
    drive = solve_static(m, ang, 50.0).te.mean()
    coast = solve_static(m, ang, -50.0).te.mean()
    assert coast == pytest.approx(-drive, rel=1e-3)                      # symmetric teeth
    before, after = (t > 0.008) & (t < 0.01), t > 0.03
    assert te[before].mean() == pytest.approx(drive, abs=0.2e-6)
    assert te[after].mean() == pytest.approx(coast, abs=0.2e-6)
    assert r.n_contacts[after].min() >= 2
    crossing = (t > 0.0125) & (t < 0.015)
    assert (r.n_contacts[crossing] == 0).any()                         # free flight across the backlash
    assert np.max(np.abs(r.energy_error)) < 1e-3 * np.max(np.abs(r.work))


@pytest.fixture(scope="module")
def damped_small_pair():
    """`damped_pair`'s dampers on a 30/30-tooth pair of module 3 (60 teeth against 134): the
    scipy peer keeps every tooth free, so its cost grows with the teeth (the Table 1 pair took
    20-50 s of CPU here, this one about 1 s), and following a table does not depend on them."""
    from study.scene_model import build_scene_model
    return build_scene_model(solid_scene(**{"gear1.spring.c_phi": 2.0, "gear2.spring.c_phi": 2.0, "contact.c_con": 3640.0,
                                            "gear1.module": 3.0, "gear1.teeth": 30,
                                            "gear2.module": 3.0, "gear2.teeth": 30}))


def test_scipy_peer_follows_the_same_profile(damped_small_pair):
    """The numpy + scipy peer (its own interpolation of the table) against the explicit
    integrator through a load step 50 -> 20 N·m (short window, the speed ramp's impacts
    included); without the table the TE differs by tens of um."""
    from solver.peers.scipy_dynamics import simulate_explicit_all_teeth, simulate_scipy
    table = [[0.0, 0.0], [0.0005, 50.0], [0.0008, 50.0], [0.001, 20.0]]
    m = damped_small_pair
    ref = simulate_explicit_all_teeth(m, 100.0, 0.0005, 50.0, 0.0005, 0.0015, dt=2e-8, load_table=table)
    sp = simulate_scipy(m, 100.0, 0.0005, 50.0, 0.0005, 0.0015, method="LSODA", rtol=1e-7, load_table=table)
    assert ref.status == 0 and sp.status == 0
    assert np.max(np.abs(sp.te - ref.te)) < 0.01e-6
    step = simulate_explicit_all_teeth(m, 100.0, 0.0005, 50.0, 0.0005, 0.0015, dt=2e-8)
    assert np.max(np.abs(step.te - ref.te)) > 1e-6                       # the step is really there

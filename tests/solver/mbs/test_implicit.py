"""Implicit HHT-alpha integrator: convergence order, agreement with the explicit solver on the
same model, energy bookkeeping with its numerical dissipation, guards, the step bound against
the eigenvalues of the linearised model, and the per-scene choice of integrator."""
import math

import numpy as np
import pytest
from helpers import RAW_DAMPING, solid_scene

from solver.mbs.dynamics import DivergenceError, simulate
from solver.mbs.implicit import simulate_implicit
from solver.mbs.kernels.laws import (
    contact_damping_tangents,
    contact_force,
    contact_tangent,
    spring_damping_tangent,
    spring_torque,
)
from solver.mbs.method import MethodLimits, choose_method
from solver.mbs.stability import highest_frequency, linearized_system, stable_time_step
from study.run import run_scene
from study.scene import SceneError
from study.scene_model import build_scene_model

UNDAMPED = {"gear1.spring.c_phi": 0.0, "gear2.spring.c_phi": 0.0, "contact.c_con": 0.0}
# 100 rad/s and 50 N·m reached in 2 ms, 3 ms in all: the end of the ramps is inside the run
RUN = (100.0, 0.002, 50.0, 0.002, 0.003)


@pytest.fixture(scope="module")
def damped(paper_solid_model):
    return paper_solid_model


@pytest.fixture(scope="module")
def undamped():
    return build_scene_model(solid_scene(**UNDAMPED))


def _order(model, alpha, dts):
    te = [simulate_implicit(model, *RUN, dt=dt, alpha=alpha, output_step=1e-5).te for dt in dts]
    e1 = np.max(np.abs(te[0] - te[1]))
    e2 = np.max(np.abs(te[1] - te[2]))
    return math.log2(e1 / e2), e2


@pytest.mark.parametrize("alpha", [0.0, -0.1, -0.3])
def test_second_order_for_every_alpha(damped, alpha):
    """HHT-alpha is second order for alpha in [-1/3, 0] (Hilber et al. 1977), also across the
    end of the speed ramp (it falls on a step boundary)."""
    order, e = _order(damped, alpha, (1e-6, 5e-7, 2.5e-7))
    assert 1.8 < order < 2.4
    assert e < 0.01e-6


def test_agrees_with_explicit_on_the_same_model(damped):
    """Both integrators converge onto the same TE: their difference at small steps is far
    below the step error of either at the explicit stability step."""
    ex = simulate(damped, *RUN, dt=1.25e-7, output_step=1e-5)
    im = simulate_implicit(damped, *RUN, dt=1.25e-7, output_step=1e-5)
    assert ex.status == 0 and im.status == 0
    assert np.max(np.abs(ex.te - im.te)) < 0.002e-6          # 0.002 um on a TE of about 40 um
    np.testing.assert_array_equal(ex.n_contacts, im.n_contacts)
    # driver torque, away from the ramp end (where the explicit solver writes the right limit
    # and the implicit one the left limit of the jump)
    away = np.abs(ex.time - RUN[1]) > 1e-9
    dtq = np.abs(ex.driver_torque - im.driver_torque)[away]
    assert np.max(dtq) < 1e-2 * np.max(np.abs(ex.driver_torque))


def test_energy_bookkeeping_closes(undamped, damped):
    """work in = kinetic + potential + dissipated + numerical dissipation of HHT.

    alpha = 0 (trapezoidal) adds none: the balance closes to O(dt^2), below 1e-6 of the work
    here. alpha < 0 removes energy: a positive numerical dissipation that grows with |alpha|,
    ten times and more the balance residual of alpha = 0 at the same step.
    """
    dt = 5e-7
    r0 = simulate_implicit(undamped, *RUN, dt=dt, alpha=0.0)
    r0h = simulate_implicit(undamped, *RUN, dt=dt / 2, alpha=0.0)
    assert np.all(r0.dissipated == 0)
    w = np.max(np.abs(r0.work))
    assert np.max(np.abs(r0.numerical_dissipation)) < 1e-6 * w
    assert 3.0 < np.max(np.abs(r0.numerical_dissipation)) / np.max(np.abs(r0h.numerical_dissipation)) < 5.5
    nd = [simulate_implicit(undamped, *RUN, dt=dt, alpha=a).numerical_dissipation[-1] for a in (-0.05, -0.1, -0.3)]
    assert 10 * np.max(np.abs(r0.numerical_dissipation)) < nd[0] < nd[1] < nd[2]
    rd = simulate_implicit(damped, *RUN, dt=dt, alpha=0.0)
    assert rd.dissipated[-1] > 0
    assert np.max(np.abs(rd.numerical_dissipation)) < 1e-5 * np.max(np.abs(rd.work))


def test_damping_tangents_against_finite_differences():
    k, m1, c, m2, m3 = 3.0e9, 1.24, 1.15e11, 1.0, 1.5
    for d, v in ((2e-6, 0.03), (1e-6, -0.002), (3e-6, 0.0)):
        f = contact_force(d, v, k, m1, c, m2, m3)
        kd, cd = contact_damping_tangents(d, v, f, c, m2, m3)
        hd, hv = 1e-12, 1e-6
        fd_d = (contact_force(d + hd, v, k, m1, c, m2, m3) - contact_force(d - hd, v, k, m1, c, m2, m3)) / (2 * hd)
        fd_d -= contact_tangent(d, k, m1)
        fd_v = (contact_force(d, v + hv, k, m1, c, m2, m3) - contact_force(d, v - hv, k, m1, c, m2, m3)) / (2 * hv)
        assert kd == pytest.approx(fd_d, rel=1e-4, abs=1e-6 * contact_tangent(d, k, m1))
        assert cd == pytest.approx(fd_v, rel=1e-5)
    assert contact_damping_tangents(1e-8, -100.0, 0.0, c, m2, m3) == (0.0, 0.0)     # clipped
    for n_c in (1.0, 1.5):
        v = 0.7
        fd = -(spring_torque(0, v + 1e-7, 0, 1, 6e-5, n_c) - spring_torque(0, v - 1e-7, 0, 1, 6e-5, n_c)) / 2e-7
        assert spring_damping_tangent(v, 6e-5, n_c) == pytest.approx(fd, rel=1e-6)


def test_newton_failure_is_named(damped):
    with pytest.raises(DivergenceError, match=r"Newton failure at t = .* s \(step \d+, dt = "):
        simulate_implicit(damped, *RUN, dt=2e-6, max_iter=1, raise_on_failure=True)
    r = simulate_implicit(damped, *RUN, dt=2e-6, max_iter=1)
    assert r.status == 4 and np.all(np.isfinite(r.te))


def test_implicit_stays_stable_far_above_the_explicit_bound(damped):
    dt_b, _w = stable_time_step(damped, 50.0, safety=1.0)
    r = simulate_implicit(damped, *RUN, dt=10e-6, alpha=-0.1)
    assert r.dt > 7 * dt_b and r.status == 0
    ex = simulate(damped, *RUN, dt=1.25e-7)
    # stable and bounded, not accurate: at 8x the explicit bound the step error is about 2 um
    assert np.max(np.abs(r.te - ex.te[::1])) < 4e-6


def test_explicit_step_bound_matches_the_eigenvalues(undamped):
    """Verlet is stable for omega*dt < 2 with omega the highest eigenfrequency of the loaded,
    linearised pair: 0.9 of the bound runs, 1.2 of it is caught by the guard naming the cause,
    time and step. The eigenvalues are those of K x = w^2 M x of `linearized_system`; the
    largest is the tooth on its contact spring (checked against the single-DOF estimate)."""
    dt_b, w = stable_time_step(undamped, 50.0, safety=1.0)
    assert dt_b == pytest.approx(2.0 / w)
    ok = simulate(undamped, 100.0, 0.01, 50.0, 0.01, 0.003, dt=0.9 * dt_b, output_step=0.9 * dt_b)
    assert ok.status == 0
    with pytest.raises(DivergenceError, match=r"(penetration|energy growth|non-finite).* at t = .* s \(step \d+"):
        simulate(undamped, 100.0, 0.01, 50.0, 0.01, 0.003, dt=1.2 * dt_b, output_step=1.2 * dt_b,
                 raise_on_failure=True)
    # the highest mode is bounded by a tooth on its spring plus its contact (Rayleigh)
    M, K, _teeth = linearized_system(undamped, 0.0, undamped.theta2_for_te(0.0, undamped.backlash_offset + 5e-6),
                                     np.zeros(undamped.n_teeth))
    diag_max = math.sqrt(np.max(np.diag(K)[1:] / np.diag(M)[1:]))
    assert 0.5 * diag_max < w < 3.0 * diag_max
    assert highest_frequency(undamped, 50.0, positions=24) == pytest.approx(w, rel=0.05)


def test_scene_selects_the_integrator():
    sc = solid_scene(**{"dynamic.duration": 0.001, "dynamic.ramp_time": 0.0005, "dynamic.method": "implicit",
                        "dynamic.alpha": -0.05, "dynamic.time_step": 2e-6})
    ds = run_scene(sc, static=False)
    assert ds.attrs["dynamic_method"] == "implicit" and ds.attrs["hht_alpha"] == -0.05
    assert ds.attrs["dt_s"] == pytest.approx(2e-6)
    auto = run_scene(sc.replace(**{"dynamic.method": "auto", "dynamic.time_step": 0.0}), static=False)
    assert auto.attrs["dynamic_method"] == "explicit" and "auto: explicit" in auto.attrs["dynamic_method_reason"]
    m = build_scene_model(sc)
    ch = choose_method(m, 50.0, 10.0, "auto", limits=MethodLimits(max_explicit_steps=1e5))
    assert ch.method == "implicit" and ch.dt > 2.0 / ch.omega_max
    with pytest.raises(SceneError, match="dynamic.alpha"):
        solid_scene(**{"dynamic.alpha": 0.2})
    with pytest.raises(SceneError, match="dynamic.method"):
        solid_scene(**{"dynamic.method": "rk4"})
    with pytest.raises(ValueError, match="alpha"):
        simulate_implicit(m, *RUN, alpha=-0.5)


def test_step_bound_includes_the_contact_damping():
    """A soft contact (k_con x 0.01) sits 40 um deep under load, where its damping term
    c*delta^1.5 overdamps the tooth-on-contact mode: Verlet with the damper at the predicted
    velocity is then limited by the damping, 2/w (sqrt(1 + 4 zeta²) - 2 zeta) for one mode
    (`verlet_damped_limit`), far below 2/w. The scene runs at half the bound that includes it,
    its energy balance closed; a little past that bound (1.2x) and at the undamped bound the
    guard catches it. (The raw contact damper: a damping ratio puts the mesh damping in the
    tooth-root joints instead.)"""
    from solver.mbs.stability import stability_limit
    m = build_scene_model(solid_scene(**RAW_DAMPING, **{"contact.k_con": 5.64e4}))
    dt_crit, w = stability_limit(m, 50.0)
    assert dt_crit < 0.1 * 2.0 / w
    ok = simulate(m, 100.0, 0.002, 50.0, 0.002, 0.003, dt=0.5 * dt_crit)
    assert ok.status == 0 and ok.time[-1] == pytest.approx(0.003)
    past = simulate(m, 100.0, 0.002, 50.0, 0.002, 0.003, dt=1.2 * dt_crit)
    assert past.status != 0
    bad = simulate(m, 100.0, 0.002, 50.0, 0.002, 0.003, dt=0.5 * 2.0 / w)
    assert bad.status != 0 and "at t = " in bad.message

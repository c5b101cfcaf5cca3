"""Pitch errors and eccentricity in the multibody statics: the closed-form runout TE of a
near-rigid pair, the rigid-tooth limit against the brute-force first touch of the displaced
flanks (with and without relief), and the orders a random set of pitch errors excites."""
import math

import numpy as np
from test_relief import RELIEF, RIGID, first_order_shift, kinematic_te, small

from solver.mbs.kernels import layout as L
from solver.mbs.statics import solve_static
from solver.pitch_errors import iso1328_pitch_tolerances
from study.scene import error_period
from study.scene_model import geometry_model, static_angles

PITCH = 15.0        # deg: one mesh pitch of the 24-tooth pair
STIFF = {"gear1.spring.k_phi": 1e8, "gear2.spring.k_phi": 1e8, "gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0,
         "contact.k_con": 1e6, "contact.m1": 1.0}


def _single_tooth(z: int, k: int, f_um: float) -> list:
    """Single pitch deviations that advance tooth k alone by f_um along the reference circle."""
    f = [0.0] * z
    f[k] += f_um
    f[(k + 1) % z] -= f_um
    return f


def _harmonic(angle, signal, rate):
    """Amplitude and phase [rad] of A*cos(rate*angle - phase) fitted by least squares
    together with a constant (one component; the record holds whole periods of it)."""
    a = np.column_stack([np.ones_like(angle), np.cos(rate * angle), np.sin(rate * angle)])
    c = np.linalg.lstsq(a, signal, rcond=None)[0]
    return math.hypot(c[1], c[2]), math.atan2(c[2], c[1])


def test_eccentricities_give_the_closed_form_runout_te_of_each_gear():
    """Both gears eccentric (5 um at 30 deg, 3 um at -50 deg), Z1 = 24, Z2 = 30, a stiff pair at a
    small torque (elastic approach ~30 nm; its mesh-order ripple is orthogonal to the gear orders
    over whole periods; the near-rigid pair of RIGID makes the statics' Newton cycle between
    contact sets at a few angles): over the hunting period (5 driver revolutions, chosen by the scene) the static
    TE is c - e1*cos(theta1 + gamma1 + ph1 - psi_n) + e2*cos(theta2 + gamma2 + ph2 - psi_n), psi_n
    = 90 deg - alpha the drive line of action's direction (the offset of a centre along the
    contact normal; across it, first order zero for involutes). Each gear's once-per-revolution
    component (theta2 = -theta1*Z1/Z2: order 1 and 0.8 of the driver) within 1 % and 0.5 deg."""
    e = {"gear1.errors.eccentricity": 5.0, "gear1.errors.eccentricity_phase": 30.0,
         "gear2.errors.eccentricity": 3.0, "gear2.errors.eccentricity_phase": -50.0}
    scene = small(**STIFF, **e, **{"gear2.teeth": 30, "quasi_static.angle_step": 3.0})
    assert error_period(scene) == 1800.0
    angles = static_angles(scene)
    assert angles[-1] == math.radians(1800.0)
    model = geometry_model(scene)
    st = solve_static(model, angles[:-1], 1.0)
    assert st.converged.all()
    psi_n = math.pi / 2 - model.pair.pressure_angle
    gp = model.gear_par
    a1, p1 = _harmonic(angles[:-1], st.te, 1.0)
    a2, p2 = _harmonic(angles[:-1], st.te, 24 / 30)
    assert abs(a1 - 5e-6) < 0.01 * 5e-6 and abs(a2 - 3e-6) < 0.01 * 3e-6, (a1, a2)
    # -e1*cos(theta1 + c1) = e1*cos(theta1 - (pi - c1)); e2*cos(-0.8 theta1 + c2) = e2*cos(0.8 theta1 - c2)
    c1 = gp[0, L.GAMMA0] + math.radians(30.0) - psi_n
    c2 = gp[1, L.GAMMA0] + math.radians(-50.0) - psi_n
    wrap = lambda x: (x + math.pi) % (2 * math.pi) - math.pi     # noqa: E731
    assert abs(wrap(p1 - (math.pi - c1))) < math.radians(0.5), math.degrees(wrap(p1 - (math.pi - c1)))
    assert abs(wrap(p2 - c2)) < math.radians(0.5), math.degrees(wrap(p2 - c2))


def test_single_advanced_tooth_gives_a_pulse_as_the_displaced_flanks_touch():
    """Tooth 5 of the driver advanced by f_pt = 4 um (its flanks turned by 4 um/r about the
    centre; F_p = 4 um for tooth 5 only): while it is in the mesh it alone carries and the rigid
    TE drops by f_pt*cos(alpha); it meets its mate early at the mate's tip corner and leaves
    late. The static TE of the near-rigid pair equals the brute-force first touch of the
    sampled, displaced flanks at every other angle across its passage, from two degrees before
    its first touch to two after its last (within the stiff pair's elastic approach, 4 nm, and
    the sampling, 1 nm); the perfect pair reads a flat TE there. The window of 41 degrees
    holds the passage (contact ratio * 15 deg, about 25) with room to see a wider one."""
    scene = small(**RIGID, **{"gear1.errors.pitch": _single_tooth(24, 5, 4.0)})
    model = geometry_model(scene)
    # tooth 5's axis is on the line of centres at theta1 = -5 pitches
    angles = np.radians(np.arange(-5 * PITCH - 20.0, -5 * PITCH + 20.5, 1.0))
    st = solve_static(model, angles, 1.0)
    rel = st.te - model.backlash_offset
    assert abs(rel.min() + 4e-6 * math.cos(model.pair.pressure_angle)) < 10e-9
    assert abs(rel.max()) < 10e-9                               # the other teeth: no error
    width = np.count_nonzero(rel < -2e-6)                       # degrees in the pulse
    assert model.pair.contact_ratio * PITCH < width < model.pair.contact_ratio * PITCH + 8, width
    inside = np.nonzero(rel < -10e-9)[0]                        # the passage, its edges included
    assert inside[0] >= 2 and inside[-1] <= angles.size - 3     # flat TE on both sides
    sel = slice(inside[0] - 2, inside[-1] + 3, 2)
    ref = np.array([kinematic_te(scene, model, a) for a in angles[sel]])
    np.testing.assert_allclose(st.te[sel], ref, atol=5e-9, rtol=0)


def test_rigid_pair_with_pitch_errors_and_relief_reads_the_kinematic_te():
    """Grade-6 random pitch errors on the driver (seed 1) with the relief of test_relief and an
    eccentric driven gear (2 um): the near-rigid static TE against the brute-force first touch
    of the displaced, modified flanks, with the relief's first-order term, within the relief
    test's tolerance, every 3 degrees over two mesh pitches (five points of the mesh cycle on
    two different sets of teeth)."""
    scene = small(**RIGID, **RELIEF, **{"gear1.errors.grade": 6, "gear1.errors.seed": 1,
                                        "gear2.errors.eccentricity": 2.0, "gear2.errors.eccentricity_phase": 80.0})
    model = geometry_model(scene)
    angles = np.radians(np.arange(0.0, 2 * PITCH, 3.0))
    st = solve_static(model, angles, 1.0)
    ref = np.array([kinematic_te(scene, model, a) for a in angles])
    shift = np.array([first_order_shift(scene, model, a) for a in angles])
    slope = 10e-6 * model.base_radii[0] / 6e-3
    tol = slope * model.gear_par[0, L.DEV_DU] / 4 + 10e-9 + 15e-9
    assert np.ptp(ref) > 2e-6                   # errors and relief show in the kinematic TE
    np.testing.assert_allclose(st.te, ref + shift, atol=tol, rtol=0)


def test_random_pitch_errors_excite_the_gear_orders_and_mesh_sidebands():
    """Grade-6 random pitch errors on the driver of the near-rigid pair over one revolution (the
    scene's period) at 1 deg: the TE repeats after the revolution; its order-1 component (per
    driver revolution) follows the first harmonic of the cumulative pitch curve along the line
    of action, -F_p,k*cos(alpha) with tooth k at the mesh at theta1 = -k pitches (within 25 %
    and 15 deg: the rigid TE follows the most advanced tooth in the mesh, not each tooth's own
    F_p); the orders Z +- 1, Z +- 2 around the mesh order Z = 24 stand 100 times above the
    perfect pair's (whose only modulation, the contact's few nm, is at the mesh harmonics) and
    above 0.2 % of the order-1 component (measured: 0.7 to 3 %)."""
    errs = {"gear1.errors.grade": 6, "gear1.errors.seed": 1}
    scene = small(**RIGID, **errs, **{"quasi_static.angle_step": 1.0})
    angles = static_angles(scene)
    assert angles.size == 361
    model = geometry_model(scene)
    st = solve_static(model, angles, 1.0)
    assert st.converged.all()
    assert abs(st.te[-1] - st.te[0]) < 1e-11
    te = st.te[:-1]
    spec = np.abs(np.fft.rfft(te)) * 2 / te.size
    perfect = solve_static(geometry_model(small(**RIGID)), angles[:-1], 1.0).te
    spec0 = np.abs(np.fft.rfft(perfect)) * 2 / perfect.size
    fp = np.asarray(scene.errors_spec(1).cumulative(24))
    curve = -fp * math.cos(model.pair.pressure_angle)           # at theta1 = -k pitches
    k = np.arange(24)
    c = np.sum(curve * np.exp(1j * k * math.radians(PITCH))) * 2 / 24   # e^{-i theta}, theta = -k pitch
    fft1 = np.fft.rfft(te)[1] * 2 / te.size
    assert abs(abs(fft1) - abs(c)) < 0.25 * abs(c), (abs(fft1), abs(c))
    assert abs(np.angle(fft1 / c)) < math.radians(15.0)
    for n in (1, 2):
        for o in (24 - n, 24 + n):
            assert spec[o] > 100 * spec0[o] + 0.002 * abs(c), (o, spec[o], spec0[o])


def test_grade_sets_hold_the_class_tolerances():
    """The random set of a class: closed, |f_pt| <= f_pT and max - min of F_p <= F_pT, a real
    share of the tolerance used; the same seed gives the same set, another seed another."""
    scene = small(**{"gear1.errors.grade": 5, "gear1.errors.seed": 3})
    geo = geometry_model(scene).geometry[0]
    f_pt, f_p = iso1328_pitch_tolerances(2 * geo.pitch_radius, geo.spec.module, 5)
    err = scene.errors_spec(1)
    f = np.asarray(err.pitch)
    assert abs(f.sum()) < 1e-12
    assert np.abs(f).max() <= f_pt and np.ptp(err.cumulative(24)) <= f_p
    assert np.ptp(err.cumulative(24)) > 0.5 * f_p
    assert scene.errors_spec(1) == err
    assert small(**{"gear1.errors.grade": 5, "gear1.errors.seed": 4}).errors_spec(1) != err


def test_a_dynamic_run_with_errors_starts_touching_without_penetration():
    """The rigid start of a run: perfect gears at jn/2; with an eccentric driver whose centre
    points into the mesh at t = 0 the first touch comes earlier (a start at jn/2 would penetrate
    by microns and kick the run): at the start TE no drive contact penetrates, 1 nm further one
    does, and the start lies the driver's offset along the line of action, e*cos(gamma1 + phase
    - psi_n), below jn/2 (first order: within 2 nm)."""
    from solver.mbs.dynamics import start_te
    from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
    scene = small(**{"gear1.errors.eccentricity": 5.0, "gear1.errors.eccentricity_phase": 20.0})
    model = geometry_model(scene)
    assert start_te(geometry_model(small()), 1.0) == model.backlash_offset
    te0 = start_te(model, 1.0)
    psi_n = math.pi / 2 - model.pair.pressure_angle
    assert abs(model.backlash_offset - te0 - 5e-6 * math.cos(math.radians(20.0) - psi_n)) < 2e-9
    rec, pairs = new_contact_buffer()
    zeros = np.zeros(model.n_teeth)
    for te, n in ((te0, 0), (te0 + 1e-9, 1)):
        nc, _ = mesh_contacts((0.0, model.theta2_for_te(0.0, te), 0.0, 0.0), zeros, zeros,
                              contact_geo(model.gear_par, model.pair_par, model.law_par), (rec, pairs))
        assert (nc > 0) == (n > 0)

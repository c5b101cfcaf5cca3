"""The FE reference (LTCA) and the multibody statics on a pair with a pitch error and an
eccentricity: they agree as well as they do on perfect gears."""
import math

import numpy as np
import pytest
from test_ltca import small_scene
from test_ltca_relief import FE_SPRINGS

from solver.fe.ltca import error_approach, mesh_points
from solver.mbs.kernels import layout as L
from solver.mbs.statics import solve_static
from study.scene_model import build_scene_model, geometry_model
from study.verify import fe_reference as ref_mod

pytestmark = pytest.mark.usefixtures("private_fe_cache")

# driver tooth 1 advanced by 3 um (the pitches before and after it 3 um longer and shorter), the
# driven gear's teeth 4 um off its bearing axis
ERRORS = {"gear1.errors.pitch": [0.0, 3.0, -3.0] + [0.0] * 21, "gear2.errors.eccentricity": 4.0,
          "gear2.errors.eccentricity_phase": 60.0}
ANGLES = np.radians(np.arange(-30.0, 0.01, 0.5))    # tooth 1's passage through the mesh


def _difference(scene):
    """(FE reference STE, statics STE - reference) [m] at ANGLES."""
    ref, _, _ = ref_mod.reference(scene, ANGLES)
    st = solve_static(build_scene_model(scene), ANGLES, scene.quasi_static.torque)
    assert st.converged.all()
    return ref.te, st.te - ref.te


def test_reference_and_statics_agree_on_a_pair_with_errors():
    """Tooth 1 of the driver advanced by 3 um (F_p = 3 um on it alone) and a 4 um eccentric
    driven gear, at 100 N*m: the errors change the reference STE by microns over tooth 1's
    passage (6.7 um: the runout and the advance), and the statics follow them: the difference of
    the two models (mean and spread) stays within 1.5 times what it is on the perfect pair, plus
    0.05 um (measured: mean 0.096 -> 0.099 um, spread 0.137 -> 0.137 um)."""
    plain = small_scene(**FE_SPRINGS)
    faulty = plain.replace(**ERRORS)
    te0, d0 = _difference(plain)
    te1, d1 = _difference(faulty)
    assert np.max(np.abs(te1 - te0)) > 1e-6                     # the errors matter to the reference
    assert abs(d1.mean()) <= 1.5 * abs(d0.mean()) + 0.05e-6, (d0.mean(), d1.mean())
    assert np.std(d1) <= 1.5 * np.std(d0) + 0.05e-6, (np.std(d0), np.std(d1))


def test_reference_gaps_hold_the_errors_approach():
    """The LTCA's initial separation of a flank contact shrinks by the tooth pair's first-order
    approach: rb1*eps of the driver tooth plus the driven centre's offset along the line of
    action, e2*cos(theta2 + gamma2 + phase - psi_n), written out here from the scene."""
    plain = small_scene()
    s = plain.replace(**ERRORS)
    m0, m1 = geometry_model(plain), geometry_model(s)
    g1 = m1.geometry[0]
    psi_n = math.pi / 2 - m1.pair.pressure_angle
    for th in np.radians(np.arange(-30.0, 0.0, 1.0)):
        a, b = mesh_points(m0, th), mesh_points(m1, th)
        np.testing.assert_array_equal(a.u1, b.u1)
        th2 = m1.theta2_for_te(th, m1.backlash_offset)
        eps = np.where(b.tooth1 % 24 == 1, 3e-6 / g1.pitch_radius, 0.0)
        e2 = 4e-6 * math.cos(th2 + m1.gear_par[1, L.GAMMA0] + math.radians(60.0) - psi_n)
        np.testing.assert_allclose(a.gap - b.gap, g1.base_radius * eps - e2, atol=1e-15, rtol=0)
        np.testing.assert_allclose(error_approach(m1, th, th2, b.tooth1, b.tooth2), a.gap - b.gap, atol=1e-15)

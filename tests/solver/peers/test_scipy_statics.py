"""scipy root-loop peer of the static solver (`solver.peers.scipy_statics`): same equations,
every tooth free, so it must give the same STE and contact count as `solve_static`."""
import numpy as np
import pytest
from helpers import solid_scene

from solver.mbs.statics import solve_static
from solver.peers.scipy_statics import static_te_root
from study.scene_model import build_scene_model


@pytest.fixture(scope="module")
def model():
    return build_scene_model(solid_scene())


def test_agrees_with_solve_static_across_contact_changes(model):
    # 4 deg of driver rotation at 0.2 deg: more than one mesh cycle (5.37 deg), so the
    # angles cross zones with different numbers of loaded contacts
    angles = np.radians(np.arange(0.0, 4.0001, 0.2))
    ref = solve_static(model, angles, 50.0)
    peer = static_te_root(model, angles, 50.0)
    assert np.all(peer.converged)
    assert len(set(ref.n_contacts)) >= 2          # the number of loaded contacts changes
    np.testing.assert_array_equal(peer.n_contacts, ref.n_contacts)
    assert np.max(np.abs(peer.te - ref.te)) < 1e-12          # m: 1e-6 um
    np.testing.assert_allclose(peer.tooth_force, ref.tooth_force, atol=1e-4)   # N


def test_reversed_torque_loads_the_coast_flanks(model):
    """Negative torque: TE below minus the backlash offset, same as the Newton solver."""
    angles = np.radians([0.0, 0.5, 1.0])
    ref = solve_static(model, angles, -50.0)
    peer = static_te_root(model, angles, -50.0)
    assert np.all(peer.te < -model.backlash_offset)
    assert np.max(np.abs(peer.te - ref.te)) < 1e-12


def test_bad_angles_name_the_field(model):
    with pytest.raises(ValueError, match="angles"):
        static_te_root(model, [], 50.0)

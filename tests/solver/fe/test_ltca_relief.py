"""The FE reference (LTCA) and the multibody statics on a relieved pair: they agree as well as
they do on perfect involutes."""
import numpy as np
import pytest
from test_ltca import small_scene

from solver.fe.ltca import mesh_points
from solver.mbs.kernels import layout as L
from study.run import run_static
from study.scene_model import build_scene_model, geometry_model
from study.verify import fe_reference as ref_mod

pytestmark = pytest.mark.usefixtures("private_fe_cache")

# the teeth coupled through the FE bodies (the model closest to the reference), a coarse mesh
FE_SPRINGS = {"coupling.model": "compliance", "fe.mesh_size": 1.8, "quasi_static.angle_step": 0.5}


def _errors(scene):
    """(FE reference STE, statics STE - reference) [m] over one mesh pitch."""
    ref, _, _ = ref_mod.reference(scene)
    st = run_static(scene, build_scene_model(scene))
    assert st.converged.all()
    return ref.te, st.te - ref.te


def test_reference_and_statics_agree_on_a_relieved_pair():
    """Tip relief on both gears (10 um, linear, 4 mm along the path of contact): the relief
    changes the reference STE by microns (p2p 3.6 -> 0.9 um), and the statics follow it: the
    difference of the two models (mean and spread) stays within 1.5 times what it is on the
    unmodified pair, plus 0.05 um (measured: mean 0.09 -> 0.15 um, spread 0.14 -> 0.13 um)."""
    plain = small_scene(**FE_SPRINGS)
    relief = {f"gear{g}.modification.{k}": v for g in (1, 2) for k, v in (("tip_relief", 10.0), ("tip_length", 4.0))}
    relieved = plain.replace(**relief)
    te0, d0 = _errors(plain)
    te1, d1 = _errors(relieved)
    assert np.ptp(te1) < 0.5 * np.ptp(te0)                      # the relief matters to the reference
    assert abs(d1.mean()) <= 1.5 * abs(d0.mean()) + 0.05e-6
    assert np.std(d1) <= 1.5 * np.std(d0) + 0.05e-6


def test_reference_gaps_hold_the_deviations():
    """The LTCA's initial separation of a flank contact grows by the relief at the contact roll
    (to within the rounding of the relief's kink by the deviation table)."""
    plain = small_scene()
    s = plain.replace(**{"gear1.modification.tip_relief": 10.0, "gear1.modification.tip_length": 4.0})
    m0, m1 = geometry_model(plain), geometry_model(s)
    g = m1.geometry[0]
    mod = s.modification_spec(1)
    seen = 0.0
    for th in np.radians(np.arange(0.0, 15.0, 1.0)):
        a, b = mesh_points(m0, th), mesh_points(m1, th)
        np.testing.assert_array_equal(a.u1, b.u1)
        dev = mod.deviation(b.u1, g.u_form, g.u_tip)
        flank = b.kind == 1
        table = 10e-6 / (4e-3 / g.base_radius) * m1.gear_par[0, L.DEV_DU] / 4    # the table's rounding of the kink
        np.testing.assert_allclose((b.gap - a.gap)[flank], dev[flank], atol=table + 1e-12, rtol=0)
        seen = max(seen, float(np.max(dev[flank], initial=0.0)))
    assert seen > 1e-6                          # a relieved contact was among them

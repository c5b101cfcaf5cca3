"""Modes of the loaded pair and damping given as a ratio of critical: a two-inertia closed
form in the rigid-tooth limit, the simulated free decay, and the conversion of the ratios."""
import math

import numpy as np
import pytest

import study
from solver.mbs.equilibria import loaded_equilibria
from solver.mbs.kernels import layout as L
from solver.mbs.modes import modal_analysis
from solver.mbs.ringdown import ring_down
from study.scene_model import build_scene_model

SOLID = {"gear2.body.holes": 0, "gear2.body.web_thickness": 17.0, "dynamic.torque": 50.0, "coupling.model": "paper"}


def _model(**over):
    return build_scene_model(study.default_scene().replace(**SOLID, **over))


def test_rigid_teeth_mesh_mode_is_the_two_inertia_closed_form():
    """Tooth springs 1e6 x stiffer: the mesh mode is the driven inertia I2 on the mesh spring
    k_m rb2² (driver prescribed), k_m = the contact tangents along the line of action, summed
    over the loaded pairs: w² = k_m rb2² / I2 at every mesh position."""
    m = _model(**{"gear1.spring.k_phi": 1.06e12, "gear2.spring.k_phi": 1.06e12, "contact.c_con": 0.0,
                  "gear1.spring.c_phi": 0.0, "gear2.spring.c_phi": 0.0})
    from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
    md = modal_analysis(m, 50.0)
    rb2 = m.base_radii[1]
    for j, eq in enumerate(loaded_equilibria(m, 50.0)):
        rec, pairs = new_contact_buffer()
        nc, _np = mesh_contacts((eq.rim1, eq.rim2, 0.0, 0.0), eq.phi, np.zeros(m.n_teeth),
                                contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
        km = sum(rec[c, L.C_KT] for c in range(nc) if rec[c, L.C_FORCE] > 0)
        f = math.sqrt(km * rb2 ** 2 / m.gear_par[1, L.I_TOT]) / (2 * math.pi)
        assert md.frequency[0, j] == pytest.approx(f, rel=0.01)
    assert md.kind[0] == "mesh"


@pytest.mark.parametrize("zeta", [0.05, 0.1])
def test_requested_mesh_ratio_is_what_the_modes_and_the_free_decay_show(zeta):
    """The mesh ratio, carried by the tooth-root joint dampers: the modal mean over the mesh
    period is the requested ratio (to the root finder's tolerance); the simulated free decay
    at driver angle 0 gives the modal ratio there within 3 % (the decay swings the load by
    +-10 %, where the power laws change the tangents by a few percent) and its frequency
    within 1 %; against the requested ratio the tolerance is the spread over the mesh period."""
    m = _model(**{"contact.damping_ratio": zeta})
    assert m.law_par[L.C_CON] == 0.0 and m.gear_par[0, L.C_PHI] > 0
    md = modal_analysis(m, 50.0)
    assert np.nanmean(md.damping[0]) == pytest.approx(zeta, rel=1e-4)
    rd = ring_down(m, 50.0, md.frequency[0, 0], md.damping[0, 0])
    assert rd.damping == pytest.approx(md.damping[0, 0], rel=0.03)
    assert rd.frequency == pytest.approx(md.frequency[0, 0], rel=0.01)
    spread = np.nanmax(md.damping[0]) - np.nanmin(md.damping[0])
    assert abs(rd.damping - zeta) <= spread + 0.03 * zeta


def test_tooth_ratio_with_a_raw_contact_and_raw_coefficients():
    """Tooth dampers as a ratio of the tooth's own mode (the contact given by c_con): 2 % is
    the 6.2e-5 N·m·s/rad the scenes used before, and with no contact damper the tooth modes of
    the linearised pair (the tooth on its spring, stiffened a little by the contact and
    coupled to its neighbour) come out within 10 % of it; raw coefficients stay as given."""
    m = _model(**{"gear1.spring.damping_ratio": 0.02, "gear2.spring.damping_ratio": 0.02, "contact.c_con": 0.0})
    assert m.gear_par[0, L.C_PHI] == pytest.approx(6.2e-5, rel=0.03)
    md = modal_analysis(m, 50.0)
    # the two lowest tooth modes (~60 kHz; median over the mesh period: where a tooth enters
    # the mesh lightly loaded, its soft spring tangent gives a slower, relatively more damped mode)
    tooth = np.nanmedian(md.damping[1:3], axis=1)
    assert np.all(np.abs(tooth - 0.02) < 0.002), tooth
    raw = _model(**{"contact.c_con": 3640.0, "gear1.spring.c_phi": 0.062, "gear2.spring.c_phi": 0.062})
    assert raw.gear_par[0, L.C_PHI] == pytest.approx(6.2e-5)
    assert raw.law_par[L.C_CON] == pytest.approx(study.scene.units.contact_damping_to_si(3640.0, 1.0, 1.5))
    with pytest.raises(study.SceneError, match="gear1.spring.c_phi: the mesh damping ratio"):
        _model(**{"gear1.spring.c_phi": 0.062, "contact.damping_ratio": 0.05})


def test_damping_given_both_ways_is_an_error():
    with pytest.raises(study.SceneError, match="contact.damping_ratio"):
        study.scene.loads_scene("[contact]\nc_con = 1.0\ndamping_ratio = 0.1\n")
    with pytest.raises(study.SceneError, match="not both"):
        study.load_scene(overrides=["gear1.spring.c_phi=0.1", "gear1.spring.damping_ratio=0.1"])
    with pytest.raises(study.SceneError, match="gear1.spring.n_c"):
        study.scene.loads_scene("[gear1.spring]\nn_c = 1.5\ndamping_ratio = 0.1\n")
    # an override one way replaces the scene's other way; a saved scene reads back the same
    sc = study.default_scene().replace(**{"contact.c_con": 100.0})
    assert sc.contact.c_con == 100.0 and math.isnan(sc.contact.damping_ratio)
    assert study.scene.loads_scene(sc.to_toml()) == sc

"""Sliding friction on the flanks: the closed-form loss, the regularised law, the energy
balance, the frictionless limit and the scene's checks."""
import dataclasses
import math
import re

import numpy as np
import pytest
from helpers import RAW_DAMPING, solid_scene

from solver.mbs.dynamics import simulate
from solver.mbs.implicit import simulate_implicit
from solver.mbs.kernels import layout as L
from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
from solver.mbs.model import build_model
from solver.mbs.statics import solve_static
from study.errors import SceneError
from study.scene_model import build_scene_model

MU = 0.05


def near_rigid(mu=MU, **over):
    """The paper pair with teeth 1000x stiffer (linear springs): the flanks' contact compliance
    alone, the same in both pairs of a double contact, so they share the load equally."""
    o = {"contact.friction": mu, **RAW_DAMPING, "gear1.spring.c_phi": 2.0, "gear2.spring.c_phi": 2.0}
    for g in (1, 2):
        o[f"gear{g}.spring.k_phi"] = 1.06e9
        o[f"gear{g}.spring.n_k"] = 1.0
    o.update(over)
    return build_scene_model(solid_scene(**o))


def ohlendorf_loss_factor(m):
    """H_V = pi (u + 1)/(z1 u cos beta_b) (1 - eps_a + eps_1^2 + eps_2^2) (spur: beta_b = 0): the
    mean power loss over the input power per unit mu, for the load shared equally in double
    contact and the sliding speed (w1 + w2)|s| at the distance s from the pitch point."""
    g1, g2 = m.geometry
    p = m.pair
    eps = [(math.sqrt(g.tip_radius ** 2 - g.base_radius ** 2) - g.base_radius * math.tan(p.pressure_angle)) / p.base_pitch
           for g in (g1, g2)]
    u = g2.teeth / g1.teeth
    return math.pi * (u + 1) / (g1.teeth * u) * (1 - p.contact_ratio + eps[0] ** 2 + eps[1] ** 2)


def test_static_driver_torque_loss_matches_ohlendorf():
    """Driver torque over three mesh periods of a near-rigid pair at 2 N·m (the extended contact
    of the deflected teeth, which adds loss at the path's ends, below 1 %): the loss
    1 - T2 rb1/(rb2 T1) is mu*H_V within 3 %; without friction it is nil."""
    m = near_rigid()
    rb1, rb2 = m.base_radii
    angles = np.arange(400) * 3 * (2 * math.pi / m.teeth[0]) / 400
    torque = 2.0
    st = solve_static(m, angles, torque, friction_speed=100.0)
    loss = 1 - torque * rb1 / rb2 / st.driver_torque.mean()
    assert loss == pytest.approx(MU * ohlendorf_loss_factor(m), rel=0.03)
    st0 = solve_static(near_rigid(0.0), angles, torque)
    assert abs(1 - torque * rb1 / rb2 / st0.driver_torque.mean()) < 2e-3 * loss
    # the static TE barely moves: friction turns the force by mu, a second-order change in the lever
    assert np.max(np.abs(st.te - st0.te)) < 0.02 * np.max(np.abs(st0.te - m.backlash_offset))


def _contacts(m, th1, w1, w2):
    rec, pairs = new_contact_buffer()
    phi = np.zeros(m.n_teeth)
    te = m.backlash_offset + 0.5e-6
    nc, _ = mesh_contacts((th1, float(m.theta2_for_te(th1, te)), w1, w2), phi, phi, contact_geo(m.gear_par, m.pair_par, m.law_par),
                          (rec, pairs))
    return rec[:nc].copy()


def test_sliding_speed_is_the_rolling_kinematics_and_the_law_is_odd():
    """Rigid rolling at w1 = 100 rad/s: v_s = (w1 + |w2|)*s with s the contact point's distance
    from the pitch point along the line of action (reversing there); reversing the motion
    reverses the friction force and keeps its size (no contact damper: F stays); the force is
    mu*F*tanh(v_s/v_reg)."""
    m = near_rigid(**{"contact.c_con": 0.0})
    rb1, rb2 = m.base_radii
    w1 = 100.0
    w2 = -w1 * rb1 / rb2
    a = m.pair.center_distance
    cx = a * rb1 / (rb1 + rb2)         # pitch point on the line of centres
    signs = set()
    for th1 in np.linspace(0.0, 2 * math.pi / m.teeth[0], 23):
        fwd = _contacts(m, th1, w1, w2)
        back = _contacts(m, th1, -w1, -w2)
        assert fwd.shape[0] > 0
        for c in range(fwd.shape[0]):
            s = (fwd[c, L.C_PX] - cx) * fwd[c, L.C_NX] + fwd[c, L.C_PY] * fwd[c, L.C_NY]
            vs = fwd[c, L.C_VS]
            assert abs(vs) == pytest.approx((w1 + abs(w2)) * abs(s), rel=1e-6, abs=1e-9)
            signs.add(np.sign(vs) * np.sign(s))
            assert fwd[c, L.C_FT] == pytest.approx(MU * fwd[c, L.C_FORCE] * math.tanh(vs / m.law_par[L.V_REG]), rel=1e-12)
            assert back[c, L.C_FT] == pytest.approx(-fwd[c, L.C_FT], rel=1e-12) and back[c, L.C_VS] == pytest.approx(-vs, rel=1e-12)
    assert len(signs) == 1, "the sliding speed must change sign with s, at the pitch point"


def test_without_friction_nothing_depends_on_the_friction_velocity():
    """mu = 0: the friction columns stay zero and the regularisation speed changes no bit."""
    runs = []
    for v in (1.0, 50.0):
        m = build_scene_model(solid_scene(**{"contact.friction_velocity": v}))
        rec = _contacts(m, 0.01, 100.0, -100.0)
        assert np.all(rec[:, L.C_VS:L.C_HB + 1] == 0.0)
        r = simulate(m, 100.0, 0.001, 50.0, 0.001, 0.002)
        st = solve_static(m, np.radians(np.linspace(0, 3, 7)), 50.0, friction_speed=v)
        runs.append((r.te, r.driver_torque, r.dissipated, st.te, st.driver_torque))
    for x, y in zip(*runs):
        assert np.array_equal(x, y)


def with_body_springs(model, k_body=(1.5e6, 1.0e6)):
    """``model`` with body-torsion springs [N m/rad] (the explicit coupled loop)."""
    g1, g2, law, mat = model.inputs
    return build_model(dataclasses.replace(g1, body_stiffness=k_body[0]), dataclasses.replace(g2, body_stiffness=k_body[1]),
                       law, mat)


@pytest.mark.parametrize("method", ["explicit", "implicit", "coupled"])
def test_energy_balance_with_friction(paper_solid_model, method):
    """Work in = kinetic + potential change + dissipation, the friction's mu*F*|v_s| included:
    the balance closes as tightly as without friction, and friction adds to the dissipation."""
    m = build_scene_model(solid_scene(**{"contact.friction": 0.1}))
    m0 = paper_solid_model
    if method == "coupled":
        m, m0 = with_body_springs(m), with_body_springs(m0)
    run = simulate_implicit if method == "implicit" else simulate
    r = run(m, 100.0, 0.002, 50.0, 0.002, 0.005)
    r0 = run(m0, 100.0, 0.002, 50.0, 0.002, 0.005)
    assert r.status == 0 and r0.status == 0
    assert np.max(np.abs(r.energy_error)) < 1e-3 * r.work[-1]
    # at least half the friction loss mu*H_V (H_V about 0.077 here) of the work put in
    assert r.dissipated[-1] - r0.dissipated[-1] > 0.5 * 0.1 * ohlendorf_loss_factor(m) * r.work[-1]


@pytest.mark.parametrize(("key", "value", "words"), [("contact.friction", 0.5, "< 0.5"),
                                                      ("contact.friction", -0.1, ">= 0.0"),
                                                      ("contact.friction_velocity", 0.0, "> 0.0")])
def test_scene_rejects_bad_friction(key, value, words):
    with pytest.raises(SceneError, match=re.escape(key) + ".*" + re.escape(words)):
        solid_scene(**{key: value})


def test_archive_carries_the_mesh_efficiency():
    """A run with friction archives mesh_efficiency [1]: its loss is the friction's mu*H_V (the
    dampers add little at a steady 100 rad/s) within 15 %; a frictionless archive has none."""
    from study.archive.summary import summarize
    from study.run import run_scene
    over = {"dynamic.duration": 0.012, "dynamic.ramp_time": 0.002, "dynamic.spectrum_start": 0.004}
    ds = run_scene(solid_scene(**over, **{"contact.friction": MU}), static=False, dynamic=True)
    eta = ds["mesh_efficiency"]
    assert eta.attrs["units"] == "1" and summarize(ds)["mesh_efficiency"] == float(eta)
    m = build_scene_model(solid_scene(**{"contact.friction": MU}))
    assert 1 - float(eta) == pytest.approx(MU * ohlendorf_loss_factor(m), rel=0.15)
    ds0 = run_scene(solid_scene(**over), static=False, dynamic=True)
    assert "mesh_efficiency" not in ds0 and math.isnan(summarize(ds0)["mesh_efficiency"])

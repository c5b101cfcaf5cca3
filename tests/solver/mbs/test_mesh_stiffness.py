"""Tangent mesh stiffness from the modal linearisation, against finite differences of the
statics; pair shares, the pitch-point lever arm and the condensation."""
import numpy as np
import pytest

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
from solver.mbs.mesh_stiffness import condense, mesh_states, pitch_lever, pitch_point_stiffness
from solver.mbs.statics import solve_static


def test_condensation_of_springs_in_series_and_a_free_dof():
    # ground -k1- DOF 0 -k2- DOF 1 -k3- ground, DOF 2 without stiffness: K00* = k1 + k2 k3 / (k2 + k3)
    k1, k2, k3 = 3.0, 5.0, 7.0
    K = np.array([[k1 + k2, -k2, 0.0], [-k2, k2 + k3, 0.0], [0.0, 0.0, 0.0]])
    k00, x = condense(K)
    assert k00 == pytest.approx(k1 + k2 * k3 / (k2 + k3), rel=1e-14)
    assert x[1] == pytest.approx(k2 / (k2 + k3)) and x[2] == 0.0


def test_mesh_stiffness_is_the_slope_of_two_static_runs(paper_solid_model):
    """k_m at 50 N·m against (F(55) - F(45)) / (TE(55) - TE(45)) over two mesh periods: the
    mean within 2 %, and the tangent within 2 % at the angles away from a change of the
    loaded contacts (where the secant spans a jump of the tangent); the pairs' shares add up."""
    m = paper_solid_model
    ang = np.radians(np.arange(0.0, 360.0 / 67 * 2, 0.05))
    ms = mesh_states(m, ang, 50.0)
    assert ms.converged.all()
    rb2 = m.base_radii[1]
    lo, hi = solve_static(m, ang, 45.0), solve_static(m, ang, 55.0)
    secant = (10.0 / rb2) / (hi.te - lo.te)
    assert ms.stiffness.mean() == pytest.approx(secant.mean(), rel=0.02)
    same = (lo.n_contacts == hi.n_contacts) & (ms.loaded_pairs() == lo.n_contacts)
    assert same.mean() > 0.8
    np.testing.assert_allclose(ms.stiffness[same], secant[same], rtol=0.02)
    np.testing.assert_allclose(ms.pair_stiffness.sum(axis=1), ms.stiffness, rtol=1e-9)
    # the static tooth forces balance the torque along the line of action (tip corners aside)
    np.testing.assert_allclose(ms.tooth_force[:, :67].sum(axis=1) * rb2, 50.0, rtol=0.01)
    np.testing.assert_allclose(ms.tooth_force[:, :67].sum(axis=1), ms.tooth_force[:, 67:].sum(axis=1), rtol=1e-12)


def test_pitch_lever_is_the_contact_gradient_at_the_pitch_point(paper_solid_model):
    """The lever arm of the line of action about the tooth pivot equals d(penetration)/d(phi)
    of the contact search at a contact on the pitch point; a linear spring reads k/h^2."""
    m = paper_solid_model
    rec, pairs = new_contact_buffer()
    z = np.zeros(m.n_teeth)
    rp = m.geometry[0].pitch_radius
    best = (np.inf, 0.0)
    for th in np.radians(np.linspace(-3.0, 3.0, 601)):
        nc, _ = mesh_contacts((th, m.theta2_for_te(th, m.backlash_offset + 2e-6), 0.0, 0.0), z, z,
                              contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
        for c in range(nc):
            d = np.hypot(rec[c, L.C_PX] - rp, rec[c, L.C_PY])
            if d < best[0]:
                best = (d, abs(rec[c, L.C_GA]))
    assert best[0] < 1e-5
    assert pitch_lever(m, 0) == pytest.approx(best[1], rel=2e-3)
    k = pitch_point_stiffness(m, 1000.0)
    n = m.gear_par[0, L.N_K]
    # the tangent from a finite difference of the spring law along the line of action
    h = pitch_lever(m, 0)
    delta = lambda f: h * (f * h / m.k_phi[0]) ** (1 / n)          # noqa: E731
    assert k[0] == pytest.approx(2.0 / (delta(1001.0) - delta(999.0)), rel=1e-6)


def test_loaded_contact_ratio_falls_to_the_geometric_one_as_the_load_vanishes(paper_solid_model):
    """Deflection brings teeth into contact before and after the geometric path (tip corners
    included): the mean number of loaded pairs over whole mesh periods grows with the torque
    and tends to the geometric transverse contact ratio as the load vanishes."""
    from study.archive.mesh import whole_periods
    m = paper_solid_model
    ang = np.radians(np.arange(0.0, 360.0 / 67 * 2, 0.02))
    sel = whole_periods(np.degrees(ang), 67)
    eps = [float(mesh_states(m, ang, t).loaded_pairs()[sel].mean()) for t in (0.5, 5.0, 50.0)]
    assert eps[0] < eps[1] < eps[2]
    assert eps[0] == pytest.approx(m.pair.contact_ratio, rel=0.03) and eps[2] > 1.1 * m.pair.contact_ratio


def _with_body_springs(model, k_body):
    """The plain model with a hub -> rim torsion spring k_body [N·m/rad] on each body."""
    import dataclasses

    from solver.mbs.model import build_model
    g1, g2, law, mat = model.inputs
    return build_model(dataclasses.replace(g1, body_stiffness=k_body[0]), dataclasses.replace(g2, body_stiffness=k_body[1]),
                       law, mat)


def test_mesh_alone_of_a_coupled_pair_is_the_pair_less_its_body_springs_in_series(paper_solid_model):
    """With body springs (hub -> rim) the pair's stiffness at the hubs is the mesh alone in
    series with both bodies: 1/k_m - 1/k_mesh = rb1^2/k_body1 + rb2^2/k_body2 at every angle
    (flank contacts act along the common line of action: exact up to the tip corners' other
    levers); the mesh alone is stiffer, its shares add up to it, and with bodies a million
    times stiffer the two are one."""
    kb = (1.6e6, 2.4e6)
    m = _with_body_springs(paper_solid_model, kb)
    ang = np.radians(np.arange(0.0, 360.0 / 67 * 2, 0.1))
    ms = mesh_states(m, ang, 50.0)
    assert ms.converged.all()
    rb1, rb2 = m.base_radii
    body = rb1**2 / kb[0] + rb2**2 / kb[1]
    rel = (1.0 / ms.stiffness - 1.0 / ms.stiffness_mesh) / body - 1.0
    assert np.max(np.abs(rel)) < 5e-3 and np.median(np.abs(rel)) < 1e-4
    assert np.all(ms.stiffness_mesh > ms.stiffness)
    np.testing.assert_allclose(ms.pair_stiffness_mesh.sum(axis=1), ms.stiffness_mesh, rtol=1e-9)
    rigid = mesh_states(_with_body_springs(paper_solid_model, (1e6 * kb[0], 1e6 * kb[1])), ang, 50.0)
    np.testing.assert_allclose(rigid.stiffness, rigid.stiffness_mesh, rtol=1e-5)
    with pytest.raises(ValueError, match="windup"):
        mesh_states(m, ang[:2], 50.0, windup=(1e-9, 1e-9))


def test_plain_mesh_alone_takes_the_windup_out_of_every_loaded_spring(paper_solid_model):
    """The plain model's springs hold the body wind-up c_w [m/N]: the mesh alone takes c_w/h^2
    (h the pitch lever) out of every loaded spring's compliance. Where one contact carries the
    load, at lever g on each tooth, 1/k_m - 1/k_mesh = c_w1 (g_a/h1)^2 + c_w2 (g_b/h2)^2 exactly;
    without wind-up the mesh alone is the pair; a plain model given none has no mesh alone."""
    m = paper_solid_model
    ang = np.radians(np.arange(0.0, 360.0 / 67, 0.05))
    w = (1.4e-9, 1.1e-9)
    ms = mesh_states(m, ang, 5.0, windup=w)
    h = (pitch_lever(m, 0), pitch_lever(m, 1))
    rec, pairs = new_contact_buffer()
    z = np.zeros(m.n_teeth)
    checked = 0
    for i in np.flatnonzero(ms.loaded_pairs() == 1):
        st = solve_static(m, ang[i:i + 1], 5.0)
        nc, _ = mesh_contacts((ang[i], float(st.theta2[0]), 0.0, 0.0), st.phi_last, z,
                              contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
        loaded = [c for c in range(nc) if rec[c, L.C_FORCE] > 0]
        if len(loaded) != 1:
            continue
        c = loaded[0]
        expect = w[0] * (rec[c, L.C_GA] / h[0]) ** 2 + w[1] * (rec[c, L.C_GB] / h[1]) ** 2
        assert 1.0 / ms.stiffness[i] - 1.0 / ms.stiffness_mesh[i] == pytest.approx(expect, rel=1e-6)
        checked += 1
    assert checked >= 5
    assert np.all(ms.stiffness_mesh > ms.stiffness)
    none = mesh_states(m, ang[:20], 5.0, windup=(0.0, 0.0))
    np.testing.assert_allclose(none.stiffness_mesh, none.stiffness, rtol=1e-12)
    assert np.isnan(mesh_states(m, ang[:3], 5.0).stiffness_mesh).all()
    # a wind-up more than a spring holds (a spring stiffer than the body alone): no mesh alone there
    assert np.isnan(mesh_states(m, ang[:3], 5.0, windup=(1e-6, 0.0)).stiffness_mesh).all()
    with pytest.raises(ValueError, match="windup"):
        mesh_states(m, ang[:3], 5.0, windup=(-1e-9, 0.0))


def test_pitch_point_stiffness_without_the_windup_a_plain_spring_holds(paper_solid_model):
    """A plain spring holds its body's wind-up: the tooth alone at the pitch point is
    1 / (1/k - c_w); more wind-up than the spring holds is refused, naming it."""
    m = paper_solid_model
    k = pitch_point_stiffness(m, 1000.0)
    alone = pitch_point_stiffness(m, 1000.0, windup=(1.4e-9, 0.0))
    np.testing.assert_allclose(alone[:67], 1.0 / (1.0 / k[:67] - 1.4e-9), rtol=1e-12)
    np.testing.assert_allclose(alone[67:], k[67:], rtol=1e-14)
    with pytest.raises(ValueError, match="windup"):
        pitch_point_stiffness(m, 1000.0, windup=(1e-6, 0.0))

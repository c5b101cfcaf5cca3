"""Teeth coupled through the body (the compliance model): the set-stiffness kernel, the
limits, the identification, and statics in single and double contact."""
import dataclasses
import math

import numpy as np
import pytest
from helpers import assert_energy_closes_at_second_order, compiled_call, slow_transient_against_statics, solid_scene

from solver.identify.coupling import InfluenceSamples, tooth_compliance_fit
from solver.identify.pivot import lever
from solver.mbs.kernels import layout as L
from solver.mbs.kernels.toothcoupling import set_energy, set_moment, set_stiffness
from solver.mbs.model import build_model
from solver.mbs.statics import solve_static

RNG = np.random.default_rng(7)


def spd(n, scale=1e-3):
    a = RNG.normal(size=(n, n))
    return scale * (a @ a.T / n + np.eye(n))


@pytest.mark.parametrize("jit", [True, False])
def test_set_stiffness_inverts_the_set_block_and_gives_moments_and_energy(jit):
    """The compiled kernels (through a compiled caller: they have no Python wrapper) and their
    sources run as plain Python (set_energy's call of set_moment too)."""
    from solver.mbs.kernels import python_calls
    f_inv, f_mom, f_en = ((compiled_call(set_stiffness), compiled_call(set_moment), compiled_call(set_energy)) if jit
                          else (set_stiffness.py_func, set_moment.py_func, set_energy.py_func))
    C = spd(9)
    lst = np.array([7, 2, 4, 3, 0, 0, 0, 0, 0])
    n = 4
    ks = np.zeros((9, 18))
    f_inv(C, lst, n, ks)
    S = lst[:n]
    K = np.linalg.inv(C[np.ix_(S, S)])
    assert ks[:n, :n] == pytest.approx(K, rel=1e-10)
    phi = RNG.normal(size=9) * 1e-4
    m = np.array([f_mom(ks, lst, n, phi, a) for a in range(n)])
    assert m == pytest.approx(K @ phi[S], rel=1e-10)
    with python_calls():
        assert f_en(ks, lst, n, phi) == pytest.approx(0.5 * phi[S] @ K @ phi[S], rel=1e-10)


def with_compliance(model, c1, c2, k_body=(math.inf, math.inf), ratio=0.02):
    g1, g2, law, mat = model.inputs
    kw = dict(n_k=1.0, body_damping_ratio=ratio)
    return build_model(dataclasses.replace(g1, tooth_compliance=c1, body_stiffness=k_body[0], **kw),
                       dataclasses.replace(g2, tooth_compliance=c2, body_stiffness=k_body[1], **kw), law, mat)


@pytest.fixture(scope="module")
def linear_pair():
    from study.scene_model import build_scene_model
    return build_scene_model(solid_scene(**{"gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0}))


def ring(z, k, coupling):
    """Compliance [rad/(N m)] of z teeth of own spring k with the neighbours coupled by
    ``coupling`` (fraction of the own compliance, one and two pitches apart)."""
    C = np.eye(z) / k
    for d, c in enumerate(coupling, start=1):
        for a in range(z):
            C[a, (a + d) % z] = C[(a + d) % z, a] = c / k
    return C


def test_diagonal_compliance_is_the_plain_linear_model(linear_pair):
    angles = np.radians(np.arange(0.0, 16.0, 0.25))
    plain = solve_static(linear_pair, angles, 50.0)
    z1, z2 = linear_pair.teeth
    k1, k2 = linear_pair.k_phi[:z1], linear_pair.k_phi[z1:]
    m = with_compliance(linear_pair, np.diag(1 / k1), np.diag(1 / k2))
    assert m.teeth_coupled and not m.coupled
    assert m.k_phi == pytest.approx(linear_pair.k_phi)
    st = solve_static(m, angles, 50.0)
    assert st.te == pytest.approx(plain.te, abs=1e-14)
    assert st.tooth_force == pytest.approx(plain.tooth_force, rel=1e-9, abs=1e-9)


def test_coupling_softens_double_contact_and_leaves_single_contact():
    """A neighbour's load turns a tooth too: where two pairs carry the load the mesh is softer;
    where one pair carries it alone the unloaded neighbours change nothing (the small pair,
    contact ratio 1.6)."""
    from study.scene import load_scene
    from study.scene_model import build_scene_model
    small = build_scene_model(load_scene("small_pair").replace(**{"coupling.model": "paper", "gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0}))
    angles = np.radians(np.arange(0.0, 15.0, 0.1))
    z1, z2 = small.teeth
    k = float(small.k_phi[0])
    plain = solve_static(with_compliance(small, ring(z1, k, ()), ring(z2, k, ())), angles, 50.0)
    coupled = solve_static(with_compliance(small, ring(z1, k, (0.3, 0.1)), ring(z2, k, (0.3, 0.1))), angles, 50.0)
    loaded = plain.n_contacts
    one, two = (loaded == 1) & (coupled.n_contacts == 1), loaded == 2
    assert one.any() and two.any()
    d = coupled.te - plain.te
    assert np.abs(d[one]).max() < 1e-12
    elastic = plain.te[two] - small.backlash_offset
    assert d[two].min() > 0 and np.median(d[two] / elastic) > 0.1


def test_compliance_of_the_body_tooth_model_is_recovered_by_the_fit():
    """Samples made by the model itself (body part + pivot levers, three teeth coupled):
    the fit returns c_body, the pivot and every pair's C."""
    rb, psi_b, z = 0.047, 0.05, 6
    c_body, r_q = 1.3e-9, 0.0465
    C = ring(z, 4000.0, (0.1, 0.02)) * (1 + 0.05 * np.cos(2 * np.pi * np.arange(z) / 3))[:, None]
    C = 0.5 * (C + C.T)
    u = np.linspace(0.25, 0.45, 7)
    pairs, sp, ur, ul, val = [], [], [], [], []
    for a in range(z):
        for d in (-2, -1, 0, 1, 2):
            b = (a + d) % z
            uu = np.column_stack([u, u]) if d == 0 else np.array([(x, y) for x in u for y in u])
            sp.append(np.full(len(uu), len(pairs)))
            pairs.append((a, b))
            ur.append(uu[:, 0]); ul.append(uu[:, 1])
            L = lever(rb, psi_b - uu[:, 0], r_q) * lever(rb, psi_b - uu[:, 1], r_q)
            val.append(c_body + L * C[a, b])
    cat = np.concatenate
    fit = tooth_compliance_fit(InfluenceSamples(np.array(pairs), cat(sp), cat(ur), cat(ul), cat(val)), z, rb, psi_b, (0.044, 0.048))
    assert fit.c_body == pytest.approx(c_body, rel=1e-6)
    assert fit.pivot_radius == pytest.approx(r_q, rel=1e-5)
    assert fit.compliance == pytest.approx(np.where(np.abs(C) > 0, C, 0.0), rel=1e-5)
    assert fit.k_body == pytest.approx(rb**2 / c_body, rel=1e-6)
    assert fit.reach == 2 and fit.rms_rel_error < 1e-6
    with pytest.raises(ValueError, match="pivot_bounds"):
        tooth_compliance_fit(InfluenceSamples(np.array(pairs), cat(sp), cat(ur), cat(ul), cat(val)), z, rb, psi_b, (0.048, 0.044))
    with pytest.raises(ValueError, match="every pair"):
        tooth_compliance_fit(InfluenceSamples(np.array(pairs + [(0, 3)]), cat(sp), cat(ur), cat(ul), cat(val)), z, rb, psi_b,
                             (0.044, 0.048))


def test_bad_compliance_matrices_are_refused(linear_pair):
    z1, z2 = linear_pair.teeth
    k = float(linear_pair.k_phi[0])
    good = ring(z2, k, (0.3,))
    with pytest.raises(ValueError, match="gear1.tooth_compliance: expected"):
        with_compliance(linear_pair, good[:5, :5], None)
    bad = good.copy()
    bad[0, 1] *= 2
    with pytest.raises(ValueError, match="gear2.tooth_compliance: must be finite and symmetric"):
        with_compliance(linear_pair, None, bad)
    with pytest.raises(ValueError, match="positive definite"):
        with_compliance(linear_pair, None, ring(z2, k, (0.9, 0.9)))
    g1, g2, law, mat = linear_pair.inputs
    with pytest.raises(ValueError, match="n_k"):
        build_model(dataclasses.replace(g1, n_k=1.1), dataclasses.replace(g2, n_k=1.0, tooth_compliance=good), law, mat)


# ------------------------------------------------------------------ dynamics

UNDAMPED = {"gear1.spring.c_phi": 0.0, "gear2.spring.c_phi": 0.0, "contact.c_con": 0.0,
            "gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0}
K_BODY = (1.5e6, 1.0e6)    # N m/rad, about the FE values of the paper's solid body
COUPLING = (0.12, 0.07)    # neighbours' share, about the FE fit of the lightened body


def coupled_pair(scene_overrides, coupling=COUPLING, ratio=0.02):
    from study.scene_model import build_scene_model
    m = build_scene_model(solid_scene(**scene_overrides))
    k = float(m.k_phi[0])
    z1, z2 = m.teeth
    return with_compliance(m, ring(z1, k, coupling), ring(z2, k, coupling), K_BODY, ratio)


def test_coupled_teeth_dynamics_conserve_energy():
    """Undamped: the energy balance closes at second order in dt, set changes included (the
    joining and leaving teeth keep the spring moments continuous)."""
    assert_energy_closes_at_second_order(coupled_pair(UNDAMPED, ratio=0.0))


def test_coupled_teeth_slow_transient_follows_statics():
    """At 1 rad/s the dynamics settle on the static STE of the same coupled model."""
    diff, _r, st = slow_transient_against_statics(coupled_pair({"gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0}))
    assert abs(diff.mean()) < 0.03e-6 and np.abs(diff).max() < 0.4e-6     # as the body-torsion model
    uncoupled = solve_static(coupled_pair({"gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0}, ()), st.angle, 50.0)
    assert (st.te - uncoupled.te).mean() > 0.1e-6          # the coupling is really there


def test_diagonal_compliance_dynamics_is_the_body_torsion_model():
    from solver.mbs.dynamics import simulate
    from study.scene_model import build_scene_model
    m = build_scene_model(solid_scene(**{"gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0}))
    z1, z2 = m.teeth
    k1, k2 = m.k_phi[:z1], m.k_phi[z1:]
    bt = with_compliance(m, None, None, K_BODY)
    tc = with_compliance(m, np.diag(1 / k1), np.diag(1 / k2), K_BODY)
    a = simulate(bt, 100.0, 0.002, 50.0, 0.002, 0.003, dt=2e-7)
    b = simulate(tc, 100.0, 0.002, 50.0, 0.002, 0.003, dt=2e-7)
    assert a.status == b.status == 0
    assert b.te == pytest.approx(a.te, abs=1e-15)


@pytest.mark.parametrize("imex", [0.0, 1.0])
def test_coupled_kernel_matches_its_plain_python_run(imex):
    """The compiled coupled loop against the same loop run as plain Python, set changes
    included (300 steps through a change of the candidate teeth), with the tooth-root dampers
    explicit and implicit."""
    from solver.mbs.kernels import python_calls
    from solver.mbs.kernels.explicit_coupled import verlet_coupled
    from solver.mbs.kernels.gearmesh import contact_parts
    from solver.mbs.kernels.stepping import work_arrays
    from solver.mbs.stability import stable_time_step
    m = coupled_pair({"gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0})
    dt, _ = stable_time_step(m, 50.0)
    th2 = float(m.theta2_for_te(0.0, m.backlash_offset))
    runs = []
    for f in (verlet_coupled, verlet_coupled.py_func):
        par = np.zeros(L.N_PAR)
        par[[L.SPEED, L.SPEED_RAMP, L.TORQUE, L.TORQUE_RAMP, L.DT, L.DELTA_MAX, L.ENERGY_TOL, L.IMEX]] = \
            300.0, 1e-9, 50.0, 1e-9, dt, 1e-4, 0.5, imex
        ipar = np.array([300, 1, 0])
        out = np.zeros((301, L.N_OUT))
        hub = np.zeros((3, L.N_HUB))
        # at 300 rad/s from the start the mesh turns a pitch in 0.3 ms: the set changes
        hub[L.POS, L.H_TH2] = hub[L.POS, L.H_H2] = th2
        hub[L.RATE, L.H_R1] = 300.0
        hub[L.RATE, L.H_TH2] = hub[L.RATE, L.H_H2] = -300.0
        teeth = np.zeros((3, m.n_teeth))
        mdl = (m.gear_par, m.pair_par, m.law_par, m.k_phi, m.tooth_compliance, contact_parts(m.gear_par, m.pair_par, m.law_par))
        with python_calls():     # the source run as plain Python down to its wrapper-less callees
            res = f(mdl, (par, ipar, np.zeros((0, 2))), hub, teeth, out, work_arrays(m.n_teeth, m.tooth_compliance))
        runs.append((res, out, teeth[L.POS]))
    (r1, o1, p1), (r2, o2, p2) = runs
    assert r1 == r2 and r1[0] == 0
    assert o1 == pytest.approx(o2, rel=1e-12, abs=1e-18)
    assert p1 == pytest.approx(p2, rel=1e-12, abs=1e-18)


@pytest.mark.parametrize("jit", [True, False])
def test_set_changes_keep_the_spring_moments(jit):
    """A tooth that joins the coupled set unloaded (from rest, as from the frozen set) takes
    the rotation its neighbours give it and changes no moment; a tooth that leaves keeps its
    moment on its own spring."""
    from solver.mbs.kernels import python_calls
    from solver.mbs.kernels.toothcoupling import coupled_set, update_set
    compiled = compiled_call(update_set)

    def f(*args):      # compiled, or its source as plain Python with its callees'
        if jit:
            return compiled(*args)
        with python_calls():
            return update_set.py_func(*args)
    z = 9
    C = ring(z, 800.0, (0.15, 0.05))
    k_own = 1.0 / np.diag(C)
    phi = RNG.normal(size=z) * 1e-4
    dphi = RNG.normal(size=z) * 1e-2
    vpred = dphi.copy()
    cset = coupled_set(C)
    _C, ks, slst, newl, inset, innew, _mo, _dmo = cset

    def joining(teeth):
        newl[:len(teeth)] = teeth
        return len(teeth)

    def moments(ns):
        return {int(slst[a]): set_moment.py_func(ks, slst, ns, phi, a) for a in range(ns)}

    ns = f(cset, 0, joining([3, 4, 5]), phi, dphi, vpred)
    before = moments(ns)
    phi[6] = dphi[6] = vpred[6] = 0.0
    ns = f(cset, ns, joining([3, 4, 5, 6]), phi, dphi, vpred)   # 6 joins
    after = moments(ns)
    for i in (3, 4, 5):
        assert after[i] == pytest.approx(before[i], rel=1e-10)
    assert after[6] == pytest.approx(0.0, abs=1e-12 * abs(before[4]))
    assert phi[6] == pytest.approx(sum(C[6, b] * before[b] for b in (3, 4, 5)), rel=1e-12)
    m3 = after[3]
    ns = f(cset, ns, joining([4, 5, 6]), phi, dphi, vpred)      # 3 leaves
    assert k_own[3] * phi[3] == pytest.approx(m3, rel=1e-10)
    assert ns == 3 and sorted(slst[:ns]) == [4, 5, 6]
    assert list(np.flatnonzero(inset)) == [4, 5, 6] and not innew.any()
    assert vpred == pytest.approx(dphi)            # rates adjusted alike

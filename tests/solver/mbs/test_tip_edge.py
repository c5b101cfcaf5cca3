"""A rounded tip edge (``gearN.modification.tip_edge_radius``, `solver.tip_edge`): the scene key's
checks, the round's geometry, the default model's round contacts (their penetration against the
round's distance to the mating flank, their force against the series law with the Hertz edge
compliance, each computed on its own), nothing changed by a sharp corner, and the default model
against the LTCA with the edge."""
import dataclasses
import math

import numpy as np
import pytest
from helpers import series_force, small_scene, solid_scene

from solver.identify.weber import edge_compliance as weber_edge
from solver.mbs.kernels import layout as L
from solver.mbs.kernels import python_calls
from solver.mbs.kernels.gearmesh import contact_parts, mesh_contacts, new_contact_buffer, pair_contacts
from solver.mbs.model import sample_local_compliance, with_flank_deviations
from solver.modification import ProfileModification
from solver.tip_edge import edge_limit, law_radius, tangent_length, tip_round
from study import SceneError


def _with_series(m):
    """The plain model with a local compliance on both gears (-5e-11 to 1e-9 m/N along the
    profile): the series law the tip edge joins, without the FE."""
    gp = m.gear_par.copy()
    for g in range(2):
        u = np.linspace(gp[g, L.U_LO], gp[g, L.U_HI], 8)
        x = (u - u[0]) / (u[-1] - u[0])
        sample_local_compliance((u, -5e-11 + 1.05e-9 * x**3), gp[g, L.U_LO], gp[g, L.U_HI], gp[g], "gear")
    return dataclasses.replace(m, gear_par=gp)


def _edged(m, r1: float, r2: float):
    return with_flank_deviations(m, (ProfileModification(tip_edge_radius=r1), ProfileModification(tip_edge_radius=r2)),
                                 (None, None))


def _records(m, deg: float, approach: float, python: bool = False):
    """Contact records (sorted by teeth and kind) of model ``m`` at driver angle ``deg``, rigid
    teeth ``approach`` [m] into the mesh; ``python``: the search run as plain Python."""
    th1 = math.radians(deg)
    state = (th1, m.theta2_for_te(th1, m.backlash_offset + approach), 0.0, 0.0)
    phi = np.zeros(m.n_teeth)
    geo = (m.gear_par, m.pair_par, m.law_par, contact_parts(m.gear_par, m.pair_par, m.law_par))
    rec, pairs = new_contact_buffer()
    nc, npair = mesh_contacts(state, phi, phi, geo, (rec, pairs))
    if python:
        ref = np.zeros_like(rec)
        with python_calls():
            n, _ = pair_contacts.py_func(state, phi, phi, geo, (ref, np.zeros_like(pairs)), *geo[3])
        assert n == nc
        np.testing.assert_array_equal(ref[:nc], rec[:nc])
    out = rec[:nc]
    return out[np.lexsort((out[:, L.C_KIND], out[:, L.C_TOOTH2], out[:, L.C_TOOTH1]))]


def test_scene_key_checked_before_any_work():
    """Negative, not finite, a round wider than half the tip land, and an edge under a model
    without the series law are refused naming the field; 0 is a sharp corner (no modification)."""
    s = solid_scene(**{"coupling.model": "compliance"})
    for bad, why in ((-0.05, ">= 0"), (float("nan"), "finite"), (float("inf"), "finite"), ("a", "number"),
                     (0.9, "tip land")):
        with pytest.raises(SceneError, match=f"gear2.modification.tip_edge_radius.*{why}"):
            s.replace(**{"gear2.modification.tip_edge_radius": bad})
    for model in ("paper", "body-torsion"):
        with pytest.raises(SceneError, match=f"gear1.modification.tip_edge_radius.*{model} model"):
            s.replace(**{"gear1.modification.tip_edge_radius": 0.1, "coupling.model": model})
    assert s.modification_spec(1) is None
    assert s.replace(**{"gear1.modification.tip_edge_radius": 0.1}).modification_spec(1).tip_edge_radius == pytest.approx(1e-4)
    # the limit: the two rounds of a tooth (module 1.5, 67 teeth) meet on its 1.15 mm tip land
    g = s.geometry(1)
    limit, why = edge_limit(g)
    assert "tip land" in why and limit * tangent_length(g, 1.0) == pytest.approx(g.tip_radius * g.tip_half_angle)


def test_round_is_tangent_to_the_flank_and_the_tip_circle():
    """The round's centre lies r inside the tip circle and r from the flank along the flank's
    normal at the tangent point; the tip tangent point is on the tip circle, both tangent points
    about r tan((90 deg - alpha_a)/2) from the sharp corner."""
    g = solid_scene().geometry(1)
    r = 0.1e-3
    t = tip_round(g, r)
    c = np.array(t.centre)
    assert np.hypot(*c) == pytest.approx(g.tip_radius - r, rel=1e-12)
    assert np.hypot(*t.tip_point) == pytest.approx(g.tip_radius, rel=1e-12)
    p = np.array(g.flank_point(t.u_flank, 1))
    tau = g.psi_base - t.u_flank
    assert np.allclose(t.flank_point, p, atol=1e-15, rtol=0)
    v = c - p
    assert np.hypot(*v) == pytest.approx(r, rel=1e-9)
    assert abs(v @ [math.cos(tau), math.sin(tau)]) < 1e-9 * r       # along the flank's normal
    corner = np.array(g.flank_point(g.u_tip, 1))
    for q in (t.flank_point, t.tip_point):
        assert np.hypot(*(np.array(q) - corner)) == pytest.approx(tangent_length(g, r), rel=0.02)
    with pytest.raises(ValueError, match="tip edge radius"):
        tip_round(g, 2 * edge_limit(g)[0])


def test_sharp_corner_changes_nothing(paper_solid_model):
    """r = 0 on both gears: the same gear_par and no edge part in the contact search (its code
    left out), the same contact records to the bit; an edge on gear 2 alone leaves every contact
    but gear 2's tip corners alone."""
    m = _with_series(paper_solid_model)
    m0 = _edged(m, 0.0, 0.0)
    np.testing.assert_array_equal(m0.gear_par, m.gear_par)
    assert contact_parts(m0.gear_par, m0.pair_par, m0.law_par).edges is None
    m2 = _edged(m, 0.0, 0.1e-3)
    assert contact_parts(m2.gear_par, m2.pair_par, m2.law_par).edges is m2.gear_par
    # the plain model (no series law) has no edge part either: it refuses the key in a scene
    p2 = _edged(paper_solid_model, 0.1e-3, 0.1e-3)
    assert contact_parts(p2.gear_par, p2.pair_par, p2.law_par).edges is None
    for deg in (3.9, 4.3, 1.2):
        a, b = _records(m, deg, 12e-6), _records(m2, deg, 12e-6)
        np.testing.assert_array_equal(_records(m0, deg, 12e-6), a)
        same = np.abs(a[:, L.C_KIND]) != 3
        np.testing.assert_array_equal(a[same], b[same])
        assert np.all(b[~same, L.C_FORCE] < a[~same, L.C_FORCE])


@pytest.mark.parametrize("deg", [3.9, 4.3])
def test_round_contact_is_the_series_law_with_the_edge(paper_solid_model, deg):
    """At single contact, 25 um into the mesh, the neighbours' tips touch; with tip edges of
    0.1 mm (gear 1) and 0.05 mm (gear 2) each round's contact has the penetration of its circle
    into the mating flank (checked against the distance of the round's centre, placed from
    `solver.tip_edge.tip_round`, to a densely sampled flank), its c_loc is the plain corner's plus
    the Hertz edge compliance 2/(pi E b) ln(R_law / r_eq) against the mating flank's radius of
    curvature there, and its force is the law in series with that compliance at the recorded
    penetration; flank contacts below the rounds are unchanged; the compiled search equals its
    plain-Python source."""
    from solver.mbs.kernels.gearmesh import local_compliance
    m = _with_series(paper_solid_model)
    radii = (0.1e-3, 0.05e-3)
    me = _edged(m, *radii)
    th1 = math.radians(deg)
    th2 = m.theta2_for_te(th1, m.backlash_offset + 25e-6)
    a, b = _records(m, deg, 25e-6), _records(me, deg, 25e-6, python=True)
    corners = np.abs(b[:, L.C_KIND]) != 1
    assert corners.any() and (~corners).any()
    flank_a = a[np.abs(a[:, L.C_KIND]) == 1]
    np.testing.assert_array_equal(flank_a, b[~corners])
    E = m.inputs[3].youngs_modulus
    width = min(g.spec.face_width for g in m.geometry)
    law_r = law_radius(*m.geometry)
    k, m1 = m.law_par[L.K_CON], m.law_par[L.M1]
    gp = m.gear_par
    for rb_ in b[corners]:
        g = int(abs(rb_[L.C_KIND])) - 2
        f = 1 - g
        tooth = (int(rb_[L.C_TOOTH1]), int(rb_[L.C_TOOTH2]))
        axis = [th + gp[i, L.GAMMA0] + tooth[i] * gp[i, L.PITCH] for i, th in enumerate((th1, th2))]

        def place(i, p):
            c, s_ = math.cos(axis[i]), math.sin(axis[i])
            p = np.atleast_2d(p)
            return np.column_stack([gp[i, L.CX] + c * p[:, 0] - s_ * p[:, 1], gp[i, L.CY] + s_ * p[:, 0] + c * p[:, 1]])
        centre = place(g, tip_round(m.geometry[g], radii[g]).centre)[0]
        uu = np.linspace(m.geometry[f].u_form, m.geometry[f].u_tip, 200001)
        flank = place(f, np.column_stack(m.geometry[f].flank_point(uu, 1)))
        dist = np.hypot(*(flank - centre).T)
        n = int(np.argmin(dist))
        assert rb_[L.C_DELTA] == pytest.approx(radii[g] - dist[n], abs=2e-9)      # 2 nm of 25 um
        rho = m.base_radii[f] * uu[n]
        extra = weber_edge(E, width, law_r, radii[g], rho)
        plain = local_compliance.py_func(gp, g, gp[g, L.U_HI])[0] + local_compliance.py_func(gp, f, uu[n])[0]
        assert extra > 0.5e-9
        assert rb_[L.C_CLOC] == pytest.approx(plain + extra, rel=1e-5)
        assert rb_[L.C_FORCE] == pytest.approx(series_force(rb_[L.C_DELTA], rb_[L.C_CLOC], k, m1), rel=1e-9)


# the teeth coupled through coarse FE bodies (the model closest to the LTCA), 300 N·m: beside the
# single pair the neighbours' tip corners carry a third of the load and more
FE_SPRINGS = {"coupling.model": "compliance", "fe.mesh_size": 1.8, "quasi_static.torque": 300.0}
SINGLE = (8.5, 9.0, 13.5)


@pytest.mark.usefixtures("private_fe_cache")
def test_default_and_ltca_agree_with_a_tip_edge():
    """The small pair at 300 N·m with 0.2 mm tip edges: where the neighbours' tips carry load
    the rounds keep them off (the round lies up to 0.16 r = 31 um inside the sharp corner) and
    raise both models' STE by 4-8 % alike: the default model's difference to the LTCA changes by
    less than 0.5 % of the STE (measured 0.38 / 0.01 / 0.29 % at 8.5 / 9 / 13.5 deg on this
    coarse FE mesh; on the paper pair at 100 N·m with 0.1 mm edges it stays within 0.32 %:
    docs/models.md); in double contact without corner load nothing changes."""
    from solver.mbs.statics import solve_static
    from study.scene_model import build_scene_model
    from study.verify import fe_reference as ref_mod
    angles = np.radians((0.0, *SINGLE))
    out = {}
    for r in (0.0, 0.2):
        s = small_scene(**FE_SPRINGS, **{f"gear{g}.modification.tip_edge_radius": r for g in (1, 2)})
        ds = ref_mod.reference_dataset(s, angles)
        off = ds.attrs["backlash_offset_um"] * 1e-6
        st = solve_static(build_scene_model(s), angles, 300.0)
        assert st.converged.all()
        out[r] = (ds["ste"].values * 1e-6 - off, st.te - off, ds["extended_contact_force"].values)
        # the archive names the edge where there is one, and is as it was without
        if r:
            np.testing.assert_array_equal(ds.attrs["tip_edge_radius_mm"], [r, r])
            assert "0.2 mm on gear 1, 0.2 mm on gear 2" in ds.attrs["tip_corner_law"]
        else:
            assert "tip_edge_radius_mm" not in ds.attrs and ds.attrs["tip_corner_law"] == "the flanks' contact law"
    (l0, d0, x0), (l1, d1, x1) = out[0.0], out[0.2]
    assert x0[0] == 0 and np.all(x0[1:] > 0)
    assert np.all(x1[1:] < x0[1:])                                    # the rounds carry less
    assert l1[0] == pytest.approx(l0[0], rel=1e-12) and d1[0] == pytest.approx(d0[0], rel=1e-12)
    rise = (l1 - l0) / l0
    assert np.all(rise[1:] > 0.03)                                    # the edge matters there ...
    assert np.all(np.abs((d1 - l1) / l1 - (d0 - l0) / l0) < 0.005)    # ... and both models see it alike


def _crossing(m, lo: float, hi: float, approach: float):
    """Records (tooth pair and side -> record) just before and just after the driver angle [deg]
    in (lo, hi) where a contact passes between its flank (kind +-1) and a round (kind +-2, +-3),
    bisected to 1e-11 deg, and the record's column of the tooth pair that crosses."""
    def by_pair(deg):
        return {(int(r[L.C_TOOTH1]), int(r[L.C_TOOTH2]), int(np.sign(r[L.C_KIND]))): r for r in _records(m, deg, approach)}

    def kinds(deg):
        return {p: int(abs(r[L.C_KIND])) for p, r in by_pair(deg).items()}
    a, b = kinds(lo), kinds(hi)
    (pair,) = [p for p in a if p in b and a[p] != b[p] and 1 in (a[p], b[p])]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if hi - lo < 1e-11:
            break
        if kinds(mid)[pair] == a[pair]:
            lo = mid
        else:
            hi = mid
    return by_pair(lo)[pair], by_pair(hi)[pair]


@pytest.mark.parametrize("gear", [1, 2])
def test_round_contact_continues_the_flank_contact(paper_solid_model, gear):
    """A contact passing from the flank onto the round of gear 1 (leaving the mesh) or gear 2
    (entering it), 12 um into the mesh with 0.1 mm edges: at the round's tangent roll the two
    records share the penetration, c_loc (the tooth's own compliance at the flank contact's roll,
    the edge compliance ramped in from 0 there), the force and its gradient, so that the series
    spring's energy and its generalised forces have no jump there (a jump of c_loc by the edge
    compliance, about 0.8e-9 m/N, made a dynamic run's energy balance fail)."""
    m = _edged(_with_series(paper_solid_model), 0.1e-3, 0.1e-3)
    # a sweep over one mesh pitch (5.4 deg): where does a contact change its kind?
    grid = np.arange(0.0, 5.5, 0.05)
    found = []
    prev = None
    for deg in grid:
        kinds = {(int(r[L.C_TOOTH1]), int(r[L.C_TOOTH2]), int(np.sign(r[L.C_KIND]))): int(abs(r[L.C_KIND]))
                 for r in _records(m, deg, 12e-6)}
        if prev is not None:
            for p, k in kinds.items():
                if p in prev[1] and {k, prev[1][p]} == {1, gear + 1}:
                    found.append((prev[0], deg))
        prev = (deg, kinds)
    assert found
    below, above = _crossing(m, *found[0], 12e-6)
    assert {int(abs(below[L.C_KIND])), int(abs(above[L.C_KIND]))} == {1, gear + 1}
    assert below[L.C_CLOC] > 1e-10 and below[L.C_FORCE] > 10.0
    for col in (L.C_DELTA, L.C_CLOC, L.C_FORCE):
        assert above[col] == pytest.approx(below[col], rel=1e-7)
    grad = [L.C_G1, L.C_GA, L.C_G2, L.C_GB]
    np.testing.assert_allclose(above[grad], below[grad], rtol=0, atol=1e-7 * np.max(np.abs(below[grad])))


def test_energy_balance_with_rounded_edges_as_with_sharp_corners():
    """Undamped paper pair with the series law, from the paper's ramps (4 ms: contacts pass from
    flanks onto the rounds and off them): with 0.1 mm edges on both gears the energy residual
    stays within 1.5x that of sharp corners at the stable step and half of it (measured 1.2-1.3x;
    a c_loc jumping by the edge compliance at the round's tangent roll left 1.9e-5 J at any
    step, 120-220x the sharp corners' 1.5e-7 / 0.9e-7 J), and the residual is 1e-7 of the work."""
    from solver.mbs.dynamics import simulate
    from solver.mbs.stability import stable_time_step
    from study.scene_model import build_scene_model
    undamped = _with_series(build_scene_model(solid_scene(**{"gear1.spring.c_phi": 0.0, "gear2.spring.c_phi": 0.0,
                                                              "contact.c_con": 0.0})))
    dt0, _ = stable_time_step(undamped, 50.0)
    errs = {}
    for r_edge in (0.0, 0.1e-3):
        m = _edged(undamped, r_edge, r_edge)
        for dt in (dt0, dt0 / 2):
            r = simulate(m, 100.0, 0.01, 50.0, 0.01, 0.004, dt=dt, output_step=1e-5, phi_quiet=0.0)
            assert r.status == 0 and np.all(r.dissipated == 0)
            errs[r_edge, dt] = np.max(np.abs(r.energy_error))
            assert errs[r_edge, dt] < 1e-6 * np.max(np.abs(r.work))
    for dt in (dt0, dt0 / 2):
        assert errs[0.1e-3, dt] < 1.5 * errs[0.0, dt]


def test_static_ste_has_no_jump_where_a_round_takes_over(paper_solid_model):
    """100 N·m, 0.1 mm edges, driver 3.0-3.8 deg in steps of 0.02 deg, where the leaving tooth's
    contact passes from its flank onto its round (3.4 deg): the default model's static STE (series
    law without the FE) and the LTCA's (rigid bodies, the law and the edge) change by at most
    60 nm a step, as steep as the curve gets (56 / 50 nm); the edge compliance taken in full from
    the round's tangent roll on made both jump by 205 / 270 nm in one step."""
    from solver.fe.ltca import ltca_sweep
    from solver.mbs.statics import solve_static
    from study.scene_model import geometry_model
    from study.verify.fe_reference import scene_edges
    angles = np.radians(np.arange(3.0, 3.8, 0.02))
    m = _edged(_with_series(paper_solid_model), 0.1e-3, 0.1e-3)
    st = solve_static(m, angles, 100.0)
    assert st.converged.all()
    s = solid_scene(**{"coupling.model": "compliance", **{f"gear{g}.modification.tip_edge_radius": 0.1 for g in (1, 2)}})
    g = geometry_model(s)
    lt = ltca_sweep(g, (None, None), angles, 100.0, edge=scene_edges(s, g))
    for te in (st.te, lt.te):
        assert np.ptp(te) > 0.3e-6                       # the rise to single contact
        assert np.max(np.abs(np.diff(te))) < 60e-9

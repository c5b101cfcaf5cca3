"""The local contact approach in plane stress against the FE, and the tip edge of the LTCA's
corner contacts (`solver.identify.weber.plane_stress_approach`, `edge_compliance`,
`solver.fe.ltca.TipEdge`)."""
import math

import numpy as np
import pytest
from helpers import series_force, solid_scene

from solver import units
from solver.fe.ltca import corner_compliance, ltca_sweep, mesh_points
from solver.identify.weber import edge_compliance, plane_stress_approach
from study.scene import SceneError
from study.scene_model import geometry_model
from study.verify.fe_reference import tip_edge

E, NU, T = 206e9, 0.3, 17e-3          # Pa, -, m (the paper pair's steel and face width)
R_LAW = 8.594e-3                       # m: the paper pair's equivalent radius at the pitch point


def _graded(length: float, fine: float, width: float, n_fine: int, growth: float = 1.12) -> np.ndarray:
    """Coordinates [m] from 0 to ``length``: ``n_fine`` steps of ``fine`` over ``width``, then
    growing by ``growth`` a step."""
    x = list(np.linspace(0.0, width, n_fine + 1))
    h = fine
    while x[-1] < length:
        h *= growth
        x.append(min(x[-1] + h, length))
    return np.array(x)


@pytest.fixture(scope="module")
def block():
    """A plane-stress block 24 x 12 mm of the pair's steel and face width (quadratic triangles,
    0.004 mm at the middle of its top edge), clamped at the bottom: a half-space for loads on
    the top edge read 1 mm below it. Returns approach(F, R): the approach [m] of the top point
    to the point 1 mm below it under the Hertz pressure of force F [N] and radius R [m]."""
    import skfem

    from solver.fe.body import plane_stress_lame, plane_stress_p2_stiffness
    from solver.fe.factor import factorise

    W, H, depth = 12e-3, 12e-3, 1e-3
    xs = _graded(W, 4e-6, 0.4e-3, 100)
    x = np.concatenate([-xs[::-1], xs[1:]])
    y = H - _graded(H, 4e-6, 0.1e-3, 25)[::-1]
    m = skfem.MeshTri.init_tensor(x, y)
    basis = skfem.Basis(m, skfem.ElementVector(skfem.ElementTriP2()))
    lam, mu = plane_stress_lame(E, NU)
    K = plane_stress_p2_stiffness(basis, lam, mu, np.full(m.t.shape[1], T)).tocsr()
    fixed = basis.get_dofs(lambda p: p[1] < 1e-12).all()
    free = np.setdiff1d(np.arange(basis.N), fixed)
    lu = factorise(K[free][:, free].tocsc())
    facets = [e for e in m.boundary_facets() if np.all(m.p[1, m.facets[:, e]] > H - 1e-12)]   # the top edge
    x0 = np.array([m.p[0, m.facets[0, e]] for e in facets])
    x1 = np.array([m.p[0, m.facets[1, e]] for e in facets])
    lo, hi = np.minimum(x0, x1), np.maximum(x0, x1)
    probe = basis.probes(np.array([[0.0, 0.0], [H, H - depth]]))

    def approach(F: float, R: float) -> float:
        b = math.sqrt(8 * F / T * R / (math.pi * E))
        xi = np.linspace(-1.0, 1.0, 4001)
        p = np.sqrt(np.clip(1.0 - xi**2, 0.0, None))
        f = np.zeros(basis.N)
        for xv, fv in zip(b * xi, F * p / p.sum()):     # the Hertz pressure as 4001 point loads
            j = int(np.flatnonzero((lo <= xv) & (xv <= hi))[0])
            e, t = facets[j], (xv - x0[j]) / (x1[j] - x0[j])
            # quadratic edge shape functions: ends and mid-side
            f[basis.nodal_dofs[1, m.facets[0, e]]] -= fv * (1 - t) * (1 - 2 * t)
            f[basis.nodal_dofs[1, m.facets[1, e]]] -= fv * t * (2 * t - 1)
            f[basis.facet_dofs[1, e]] -= fv * 4 * t * (1 - t)
        u = np.zeros(basis.N)
        u[free] = lu.solve(f[free])
        uy = (probe @ u)[2:]
        return float(uy[1] - uy[0])                       # the top point moves down more

    return approach


def test_plane_stress_approach_matches_the_fe_at_two_loads(block):
    """Weber's approach in plane stress holds the load through ln(1/b), b ~ sqrt(F): the FE's
    approach per unit force falls by ln(4)/(pi E t) from 500 to 2000 N, and both values agree
    with the formula within 1.5 % (a power law fitted at one load has no such term)."""
    F1, F2 = 500.0, 2000.0
    a1, a2 = block(F1, R_LAW), block(F2, R_LAW)
    w1, w2 = (plane_stress_approach(F, T, R_LAW, 1e-3, E, NU) for F in (F1, F2))
    assert a1 == pytest.approx(w1, rel=0.015) and a2 == pytest.approx(w2, rel=0.015)
    drop = a1 / F1 - a2 / F2
    assert drop == pytest.approx(math.log(4.0) / (math.pi * E * T), rel=0.03)
    # the power law k*delta^m fitted through the FE at F1 with the paper's m1 misses F2's value
    m1 = 1.24
    assert abs(a1 * (F2 / F1) ** (1 / m1) / a2 - 1) > 0.02


def test_edge_compliance_is_the_fe_difference_of_the_narrower_patch(block):
    """A corner of edge radius r against a flank: both bodies' approach grows by
    2F/(pi E t) ln(R/r) over the flanks' R at the same force, linear in F (a compliance): the
    FE (one body, twice) gives it within 2 % at 500 and 2000 N."""
    r = 0.5e-3
    c = edge_compliance(E, T, R_LAW, r)
    for F in (500.0, 2000.0):
        fe = 2 * (block(F, r) - block(F, R_LAW)) / F
        assert fe == pytest.approx(c, rel=0.02)
    # the mating flank's own curvature in series, and a corner as blunt as the flanks adds nothing
    assert edge_compliance(E, T, R_LAW, r, 13.4e-3) == pytest.approx(
        2 / (math.pi * E * T) * math.log(R_LAW / (r * 13.4e-3 / (r + 13.4e-3))))
    assert edge_compliance(E, T, R_LAW, 2 * R_LAW) == 0.0
    with pytest.raises(ValueError, match="tip edge radius"):
        edge_compliance(E, T, R_LAW, 0.0)


def test_tip_edge_moves_load_off_the_corners_and_keeps_the_balance():
    """Rigid bodies at 300 N·m, where the tip corners beside a single pair touch: with a tip edge
    radius the corner contacts take the edge's compliance in series, carry less and the single
    pair more, the approach grows, and at every angle the forces sum to the load and each
    loaded contact's approach is the law's plus the edge's c*F; flank contacts are unchanged."""
    s = solid_scene(**{"quasi_static.torque": 300.0})
    model = geometry_model(s)
    edge = tip_edge(s, model, 0.035e-3)
    angles = np.radians([1.34, 3.9, 4.0, 4.2])
    plain = ltca_sweep(model, (None, None), angles, 300.0)
    rounded = ltca_sweep(model, (None, None), angles, 300.0, edge=edge)
    load = 300.0 / model.base_radii[1]
    k, m1 = float(model.law_par[0]), float(model.law_par[1])
    assert plain.extended[0] == 0 and rounded.approach[0] == pytest.approx(plain.approach[0], rel=1e-12)
    assert np.all(plain.extended[1:] > 0.05 * load)
    assert np.all(rounded.extended[1:] < plain.extended[1:]) and np.all(rounded.approach[1:] > plain.approach[1:])
    for a, th in enumerate(angles):
        mp = mesh_points(model, float(th))
        c = corner_compliance(model, mp, edge)
        assert np.all(c[mp.kind == 1] == 0) and np.all(c[mp.kind != 1] > 0)
        assert rounded.tooth_force[a].sum() == pytest.approx(load, rel=1e-9)
        # each closed contact carries the force of the law and the edge in series,
        # (F/k)^(1/m1) + c F = w - gap, and these forces sum to the load
        w = rounded.approach[a]
        total = sum(series_force(w - g, ci, k, m1) for g, ci in zip(mp.gap, c) if w > g)
        assert total == pytest.approx(load, rel=1e-6)


def test_tip_edge_radius_refused_where_it_has_no_meaning():
    """A radius that is not positive or not below the module, and the option with the CalculiX
    peer (which meshes the sharp corner), are refused naming --tip-edge-radius before any work."""
    import study
    s = solid_scene()
    model = geometry_model(s)
    for bad in (0.0, -0.01e-3, 2.0e-3, float("nan")):
        with pytest.raises(SceneError, match="--tip-edge-radius"):
            tip_edge(s, model, bad)
    with pytest.raises(SceneError, match="--tip-edge-radius.*ltca only"):
        study.reference(s, solver="calculix", tip_edge_radius=0.035)
    # the peer's options with the LTCA, and a name that is no option, refused the same way
    with pytest.raises(SceneError, match="--flank-size.*calculix only"):
        study.reference(s, flank_size=0.1)
    with pytest.raises(SceneError, match="--flank-sise.*not an option of reference"):
        study.reference(s, flank_sise=0.1)
    e = tip_edge(s, model, 0.035e-3)
    assert e.law_radius == pytest.approx(R_LAW, rel=1e-3) and e.face_width == pytest.approx(17.0 * units.MM)

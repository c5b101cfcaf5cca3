"""Plane-stress FE of gear bodies: analytic torsion of a thick ring, thickness field, mesh checks."""
import math

import numpy as np
import pytest
import skfem

from solver.fe import body as fe
from solver.fe.factor import influence
from solver.fe.mesh import REGION_WEB, mesh_annulus, mesh_body
from solver.geometry import Material, gear_geometry

STEEL = Material(206e9, 0.3, 7850.0)
A, C, B = 0.010, 0.020, 0.030       # bore, web/rim split, outer radius [m]
T_RIM, T_WEB = 0.017, 0.008         # thickness [m]
TORQUE = 100.0                      # N·m


def ring_rotation(r, t_web=T_WEB, t_rim=T_RIM):
    """Exact rotation [rad] at radius r >= C of a bore-clamped two-thickness ring under torque."""
    G = STEEL.youngs_modulus / (2 * (1 + STEEL.poisson_ratio))
    return TORQUE / (4 * math.pi * G) * ((1 / A**2 - 1 / C**2) / t_web + (1 / C**2 - 1 / r**2) / t_rim)


def ring_rotation_fe(size, t_web=T_WEB):
    mesh = mesh_annulus(A, C, B, size)
    model = fe.assemble(mesh, T_RIM, t_web, STEEL)
    m = model.basis.mesh
    outer = m.facets_satisfying(lambda x: np.hypot(x[0], x[1]) > (A + B) / 2, boundaries_only=True)
    fb = skfem.FacetBasis(m, model.basis.elem, facets=outer)
    q = TORQUE / (2 * math.pi * B**2)       # tangential line load [N/m] -> torque TORQUE

    @skfem.LinearForm
    def shear(v, w):
        r = np.hypot(w.x[0], w.x[1])
        return q * (-w.x[1] / r * v[0] + w.x[0] / r * v[1])

    u = fe.solve_load(model, skfem.asm(shear, fb))
    # rotation u_theta / r averaged over the vertices on the outer circle
    p = mesh.points
    on = np.nonzero(np.hypot(p[:, 0], p[:, 1]) > B * (1 - 1e-9))[0]
    nd = model.basis.nodal_dofs
    ux, uy = u[nd[0, on]], u[nd[1, on]]
    rot = (-p[on, 1] * ux + p[on, 0] * uy) / B**2
    return float(np.mean(rot)), mesh


def test_thick_ring_torsion_matches_the_exact_solution_and_converges():
    exact = ring_rotation(B)
    errors = []
    for h in (4e-3, 2e-3, 1e-3):
        phi, mesh = ring_rotation_fe(h)
        errors.append(abs(phi / exact - 1))
    # both thicknesses enter: the web carries the larger part of the compliance
    assert np.count_nonzero(mesh.region == REGION_WEB) > 0
    assert errors[-1] < 2e-3
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # quadratic elements on a polygonal boundary: the geometric error is second order
    assert rates.min() > 1.6, (errors, rates)


def test_ring_rotation_follows_the_web_thickness():
    # the thickness field weights each region: halving the web thickness doubles its compliance share
    full, _ = ring_rotation_fe(2e-3)
    half, mesh = ring_rotation_fe(2e-3, t_web=T_WEB / 2)
    exact = ring_rotation(B, t_web=T_WEB / 2) / ring_rotation(B)
    assert exact > 1.5
    assert half / full == pytest.approx(exact, rel=1e-3)


def small_gear(holes=0, web=0.020, phase=0.0):
    from solver.geometry import BodySpec, ToothSpec
    spec = ToothSpec(module=3e-3, teeth=24, pressure_angle=math.radians(20), addendum_coef=1.0, dedendum_coef=1.25,
                     fillet_radius=0.9e-3, face_width=0.020, thinning=0.0)
    body = BodySpec(rim_height=4e-3, web_height=14e-3, hub_height=6e-3, web_thickness=web, holes=holes,
                    hole_radius=3e-3, hole_circle_radius=19.5e-3, hole_phase=phase)
    return gear_geometry(spec), body


def test_body_mesh_regions_and_holes():
    g, body = small_gear(holes=4, web=0.008)
    mesh = mesh_body(g, body)
    p = mesh.points
    r = np.hypot(p[:, 0], p[:, 1])
    assert r.min() == pytest.approx(body_bore := g.root_radius - 24e-3, rel=1e-6) and body_bore > 0
    assert r.max() == pytest.approx(g.tip_radius, rel=1e-6)
    # no node inside a hole
    for i in range(4):
        a = 2 * math.pi * i / 4
        c = 19.5e-3 * np.array([math.cos(a), math.sin(a)])
        assert np.hypot(*(p - c).T).min() > 3e-3 * (1 - 1e-6)
    # area = disc - bore - holes - tooth spaces: check against the polygon area of the outline
    tri = p[mesh.triangles]
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    from solver.geometry import gear_outline
    from solver.inertia import polygon_properties
    outline = polygon_properties(*gear_outline(g, n_involute=200, n_fillet=50, n_tip=20, n_root=20))[0]
    expected = outline - math.pi * body_bore**2 - 4 * math.pi * 3e-3**2
    assert area == pytest.approx(expected, rel=2e-3)
    # web elements lie between the rim and the hub
    cw = tri[mesh.region == REGION_WEB].mean(axis=1)
    rw = np.hypot(cw[:, 0], cw[:, 1])
    assert rw.min() > g.root_radius - 4e-3 - 14e-3 - 1e-9 and rw.max() < g.root_radius - 4e-3


def test_bad_mesh_size_is_named():
    g, body = small_gear()
    with pytest.raises(ValueError, match="fe.mesh_size"):
        mesh_body(g, body, size=-1.0)


def test_load_case_geometry():
    g, _ = small_gear()
    c = fe.load_case(g, 0, g.root_radius)
    # the load point is on the pitch circle, the load along the line of action (tangent to the base circle)
    assert np.hypot(*c.point) == pytest.approx(g.pitch_radius, rel=1e-12)
    assert abs(c.point[0] * c.direction[1] - c.point[1] * c.direction[0]) == pytest.approx(g.base_radius, rel=1e-12)
    assert c.centre_point[1] == pytest.approx(0.0, abs=1e-15)
    # it pushes the tooth toward negative polar angle (the mating driver's action on the + flank)
    assert c.point[0] * c.direction[1] - c.point[1] * c.direction[0] < 0
    # tooth k is tooth 0 rotated by k pitches
    c3 = fe.load_case(g, 3, g.root_radius)
    a = 3 * g.pitch_angle
    R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    assert np.allclose(c3.point, R @ c.point) and c3.lever == pytest.approx(c.lever)


def test_patch_load_equals_the_quadrature_of_a_uniform_traction():
    mesh = mesh_annulus(A, C, B, 2e-3)
    model = fe.assemble(mesh, T_RIM, T_WEB, STEEL)
    d = np.array([0.6, 0.8])
    case = fe.LoadCase(np.array([B, 0.0]), d, np.zeros(2), 1.0)
    f = fe.load_vector(model, case, 10.0, 3e-3)
    m = model.basis.mesh
    bf = m.boundary_facets()
    mid = m.p[:, m.facets[:, bf]].mean(axis=1)
    sel = bf[np.hypot(mid[0] - B, mid[1]) <= 3e-3]
    fb = skfem.FacetBasis(m, model.basis.elem, facets=sel)
    length = skfem.asm(skfem.Functional(lambda w: 1.0 + 0 * w.x[0]), fb)
    ref = skfem.asm(skfem.LinearForm(lambda v, w: 10.0 / length * (d[0] * v[0] + d[1] * v[1])), fb)
    assert np.allclose(f, ref, atol=1e-12)
    # the resultant is the requested force along d
    nd = model.basis.nodal_dofs
    total = np.array([f[nd[0]].sum() + f[model.basis.facet_dofs[0]].sum(), f[nd[1]].sum() + f[model.basis.facet_dofs[1]].sum()])
    assert np.allclose(total, 10.0 * d, rtol=1e-12)


def test_closed_form_stiffness_equals_the_generic_form_assembly():
    """The closed-form P2 plane-stress matrix (edge-midpoint rule, exact on straight triangles)
    is scikit-fem's linear_elasticity assembly region by region, to rounding, and K is symmetric
    with the three rigid-body motions in its null space."""
    from skfem.models.elasticity import linear_elasticity
    mesh = mesh_annulus(A, C, B, 3e-3)
    m = skfem.MeshTri(mesh.points.T.copy(), mesh.triangles.T.copy())
    basis = skfem.Basis(m, skfem.ElementVector(skfem.ElementTriP2()))
    lam, mu = fe.plane_stress_lame(STEEL.youngs_modulus, STEEL.poisson_ratio)
    thickness = np.where(mesh.region == REGION_WEB, T_WEB, T_RIM)
    K = fe.plane_stress_p2_stiffness(basis, lam, mu, thickness).tocsr()
    ref = sum(t * skfem.asm(linear_elasticity(lam, mu), skfem.Basis(m, basis.elem, elements=np.flatnonzero(thickness == t)))
              for t in (T_WEB, T_RIM))
    assert abs(K - ref).max() < 1e-12 * abs(ref).max()
    assert abs(K - K.T).max() < 1e-12 * abs(K).max()
    x, y = basis.doflocs
    nd = np.zeros(basis.N, int)
    nd[basis.nodal_dofs[1]] = nd[basis.facet_dofs[1]] = 1            # y-component DOFs
    for rigid in (nd == 0, nd == 1, np.where(nd == 0, -y, x)):      # shift x, shift y, rotation
        assert np.abs(K @ rigid.astype(float)).max() < 1e-9 * abs(K).max() * B


def test_influence_equals_one_solve_per_load():
    """influence (all loads at once, triangular solves restricted to the DOFs the loads and
    reads reach) gives R K^-1 f for every load f exactly as a solve per load does, loads on
    clamped DOFs included (they carry no displacement either way)."""
    import scipy.sparse as sp
    mesh = mesh_annulus(A, C, B, 2e-3)
    model = fe.assemble(mesh, T_RIM, T_WEB, STEEL)
    rng = np.random.default_rng(7)
    N = model.basis.N
    F = sp.random(N, 9, density=4e-3, random_state=rng, format="lil")      # scattered loads
    F[model.basis.nodal_dofs[0, 0], 0] = 1.0                               # a node on the bore
    F = F.tocsc()
    pts = np.array([[0.025, 0.0], [0.0, -0.029], [-0.015, 0.012], [0.021, 0.021]]).T
    P = model.basis.probes(pts).tocsr()
    R = sp.vstack([P, 0.6 * P[:4] - 0.8 * P[4:]])                          # reads along x, y, a direction
    G = influence(model, R, F, block=4)
    ref = np.column_stack([R @ fe.solve_load(model, F[:, j].toarray().ravel()) for j in range(F.shape[1])])
    assert np.abs(G - ref).max() < 1e-10 * np.abs(ref).max()
    # a body without its factor object falls back to plain block solves: the same numbers
    import dataclasses
    plain = influence(dataclasses.replace(model, factor=None, triangles=None), R, F)
    assert np.abs(plain - ref).max() < 1e-10 * np.abs(ref).max()
    # Maxwell-Betti: reading where the other loads gives the transposed coefficient
    Gs = influence(model, F.T, F)
    assert np.abs(Gs - Gs.T).max() < 1e-10 * np.abs(Gs).max()

"""Static condensation of the teeth and rim: the condensed body solves the same equations as the
whole body (to rounding), the rim's products give the same influence coefficients, and a rim
that does not fit the body is refused."""
import math

import numpy as np
import pytest
import scipy.sparse as sp

from solver.fe import body as fe
from solver.fe import condense as cd
from solver.fe.factor import influence
from solver.fe.mesh import REGION_RIM, mesh_annulus
from solver.geometry import Material

STEEL = Material(206e9, 0.3, 7850.0)
A, C, B = 0.010, 0.020, 0.030       # bore, web/rim split (the interface), outer radius [m]
T_RIM = 0.017                       # m


@pytest.fixture(scope="module")
def ring():
    """An annulus meshed once: its outer part is the 'rim', condensed onto r = C."""
    mesh = mesh_annulus(A, C, B, 2.5e-3)
    return mesh, cd.rim_block(mesh, T_RIM, STEEL, C)


def _bodies(mesh, rim, t_web: float) -> tuple:
    """The body of ``mesh`` with a web ``t_web`` [m] thick, factorised whole and through the
    condensed ``rim``."""
    return fe.assemble(mesh, T_RIM, t_web, STEEL), cd.assemble_condensed(mesh, T_RIM, t_web, STEEL, rim)


def _loads_and_reads(model, n_loads=7, seed=3):
    """Scattered loads and point reads in the rim, away from the interface, in the numbering
    of ``model``'s basis (the loads chosen by DOF position: the same in any numbering)."""
    from scipy.spatial import cKDTree
    rng = np.random.default_rng(seed)
    b = model.basis
    keys = cd._dof_keys(b)
    ring_dofs = np.array([[0.026 * math.cos(a), 0.026 * math.sin(a)] for a in np.linspace(0.1, 6.0, 40)])
    F = sp.lil_matrix((b.N, n_loads))
    for j in range(n_loads):
        for p in ring_dofs[rng.choice(40, 3, replace=False)]:
            near = cKDTree(keys[:, :2]).query(p, k=1)[1]            # the DOF nearest the point
            comp = rng.integers(2)
            dof = np.flatnonzero((np.abs(keys[:, :2] - keys[near, :2]).sum(axis=1) < 1e-12) & (keys[:, 2] == comp))[0]
            F[dof, j] = rng.standard_normal()
    ang = np.linspace(0.3, 5.9, 5)
    pts = np.array([0.027 * np.cos(ang), 0.027 * np.sin(ang)])
    P = b.probes(pts).tocsr()
    return sp.vstack([P, 0.6 * P[:5] - 0.8 * P[5:]]).tocsr(), F.tocsc()


@pytest.mark.parametrize("t_web", [0.006, 0.017])
def test_condensed_body_solves_as_the_whole_body(ring, t_web):
    """Two webs on one condensed rim: every load (in rim, web and on the interface) gives the
    whole body's displacement field to rounding."""
    mesh, rim = ring
    whole, cond = _bodies(mesh, rim, t_web)
    assert cond.condensed is not None and cond.n_dofs == whole.n_dofs
    assert np.array_equal(cond.free, whole.free)
    f = np.random.default_rng(1).standard_normal((whole.free.size, 4))
    u_whole, u_cond = whole.solve(f), cond.solve(f)
    assert np.abs(u_cond - u_whole).max() < 1e-9 * np.abs(u_whole).max()
    # the same loads again (the rim part of the solve is kept): the same answer
    assert np.array_equal(cond.solve(f), u_cond)
    # and one load vector as a 1-D array
    assert np.allclose(cond.solve(f[:, 0]), u_cond[:, 0], rtol=0, atol=1e-12 * np.abs(u_cond).max())


def test_rim_products_give_the_influence_coefficients(ring):
    """R K^-1 F through the rim's products (G0 + A S^-1 B) equals the whole body's influence;
    the products are made once per load set and serve a second web."""
    mesh, rim = ring
    R_rim, F_rim = _loads_and_reads(rim.model)
    for t_web in (0.006, 0.012):
        whole, cond = _bodies(mesh, rim, t_web)
        R, F = _loads_and_reads(whole)                 # the same loads and reads, body numbering
        ref = influence(whole, R, F)
        G = cond.condensed.influence(R_rim, F_rim, "test-set")
        assert np.abs(G - ref).max() < 1e-9 * np.abs(ref).max()
    assert list(rim.products) == ["test-set"]
    assert np.array_equal(cond.condensed.influence(None, None, "test-set"), G)     # kept: no loads needed


def test_condensed_stiffness_is_symmetric_and_holds_the_rigid_rotation(ring):
    """S_R is symmetric positive semi-definite, and a rigid rotation of the interface costs
    no force (the free rim follows it without strain)."""
    _, rim = ring
    S = rim.S
    assert np.abs(S - S.T).max() < 1e-12 * np.abs(S).max()
    keys = rim.keys[rim.interface]
    x, y, comp = keys[:, 0], keys[:, 1], keys[:, 2]
    rot = np.where(comp == 0, -y, x)
    assert np.abs(S @ rot).max() < 1e-8 * np.abs(S).max() * C
    assert np.linalg.eigvalsh(S).min() > -1e-8 * np.abs(S).max()


def test_rim_from_the_stored_stiffness_is_the_same(ring):
    """A rim rebuilt around its condensed stiffness read back (as from the disk cache) solves
    and makes products as the rim condensed anew."""
    mesh, rim = ring
    again = cd.rim_block(mesh, T_RIM, STEEL, C, S=rim.S.copy())
    assert again.split is None and np.array_equal(again.keys, rim.keys)
    R_rim, F_rim = _loads_and_reads(rim.model, seed=5)
    a = cd.assemble_condensed(mesh, T_RIM, 0.008, STEEL, rim).condensed.influence(R_rim, F_rim, "x")
    b = cd.assemble_condensed(mesh, T_RIM, 0.008, STEEL, again).condensed.influence(R_rim, F_rim, "x")
    assert np.abs(a - b).max() < 1e-10 * np.abs(a).max()


def test_a_rim_that_does_not_fit_is_refused(ring):
    """Another mesh's rim (other element size), or loads on the interface, are errors, not
    wrong numbers."""
    mesh, rim = ring
    other = mesh_annulus(A, C, B, 2.0e-3)
    with pytest.raises(cd.RimMismatch):
        cd.assemble_condensed(other, T_RIM, 0.008, STEEL, rim)
    cond = cd.assemble_condensed(mesh, T_RIM, 0.008, STEEL, rim)
    R_rim, _ = _loads_and_reads(rim.model)
    F = sp.csc_matrix(([1.0], ([rim.interface[0]], [0])), shape=(rim.model.basis.N, 1))
    with pytest.raises(ValueError, match="interface"):
        cond.condensed.influence(R_rim, F, "on the interface")


def test_rim_mesh_numbering_does_not_depend_on_the_body(ring):
    """The rim's own mesh is numbered from its geometry: renumbering the body's vertices and
    reordering its elements gives the same rim mesh."""
    mesh, _ = ring
    rng = np.random.default_rng(0)
    perm = rng.permutation(mesh.points.shape[0])
    inv = np.empty_like(perm)
    inv[perm] = np.arange(perm.size)
    order = rng.permutation(mesh.n_elements)
    shuffled = fe.BodyMesh(mesh.points[perm], inv[mesh.triangles][order], mesh.region[order], mesh.bore_radius, mesh.size)
    a, b = cd.rim_mesh(mesh), cd.rim_mesh(shuffled)
    assert np.array_equal(a.points, b.points) and np.array_equal(a.triangles, b.triangles)
    assert a.n_elements == int(np.sum(mesh.region == REGION_RIM))
    assert math.isclose(np.hypot(*a.points.T).min(), C, rel_tol=1e-9)


def _column_reads(model, n_cols, seed):
    """Per load column, a different handful of free DOFs in the rim (r > 22 mm), as body free
    positions of ``model`` (picked by DOF location: the same DOFs in any numbering)."""
    rng = np.random.default_rng(seed)
    keys = cd._dof_keys(model.basis)[model.free]
    outer = np.flatnonzero(np.hypot(keys[:, 0], keys[:, 1]) > 0.022)
    outer = outer[np.lexsort((keys[outer, 2], keys[outer, 1], keys[outer, 0]))]
    return [np.sort(rng.choice(outer, 25, replace=False)) for _ in range(n_cols)]


def test_column_reads_equal_the_whole_body_solve(ring):
    """Each load column read at its own DOFs through the rim's restricted back-substitutions
    equals the whole body's full solve there, for two webs on one rim (the rim's read set made
    once); loads off the rim fall back to the full solve, with the same numbers."""
    mesh, rim = ring
    for t_web in (0.006, 0.012):
        whole, cond = _bodies(mesh, rim, t_web)
        _, F = _loads_and_reads(whole)
        f = np.ascontiguousarray(F.toarray()[whole.free])
        reads = _column_reads(whole, f.shape[1], seed=7)
        u = whole.solve(f)
        got = cond.condensed.column_reads(f, reads)
        scale = np.abs(u).max()
        for j, r in enumerate(reads):
            assert np.abs(got[j] - u[r, j]).max() < 1e-9 * scale
    assert len(rim.read_sets) == 1
    # a load in the web (r < C): the full solve, the same numbers
    web_dof = np.flatnonzero(np.hypot(*cd._dof_keys(whole.basis)[whole.free, :2].T) < 0.015)[0]
    f2 = f.copy()
    f2[web_dof, 0] = 1.0
    u2 = whole.solve(f2)
    got2 = cond.condensed.column_reads(f2, reads)
    assert np.abs(got2[0] - u2[reads[0], 0]).max() < 1e-9 * np.abs(u2).max()


def test_solve_at_reads_rim_interface_and_web_as_the_whole_body(ring):
    """K^-1 F read only at chosen DOFs (loads in the rim; reads in the rim, on the interface
    and in the web, the strength sites' mix) through the rim's restricted forward and back
    solves and the web from the interface: the whole body's full solve there to rounding, for
    two webs on one rim (the rim's back-substitution made once); a load in the web falls back
    to the full solve, with the same numbers."""
    mesh, rim = ring
    for t_web in (0.006, 0.012):
        whole, cond = _bodies(mesh, rim, t_web)
        _, F = _loads_and_reads(whole)
        f = sp.csc_matrix(F.tocsr()[whole.free])
        r = np.hypot(*cd._dof_keys(whole.basis)[whole.free, :2].T)
        rng = np.random.default_rng(11)
        at = np.concatenate([rng.choice(np.flatnonzero(r > 0.022), 60, replace=False),
                             rng.choice(np.flatnonzero(np.abs(r - C) < 1e-9), 10, replace=False),
                             rng.choice(np.flatnonzero(r < C - 1e-9), 30, replace=False)])
        rng.shuffle(at)
        u = whole.solve(f.toarray())
        got = cond.condensed.solve_at(f, at)
        assert got.shape == (at.size, f.shape[1])
        assert np.abs(got - u[at]).max() < 1e-9 * np.abs(u).max()
        # the web's and the interface's reads are not zero: the test reads the field there
        assert np.abs(u[at][r[at] <= C + 1e-9]).max() > 1e-3 * np.abs(u).max()
    assert len(rim.backs) == 1
    f2 = f.toarray()
    f2[np.flatnonzero(r < 0.015)[0], 0] = 1.0
    u2 = whole.solve(f2)
    assert np.abs(cond.condensed.solve_at(f2, at) - u2[at]).max() < 1e-9 * np.abs(u2).max()


def test_congruence_equals_the_solves(ring):
    """C^T K^-1 C by restricted solves and a product over the runs of columns each row reaches
    (`factor.congruence`, the web's condensation onto the interface) equals C^T times the full
    solves of C and is exactly symmetric, whatever the order of C's columns given for the runs,
    and with its last rows solved sparse or dense."""
    from solver.fe.factor import congruence
    mesh, _ = ring
    whole = fe.assemble(mesh, T_RIM, 0.008, STEEL)
    C = sp.random(whole.free.size, 30, density=0.002, random_state=np.random.default_rng(4), format="csc")
    C = C + sp.csc_matrix(([1.0], ([5], [0])), shape=C.shape)        # no empty column
    ref = C.T @ whole.solve(C.toarray())
    for order in (None, np.random.default_rng(5).permutation(30)):
        for dense_rows in (0, 40, 10**6):
            W = congruence(whole.factor, C, order=order, dense_rows=dense_rows)
            assert W is not None and np.array_equal(W, W.T)
            assert np.abs(W - ref).max() < 1e-10 * np.abs(ref).max()


def test_a_joined_body_matches_its_rim_by_numbering(ring):
    """A body meshed as `join_rim` makes it (the rim's vertices and elements first, as they are)
    takes its rim DOFs from the numbering, not by a search of DOF locations, and solves as the
    same body with its DOFs matched by location."""
    mesh, rim = ring
    joined = cd.join_rim(rim, mesh)
    rim.tree = None
    fast = cd.assemble_condensed(joined, T_RIM, 0.009, STEEL, rim)
    assert rim.tree is None                                          # no location search made
    rim.tree = None
    shuffled = cd.BodyMesh(joined.points, joined.triangles[::-1].copy(), joined.region[::-1].copy(),
                           joined.bore_radius, joined.size)
    slow = cd.assemble_condensed(shuffled, T_RIM, 0.009, STEEL, rim)
    assert rim.tree is not None                                      # matched by location
    f = np.random.default_rng(8).standard_normal(fast.free.size)
    assert np.array_equal(fast.free, slow.free)
    u_fast, u_slow = fast.solve(f), slow.solve(f)
    assert np.abs(u_fast - u_slow).max() < 1e-12 * np.abs(u_slow).max()

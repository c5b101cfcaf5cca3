"""Stress recovery of the plane-stress gear body and the places where lightened gears fail.

`stress_operator` turns a displacement field into the stress at chosen mesh nodes: the stress
of each quadratic element at its vertices (linear in the element, exact derivative of the P2
field), averaged over the elements of a set that meet at the node. At a free edge this is the
surface stress (Kirsch's plate: K_t = 3 within 1-2 % with about 100 elements around the hole,
`tests/solver/fe/test_stress.py`). The operator is a sparse matrix per component, so any load
case, and any superposition of load cases, costs one sparse product.

`strength_sites` finds, from the mesh alone, the nodes where a lightened gear's stress is read:

* root: the outline's nodes from the root circle up to the form circle (fillets and root lands),
  each with the tooth it belongs to (nearest tooth axis);
* rim: the nodes of the teeth-and-rim elements in the inner half of the rim (below the root's
  notch, where a thin rim bends);
* web openings: the free edges of the web elements that are not the bore (the circles where
  the web meets the rim and the hub are inner interfaces, not free edges), grouped into one
  closed loop per opening: whatever the openings' shape (round holes, slots, windows);
* ligaments: the narrowest section between each opening and the rim circle, the hub circle
  (the bore without a hub) and the next opening, found geometrically from the edge nodes, with
  the web nodes that lie on the section.

Units: SI (m, Pa).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from solver.fe.mesh import REGION_RIM, REGION_WEB

LIGAMENT_KINDS = ("hole-rim", "hole-hole", "hole-hub")
_VERTICES = (np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), np.full(3, 1.0 / 6.0))   # reference vertices


@dataclass(frozen=True)
class StressOperator:
    """Stress at ``nodes`` [Pa] of a displacement field u [m]: ``xx @ u``, ``yy @ u``, ``xy @ u``
    (sparse, n_nodes x N_dofs), in the gear (global) frame."""

    nodes: np.ndarray
    xx: object
    yy: object
    xy: object

    @property
    def dofs(self) -> np.ndarray:
        """The DOFs the operator reads (sorted): its nonzero columns in any component."""
        return np.unique(np.concatenate([c.tocsr().indices for c in (self.xx, self.yy, self.xy)]))

    def apply(self, U: np.ndarray) -> np.ndarray:
        """(3, n_nodes, ...) stress components sxx, syy, sxy [Pa] of displacements U (N_dofs, ...)."""
        return np.stack([np.asarray(self.xx @ U), np.asarray(self.yy @ U), np.asarray(self.xy @ U)])


def stress_operator(basis, lam: float, mu: float, nodes, elements=None) -> StressOperator:
    """`StressOperator` of the vector P2 ``basis`` (scikit-fem; plane-stress Lame parameters
    ``lam`` (lambda*), ``mu`` [Pa]) at the mesh vertices ``nodes``: each element's vertex stress,
    averaged over the elements of ``elements`` (a boolean mask or indices; None: all) that have
    the node as a vertex. A node no such element touches reads NaN."""
    import scipy.sparse as sp
    import skfem

    mesh = basis.mesh
    nodes = np.asarray(nodes, np.int64)
    allowed = np.ones(mesh.t.shape[1], bool) if elements is None else _mask(elements, mesh.t.shape[1])
    wanted = np.zeros(mesh.p.shape[1], bool)
    wanted[nodes] = True
    sel = np.flatnonzero(allowed & wanted[mesh.t].any(axis=0))
    row_of = np.full(mesh.p.shape[1], -1, np.int64)
    row_of[nodes] = np.arange(nodes.size)
    if sel.size == 0:
        empty = sp.csr_matrix((nodes.size, basis.N))
        return StressOperator(nodes, empty, empty, empty)
    b = skfem.Basis(mesh, basis.elem, elements=sel, quadrature=_VERTICES)
    nb = b.Nbfun
    # strain-displacement coefficients at each (element, vertex) for each local basis function
    g = np.stack([b.basis[i][0].grad for i in range(nb)])       # (nb, 2 comp, 2 deriv, nel, 3)
    exx, eyy = g[:, 0, 0], g[:, 1, 1]
    exy = 0.5 * (g[:, 0, 1] + g[:, 1, 0])
    comps = (lam * (exx + eyy) + 2 * mu * exx, lam * (exx + eyy) + 2 * mu * eyy, 2 * mu * exy)   # (nb, nel, 3)
    vertex = mesh.t[:, sel]                                      # (3, nel)
    rows = row_of[vertex.T]                                      # (nel, 3)
    keep = rows >= 0
    count = np.bincount(rows[keep], minlength=nodes.size).astype(float)
    weight = np.where(keep, 1.0 / np.maximum(count[np.maximum(rows, 0)], 1.0), 0.0)   # (nel, 3)
    dofs = b.element_dofs                                        # (nb, nel)
    out = []
    for c in comps:
        data = (c * weight[None]).transpose(1, 2, 0)             # (nel, 3, nb)
        r = np.broadcast_to(np.maximum(rows, 0)[:, :, None], data.shape)
        col = np.broadcast_to(dofs.T[:, None, :], data.shape)
        m = np.broadcast_to(keep[:, :, None], data.shape)
        out.append(sp.csr_matrix((data[m], (r[m], col[m])), shape=(nodes.size, basis.N)))
    missing = count == 0
    if missing.any():    # NaN rows: a node without elements of the set
        nan = sp.csr_matrix((np.full(missing.sum(), np.nan), (np.flatnonzero(missing), np.zeros(missing.sum(), int))),
                            shape=(nodes.size, basis.N))
        out = [o + nan for o in out]
    return StressOperator(nodes, *out)


def _mask(elements, n: int) -> np.ndarray:
    e = np.asarray(elements)
    if e.dtype == bool:
        return e
    m = np.zeros(n, bool)
    m[e] = True
    return m


def max_principal(s: np.ndarray) -> np.ndarray:
    """Largest principal stress [Pa] of plane-stress components s = (sxx, syy, sxy, ...)."""
    return 0.5 * (s[0] + s[1]) + np.sqrt(0.25 * (s[0] - s[1]) ** 2 + s[2] ** 2)


def von_mises(s: np.ndarray) -> np.ndarray:
    """Von Mises stress [Pa] of plane-stress components s = (sxx, syy, sxy, ...)."""
    return np.sqrt(s[0] ** 2 - s[0] * s[1] + s[1] ** 2 + 3 * s[2] ** 2)


def boundary_edges(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(edges (k, 2) vertex indices, element of each) of the free edges of a triangle mesh: the
    edges that belong to one triangle only."""
    t = np.asarray(triangles)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    owner = np.tile(np.arange(t.shape[0]), 3)
    key = np.sort(e, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    free = cnt[inv.ravel()] == 1
    return key[free], owner[free]


@dataclass(frozen=True)
class Ligament:
    """The narrowest section between an opening and the rim, the hub or the next opening."""

    kind: str               # one of LIGAMENT_KINDS
    opening: int            # the opening it starts from
    start: np.ndarray       # (2,) end on the opening's edge [m]
    end: np.ndarray         # (2,) the other end [m]
    nodes: np.ndarray       # mesh vertices on the section

    @property
    def width(self) -> float:
        return float(np.hypot(*(self.end - self.start)))


@dataclass(frozen=True)
class StrengthSites:
    """Where a gear body's strength is read (mesh vertex indices; see the module)."""

    root: np.ndarray                  # outline nodes of the fillets and root lands
    root_tooth: np.ndarray            # the tooth of each root node
    rim: np.ndarray                   # nodes in the inner half of the rim
    openings: list = field(default_factory=list)     # vertex indices of each opening's edge
    ligaments: list = field(default_factory=list)    # `Ligament` of each opening and kind

    @property
    def web(self) -> np.ndarray:
        """Every node read in the web: opening edges and ligament sections."""
        parts = [*self.openings, *(lg.nodes for lg in self.ligaments)]
        return np.unique(np.concatenate(parts)) if parts else np.empty(0, np.int64)


@dataclass(frozen=True)
class SiteRadii:
    """The radii [m] that place a body's strength sites: the gear's root and form circles, where
    the web meets the rim (``rim``), where it meets the hub or the bore (``web_inner``), and
    the bore."""

    root: float
    form: float
    rim: float
    web_inner: float
    bore: float


def strength_sites(points: np.ndarray, triangles: np.ndarray, region: np.ndarray, radii: SiteRadii,
                   teeth: int) -> StrengthSites:
    """`StrengthSites` of a body mesh (points (n, 2) [m], triangles (m, 3), region of each
    triangle, `solver.fe.mesh`), from its `SiteRadii` and the tooth count. Shape-agnostic: the
    openings are the web's free edges."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    root_radius, form_radius, rim_radius = radii.root, radii.form, radii.rim
    web_inner_radius, bore_radius = radii.web_inner, radii.bore

    r = np.hypot(points[:, 0], points[:, 1])
    edges, owner = boundary_edges(triangles)
    tol = 1e-6 * root_radius
    er = r[edges]
    # root: outline edges (free edges of the teeth and rim above the rim's inner circle)
    outline = (region[owner] == REGION_RIM) & (er.min(axis=1) > rim_radius + tol)
    on = np.unique(edges[outline])
    root = on[(r[on] >= root_radius - tol) & (r[on] <= form_radius + tol)]
    pitch = 2 * math.pi / teeth
    root_tooth = np.rint(np.arctan2(points[root, 1], points[root, 0]) / pitch).astype(np.int64) % teeth
    # rim: the inner half of the rim, clear of the roots' notch
    in_rim = np.zeros(points.shape[0], bool)
    in_rim[np.unique(triangles[region == REGION_RIM])] = True
    rim = np.flatnonzero(in_rim & (r <= 0.5 * (root_radius + rim_radius) + tol))
    # web openings: free edges of web elements off the bore, one connected loop per opening
    web_edge = (region[owner] == REGION_WEB) & (er.min(axis=1) > bore_radius + tol)
    openings, ligaments = [], []
    if web_edge.any():
        e = edges[web_edge]
        n = points.shape[0]
        graph = coo_matrix((np.ones(e.shape[0]), (e[:, 0], e[:, 1])), shape=(n, n))
        _, label = connected_components(graph, directed=False)
        used = np.unique(e)
        for lab in np.unique(label[used]):
            openings.append(used[label[used] == lab])
        centre = [np.arctan2(*points[o].mean(axis=0)[::-1]) for o in openings]
        openings = [openings[i] for i in np.argsort(centre)]
        edge_len = np.hypot(*(points[e[:, 1]] - points[e[:, 0]]).T)
        ligaments = _ligaments(points, triangles, region, openings, rim_radius, web_inner_radius, float(edge_len.max()))
    return StrengthSites(root, root_tooth, rim, openings, ligaments)


def _ligaments(points, triangles, region, openings, rim_radius, inner_radius, h) -> list:
    """The narrowest section of each opening to the rim circle, the hub circle and the next
    opening (``h`` [m]: the largest edge length on the openings, the tolerance of a node on a
    section)."""
    from scipy.spatial import cKDTree

    web_nodes = np.unique(triangles[region == REGION_WEB])
    tree = cKDTree(points[web_nodes])
    r = np.hypot(points[:, 0], points[:, 1])
    out = []

    def section(kind, i, ends, b=None):
        """The ligament from node ends[0] to the point b (or to node ends[1])."""
        a = points[ends[0]]
        b = points[ends[1]] if b is None else b
        length = float(np.hypot(*(b - a)))
        nodes = web_nodes[tree.query_ball_point(0.5 * (a + b), 0.5 * length + h)]
        p = points[nodes]
        d = b - a
        s = np.clip(((p - a) @ d) / max(length**2, 1e-30), 0.0, 1.0)
        near = np.hypot(*(p - (a + s[:, None] * d)).T) <= 0.6 * h
        out.append(Ligament(kind, i, a, b, np.union1d(nodes[near], ends)))    # its ends on the edges always

    for i, o in enumerate(openings):
        top = o[np.argmax(r[o])]
        section("hole-rim", i, [top], points[top] * rim_radius / r[top])
        low = o[np.argmin(r[o])]
        section("hole-hub", i, [low], points[low] * inner_radius / r[low])
        if len(openings) > 1:
            nxt = openings[(i + 1) % len(openings)]
            if len(openings) == 2 and i == 1:
                continue        # two openings: one pair
            d, j = cKDTree(points[nxt]).query(points[o])
            k = int(np.argmin(d))
            section("hole-hole", i, [o[k], nxt[j[k]]])
    return out


def load_case_stress(model, op: StressOperator, teeth, rolls, load_vector) -> np.ndarray:
    """Stress per unit load (3 components, n_nodes, n_teeth, n_rolls) [Pa/N] at the nodes of
    ``op`` under a 1 N load on each of ``teeth`` at each roll parameter of ``rolls``;
    ``load_vector(tooth, roll)`` gives the nodal forces of that load [N] (e.g. the flank load
    of `solver.fe.flank_compliance.flank_load_vector`, whose patch moves continuously with the roll).

    A body solved through a condensed rim (`solver.fe.condense.CondensedBody.solve_at`) gives
    the displacements only at the DOFs ``op`` reads (`StressOperator.dofs`), every load case in
    one block: the full solve's stresses to rounding at a fraction of its cost. Any other body:
    one block of right-hand sides per roll through its one factorisation."""
    from solver.fe.body import sparse_columns

    teeth = [int(t) for t in teeth]
    out = np.empty((3, op.nodes.size, len(teeth), len(rolls)))
    cb = getattr(model, "condensed", None)
    if cb is None:
        for j, u in enumerate(rolls):
            F = np.column_stack([load_vector(t, float(u)) for t in teeth])
            U = np.zeros((model.basis.N, len(teeth)))
            U[model.free] = model.solve(np.ascontiguousarray(F[model.free]))
            out[..., j] = op.apply(U)
        return out
    # columns tooth-major (tooth position * n_rolls + roll), as ``out`` holds them
    cols = []
    for t in teeth:
        for u in rolls:
            f = load_vector(t, float(u))[model.free]
            nz = np.flatnonzero(f)
            cols.append((nz, f[nz]))
    F = sparse_columns(cols, model.free.size)
    pos = np.full(model.basis.N, -1, np.int64)
    pos[model.free] = np.arange(model.free.size)
    dofs = op.dofs
    U = np.zeros((dofs.size, F.shape[1]))          # clamped DOFs: 0
    free = pos[dofs] >= 0
    U[free] = cb.solve_at(F, pos[dofs[free]])
    out[:] = np.stack([np.asarray(c[:, dofs] @ U) for c in (op.xx, op.yy, op.xy)]).reshape(out.shape)
    return out


def load_weights(rolls: np.ndarray, case_tooth: np.ndarray, step: np.ndarray, tooth: np.ndarray, u: np.ndarray,
                 force: np.ndarray, n_steps: int):
    """Sparse weights W (n_teeth * n_rolls, n_steps) [N] of the load cases of
    `load_case_stress` (tooth-major: case = tooth position * n_rolls + roll) for the contact
    loads ``force`` [N] on ``tooth`` at roll ``u`` at each ``step``: each load shared between
    the two nearest rolls of the grid ``rolls`` (linear in u; outside the grid: the nearest
    end). ``case_tooth``: the teeth of the load cases; a load on another tooth is an error."""
    import scipy.sparse as sp

    rolls = np.asarray(rolls, float)
    pos = np.full(int(max(case_tooth.max(), tooth.max(initial=0))) + 1, -1, np.int64)
    pos[case_tooth] = np.arange(case_tooth.size)
    p = pos[tooth]
    if (p < 0).any():
        raise ValueError(f"load_weights: a load on tooth {int(tooth[p < 0][0])}, which has no load case")
    uc = np.clip(u, rolls[0], rolls[-1])
    if rolls.size == 1:
        i, t = np.zeros(u.size, np.int64), np.zeros(u.size)
    else:
        i = np.clip(np.searchsorted(rolls, uc) - 1, 0, rolls.size - 2)
        t = (uc - rolls[i]) / (rolls[i + 1] - rolls[i])
    nr = rolls.size
    rows = np.concatenate([p * nr + i, p * nr + np.minimum(i + 1, nr - 1)])
    cols = np.concatenate([step, step])
    vals = np.concatenate([force * (1 - t), force * t])
    return sp.csr_matrix((vals, (rows, cols)), shape=(case_tooth.size * nr, n_steps))


def peak_stress(S: np.ndarray, W, chunk: int = 256) -> dict:
    """Largest stress at each node over the load steps: S (3, n_nodes, n_cases) [Pa/N] the
    stress per unit load of each case, W (n_cases, n_steps) [N] the loads of each step
    (`load_weights`). Returns {'max_principal', 'von_mises': (n_nodes,) [Pa], and
    'max_principal_step', 'von_mises_step': the step of each node's largest value}."""
    n_nodes, n_steps = S.shape[1], W.shape[1]
    flat = S.reshape(3 * n_nodes, -1)
    best = {k: np.full(n_nodes, -np.inf) for k in ("max_principal", "von_mises")}
    at = {k: np.zeros(n_nodes, np.int64) for k in best}
    Wt = W.T.tocsr()
    for a in range(0, n_steps, chunk):
        block = np.asarray((Wt[a:a + chunk] @ flat.T).T).reshape(3, n_nodes, -1)   # (3, nodes, steps)
        for k, f in (("max_principal", max_principal), ("von_mises", von_mises)):
            v = f(block)
            j = np.argmax(v, axis=1)
            m = v[np.arange(n_nodes), j]
            better = m > best[k]
            best[k][better] = m[better]
            at[k][better] = a + j[better]
    return {**best, **{f"{k}_step": v for k, v in at.items()}}

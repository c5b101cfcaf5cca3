"""Plane-stress FE of a gear body (scikit-fem, quadratic triangles) and per-tooth stiffness.

The body is clamped at the bore. Its thickness is the face width on the teeth, rim and hub and
the web thickness t1 in the web; the stiffness matrix is the sum of the region matrices scaled
by their thickness. One LU factorisation serves all Z load cases. Load case k: a force F on the drive (+) flank of tooth k at the pitch point, along the line of
action (pushing the tooth toward negative polar angle, as the mating gear does), spread
uniformly over a patch of half-width ``patch`` along the profile (a 2D point load has a
mesh-dependent log singularity).

Tooth stiffness about the pivot Q (on the tooth axis at the pivot radius): the load line
crosses the tooth axis at C; a rigid rotation phi about Q moves C along the load by phi*lever,
lever = distance from Q to the load line. So

    k_phi = F * lever**2 / delta_C,   delta_C = u(C) . d

Reading the deflection at the tooth centreline (not under the load) keeps the local contact
flattening out of the spring: that part belongs to the contact law, whose Weber fit measures
the flattening down to the same centreline (see `solver.identify.weber`). delta_C holds tooth
bending and shear, the fillet/foundation deflection and the wind-up of the whole body to the
bore. Units: SI in and out (m, N, Pa, N·m/rad).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from solver.fe.factor import blas1_solver, factorise
from solver.fe.mesh import REGION_WEB, BodyMesh
from solver.geometry import GearGeometry, Material, fillet_band


@dataclass(frozen=True)
class LoadCase:
    """Pitch-point load on the + flank of one tooth (gear frame)."""

    point: np.ndarray       # load point P on the flank [m]
    direction: np.ndarray   # unit load direction d (along the line of action)
    centre_point: np.ndarray  # C: load line on the tooth axis [m]
    lever: float            # distance pivot -> load line [m]


def load_case(g: GearGeometry, tooth: int, pivot_radius: float, u: float | None = None) -> LoadCase:
    """Geometry of the load on the + flank of tooth ``tooth`` at roll parameter u (default: the
    pitch point), with the tooth's pivot at ``pivot_radius`` [m]."""
    u = math.tan(g.spec.pressure_angle) if u is None else float(u)
    t = g.psi_base - u
    rb = g.base_radius
    p = np.array([rb * math.cos(t) - rb * u * math.sin(t), rb * math.sin(t) + rb * u * math.cos(t)])
    d = np.array([math.sin(t), -math.cos(t)])     # -n(t): into the tooth, toward -polar angle
    s = p[1] / math.cos(t)                        # P + s*d lies on the axis (y = 0)
    c = p + s * d
    q = np.array([pivot_radius, 0.0])
    lever = abs((p[0] - q[0]) * d[1] - (p[1] - q[1]) * d[0])
    a = tooth * g.pitch_angle
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return LoadCase(rot @ p, rot @ d, rot @ c, lever)


@dataclass
class BodyModel:
    """Assembled and factorised plane-stress model of a clamped gear body."""

    mesh: BodyMesh
    basis: object           # skfem Basis (vector P2)
    thickness: np.ndarray   # (m,) element thickness [m]
    free: np.ndarray        # free DOF indices
    solve: object           # factorised K_ff: rhs -> displacement of the free DOFs (one BLAS thread)
    material: Material
    assembly_time: float = 0.0   # wall seconds of the assembly (incl. basis and clamping)
    factor_time: float = 0.0     # wall seconds of the factorisation
    assembly_cpu: float = 0.0    # CPU seconds of the same (all threads of the process)
    factor_cpu: float = 0.0
    factor: object = None        # the SuperLU object behind ``solve`` (for `solver.fe.factor.influence`)
    triangles: tuple | None = field(default=None, repr=False)   # (L, U^T) in CSC, made once on demand
    condensed: object = field(default=None, repr=False)   # `solver.fe.condense.CondensedBody` behind ``solve``, if any

    @property
    def n_dofs(self) -> int:
        return self.basis.N


def plane_stress_lame(E: float, nu: float) -> tuple[float, float]:
    """Lame parameters (lambda*, mu) of plane stress [Pa]."""
    mu = E / (2 * (1 + nu))
    lam = E * nu / (1 - nu**2)   # = 2 lambda mu / (lambda + 2 mu)
    return lam, mu


def plane_stress_p2_stiffness(basis, lam: float, mu: float, thickness: np.ndarray, elements: np.ndarray | None = None):
    """Stiffness matrix (COO, N x N) [N/m] of straight-sided quadratic triangles in plane stress
    with Lame parameters ``lam`` (plane-stress lambda*), ``mu`` [Pa] and per-element
    ``thickness`` [m], in the DOF numbering of the vector P2 ``basis`` (scikit-fem).
    ``elements``: only these elements (indices; ``thickness`` still indexed by element).

    Closed form instead of the generic form assembly (about 4x faster on a gear body): on an
    affine triangle the P2 gradients are linear, the integrand quadratic, so the edge-midpoint
    rule integrates it exactly; the result equals ``skfem.asm(linear_elasticity)`` to rounding.
    """
    import scipy.sparse as sp

    m = basis.mesh
    sel = np.arange(m.t.shape[1]) if elements is None else np.asarray(elements)
    t = m.t[:, sel]                                      # (3, nel) vertex indices
    t2f = m.t2f[:, sel]
    thickness = np.asarray(thickness)[sel]
    nel = t.shape[1]
    x, y = m.p[0, t], m.p[1, t]
    a2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0])     # twice the signed area
    gl = np.empty((nel, 3, 2))                           # gradients of the barycentric coordinates
    for k in range(3):
        k1, k2 = (k + 1) % 3, (k + 2) % 3
        gl[:, k, 0] = (y[k1] - y[k2]) / a2
        gl[:, k, 1] = (x[k2] - x[k1]) / a2
    # local vertex pair (a, b) of each element edge, in the basis' own edge order (t2f)
    ends = m.facets[:, t2f]                              # (2, 3, nel) global vertices
    loc = np.stack([[np.argmax(t == ends[s_, j][None, :], axis=0) for j in range(3)] for s_ in range(2)])
    e = np.arange(nel)
    xx, yy, xy = (np.zeros((nel, 6, 6)) for _ in range(3))
    for q in range(3):                                   # midpoint of the edge opposite vertex q
        bary = np.full((nel, 3), 0.5)
        bary[:, q] = 0.0
        g = np.empty((nel, 6, 2))                        # scalar P2 gradients: vertices, then edges
        for k in range(3):
            g[:, k] = (4 * bary[:, k] - 1)[:, None] * gl[:, k]
        for j in range(3):
            a, b = loc[0, j], loc[1, j]
            g[:, 3 + j] = 4 * (bary[e, a][:, None] * gl[e, b] + bary[e, b][:, None] * gl[e, a])
        gx, gy = g[:, :, 0], g[:, :, 1]
        xx += gx[:, :, None] * gx[:, None, :]
        yy += gy[:, :, None] * gy[:, None, :]
        xy += gx[:, :, None] * gy[:, None, :]
    w = (0.5 * np.abs(a2) * thickness / 3.0)[:, None, None]      # area/3 per point, times thickness
    xx *= w; yy *= w; xy *= w
    yx = xy.transpose(0, 2, 1)
    ke = np.empty((nel, 12, 12))                         # local order: (x, y) of each scalar function
    ke[:, 0::2, 0::2] = (lam + 2 * mu) * xx + mu * yy
    ke[:, 1::2, 1::2] = (lam + 2 * mu) * yy + mu * xx
    ke[:, 0::2, 1::2] = lam * xy + mu * yx
    ke[:, 1::2, 0::2] = lam * yx + mu * xy
    nd, fd = basis.nodal_dofs, basis.facet_dofs
    dofs = np.empty((nel, 12), dtype=np.int64)
    for k in range(3):
        dofs[:, 2 * k], dofs[:, 2 * k + 1] = nd[0, t[k]], nd[1, t[k]]
    for j in range(3):
        dofs[:, 6 + 2 * j], dofs[:, 7 + 2 * j] = fd[0, t2f[j]], fd[1, t2f[j]]
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    return sp.coo_matrix((ke.ravel(), (rows, cols)), shape=(basis.N, basis.N))


def assemble(mesh: BodyMesh, face_width: float, web_thickness: float, material: Material, order: int = 2) -> BodyModel:
    """Assemble K (thickness-weighted), clamp the bore and factorise once."""
    import time

    import skfem
    from skfem.models.elasticity import linear_elasticity

    t0, c0 = time.perf_counter(), time.process_time()
    m = skfem.MeshTri(mesh.points.T.copy(), mesh.triangles.T.copy())
    elem = skfem.ElementVector(skfem.ElementTriP2() if order == 2 else skfem.ElementTriP1())
    basis = skfem.Basis(m, elem)
    lam, mu = plane_stress_lame(material.youngs_modulus, material.poisson_ratio)
    thickness = np.where(mesh.region == REGION_WEB, web_thickness, face_width)
    if order == 2:
        K = plane_stress_p2_stiffness(basis, lam, mu, thickness)
    else:
        form = linear_elasticity(lam, mu)
        K = None
        for t in np.unique(thickness):
            idx = np.nonzero(thickness == t)[0]
            Kr = t * skfem.asm(form, skfem.Basis(m, elem, elements=idx))
            K = Kr if K is None else K + Kr
    r_tol = 1e-6 * mesh.bore_radius + 1e-9
    clamped = basis.get_dofs(lambda x: np.hypot(x[0], x[1]) < mesh.bore_radius + r_tol).all()
    keep = np.ones(basis.N, bool)
    keep[clamped] = False
    free = np.flatnonzero(keep)
    Kff = K.tocsc()[:, free][free, :].tocsc()
    t1, c1 = time.perf_counter(), time.process_time()
    lu = factorise(Kff)
    t2, c2 = time.perf_counter(), time.process_time()
    return BodyModel(mesh, basis, thickness, free, blas1_solver(lu), material, t1 - t0, t2 - t1, c1 - c0, c2 - c1, lu)


def load_vector(model: BodyModel, case: LoadCase, force: float, patch: float, edges: tuple | None = None,
                sparse: bool = False):
    """Nodal forces of ``force`` [N] spread uniformly over the boundary within ``patch`` [m] of the
    load point, along the load direction. ``edges``: the mesh's `boundary_edges`, if at hand.
    ``sparse``: (the loaded DOFs, sorted; their forces [N]) instead of the vector of every DOF.

    A uniform traction q on a straight quadratic edge of length L has the consistent nodal
    loads q L/6 at each end and 2 q L/3 at the mid-side node (exact), so no quadrature is needed.
    """
    m = model.basis.mesh
    p, d = case.point, case.direction
    bf, mid = boundary_edges(model) if edges is None else edges
    dist = np.hypot(mid[0] - p[0], mid[1] - p[1])
    sel = bf[dist <= patch]
    if sel.size == 0:       # patch narrower than an element: the nearest edge carries the load
        sel = bf[[np.argmin(dist)]]
    ends = m.facets[:, sel]                                   # (2, n) vertex indices
    length = np.hypot(*(m.p[:, ends[1]] - m.p[:, ends[0]]))
    q = force / length.sum()
    nd = model.basis.nodal_dofs
    dofs, loads = [], []                                      # summed in this order (`np.add.at`)
    for c in range(2):
        dofs += [nd[c, ends[0]], nd[c, ends[1]]]
        loads += [q * d[c] * length / 6] * 2
        if model.basis.facet_dofs.size:                       # P2: mid-side dofs
            dofs.append(model.basis.facet_dofs[c, sel])
            loads.append(2 * q * d[c] * length / 3)
        else:                                                 # P1: ends take half each
            dofs += [nd[c, ends[0]], nd[c, ends[1]]]
            loads += [q * d[c] * length / 3] * 2
    dofs, loads = np.concatenate(dofs), np.concatenate(loads)
    if sparse:
        at, inv = np.unique(dofs, return_inverse=True)
        return at, np.bincount(inv, weights=loads, minlength=at.size)
    f = np.zeros(model.basis.N)
    np.add.at(f, dofs, loads)
    return f


def boundary_edges(model: BodyModel) -> tuple:
    """(the boundary facets of the model's mesh, their midpoints (2, n) [m])."""
    m = model.basis.mesh
    bf = m.boundary_facets()
    return bf, m.p[:, m.facets[:, bf]].mean(axis=1)


def solve_load(model: BodyModel, f: np.ndarray) -> np.ndarray:
    """Displacement [m] of all DOFs for the nodal force vector f [N]."""
    u = np.zeros(model.basis.N)
    u[model.free] = model.solve(f[model.free])
    return u


def point_displacement(model: BodyModel, u: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Displacement (2,) [m] at point x (2,) [m]."""
    P = model.basis.probes(np.asarray(x, float).reshape(2, 1))
    return np.asarray(P @ u).ravel()


def sparse_columns(cols, n_rows: int):
    """CSC matrix (n_rows, len(cols)) of columns given as (rows, values) each: load vectors
    that touch a few dozen DOFs, stacked without a dense block."""
    import scipy.sparse as sp
    return sp.csc_matrix((np.concatenate([v for _, v in cols]), np.concatenate([r for r, _ in cols]),
                          np.cumsum([0] + [r.size for r, _ in cols])), shape=(n_rows, len(cols)))


def _map_loads(model: BodyModel, g: GearGeometry, pivot_radius: float, teeth: list, force: float, patch: float,
               free_sparse: bool = False):
    """(load cases, their nodal forces F (N_dofs, n) [N], the probes P (2n, N_dofs) of their
    tooth-centreline points: rows x of all points, then y) of the spring map. ``free_sparse``:
    F on the free DOFs only, (n_free, n) CSC (a few dozen nonzeros a column, against a dense
    block of some 70,000 rows)."""
    cases = [load_case(g, i, pivot_radius) for i in teeth]
    edges = boundary_edges(model)
    if free_sparse:
        pos = np.full(model.basis.N, -1, np.int64)
        pos[model.free] = np.arange(model.free.size)
        cols = []
        for c in cases:
            dofs, f = load_vector(model, c, force, patch, edges, sparse=True)
            keep = (pos[dofs] >= 0) & (f != 0)                         # (a clamped DOF takes no load)
            cols.append((pos[dofs[keep]], f[keep]))
        F = sparse_columns(cols, model.free.size)
    else:
        F = np.column_stack([load_vector(model, c, force, patch, edges) for c in cases])
    P = model.basis.probes(np.column_stack([c.centre_point for c in cases])).tocsr()
    return cases, F, P


def tooth_stiffness(model: BodyModel, g: GearGeometry, pivot_radius: float, teeth, force: float,
                    patch: float) -> tuple[np.ndarray, np.ndarray]:
    """Torsion stiffness k_phi [N·m/rad] of the listed teeth and their displacement fields.

    All load cases go through the one factorisation as a block of right-hand sides.
    Returns (k (n,), u (N_dofs, n)).
    """
    teeth = [int(i) for i in teeth]
    cases, F, P = _map_loads(model, g, pivot_radius, teeth, force, patch)
    U = np.zeros((model.basis.N, len(teeth)))
    U[model.free] = model.solve(np.ascontiguousarray(F[model.free]))
    return _stiffness(teeth, cases, P, U, force), U


def tooth_map(model: BodyModel, g: GearGeometry, pivot_radius: float, teeth, force: float,
              patch: float) -> tuple[np.ndarray, np.ndarray]:
    """(k_phi [N·m/rad], largest von Mises fillet stress [Pa]) of the listed teeth: the numbers
    of `tooth_stiffness` and `fillet_stress` (to rounding), from only the displacements they
    read, each load case's at its own tooth's centreline probe and fillet-band DOFs. A body
    solved through a condensed rim reads them by restricted solves
    (`solver.fe.condense.CondensedBody.column_reads`) instead of back-substituting the whole
    rim for every load case; any other body is solved in full."""
    teeth = [int(i) for i in teeth]
    if model.condensed is None:
        k, U = tooth_stiffness(model, g, pivot_radius, teeth, force, patch)
        return k, fillet_stress(model, g, U, teeth)
    cases, F, P = _map_loads(model, g, pivot_radius, teeth, force, patch, free_sparse=True)
    bands = _fillet_bands(model, g, teeth)
    n, ed = len(teeth), model.basis.element_dofs
    pos = np.full(model.basis.N, -1, np.int64)
    pos[model.free] = np.arange(model.free.size)
    reads = []
    for j, band in enumerate(bands):
        probe = [P.indices[P.indptr[i]:P.indptr[i + 1]] for i in (j, n + j)]
        dofs = np.unique(np.concatenate([ed[:, band].ravel(), *probe]))
        reads.append(dofs[pos[dofs] >= 0])                  # a clamped DOF reads 0
    cols = model.condensed.column_reads(F, [pos[r] for r in reads])
    U = np.full((model.basis.N, n), np.nan)                 # NaN: not read (would show in k or stress)
    U[pos < 0] = 0.0
    for j, (r, c) in enumerate(zip(reads, cols)):
        U[r, j] = c
    k = _stiffness(teeth, cases, P, U, force)
    stress = fillet_stress(model, g, U, teeth, bands=bands)
    if not (np.all(np.isfinite(k)) and np.all(np.isfinite(stress) | np.array([b.size == 0 for b in bands]))):
        raise RuntimeError("tooth_map: a load case read a displacement it did not solve for")
    return k, stress


def _stiffness(teeth: list, cases: list, P, U: np.ndarray, force: float) -> np.ndarray:
    """k_phi [N·m/rad] of each tooth from its load case's displacement U[:, j] [m] read by the
    probes P at its centreline point."""
    n = len(teeth)
    uc = np.asarray(P @ U)
    k = np.empty(n)
    for j, c in enumerate(cases):
        delta = uc[j, j] * c.direction[0] + uc[n + j, j] * c.direction[1]
        if not delta > 0:
            raise RuntimeError(f"tooth {teeth[j]}: non-positive deflection {delta:.3g} m at the tooth centreline")
        k[j] = force * c.lever**2 / delta
    return k


def stress_basis(model: BodyModel):
    """The basis `von_mises` reads the strains with: the body's own, over the points of the
    element's default quadrature (a condensed body's basis holds one point an element: a new one
    of those points, worth building once for several displacement fields)."""
    import skfem

    basis = model.basis
    if basis.X.shape[1] == 1:
        basis = skfem.Basis(basis.mesh, basis.elem)
    return basis


def von_mises(model: BodyModel, u: np.ndarray, basis=None) -> np.ndarray:
    """Element-mean von Mises stress [Pa] (plane stress) of displacement u, over the points of the
    element's default quadrature (``basis``: `stress_basis` of the model, made here if None)."""
    from skfem.helpers import sym_grad

    w = (stress_basis(model) if basis is None else basis).interpolate(u)
    eps = sym_grad(w)                     # (2, 2, nelem, nqp)
    lam, mu = plane_stress_lame(model.material.youngs_modulus, model.material.poisson_ratio)
    tr = eps[0, 0] + eps[1, 1]
    sxx = lam * tr + 2 * mu * eps[0, 0]
    syy = lam * tr + 2 * mu * eps[1, 1]
    sxy = 2 * mu * eps[0, 1]
    vm = np.sqrt(sxx**2 - sxx * syy + syy**2 + 3 * sxy**2)
    return vm.mean(axis=1)


@dataclass(frozen=True)
class BodyField:
    """FE mesh and the response to one tooth load, for renders. SI units."""

    points: np.ndarray        # (n, 2) vertex coordinates [m]
    triangles: np.ndarray     # (m, 3)
    thickness: np.ndarray     # (m,) element thickness [m]
    web: np.ndarray           # (m,) True in the web
    displacement: np.ndarray  # (n, 2) vertex displacement [m]
    von_mises: np.ndarray     # (m,) element-mean von Mises stress [Pa]
    tooth: int                # loaded tooth
    load_N: float             # load [N]
    load_point: np.ndarray    # (2,) [m]
    load_direction: np.ndarray  # (2,)


def body_field(model: BodyModel, g: GearGeometry, u: np.ndarray, tooth: int, force: float, pivot_radius: float,
               basis=None) -> BodyField:
    """Pack the vertex displacement and element stress of one load case (``basis``: the model's
    `stress_basis`, shared by the load cases of one body; made here if None)."""
    nv = model.mesh.points.shape[0]
    # vertex DOFs of the vector P2 basis: nodal_dofs[c, vertex]
    nd = model.basis.nodal_dofs
    disp = np.column_stack([u[nd[0, :nv]], u[nd[1, :nv]]])
    case = load_case(g, tooth, pivot_radius)
    return BodyField(model.mesh.points, model.mesh.triangles, model.thickness, model.mesh.region == REGION_WEB,
                     disp, von_mises(model, u, basis), tooth, force, case.point, case.direction)


def _fillet_bands(model: BodyModel, g: GearGeometry, teeth) -> list:
    """The elements (sorted indices) of each listed tooth's `fillet_band`."""
    mesh = model.mesh
    centroids = mesh.points[mesh.triangles].mean(axis=1)
    # each band lies within a module of the root circle and a pitch of its tooth's axis: only the
    # elements of a ring twice as wide, within 1.5 pitches of the axis, are tested tooth by tooth
    # (the same bands)
    ring = np.flatnonzero(np.abs(np.hypot(centroids[:, 0], centroids[:, 1]) - g.root_radius) < 2 * g.spec.module)
    angle = np.arctan2(centroids[ring, 1], centroids[ring, 0])
    by_angle = np.argsort(angle)
    angle = angle[by_angle]
    out = []
    for t in teeth:
        axis = (int(t) * g.pitch_angle + math.pi) % (2 * math.pi) - math.pi
        lo, hi = axis - 1.5 * g.pitch_angle, axis + 1.5 * g.pitch_angle
        spans = [(lo, hi)] if -math.pi <= lo and hi <= math.pi else \
            [(lo + 2 * math.pi, math.pi), (-math.pi, hi)] if lo < -math.pi else [(lo, math.pi), (-math.pi, hi - 2 * math.pi)]
        near = np.sort(ring[np.concatenate([by_angle[np.searchsorted(angle, a):np.searchsorted(angle, b, "right")]
                                            for a, b in spans])])
        out.append(near[fillet_band(centroids[near], g, int(t))])
    return out


def fillet_stress(model: BodyModel, g: GearGeometry, U: np.ndarray, teeth, kind: str = "von_mises",
                  bands: list | None = None) -> np.ndarray:
    """Largest fillet stress [Pa] of each listed tooth under its own load case (column j of the
    displacements U (N_dofs, n) belongs to ``teeth[j]``).

    The stress is evaluated at the vertices of the elements of the tooth's `fillet_band` (the
    quadratic elements' stress is linear, its vertex values on the fillet surface are the
    surface stress; element means read some 15 % low and vary from tooth to tooth with the
    mesh). ``kind``: 'von_mises' (plane stress; both fillets, the compression side usually
    carries the peak) or 'max_principal' (the largest tensile principal stress: the loaded
    flank's fillet, what ISO 6336-3 rates). ``bands``: the teeth's `_fillet_bands` (element indices), if at hand.
    """
    import skfem
    from skfem.element import DiscreteField
    from skfem.helpers import sym_grad

    if kind not in ("von_mises", "max_principal"):
        raise ValueError(f"kind: 'von_mises' or 'max_principal', got {kind!r}")
    lam, mu = plane_stress_lame(model.material.youngs_modulus, model.material.poisson_ratio)
    vertices = (np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), np.full(3, 1.0 / 6.0))   # reference vertices
    bands = _fillet_bands(model, g, teeth) if bands is None else bands
    union = np.unique(np.concatenate(bands)) if bands else np.empty(0, np.int64)
    # one basis over the bands of all teeth (a basis per tooth cost more than the rest of the
    # stress); every (tooth, band element) pair at once, each summing its tooth's displacement
    # times the basis gradients in the order skfem's `interpolate` does (the same numbers)
    out = np.full(len(teeth), np.nan)
    if not union.size:
        return out
    b = skfem.Basis(model.basis.mesh, model.basis.elem, elements=union, quadrature=vertices)
    sels = [np.searchsorted(union, band) for band in bands]
    sel = np.concatenate(sels)
    col = np.repeat(np.arange(len(teeth)), [x.size for x in sels])
    grads = [b.basis[i][0].grad[:, :, sel] for i in range(b.Nbfun)]      # (2, 2, n_pairs, 3) each
    grad = 0.0 * (U[b.element_dofs[0, sel], col][:, None] * grads[0])
    for i, gi in enumerate(grads):
        grad += U[b.element_dofs[i, sel], col][:, None] * gi
    eps = sym_grad(DiscreteField(grad=grad))
    tr = eps[0, 0] + eps[1, 1]
    sxx, syy, sxy = lam * tr + 2 * mu * eps[0, 0], lam * tr + 2 * mu * eps[1, 1], 2 * mu * eps[0, 1]
    if kind == "von_mises":
        s = np.sqrt(sxx**2 - sxx * syy + syy**2 + 3 * sxy**2)
    else:
        s = 0.5 * (sxx + syy) + np.sqrt(0.25 * (sxx - syy) ** 2 + sxy**2)
    peak = s.max(axis=1)                                                 # (n_pairs,)
    has = np.flatnonzero([x.size > 0 for x in sels])
    out[has] = np.maximum.reduceat(peak, np.cumsum([0] + [x.size for x in sels])[has])
    return out

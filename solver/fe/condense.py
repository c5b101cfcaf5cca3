"""Static condensation of a gear body's teeth and rim onto the circle where the web begins.

The teeth and the rim (the region `REGION_RIM` of `solver.fe.mesh`, down to ``root -
rim_height``) are the same for every web of one rim height: same outline, same size field, and
gmsh meshes each region from its own boundary, so their elements are the same whatever the
holes and the web thickness. Their stiffness is condensed once onto the interface DOFs ``i``
(shared with the web) and every body then factors only its web:

    rim:   K_R = [[K_rr, K_ri], [K_ir, K_ii^R]],   S_R = K_ii^R - K_ir K_rr^-1 K_ri      (once)
    body:  S = S_R + K_ii^W - K_iw K_ww^-1 K_wi,   one Cholesky of the dense S            (per web)

A load f on the whole body (parts f_r, f_i, f_w) is then solved exactly (the same equations as
the whole-body factorisation, to rounding):

    y = K_rr^-1 f_r,  t = K_ww^-1 f_w,  S u_i = f_i - K_ir y - K_iw t,
    u_w = t - K_ww^-1 K_wi u_i,  u_r = y - K_rr^-1 K_ri u_i.

Influence coefficients R K^-1 F with loads and reads in the teeth (the compliance of
`solver.fe.ltca`) need only the rim's products G0 = R K_rr^-1 F, A = R K_rr^-1 K_ri and
B = K_ir K_rr^-1 F, made once per rim and load set (`RimBlock.products`):

    R K^-1 F = G0 + A S^-1 B     (the interface, free, moves by u_i = -S^-1 B).

Where each load case reads its own few DOFs (the spring map: load case j at its tooth's probe
and fillet band), the reads are made per column instead (`CondensedBody.column_reads`): with
the interface-last factorisation, the forward solve s = L11^-1 Pr1 f_j and B are the rim's
(made once per load set), and per body only u_i = -S^-1 B and, per column, the back-substitution
U11 w = s - U12 u_i restricted to the rows the column's reads depend on (their ancestors in
U11's graph: some 2,000 of the rim's 71,000 interior DOFs on a gear), not the whole rim.
The rim's restricted solves are in `solver.fe.rim_solves`.

Units: SI (m, N, N/m).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from solver.fe.body import BodyModel, plane_stress_lame, plane_stress_p2_stiffness
from solver.fe.factor import blas1_solver, congruence, factorise, influence, one_blas_thread
from solver.fe.mesh import REGION_RIM, REGION_WEB, BodyMesh
from solver.fe.rim_dofs import MATCH_TOL, RimMismatch, rim_dofs_in_body
from solver.fe.rim_solves import ReadSet, RimBack, make_read_set, rim_back, rim_forward, rim_products, rim_reads
from solver.geometry import Material
from solver.store import Shelf, digest

SOLVES_KEPT = 2         # rim solves and column-read sets kept for reuse (`RimBlock.rim_solve`, `RimBlock.read_set`)


class _Size:
    """Stands for a basis where only the number of DOFs ``N`` is read (`solver.fe.factor.influence`)."""

    def __init__(self, n: int):
        self.N = n


def _dof_keys(basis) -> np.ndarray:
    """(N, 3) location [m] and component of every DOF of a vector P2 basis (the component as a
    third coordinate 1 m apart, so that one nearest-point search matches both)."""
    comp = np.empty(basis.N)
    for c in range(2):
        comp[basis.nodal_dofs[c]] = c
        if basis.facet_dofs.size:
            comp[basis.facet_dofs[c]] = c
    return np.column_stack([basis.doflocs.T, comp])


def _basis(points: np.ndarray, triangles: np.ndarray):
    """The vector P2 basis of the mesh, its functions evaluated at one point an element (the
    centroid): what the condensed bodies read of it is its DOF numbering and locations, probes and
    the stiffness in closed form (`plane_stress_p2_stiffness`), none of its quadrature."""
    import skfem
    m = skfem.MeshTri(points.T.copy(), triangles.T.copy())
    return skfem.Basis(m, skfem.ElementVector(skfem.ElementTriP2()), quadrature=_CENTROID)


_CENTROID = (np.array([[1.0 / 3.0], [1.0 / 3.0]]), np.array([0.5]))     # reference point and weight


def _canonical(points: np.ndarray, triangles: np.ndarray, region: np.ndarray) -> tuple:
    """(points, triangles, region) of the used vertices renumbered by x then y, triangles
    sorted by their vertices, each from its lowest vertex with the orientation kept: the same
    arrays for the same elements whatever their numbering before."""
    used, inv = np.unique(triangles.ravel(), return_inverse=True)
    pts = points[used]
    order = np.lexsort((pts[:, 1], pts[:, 0]))
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    t = rank[inv.reshape(-1, 3)]
    first = np.argmin(t, axis=1)
    t = np.take_along_axis(t, (first[:, None] + np.arange(3)) % 3, axis=1)
    sort = np.lexsort((t[:, 2], t[:, 1], t[:, 0]))
    return pts[order], t[sort], region[sort]


def rim_mesh(mesh: BodyMesh) -> BodyMesh:
    """The teeth-and-rim elements of a body mesh as a mesh of their own, numbered canonically
    (`_canonical`), so that the rims of two bodies with the same teeth and rim number their
    DOFs alike whatever the rest of the body did to the numbering."""
    rim = mesh.region == REGION_RIM
    p, t, r = _canonical(mesh.points, mesh.triangles[rim], mesh.region[rim])
    return BodyMesh(p, t, r, mesh.bore_radius, mesh.size)


def web_mesh(mesh: BodyMesh) -> BodyMesh:
    """The web-and-hub elements of a body mesh as a mesh of their own."""
    web = mesh.region != REGION_RIM
    p, t, r = _canonical(mesh.points, mesh.triangles[web], mesh.region[web])
    return BodyMesh(p, t, r, mesh.bore_radius, mesh.size)


@dataclass
class RimBlock:
    """The teeth and rim of one rim height, factorised with the interface held, and condensed
    onto it. DOF numbering: the rim's own vector P2 basis (``model.basis``)."""

    model: BodyModel          # the rim alone; ``free`` = its interior DOFs, ``solve`` = K_rr^-1
    interface: np.ndarray     # (n_i,) rim DOFs shared with the web, sorted
    K_ri: object              # (n_interior, n_i) CSR: coupling of interior and interface [N/m]
    S: np.ndarray             # (n_i, n_i) condensed stiffness of the rim on the interface [N/m]
    keys: np.ndarray          # (N_R, 3) DOF location [m] and component (`_dof_keys`)
    products: dict = field(default_factory=dict)   # load-set key -> (G0, A, B), see the module doc
    blocks: tuple = field(default=(), repr=False)          # (K_rr CSC, K_ii^R CSC) [N/m], for `make_split`
    split: dict | None = field(default=None, repr=False)   # factors of the interface-last factorisation
    key: str = ""                                          # the cache's name for this rim, if any
    tree: object = field(default=None, repr=False)         # cKDTree of ``keys``, made on a body's first match
    # kept K_rr^-1 f (`rim_solve`) and `ReadSet`s (`read_set`): shelves of the rim itself, gone with it
    solves: Shelf = field(default_factory=lambda: Shelf("rim solves", SOLVES_KEPT), repr=False)
    read_sets: Shelf = field(default_factory=lambda: Shelf("rim read sets", SOLVES_KEPT), repr=False)
    backs: Shelf = field(default_factory=lambda: Shelf("rim back-substitutions", SOLVES_KEPT), repr=False)

    @property
    def n_interface(self) -> int:
        return self.interface.size

    def make_split(self) -> None:
        """The interface-last factorisation (see `rim_block`): sets ``split`` and, when not
        given, ``S``."""
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        Krr, K_ii = self.blocks
        order = np.argsort(self.model.factor.perm_c)     # interior positions in K_rr's elimination order
        n = order.size
        K_ri = self.K_ri[order]
        Kp = sp.bmat([[Krr[order][:, order], K_ri], [K_ri.T, K_ii]]).tocsc()
        with one_blas_thread():
            lu = splu(Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
        pr, pc = lu.perm_r, lu.perm_c
        if not (np.all(pr[n:] >= n) and np.all(pc[n:] >= n)):
            raise RimMismatch("the interface did not stay last in the rim's factorisation")
        L, U = lu.L.tocsc(), lu.U.tocsc()
        if self.S is None:
            with one_blas_thread():
                LU = L[n:, n:].toarray() @ U[n:, n:].toarray()      # Pr_b S_R Pc_b
            S = LU[np.ix_(pr[n:] - n, pc[n:] - n)]
            self.S = 0.5 * (S + S.T)
        self.split = dict(order=order, n=n, L11=L[:n, :n].tocsc(), Ut11=U[:n, :n].T.tocsc(), L21=L[n:, :n].tocsr(),
                          U12=U[:n, n:].tocsr(), pr=pr, pc=pc)
        self.blocks = ()                                  # not needed again

    def read_set(self, F, reads: list) -> ReadSet:
        """The rim's part of `CondensedBody.column_reads` for the loads F (n_interior, k) [N]
        (CSC, indices sorted) and the reads ``reads`` (k arrays of rim interior indices, column
        j's reads), made by restricted triangular solves of the interface-last factorisation;
        the last `SOLVES_KEPT` are kept by the loads' and reads' bytes (every web of the rim
        reads the same teeth under the same loads)."""
        key = digest(F.shape, F.data, F.indices.astype(np.int64), F.indptr.astype(np.int64),
                     *(np.asarray(r, np.int64) for r in reads))
        return self.read_sets.kept(key, lambda: make_read_set(self, F, reads))

    def back(self, reads: np.ndarray) -> RimBack:
        """The rim's part of `CondensedBody.solve_at` for the rim interior indices ``reads``
        (`solver.fe.rim_solves.rim_back`); the last `SOLVES_KEPT` are kept by the reads' bytes
        (every web of the rim reads the same strength sites in its teeth and rim)."""
        reads = np.asarray(reads, np.int64)
        return self.backs.kept(digest(reads), lambda: rim_back(self, reads))

    def rim_solve(self, f: np.ndarray) -> np.ndarray:
        """K_rr^-1 f [m] for loads f (n_interior, k) [N]; the last `SOLVES_KEPT` results are
        kept by the loads' bytes (every web of the rim solves its teeth's reference loads)."""
        return self.solves.kept(digest(f), lambda: self.model.solve(f))


def rim_block(mesh: BodyMesh, face_width: float, material: Material, r_interface: float,
              S: np.ndarray | None = None) -> RimBlock:
    """Assemble and factorise the teeth and rim of ``mesh`` (thickness ``face_width`` [m]) with
    the interface circle of radius ``r_interface`` [m] held, and condense onto it (unless the
    condensed stiffness ``S`` [N/m] is given, e.g. read from a cache).

    The condensation is one more factorisation of the rim, interior DOFs first (in the fill-
    reducing order of K_rr's own), interface last: its trailing blocks are the LU factors of
    S_R (S_R = L22 U22), and its leading and coupling blocks give the products of any load
    set by triangular solves restricted to the DOFs the loads and reads reach (`rim_products`).
    """
    rm = rim_mesh(mesh)
    basis = _basis(rm.points, rm.triangles)
    lam, mu = plane_stress_lame(material.youngs_modulus, material.poisson_ratio)
    K = plane_stress_p2_stiffness(basis, lam, mu, np.full(rm.n_elements, face_width)).tocsr()
    # interface: the rim mesh's boundary edges on the inner circle (the outline lies at least a
    # rim height further out) and their end and mid-side DOFs
    m = basis.mesh
    bf = m.boundary_facets()
    r_mid = np.hypot(*m.p[:, m.facets[:, bf]].mean(axis=1))
    inner = bf[r_mid < r_interface + 0.5 * (mesh.size + 1e-9)]
    if inner.size == 0:
        raise RimMismatch("the rim has no inner boundary (no web or hub below it)")
    verts = np.unique(m.facets[:, inner])
    iface = np.unique(np.concatenate([basis.nodal_dofs[:, verts].ravel(), basis.facet_dofs[:, inner].ravel()]))
    keep = np.ones(basis.N, bool)
    keep[iface] = False
    interior = np.flatnonzero(keep)
    Krr = K[interior][:, interior].tocsc()
    lu = factorise(Krr)
    K_ri = K[interior][:, iface].tocsr()
    model = BodyModel(rm, basis, np.full(rm.n_elements, face_width), interior, blas1_solver(lu), material, factor=lu)
    block = RimBlock(model, iface, K_ri, S, _dof_keys(basis), blocks=(Krr, K[iface][:, iface].tocsc()))
    if S is None:
        block.make_split()
    elif S.shape != (iface.size, iface.size):
        raise RimMismatch(f"condensed stiffness of shape {S.shape} for {iface.size} interface DOFs")
    return block


def _dense_rows(U12, share: float = 0.125) -> tuple:
    """(position in the dense block of each row, -1 for the others; the rows of U12 (n, n_i) CSR
    with more than ``share`` of n_i entries, dense; U12 without them, CSR): the rows of the
    interface-last factorisation's coupling block near the interface, which every column read
    passes through, multiplied by the interface displacements at once."""
    import scipy.sparse as sp
    nnz = np.diff(U12.indptr)
    rows = np.flatnonzero(nnz > share * U12.shape[1])
    at = np.full(U12.shape[0], -1, np.int64)
    at[rows] = np.arange(rows.size)
    keep = np.ones(U12.shape[0])
    keep[rows] = 0.0
    rest = sp.csr_matrix(sp.diags(keep) @ U12)
    rest.eliminate_zeros()
    return at, U12[rows].toarray(), rest


@dataclass
class CondensedBody:
    """A whole body solved through its condensed rim and its own web (see the module doc).
    Positions ``pos_*`` index the body's free DOF vector (`BodyModel.free` order)."""

    rim: RimBlock
    pos_r: np.ndarray         # body free position of each rim interior DOF (rim ``model.free`` order)
    pos_i: np.ndarray         # body free position of each interface DOF (rim ``interface`` order)
    pos_w: np.ndarray         # body free position of each free web DOF
    web_solve: object         # K_ww^-1 (one BLAS thread)
    K_wi: object              # (n_w, n_i) CSR [N/m]
    schur: tuple              # Cholesky factor of S (scipy.linalg.cho_factor)
    n_free: int
    _to_rim: np.ndarray | None = field(default=None, repr=False)   # body free position -> rim interior index (-1: not in the rim)

    def schur_solve(self, b: np.ndarray) -> np.ndarray:
        """S^-1 b in single-threaded BLAS (the same bits in a study's workers and in one process)."""
        from scipy.linalg import cho_solve
        with one_blas_thread():
            return cho_solve(self.schur, b)

    def solve(self, f: np.ndarray) -> np.ndarray:
        """K_ff^-1 f for loads f (n_free,) or (n_free, k) [N] on the body's free DOFs [m]."""
        f = np.asarray(f, float)
        vec = f.ndim == 1
        f = f.reshape(f.shape[0], -1)
        rim = self.rim
        y = rim.rim_solve(np.ascontiguousarray(f[self.pos_r]))
        t = self.web_solve(np.ascontiguousarray(f[self.pos_w])) if self.pos_w.size else np.zeros((0, f.shape[1]))
        g = f[self.pos_i] - rim.K_ri.T @ y - (self.K_wi.T @ t if self.pos_w.size else 0.0)
        u_i = self.schur_solve(g)
        u = np.empty((self.n_free, f.shape[1]))
        u[self.pos_i] = u_i
        if self.pos_w.size:
            u[self.pos_w] = t - self.web_solve(np.ascontiguousarray(self.K_wi @ u_i))
        u[self.pos_r] = y - rim.model.solve(np.ascontiguousarray(rim.K_ri @ u_i))
        return u[:, 0] if vec else u

    def _rim_index(self) -> np.ndarray:
        """Rim interior index of each body free position (-1: not in the rim's interior)."""
        if self._to_rim is None:
            to_rim = np.full(self.n_free, -1, np.int64)
            to_rim[self.pos_r] = np.arange(self.pos_r.size)
            self._to_rim = to_rim
        return self._to_rim

    def solve_at(self, f, at: np.ndarray) -> np.ndarray:
        """K_ff^-1 f [m] at the body free positions ``at`` only ((len(at), k)), for loads f
        (n_free, k) [N], dense or sparse: the full solve's numbers (to rounding) without its
        whole field where the loads lie in the rim's interior (teeth and rim). The rim's forward
        solve runs over the rows the loads reach, the interface displacements come from the
        Schur complement, the web's (where read) from one web solve, and the rim's back-
        substitution runs over the rows its reads depend on (`solver.fe.rim_solves`), for every
        column at once: not the two whole-rim and two web solves of `solve`. Loads elsewhere
        (web, interface): the full solve."""
        import scipy.sparse as sp

        fs = sp.csc_matrix(f)
        at = np.asarray(at, np.int64)
        to_rim = self._rim_index()
        if fs.shape[1] == 0 or not np.all(to_rim[fs.indices] >= 0):
            return self.solve(fs.toarray())[at]
        rim = self.rim
        fw = rim_forward(rim, sp.csc_matrix((fs.data, to_rim[fs.indices], fs.indptr), shape=(self.pos_r.size, fs.shape[1])))
        u_i = -self.schur_solve(fw.B)                       # interface displacement [m], rim interface order
        out = np.empty((at.size, fs.shape[1]))
        r = to_rim[at]
        in_rim = r >= 0
        if in_rim.any():
            out[in_rim] = rim_reads(rim, fw, rim.back(r[in_rim]), u_i)
        where = np.full(self.n_free, -1, np.int64)          # interface index, or web index + n_i
        where[self.pos_i] = np.arange(self.pos_i.size)
        where[self.pos_w] = self.pos_i.size + np.arange(self.pos_w.size)
        q = where[at]
        iface = ~in_rim & (q < self.pos_i.size)
        out[iface] = u_i[q[iface]]
        web = ~in_rim & ~iface
        if web.any():       # no load in the web: u_w = -K_ww^-1 K_wi u_i
            out[web] = -self.web_solve(np.ascontiguousarray(self.K_wi @ u_i))[q[web] - self.pos_i.size]
        return out

    def column_reads(self, f, reads: list) -> list:
        """Column j of K_ff^-1 f (f (n_free, k) [N], dense or sparse) at the body free positions
        ``reads[j]`` [m], for each j: the full solve's numbers (to rounding) at a fraction of its
        cost where the loads lie in the teeth and rim and each column reads a few DOFs there (see
        the module doc). Loads or reads elsewhere (web, interface loads): the full solve."""
        import scipy.sparse as sp

        from solver.fe.kernels import back_substitute_reads

        f = f.tocsc() if sp.issparse(f) else np.asarray(f, float).reshape(f.shape[0], -1)
        reads = [np.asarray(r, np.int64) for r in reads]
        rim = self.rim
        to_rim = self._rim_index()
        fs = sp.csc_matrix(f)
        in_rim = all(np.all(to_rim[r] >= 0) for r in reads) and np.all(to_rim[fs.indices] >= 0)
        if not in_rim:
            u = self.solve(fs.toarray())
            return [u[r, j] for j, r in enumerate(reads)]
        F_r = sp.csc_matrix((fs.data, to_rim[fs.indices], fs.indptr), shape=(self.pos_r.size, f.shape[1]))
        F_r.sort_indices()
        rs = rim.read_set(F_r, [to_rim[r] for r in reads])
        n = rim.split["n"]
        u_i = -self.schur_solve(rs.B)                        # interface displacement [m], rim interface order
        w2 = np.empty_like(u_i)
        w2[rim.split["pc"][n:] - n] = u_i                    # in the factorisation's interface order
        Ut11 = rim.split["Ut11"]
        if "inv_diag" not in rim.split:
            rim.split["inv_diag"] = 1.0 / Ut11.diagonal()
            rim.split["U12 rows"] = _dense_rows(rim.split["U12"])
        dense, U12_dense, U12_rest = rim.split["U12 rows"]
        with one_blas_thread():
            u12w = U12_dense @ w2                            # U12 u_i on its rows that hold most of it
        # every column's restricted back-substitution U11 w = s - U12 u_i in one compiled call
        # (Ut11 in CSC is U11 in CSR)
        rows_ptr = np.cumsum([0] + [r.size for r in rs.rows])
        w = back_substitute_reads(Ut11.indptr, Ut11.indices, Ut11.data, rim.split["inv_diag"], U12_rest.indptr,
                                  U12_rest.indices, U12_rest.data, np.ascontiguousarray(w2.T), dense, u12w,
                                  np.concatenate(rs.rows), rows_ptr, np.concatenate(rs.s))
        return [w[rows_ptr[j] + rs.at[j]] for j in range(f.shape[1])]

    def influence(self, R_rim, F_rim, key) -> np.ndarray:
        """R K^-1 F [m/N for unit loads] of reads R (m, N_R) and loads F (N_R, k) on the rim's
        interior DOFs (rim numbering), through the rim's products of the load set ``key``
        (made and kept in ``rim.products`` on first use; R and F may be None once kept)."""
        G0, A, B = rim_products(self.rim, R_rim, F_rim, key)
        X = self.schur_solve(B)
        with one_blas_thread():
            return G0 + A @ X


def assemble_condensed(mesh: BodyMesh, face_width: float, web_thickness: float, material: Material,
                       rim: RimBlock) -> BodyModel:
    """The body of ``mesh`` clamped at the bore, solved through the condensed ``rim`` (which
    must hold the same teeth-and-rim elements: `RimMismatch` otherwise) and its own web and hub
    (thickness ``web_thickness`` in the web, ``face_width`` in the hub [m]). The returned model
    solves exactly as `solver.fe.body.assemble`'s; ``factor`` is None, ``condensed`` set."""
    import time

    import scipy.sparse as sp
    from scipy.linalg import cho_factor

    t0, c0 = time.perf_counter(), time.process_time()
    basis = _basis(mesh.points, mesh.triangles)
    is_rim = mesh.region == REGION_RIM
    if is_rim.sum() != rim.model.mesh.n_elements:
        raise RimMismatch(f"{int(is_rim.sum())} teeth-and-rim elements, the condensed rim has {rim.model.mesh.n_elements}")
    ed = basis.element_dofs
    in_rim = np.zeros(basis.N, bool)
    in_rim[ed[:, is_rim].ravel()] = True
    in_web = np.zeros(basis.N, bool)
    in_web[ed[:, ~is_rim].ravel()] = True
    rim_dofs = np.flatnonzero(in_rim)
    keys = _dof_keys(basis)
    from_rim = rim_dofs_in_body(basis, is_rim, rim, rim_dofs, keys)     # body DOF of each rim DOF
    to_rim = np.full(basis.N, -1)
    to_rim[from_rim] = np.arange(from_rim.size)
    shared = np.flatnonzero(in_rim & in_web)
    if not np.array_equal(np.sort(to_rim[shared]), rim.interface):
        raise RimMismatch("the body's rim-web interface differs from the condensed rim's")
    lam, mu = plane_stress_lame(material.youngs_modulus, material.poisson_ratio)
    thickness = np.where(mesh.region == REGION_WEB, web_thickness, face_width)
    K_W = plane_stress_p2_stiffness(basis, lam, mu, thickness, elements=np.flatnonzero(~is_rim)).tocsr()
    r_tol = 1e-6 * mesh.bore_radius + 1e-9
    clamped = basis.get_dofs(lambda x: np.hypot(x[0], x[1]) < mesh.bore_radius + r_tol).all()
    keep = np.ones(basis.N, bool)
    keep[clamped] = False
    free = np.flatnonzero(keep)
    pos = np.full(basis.N, -1)
    pos[free] = np.arange(free.size)
    if np.any(pos[rim_dofs] < 0):
        raise RimMismatch("the bore clamp reaches the teeth and rim")
    # positions in the body's free vector
    pos_r = pos[from_rim[rim.model.free]]
    body_i = from_rim[rim.interface]
    pos_i = pos[body_i]
    web_free = np.flatnonzero(in_web & keep & ~in_rim)
    pos_w = pos[web_free]
    K_ww = K_W[web_free][:, web_free].tocsc()
    K_wi = K_W[web_free][:, body_i].tocsr()
    S = rim.S + K_W[body_i][:, body_i].toarray()
    t1, c1 = time.perf_counter(), time.process_time()
    web_solve = None
    if web_free.size:
        lu_w = factorise(K_ww)
        web_solve = blas1_solver(lu_w)
        # K_iw K_ww^-1 K_wi by triangular solves over the web DOFs each interface DOF reaches
        # and a product over the arcs of the interface circle they couple to (interface DOFs
        # in the order of their polar angle); two solves and a general product if the web's
        # factorisation is not symmetric
        around = np.lexsort((keys[body_i, 2], np.arctan2(keys[body_i, 1], keys[body_i, 0])))
        W = congruence(lu_w, K_wi, order=around)
        if W is None:
            web = BodyModel(mesh, _Size(web_free.size), None, np.arange(web_free.size), web_solve, material, factor=lu_w)
            W = influence(web, K_wi.T.tocsr(), K_wi)
        S -= W
    if not np.array_equal(S, S.T):      # (S_R + K_ii^W - W as assembled is symmetric to the bit)
        S = 0.5 * (S + S.T)
    with one_blas_thread():
        schur = cho_factor(S, lower=True, check_finite=False)
    cb = CondensedBody(rim, pos_r, pos_i, pos_w, web_solve, K_wi if web_free.size else sp.csr_matrix((0, body_i.size)),
                       schur, free.size)
    t2, c2 = time.perf_counter(), time.process_time()
    return BodyModel(mesh, basis, thickness, free, cb.solve, material, t1 - t0, t2 - t1, c1 - c0, c2 - c1,
                     factor=None, condensed=cb)


def join_rim(rim: RimBlock, web: BodyMesh) -> BodyMesh:
    """The whole body mesh: the condensed rim's teeth-and-rim elements and the web-and-hub
    elements of ``web`` (a body mesh; `solver.fe.mesh.mesh_body` with ``rim=False`` meshes
    only those), their interface vertices merged, every number canonical. `RimMismatch` when the web's outer boundary does not meet the rim's inner
    one node for node."""
    from scipy.spatial import cKDTree

    rm = rim.model.mesh
    # canonical order: the same body mesh whether the web came from the whole body's mesh or
    # was meshed alone (the same solves, to the last bit)
    web = web_mesh(web)
    nodes = np.unique(rim.model.basis.mesh.facets[:, rim.model.basis.mesh.boundary_facets()])
    r_rim = np.hypot(*rm.points[nodes].T)
    inner = nodes[r_rim < r_rim.min() + 0.5 * rm.size]              # the rim's interface vertices
    dist, idx = cKDTree(rm.points[inner]).query(web.points)
    shared = dist < MATCH_TOL
    if np.unique(idx[shared]).size != inner.size or shared.sum() != inner.size:
        raise RimMismatch("the web's outer boundary does not meet the condensed rim's nodes")
    new = np.full(web.points.shape[0], -1, np.int64)
    new[shared] = inner[idx[shared]]
    own = np.flatnonzero(~shared)
    new[own] = rm.points.shape[0] + np.arange(own.size)
    points = np.vstack([rm.points, web.points[own]])
    return BodyMesh(points, np.vstack([rm.triangles, new[web.triangles]]), np.concatenate([rm.region, web.region]),
                    web.bore_radius, web.size)

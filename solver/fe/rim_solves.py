"""Restricted triangular solves through a condensed rim's interface-last factorisation
(`solver.fe.condense.RimBlock.make_split`): the rim's part of a body's influence coefficients
(`rim_products`: G0, A, B) and of its per-column reads (`make_read_set`), each made once per rim and
load set and shared by every web of the rim. Each solve runs only over the rows the loads (the
reads) reach through the factors' graphs (`solver.fe.factor`). Units: SI (m, N, N/m).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.fe.factor import SOLVE_BLOCK, _lower_solve, _reach, one_blas_thread


@dataclass
class ReadSet:
    """The rim's part of per-column reads (`RimBlock.read_set`): for each load column j, the
    rows ``rows[j]`` of the interface-last factorisation's U11 that its reads depend on (sorted,
    closed under U11's graph), the forward solution s_j = L11^-1 Pr1 f_j on them, and where in
    them each read lies; and B = K_ir K_rr^-1 F of the module doc."""

    rows: list            # k arrays: U11 positions of column j's restricted back-substitution
    s: list               # k arrays: L11^-1 Pr1 f_j on ``rows[j]`` (U11 w = s gives w in m)
    at: list              # k arrays: position in ``rows[j]`` of each of column j's reads
    B: np.ndarray         # (n_i, k) K_ir K_rr^-1 F [N]


def _closed_block(T, rows: np.ndarray):
    """T[rows][:, rows] (CSC) of a lower-triangular T (CSC) whose ``rows`` (sorted) are closed
    under its graph (every entry of those columns lies in those rows): a column slice and a
    renumbering, not a row search through all of T."""
    import scipy.sparse as sp
    sub = T[:, rows]
    inv = np.full(T.shape[0], -1, np.int64)
    inv[rows] = np.arange(rows.size)
    return sp.csc_matrix((sub.data, inv[sub.indices], sub.indptr), shape=(rows.size, rows.size))


def _split(rim) -> tuple:
    """(the interface-last factorisation's factors ``rim.split``, made when the rim's S_R was
    read from a cache; for each rim interior index the row of Pr1 f and the U11 position of its
    unknown)."""
    if rim.split is None:           # a rim whose S_R was read from a cache
        rim.make_split()
    sp_ = rim.split
    if "to_row" not in sp_:
        n = sp_["n"]
        inv_order = np.empty(n, np.int64)
        inv_order[sp_["order"]] = np.arange(n)
        sp_["to_row"] = sp_["pr"][:n][inv_order]
        sp_["to_col"] = sp_["pc"][:n][inv_order]
        sp_["L21c"] = sp_["L21"].tocsc()
    return sp_, sp_["to_row"], sp_["to_col"]


def make_read_set(rim, F, reads: list) -> ReadSet:
    """`ReadSet` of the loads F (n_interior, k; CSC) and reads (k arrays of rim interior
    indices) on the rim interior of ``rim`` (a `solver.fe.condense.RimBlock`)."""
    from solver.fe.kernels import lower_solve_rows
    sp_, to_row, to_col = _split(rim)
    n = sp_["n"]
    L11, Ut11, L21 = sp_["L11"], sp_["Ut11"], sp_["L21c"]
    prb = sp_["pr"][n:] - n
    B = np.zeros((rim.n_interface, F.shape[1]))
    rows, s, at = [], [], []
    for j in range(F.shape[1]):
        loaded = F.indices[F.indptr[j]:F.indptr[j + 1]]
        fwd = np.flatnonzero(_reach(L11, to_row[loaded]))
        b = np.zeros(n)
        b[to_row[loaded]] = F.data[F.indptr[j]:F.indptr[j + 1]]
        full = lower_solve_rows(L11.indptr, L11.indices, L11.data, fwd, b)
        B[:, j] = (L21[:, fwd] @ full[fwd])[prb]
        read = to_col[np.asarray(reads[j], np.int64)]
        back = np.flatnonzero(_reach(Ut11, read))
        rows.append(back)
        s.append(full[back])
        at.append(np.searchsorted(back, read))
    return ReadSet(rows, s, at, B)


def rim_products(rim, R, F, key) -> tuple:
    """(G0, A, B) of the module doc for reads R (m, N_R) and loads F (N_R, k) on the rim's
    interior DOFs, kept in ``rim.products[key]``. With Pr Kp Pc = L U the interface-last
    factorisation (`rim_block`), y = L11^-1 Pr1 F and z = U11^-T (R Pc1)^T:

        G0 = z^T y,   B = Pr_b^T L21 y,   A = z^T U12 Pc_b^T,

    each triangular solve restricted to the DOFs the loads (reads) reach (`solver.fe.factor`);
    ``rim``: a `solver.fe.condense.RimBlock`."""
    import scipy.sparse as sp

    if key in rim.products:
        return rim.products[key]
    sp_, _, _ = _split(rim)
    free, n = rim.model.free, sp_["n"]
    F = sp.csr_matrix(F)
    R = sp.csr_matrix(R)
    on_iface = np.zeros(rim.model.basis.N, bool)
    on_iface[rim.interface] = True
    if np.any(on_iface[F.nonzero()[0]]) or np.any(on_iface[R.nonzero()[1]]):
        raise ValueError("loads or reads on the rim's interface with the web: condense a deeper rim")
    order = sp_["order"]
    pr1, pc1 = sp_["pr"][:n], sp_["pc"][:n]
    Ff = F[free][order]                                           # (n, k) in Kp's interior order
    Rt = sp.csr_matrix(R[:, free][:, order].T)                    # (n, m)
    inv_c = np.empty(n, dtype=np.int64)
    inv_c[pc1] = np.arange(n)
    b_f = Ff[np.argsort(pr1)]                                     # Pr1 F
    b_r = Rt[inv_c]                                               # (R Pc1)^T
    ry, yt = _columns_solve(sp_["L11"], b_f)            # y^T on the rows the loads reach
    rz, zt = _columns_solve(sp_["Ut11"], b_r)           # z^T on the rows the reads depend on
    _, iy, iz = np.intersect1d(ry, rz, assume_unique=True, return_indices=True)
    prb, pcb = sp_["pr"][n:] - n, sp_["pc"][n:] - n
    with one_blas_thread():
        G0 = zt[:, iz] @ yt[:, iy].T
        B = np.asarray(sp_["L21"][:, ry] @ yt.T)[prb]
        A = np.asarray(zt @ sp_["U12"][rz])[:, pcb]
    rim.products[key] = (G0, A, B)
    return rim.products[key]


def _columns_solve(T, b) -> tuple[np.ndarray, np.ndarray]:
    """(rows, X^T on them) of X = T^-1 b for a lower-triangular T (CSC, diagonal stored) and a
    sparse b (n, k): each block of `SOLVE_BLOCK` neighbouring columns substituted over the rows
    it reaches only (`solver.fe.kernels.lower_solve_columns`); rows: those any column reaches,
    sorted (X is zero on the others). Loads along a flank reach a few percent of the rim's
    rows each: a dense solve over all the rows they reach together multiplies mostly zeros."""
    import scipy.sparse as sp

    from solver.fe.kernels import lower_solve_columns
    strict = sp.tril(T, -1, format="csc")
    bc = sp.csc_matrix(b)
    bc.sort_indices()
    n = T.shape[0]
    rows, xt, _, _, _ = lower_solve_columns(strict.indptr, strict.indices, strict.data, T.diagonal(),
                                            bc.indptr, bc.indices, bc.data, n, SOLVE_BLOCK)
    return rows, xt


@dataclass
class RimForward:
    """The rim's forward solve of a load set (`rim_forward`): the rows of L11 the loads reach,
    y = L11^-1 Pr1 F on them, and B = K_ir K_rr^-1 F (n_i, k) [N] (the module doc of
    `solver.fe.condense`)."""

    rows: np.ndarray      # sorted L11 positions the loads reach
    y: np.ndarray         # (rows.size, k) L11^-1 Pr1 F on ``rows`` (U11 w = y gives w in m)
    B: np.ndarray         # (n_i, k) [N], rim interface order


def rim_forward(rim, F) -> RimForward:
    """`RimForward` of the loads F (n_interior, k) [N] (sparse, rim interior indices) on the
    rim of ``rim`` (a `solver.fe.condense.RimBlock`): one blocked triangular solve of every
    column over the rows the loads reach."""
    import scipy.sparse as sp

    sp_, to_row, _ = _split(rim)
    n = sp_["n"]
    F = sp.coo_matrix(F)
    F.sum_duplicates()
    rows = to_row[F.row]
    fwd = np.flatnonzero(_reach(sp_["L11"], np.unique(rows)))
    b = np.zeros((fwd.size, F.shape[1]))
    b[np.searchsorted(fwd, rows), F.col] = F.data
    y = _lower_solve(_closed_block(sp_["L11"], fwd), b, 48)
    B = (sp_["L21c"][:, fwd] @ y)[sp_["pr"][n:] - n]
    return RimForward(fwd, y, B)


@dataclass
class RimBack:
    """The rim's part of reading given interior DOFs after every load set (`rim_back`): the
    rows of U11 the reads depend on (sorted, closed under U11's graph), U11 on them reversed
    (lower-triangular, CSC), U12 on them (CSR) and where each read lies in them."""

    rows: np.ndarray
    U_rev: object
    U12: object
    at: np.ndarray


def rim_back(rim, reads: np.ndarray) -> RimBack:
    """`RimBack` of the rim interior indices ``reads`` on ``rim`` (a
    `solver.fe.condense.RimBlock`)."""
    sp_, _, to_col = _split(rim)
    cols = to_col[np.asarray(reads, np.int64)]
    back = np.flatnonzero(_reach(sp_["Ut11"], cols))
    U = _closed_block(sp_["Ut11"], back).T.tocsc()          # U11 on ``back``: upper-triangular
    return RimBack(back, U[::-1, ::-1].tocsc(), sp_["U12"][back], np.searchsorted(back, cols))


def rim_reads(rim, fw: RimForward, bk: RimBack, u_i: np.ndarray) -> np.ndarray:
    """K_rr^-1 (F - K_ri u_i) [m] at the reads of ``bk`` ((n_reads, k)): the loads' forward
    solve ``fw`` and the interface displacements u_i (n_i, k) [m] (rim interface order)
    through the back-substitution U11 w = y - U12 u_i restricted to the rows the reads depend
    on (`rim_back`), for every column in one blocked solve."""
    sp_ = rim.split
    n = sp_["n"]
    w2 = np.empty_like(u_i)
    w2[sp_["pc"][n:] - n] = u_i                 # in the factorisation's interface order
    rhs = -np.asarray(bk.U12 @ w2)
    _, i_back, i_fwd = np.intersect1d(bk.rows, fw.rows, assume_unique=True, return_indices=True)
    rhs[i_back] += fw.y[i_fwd]
    w = _lower_solve(bk.U_rev, np.ascontiguousarray(rhs[::-1]), 48)[::-1]
    return w[bk.at]

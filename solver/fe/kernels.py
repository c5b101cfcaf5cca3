"""Compiled sparse triangular solves of the FE bodies: arrays and scalars in, arrays out.

SuperLU's solves work on supernodes with dense kernels over every right-hand side of a block:
where each column reaches only a few percent of the rows (the web's condensation onto the
interface, a column's reads in the rim), most of that work multiplies zeros, and a solve per
column from Python costs more in calls than in arithmetic. These kernels solve column by
column, each over the rows its own column reaches, in one compiled call.

They sit with the FE (not with the multibody kernels in `solver.mbs.kernels`, which the FE does
not import): numba's disk cache (``cache=True``, ``$NUMBA_CACHE_DIR``) checks this file's time
stamp, and every kernel here calls only numpy, so that is enough to know a cached one is current.
Units follow the caller (SI: N, m, N/m).
"""
from __future__ import annotations

import numpy as np


def _njit(fn):
    import numba
    return numba.njit(cache=True, nogil=True, no_cfunc_wrapper=True)(fn)


@_njit
def lower_solve_columns(l_ptr, l_idx, l_val, diag, b_ptr, b_idx, b_val, top):
    """The rows below ``top`` of X = L^-1 B, for a lower-triangular L (n, n) given as its
    strictly lower part in CSC (``l_ptr``, ``l_idx``, ``l_val``; every entry below the diagonal)
    and its diagonal ``diag``, and a sparse B (n, k) in CSC; with what is left for the rows from
    ``top`` on. Returns (rows, X, R): the sorted rows below ``top`` that any column reaches (each
    of X's other rows there is zero), X (rows.size, k) on them, and R (n - top, k) = B_t - L_tb X
    (the right-hand side of L_tt X_t = R, the rest of the solve: a dense triangular one).

    Each column first gathers the rows below ``top`` its nonzeros reach through L's graph, then
    substitutes forward over them in L's order (the graph points to higher rows only): the
    arithmetic of the column's own reach, no pass over the rows it does not reach."""
    n = diag.size
    k = b_ptr.size - 1
    mark = np.zeros(n, np.bool_)
    for p in range(b_ptr[k]):                         # the rows the columns together reach
        mark[b_idx[p]] = True
    for c in range(top):
        if mark[c]:
            for p in range(l_ptr[c], l_ptr[c + 1]):
                mark[l_idx[p]] = True
    pos = np.full(top, -1, np.int64)
    m = 0
    for c in range(top):
        if mark[c]:
            pos[c] = m
            m += 1
    rows = np.empty(m, np.int64)
    for c in range(top):
        if pos[c] >= 0:
            rows[pos[c]] = c
    X = np.zeros((m, k))
    R = np.zeros((n - top, k))
    x = np.zeros(top)
    mark[:] = False
    reach = np.empty(top, np.int64)
    for j in range(k):
        m = 0
        for p in range(b_ptr[j], b_ptr[j + 1]):
            i = b_idx[p]
            if i >= top:
                R[i - top, j] += b_val[p]
            else:
                x[i] += b_val[p]
                if not mark[i]:
                    mark[i] = True
                    reach[m] = i
                    m += 1
        h = 0
        while h < m:                                  # the rows below top the column reaches
            c = reach[h]
            h += 1
            for p in range(l_ptr[c], l_ptr[c + 1]):
                i = l_idx[p]
                if i < top and not mark[i]:
                    mark[i] = True
                    reach[m] = i
                    m += 1
        for c in np.sort(reach[:m]):                 # in L's order: each row after those it needs
            xc = x[c] / diag[c]
            x[c] = 0.0
            mark[c] = False
            X[pos[c], j] = xc
            for p in range(l_ptr[c], l_ptr[c + 1]):
                i = l_idx[p]
                if i >= top:
                    R[i - top, j] -= l_val[p] * xc
                else:
                    x[i] -= l_val[p] * xc
    return rows, X, R


@_njit
def back_substitute_reads(u_ptr, u_idx, u_val, inv_diag, c_ptr, c_idx, c_val, w2t, dense, dense_w, rows, rows_ptr, rhs):
    """Column j's restricted back-substitution of an interface-last factorisation, for every j:
    U11 w = s_j - U12 w2_j on the rows ``rows[rows_ptr[j]:rows_ptr[j + 1]]`` (sorted, closed
    under U11's graph: each row's entries lie in the same rows), with U11 (n, n) upper-triangular
    in CSR (``u_*``, diagonal included), ``inv_diag`` 1 / its diagonal, U12 (n, n_i) in CSR
    (``c_*``), the rows w2_j of ``w2t`` (k, n_i) and s_j = ``rhs`` at the same places as ``rows``.
    U12's rows with ``dense[i]`` >= 0 are left out of ``c_*``: their products U12 w2 are
    ``dense_w[dense[i], j]``, made beforehand. Returns w at the places of ``rows``."""
    n = inv_diag.size
    out = np.empty(rows.size)
    w = np.zeros(n)
    for j in range(rows_ptr.size - 1):
        a, b = rows_ptr[j], rows_ptr[j + 1]
        for q in range(b - 1, a - 1, -1):
            i = rows[q]
            s = rhs[q]
            if dense[i] >= 0:
                s -= dense_w[dense[i], j]
            for p in range(c_ptr[i], c_ptr[i + 1]):
                s -= c_val[p] * w2t[j, c_idx[p]]
            for p in range(u_ptr[i], u_ptr[i + 1]):
                r = u_idx[p]
                if r != i:
                    s -= u_val[p] * w[r]
            w[i] = s * inv_diag[i]
            out[q] = w[i]
        for q in range(a, b):
            w[rows[q]] = 0.0
    return out


@_njit
def row_arcs(X):
    """(start, length) of the shortest circular run of columns of X (m, n) that holds every
    nonzero of each row (columns n - 1 and 0 adjacent; length 0: an empty row), for the
    products of rows whose nonzeros sit on an arc of the interface circle."""
    m, n = X.shape
    start = np.zeros(m, np.int64)
    length = np.zeros(m, np.int64)
    for r in range(m):
        first, last, prev, gap, after = -1, -1, -1, -1, 0
        for c in range(n):
            if X[r, c] != 0.0:
                if first < 0:
                    first = c
                elif c - prev - 1 > gap:
                    gap, after = c - prev - 1, c
                prev = c
                last = c
        if first < 0:
            continue
        wrap = first + n - last - 1                  # the gap across column 0
        if wrap >= gap:
            start[r], length[r] = first, last - first + 1
        else:
            start[r], length[r] = after, n - gap
    return start, length

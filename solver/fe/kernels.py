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
def lower_solve_columns(l_ptr, l_idx, l_val, diag, b_ptr, b_idx, b_val, top, block):
    """The rows below ``top`` of X = L^-1 B, for a lower-triangular L (n, n) given as its
    strictly lower part in CSC (``l_ptr``, ``l_idx``, ``l_val``; every entry below the diagonal)
    and its diagonal ``diag``, and a sparse B (n, k) in CSC; with what is left for the rows from
    ``top`` on. Returns (rows, Xt, start, length, Rt):

    - rows: the sorted rows below ``top`` that any column reaches (X's other rows there are zero);
    - Xt (k, rows.size + n - top): X^T on them, its last n - top columns left zero (for the rest);
    - start, length: the shortest circular run of columns holding each of those rows' nonzeros
      (as `row_arcs`; columns k - 1 and 0 adjacent);
    - Rt (k, n - top): (B_t - L_tb X)^T, the right-hand side of L_tt X_t = R (the rest of the
      solve: a dense triangular one).

    The columns go in blocks of ``block`` neighbours: a block substitutes forward in L's order
    (the graph points to higher rows only) from its first nonzero row, over the rows its
    nonzeros reach (marked as they are reached), each entry of L applied to the block's columns
    at once: the arithmetic of the block's own reach. (Columns whose nonzeros lie close, such as
    DOFs along a curve in their order along it, reach nearly the same rows.) A row's run counts
    its nonzero values."""
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
    Xt = np.zeros((k, m + n - top))
    Rt = np.zeros((k, n - top))
    first = np.full(m, -1, np.int64)                  # each row's first and last column, widest gap
    last = np.zeros(m, np.int64)
    gap = np.full(m, -1, np.int64)
    after = np.zeros(m, np.int64)
    x = np.zeros((top, block))
    xc = np.zeros(block)
    mark[:] = False
    for j0 in range(0, k, block):
        nb = min(block, k - j0)
        lo = top
        for b in range(nb):
            for p in range(b_ptr[j0 + b], b_ptr[j0 + b + 1]):
                i = b_idx[p]
                if i >= top:
                    Rt[j0 + b, i - top] += b_val[p]
                else:
                    x[i, b] += b_val[p]
                    mark[i] = True
                    lo = min(lo, i)
        for c in range(lo, top):                      # in L's order: each row after those it needs
            if not mark[c]:
                continue
            r = pos[c]
            for b in range(nb):
                v = x[c, b] / diag[c]
                xc[b] = v
                x[c, b] = 0.0
                Xt[j0 + b, r] = v
                if v != 0.0:
                    j = j0 + b
                    if first[r] < 0:
                        first[r] = j
                    elif j - last[r] - 1 > gap[r]:
                        gap[r] = j - last[r] - 1
                        after[r] = j
                    last[r] = j
            mark[c] = False
            for p in range(l_ptr[c], l_ptr[c + 1]):
                i = l_idx[p]
                lv = l_val[p]
                if i >= top:
                    for b in range(nb):
                        Rt[j0 + b, i - top] -= lv * xc[b]
                else:
                    mark[i] = True
                    for b in range(nb):
                        x[i, b] -= lv * xc[b]
    start = np.zeros(m, np.int64)
    length = np.zeros(m, np.int64)
    for r in range(m):
        if first[r] >= 0:
            if first[r] + k - last[r] - 1 >= gap[r]:  # the widest gap is the one across column 0
                start[r], length[r] = first[r], last[r] - first[r] + 1
            else:
                start[r], length[r] = after[r], k - gap[r]
    return rows, Xt, start, length, Rt


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


@_njit
def reach_mask(t_ptr, t_idx, sources):
    """Boolean mask of the rows that a solve with a triangular T (CSC: ``t_ptr``, ``t_idx``;
    n = t_ptr.size - 1 rows), whose graph points to higher rows only, can make nonzero from
    right-hand sides nonzero at the rows ``sources``: one sweep in column order from the first
    source, each marked row marking its column's entries."""
    n = t_ptr.size - 1
    mark = np.zeros(n, np.bool_)
    first = n
    for s in sources:
        mark[s] = True
        first = min(first, s)
    for j in range(first, n):
        if mark[j]:
            for p in range(t_ptr[j], t_ptr[j + 1]):
                mark[t_idx[p]] = True
    return mark


@_njit
def lower_solve_rows(t_ptr, t_idx, t_val, rows, b):
    """x = T^-1 b for a lower-triangular T (CSC: ``t_ptr``, ``t_idx``, ``t_val``, its diagonal
    among each column's entries) and a right-hand side b (n,) nonzero on ``rows`` only, where
    ``rows`` (sorted) is closed under T's graph (`reach_mask`): forward substitution over those
    columns alone. Returns x (n,), zero off ``rows``. One column's solve in a compiled loop,
    where a factorisation of T's block and a solve from Python cost some 20 ms a column."""
    x = b.copy()
    for j in rows:
        d = 0.0
        for p in range(t_ptr[j], t_ptr[j + 1]):
            if t_idx[p] == j:
                d = t_val[p]
        xj = x[j] / d
        x[j] = xj
        for p in range(t_ptr[j], t_ptr[j + 1]):
            i = t_idx[p]
            if i > j:
                x[i] -= t_val[p] * xj
    return x

"""The compiled sparse solves of the FE bodies (`solver.fe.kernels`) and the product over runs of
columns (`solver.fe.factor.arc_gram`) against dense numpy on random cases."""
import numpy as np
import pytest
import scipy.sparse as sp

from solver.fe.factor import arc_gram
from solver.fe.kernels import back_substitute_reads, lower_solve_columns, lower_solve_rows, reach_mask, row_arcs


def _lower(n, density, seed):
    rng = np.random.default_rng(seed)
    L = sp.tril(sp.random(n, n, density=density, random_state=rng), -1, format="csc")
    return L, 1.0 + rng.random(n)


@pytest.mark.parametrize("top, block", [(60, 1), (45, 3), (0, 16)])
def test_lower_solve_columns_is_the_dense_solve(top, block):
    """The rows below ``top`` of L^-1 B, each column over the rows it reaches, the runs of
    columns holding each row's nonzeros, and the rest's right-hand side B_t - L_tb X: with the
    dense triangular solve of the last rows, L^-1 B."""
    n, k = 60, 7
    L, d = _lower(n, 0.04, 1)
    B = sp.random(n, k, density=0.05, random_state=np.random.default_rng(2), format="csc")
    B.sort_indices()
    full = np.linalg.solve(L.toarray() + np.diag(d), B.toarray())
    rows, Xt, start, length, Rt = lower_solve_columns(L.indptr, L.indices, L.data, d, B.indptr, B.indices, B.data, top, block)
    assert np.all(np.diff(rows) > 0) and np.all(rows < top)
    assert Xt.shape == (k, rows.size + n - top) and not Xt[:, rows.size:].any()
    off = np.setdiff1d(np.arange(top), rows)
    assert np.abs(full[off]).max(initial=0.0) == 0.0                 # rows no column reaches: zero
    X = Xt[:, :rows.size].T
    assert np.allclose(X, full[rows], rtol=1e-12, atol=1e-14)
    s_ref, l_ref = row_arcs(np.ascontiguousarray(X))                 # the runs, as found afterwards
    assert np.all(length >= l_ref) and np.array_equal(length == 0, l_ref == 0)
    for r in range(rows.size):
        assert np.all(((np.flatnonzero(X[r]) - start[r]) % k) < length[r])
    Ltt = L.toarray()[top:, top:] + np.diag(d[top:])
    assert np.allclose(np.linalg.solve(Ltt, Rt.T) if top < n else Rt.T, full[top:], rtol=1e-12, atol=1e-14)


def test_back_substitute_reads_is_the_dense_solve():
    """Each column's restricted back-substitution U11 w = s - U12 w2 over rows closed under
    U11's graph equals the dense solve of the whole system there, with some rows' U12 w2 made
    beforehand or not."""
    n, n_i, k = 50, 6, 3
    rng = np.random.default_rng(3)
    L, d = _lower(n, 0.05, 4)
    U = (L.T + sp.diags(d)).tocsr()                                  # upper, diagonal included
    U12 = sp.random(n, n_i, density=0.2, random_state=rng, format="csr")
    w2 = rng.standard_normal((n_i, k))
    rows, rhs, want = [], [], []
    for j in range(k):
        seed = rng.choice(n, 3, replace=False)
        closed = set(seed.tolist())
        stack = list(seed)
        while stack:                                                 # close the rows under U's graph
            i = stack.pop()
            for c in U.indices[U.indptr[i]:U.indptr[i + 1]]:
                if c not in closed:
                    closed.add(c)
                    stack.append(c)
        r = np.array(sorted(closed))
        s = rng.standard_normal(n)
        full = np.linalg.solve(U.toarray(), s - U12 @ w2[:, j])
        rows.append(r)
        rhs.append(s[r])
        want.append(full[r])
    ptr = np.cumsum([0] + [r.size for r in rows])
    for dense_rows in (np.array([], int), np.array([3, 17, 40, 49])):    # U12 w2 on these rows made beforehand
        dense = np.full(n, -1)
        dense[dense_rows] = np.arange(dense_rows.size)
        keep = np.ones(n)
        keep[dense_rows] = 0.0
        rest = sp.csr_matrix(sp.diags(keep) @ U12)
        got = back_substitute_reads(U.indptr, U.indices, U.data, 1.0 / d, rest.indptr, rest.indices, rest.data,
                                    np.ascontiguousarray(w2.T), dense, U12[dense_rows] @ w2, np.concatenate(rows), ptr,
                                    np.concatenate(rhs))
        assert np.allclose(got, np.concatenate(want), rtol=1e-11, atol=1e-13)


def testarc_gram_is_the_dense_product():
    """Y^T Y summed over blocks of rows with short runs of columns, runs across column 0
    included, equals the dense product and is exactly symmetric; `row_arcs` finds the
    shortest run holding each row's nonzeros."""
    rng = np.random.default_rng(6)
    m, n = 400, 90
    Y = np.zeros((m, n))
    runs = np.array([[0, 1, 5, 20, 60, n][r % 6] for r in range(m)])
    for r in range(m):
        Y[r, (rng.integers(n) + np.arange(runs[r])) % n] = rng.standard_normal(runs[r])
    start, length = row_arcs(Y)
    assert np.array_equal(length, runs)
    for r in range(m):
        assert np.all(((np.flatnonzero(Y[r]) - start[r]) % n) < length[r])
    W = arc_gram(np.ascontiguousarray(Y.T), start, length, rows_max=16)
    assert np.array_equal(W, W.T)
    assert np.allclose(W, Y.T @ Y, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_reach_and_restricted_solve_are_the_dense_solve(compiled):
    """The rows a triangular solve can reach from a right-hand side's nonzeros hold every
    nonzero of the solution (and are closed under L's graph); the forward substitution over
    those rows alone is the dense solve, zero elsewhere."""
    reach = reach_mask if compiled else reach_mask.py_func
    solve = lower_solve_rows if compiled else lower_solve_rows.py_func
    n = 60
    L, d = _lower(n, 0.04, 5)
    T = (L + sp.diags(d)).tocsc()                                    # the diagonal among the entries
    T.sort_indices()
    rng = np.random.default_rng(6)
    for seeds in ([3], [10, 40], rng.choice(n, 4, replace=False)):
        seeds = np.asarray(seeds, np.int64)
        b = np.zeros(n)
        b[seeds] = rng.standard_normal(seeds.size)
        mark = reach(T.indptr, T.indices, seeds)
        rows = np.flatnonzero(mark)
        assert np.all(mark[seeds])
        for j in rows:                                               # closed: j's column stays in the set
            assert np.all(mark[T.indices[T.indptr[j]:T.indptr[j + 1]]])
        full = np.linalg.solve(T.toarray(), b)
        assert np.abs(full[~mark]).max(initial=0.0) == 0.0
        x = solve(T.indptr, T.indices, T.data, rows, b)
        assert np.allclose(x, full, rtol=1e-12, atol=1e-14) and not x[~mark].any()

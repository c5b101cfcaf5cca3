"""Sparse solves of a plane-stress FE body: the LU factorisation of the clamped stiffness matrix
in single-threaded BLAS, and the influence R K^-1 F through triangular solves restricted to the
DOFs the loads and reads reach. Units follow the caller (SI: N, m).
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

_BLAS_THREADS: dict = {}     # library path -> [(get, set)] of its thread-count functions
_BLAS_SEEN: list = []        # [the number of modules imported when last listed, the controls then]
DENSE_ROWS = 320             # `congruence`: the last rows of a factor's order solved as one dense block
SOLVE_BLOCK = 16             # `congruence`: columns solved together (`solver.fe.kernels.lower_solve_columns`)


def _openblas_controls() -> list:
    """(get_num_threads, set_num_threads) of every OpenBLAS library loaded in this process
    (numpy's and scipy's wheels each bundle one, with prefixed symbol names); empty where they
    cannot be found (not Linux, another BLAS). The loaded libraries are listed anew whenever the
    process has imported a module since the last call (reading the memory map costs some
    milliseconds a call on a busy machine, and a BLAS library is loaded by an import), so one
    loaded later is not missed."""
    import ctypes
    import re
    import sys

    if _BLAS_SEEN and _BLAS_SEEN[0] == len(sys.modules):
        return _BLAS_SEEN[1]
    try:
        with open("/proc/self/maps") as f:
            paths = sorted(set(re.findall(r"(/\S*openblas\S*\.so\S*)", f.read())))
    except OSError:
        return []
    out = []
    for path in paths:
        if path not in _BLAS_THREADS:
            found = []
            try:
                lib = ctypes.CDLL(path)
            except OSError:
                lib = None
            for prefix in ("openblas", "scipy_openblas") if lib is not None else ():
                for suffix in ("", "64_"):
                    get = getattr(lib, f"{prefix}_get_num_threads{suffix}", None)
                    put = getattr(lib, f"{prefix}_set_num_threads{suffix}", None)
                    if get is not None and put is not None:
                        get.restype, put.argtypes = ctypes.c_int, [ctypes.c_int]
                        found.append((get, put))
            _BLAS_THREADS[path] = found
        out += _BLAS_THREADS[path]
    _BLAS_SEEN[:] = [len(sys.modules), out]
    return out


@contextmanager
def one_blas_thread():
    """Run the block in single-threaded OpenBLAS, then restore the thread counts.

    SuperLU calls the dense BLAS once per supernode, thousands of small calls per factorisation
    or block solve: with two BLAS threads on a two-core machine that was also running something
    else, the reach-restricted solves of the paper reference took 14-15 s instead of 2.2-2.6 s
    (threads waiting for each other at every call); the factorisation took the same time with
    one thread or two. The setting is process-wide: other threads of the process run
    single-threaded BLAS meanwhile.
    """
    controls = _openblas_controls()
    old = [get() for get, _ in controls]
    for _, put in controls:
        put(1)
    try:
        yield
    finally:
        for (_, put), n in zip(controls, old):
            put(n)


def blas1_solver(lu):
    """lu.solve in single-threaded BLAS (see `one_blas_thread`)."""
    def solve(rhs):
        with one_blas_thread():
            return lu.solve(rhs)
    return solve


def factorise(K):
    """Sparse LU of the symmetric positive definite K (CSC) for repeated solves.

    Symmetric mode (one minimum-degree ordering of K + K^T for rows and columns, no pivoting,
    which an SPD matrix does not need) has about half the fill of the default unsymmetric
    COLAMD ordering: faster to factorise and to solve, half the memory.
    """
    from scipy.sparse.linalg import splu

    with one_blas_thread():
        return splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))


def influence(model, R, F, block: int = 48) -> np.ndarray:
    """R K^-1 F (m, k): the response read by the rows of R (m, N) to the loads in the columns of
    F (N, k), through the factorisation of K of the `solver.fe.body.BodyModel` ``model`` (for
    unit loads [N] and displacement reads: m/N).

    The same numbers as ``R @ solve_load(model, f)`` for every column f, computed far cheaper when
    R and F touch few DOFs (loads on a few flanks, reads at a few points): with Pr K Pc = L U,

        R K^-1 F = (U^-T (R Pc)^T)^T (L^-1 Pr F),

    and both triangular solves only reach the DOFs on the paths from the loaded (read) DOFs
    through the factors' graphs, about a tenth of a gear body. The solves are restricted to that
    set S (exact: every other entry of the solutions is zero) and run as blocked supernodal solves
    of the triangular submatrices. (SuperLU's own full solve reads all of U once per right-hand
    side; this is what makes many load cases expensive.)
    """
    import scipy.sparse as sp

    lu = model.factor
    if lu is None:                                   # a body without its factor object: plain solves
        U = np.zeros((model.basis.N, F.shape[1]))
        Fd = F.toarray() if sp.issparse(F) else np.asarray(F)
        U[model.free] = model.solve(np.ascontiguousarray(Fd[model.free]))
        return np.asarray(R @ U)
    if model.triangles is None:
        model.triangles = (sp.csc_matrix(lu.L), sp.csr_matrix(lu.U).T.tocsc())
    L, Ut = model.triangles
    n = model.free.size
    Ff = sp.csr_matrix(F)[model.free]                        # (n, k)
    Rt = sp.csr_matrix(sp.csr_matrix(R)[:, model.free].T)    # (n, m)
    # scipy's convention Pr K Pc = L U: row i of K goes to row perm_r[i], column j to perm_c[j]
    inv_c = np.empty(n, dtype=np.int64)
    inv_c[lu.perm_c] = np.arange(n)
    b_f = Ff[np.argsort(lu.perm_r)]                  # Pr F
    b_r = Rt[inv_c]                                  # (R Pc)^T
    reach = (_reach(L, lu.perm_r[np.flatnonzero(np.diff(Ff.indptr))])
             | _reach(Ut, lu.perm_c[np.flatnonzero(np.diff(Rt.indptr))]))
    S = np.flatnonzero(reach)
    y = _lower_solve(L[S][:, S], b_f[S].toarray(), block)
    z = _lower_solve(Ut[S][:, S], b_r[S].toarray(), block)
    with one_blas_thread():          # the same bits whatever the process's BLAS threads
        return z.T @ y


def congruence(lu, C, order: np.ndarray | None = None, dense_rows: int = DENSE_ROWS) -> np.ndarray | None:
    """C^T K^-1 C (k, k), dense and exactly symmetric, for the SPD K factorised by `factorise`
    (``lu``) and C (n, k) sparse (the condensation of a block onto the DOFs C couples to: [N/m]
    for stiffness).

    Symmetric mode pivots on the diagonal in one order for rows and columns (perm_r equal to
    perm_c), so P K P^T = L U with U = D L^T, D = diag(U), and

        C^T K^-1 C = Y^T Y,   Y = D^-1/2 L^-1 P C,

    one triangular solve and one symmetric product. Both use the sparsity of Y: each column
    is solved over the rows it reaches only (`solver.fe.kernels.lower_solve_columns`), and the
    product is summed over blocks of rows whose nonzeros lie on a common run of columns
    (`arc_gram`). Where C's columns are DOFs along a curve (a web's interface circle), a row's
    nonzeros are the DOFs of one arc of it; ``order``: C's columns in that order along the
    curve (any order gives the same result, to rounding; this one makes the runs short).
    None where the factorisation is not of that form (then use `influence`)."""
    import scipy.sparse as sp
    from scipy.linalg import solve_triangular

    from solver.fe.kernels import lower_solve_columns, row_arcs

    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    d = lu.U.diagonal()
    if not np.all(d > 0):
        return None
    L = sp.csc_matrix(lu.L)
    strict = sp.tril(L, -1, format="csc")
    Cp = sp.csc_matrix(sp.csr_matrix(C)[np.argsort(lu.perm_r)])            # P C
    if order is not None:
        Cp = Cp[:, order]
    Cp.sort_indices()
    n = L.shape[0]
    top = max(n - dense_rows, 0)
    rows, Yt, start, length, Rt = lower_solve_columns(strict.indptr, strict.indices, strict.data, L.diagonal(),
                                                      Cp.indptr, Cp.indices, Cp.data, top, SOLVE_BLOCK)
    if top < n:                                      # the last rows, which most columns reach: dense
        m = rows.size
        with one_blas_thread():
            Yt[:, m:] = solve_triangular(L[top:, top:].toarray(), Rt.T, lower=True, check_finite=False).T
        rows = np.concatenate([rows, np.arange(top, n)])
        s_top, l_top = row_arcs(Yt[:, m:].T)
        start, length = np.concatenate([start, s_top]), np.concatenate([length, l_top])
    Yt *= 1.0 / np.sqrt(d[rows])                                            # (D^-1/2 L^-1 P C)^T
    W = arc_gram(Yt, start, length)
    if order is not None:
        back = np.empty_like(order)
        back[order] = np.arange(order.size)
        W = W[np.ix_(back, back)]
    return W


def arc_gram(Yt: np.ndarray, start: np.ndarray, length: np.ndarray, rows_max: int = 256) -> np.ndarray:
    """Y^T Y (n, n), exactly symmetric, for Y (m, n) given as Yt = Y^T (n, m), whose row r (Yt's
    column r) is zero outside the circular run of ``length[r]`` columns from ``start[r]``
    (`solver.fe.kernels.row_arcs`).

    The rows are grouped by the size of their runs (within a factor of two) and, in each group,
    by where the run starts, into blocks whose common run is at most 1.5 times the group's
    bound; each block adds its dense product on its run (a symmetric rank-k update)
    to the lower triangle of the columns of that run, mirrored once at the end. The arithmetic is
    about the rows' own runs squared instead of every row times n squared."""
    from scipy.linalg.blas import dsyrk

    n, m = Yt.shape
    W = np.zeros((n, n))
    live = np.flatnonzero(length > 0)
    by_size = np.floor(np.log2(length[live])).astype(np.int64)
    sort = np.lexsort((start[live], by_size))
    order, group = live[sort], by_size[sort]
    with one_blas_thread():                          # the same bits whatever the process's BLAS threads
        i = 0
        while i < order.size:
            g, s0 = group[i], start[order[i]]
            cap = max(int(1.5 * 2 ** (g + 1)), 32)
            end = s0 + length[order[i]]
            j = i + 1
            while (j < order.size and j - i < rows_max and group[j] == g
                   and max(end, start[order[j]] + length[order[j]]) - s0 <= cap):
                end = max(end, start[order[j]] + length[order[j]])
                j += 1
            span = min(end - s0, n)
            if span == n:
                s0 = 0
            rows = order[i:j]
            if s0 + span <= n:
                G = dsyrk(1.0, Yt[s0:s0 + span][:, rows].T, trans=1, lower=1)    # lower triangle of Yb^T Yb
                W[s0:s0 + span, s0:s0 + span] += G
            else:                                    # a run across column 0: its parts' blocks
                a = n - s0
                G = dsyrk(1.0, Yt[(s0 + np.arange(span)) % n][:, rows].T, trans=1, lower=1)
                W[s0:, s0:] += G[:a, :a]
                W[:span - a, :span - a] += G[a:, a:]
                W[s0:, :span - a] += G[a:, :a].T     # (the upper part of the run's block)
            i = j
    W += np.tril(W, -1).T                            # the lower triangle, summed, mirrored
    return W


def _reach(T, sources: np.ndarray) -> np.ndarray:
    """Boolean mask of the rows that a lower-triangular solve with T (CSC) can make nonzero from
    right-hand sides nonzero at ``sources`` (`solver.fe.kernels.reach_mask`: one compiled sweep
    in column order, T's graph only pointing to higher indices)."""
    from solver.fe.kernels import reach_mask
    return reach_mask(T.indptr, T.indices, np.asarray(sources, np.int64))


def _lower_solve(T, B: np.ndarray, block: int) -> np.ndarray:
    """T^-1 B for a sparse lower-triangular T (CSC). SuperLU of a triangular matrix in its own
    order is T itself (no fill, no pivoting: a few hundredths of a second) and its solve works on
    supernodes with dense kernels over a block of right-hand sides; scipy's
    ``spsolve_triangular`` is about four times slower here."""
    from scipy.sparse.linalg import splu

    X = np.empty_like(B)
    with one_blas_thread():
        lu = splu(T.tocsc(), permc_spec="NATURAL", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
        for s in range(0, B.shape[1], block):
            X[:, s:s + block] = lu.solve(np.ascontiguousarray(B[:, s:s + block]))
    return X

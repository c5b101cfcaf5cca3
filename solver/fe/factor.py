"""Sparse solves of a plane-stress FE body: the LU factorisation of the clamped stiffness matrix
in single-threaded BLAS, and the influence R K^-1 F through triangular solves restricted to the
DOFs the loads and reads reach. Units follow the caller (SI: N, m).
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

_BLAS_THREADS: dict = {}     # library path -> [(get, set)] of its thread-count functions


def _openblas_controls() -> list:
    """(get_num_threads, set_num_threads) of every OpenBLAS library loaded in this process
    (numpy's and scipy's wheels each bundle one, with prefixed symbol names); empty where they
    cannot be found (not Linux, another BLAS). The loaded libraries are listed anew each call
    (a millisecond), so one loaded later is not missed."""
    import ctypes
    import re

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


def congruence(lu, C, block: int = 48, lower: bool = False) -> np.ndarray | None:
    """C^T K^-1 C (k, k), dense, for the SPD K factorised by `factorise` (``lu``) and C (n, k)
    sparse (the condensation of a block onto the DOFs C couples to: [N/m] for stiffness).

    Symmetric mode pivots on the diagonal in one order for rows and columns (perm_r equal to
    perm_c), so P K P^T = L U with U = D L^T, D = diag(U), and

        C^T K^-1 C = Y^T D^-1 Y,   Y = L^-1 P C,

    one triangular solve (restricted to the rows C reaches, as in `influence`) and one
    symmetric rank-k product: about half the work of `influence`'s two solves and general
    product. None where the factorisation is not of that form (then use `influence`).
    ``lower``: only the lower triangle (the upper one zero), for a caller that reads no more
    (a Cholesky factorisation), without the copies that fill the upper one."""
    import scipy.sparse as sp
    from scipy.linalg.blas import dsyrk

    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    L = sp.csc_matrix(lu.L)
    d = lu.U.diagonal()
    if not np.all(d > 0):
        return None
    Cf = sp.csr_matrix(C)
    b = Cf[np.argsort(lu.perm_r)]                    # P C
    S = np.flatnonzero(_reach(L, lu.perm_r[np.flatnonzero(np.diff(Cf.indptr))]))
    Y = _lower_solve(L[S][:, S], b[S].toarray(), block)
    Y *= (1.0 / np.sqrt(d[S]))[:, None]              # D^-1/2 Y
    with one_blas_thread():                          # the same bits whatever the process's BLAS threads
        W = dsyrk(1.0, Y.T, lower=1)                 # Y^T Y, lower triangle (Y.T: Fortran order, no copy)
    if lower:
        return W                                     # (dsyrk leaves the upper triangle zero)
    return np.tril(W) + np.tril(W, -1).T


def _reach(T, sources: np.ndarray) -> np.ndarray:
    """Boolean mask of the rows that a lower-triangular solve with T (CSC) can make nonzero from
    right-hand sides nonzero at ``sources``: one sweep in column order (T's graph only points to
    higher indices)."""
    mark = np.zeros(T.shape[0], bool)
    mark[sources] = True
    ptr, idx = T.indptr, T.indices
    for j in range(T.shape[0]):
        if mark[j]:
            mark[idx[ptr[j]:ptr[j + 1]]] = True
    return mark


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

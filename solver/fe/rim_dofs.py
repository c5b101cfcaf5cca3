"""Which DOF of a body is which DOF of its condensed rim (`solver.fe.condense`): by the joined
mesh's numbering where the body's mesh begins with the rim's (`condense.join_rim` makes it
so), else by location."""
from __future__ import annotations

import numpy as np

MATCH_TOL = 1e-9        # m: two DOF locations closer than this are the same node


class RimMismatch(ValueError):
    """The body's teeth-and-rim elements or nodes are not those of the condensed rim."""


def rim_dofs_in_body(basis, is_rim: np.ndarray, rim, rim_dofs: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """The body DOF of each DOF of the condensed ``rim`` (a `condense.RimBlock`): by
    `_rim_numbering`, else by the DOFs' location keys (``keys``, `condense._dof_keys`, of the
    body's ``rim_dofs``) within `MATCH_TOL`; `RimMismatch` when they differ."""
    from_rim = _rim_numbering(basis, is_rim, rim)
    if from_rim is not None:
        return from_rim
    from scipy.spatial import cKDTree
    if rim.tree is None:
        rim.tree = cKDTree(rim.keys)
    dist, idx = rim.tree.query(keys[rim_dofs])
    if rim_dofs.size != rim.keys.shape[0] or np.any(dist > MATCH_TOL) or np.unique(idx).size != idx.size:
        raise RimMismatch("the body's teeth-and-rim nodes differ from the condensed rim's")
    from_rim = np.empty(rim.keys.shape[0], np.int64)
    from_rim[idx] = rim_dofs
    return from_rim


def _rim_numbering(basis, is_rim: np.ndarray, rim) -> np.ndarray | None:
    """The body DOF of each DOF of the condensed rim, where the body's mesh begins with the rim's
    vertices and elements as they are (`condense.join_rim` makes it so): vertex DOFs alike, edge DOFs
    through the edges' end vertices. None for a mesh numbered otherwise."""
    m, rm = basis.mesh, rim.model.basis.mesh
    nv, nt = rm.p.shape[1], rm.t.shape[1]
    if (m.p.shape[1] < nv or m.t.shape[1] < nt or not np.array_equal(m.p[:, :nv], rm.p)
            or not np.array_equal(m.t[:, :nt], rm.t) or is_rim.sum() != nt or not is_rim[:nt].all()):
        return None
    key = m.facets[0].astype(np.int64) * m.p.shape[1] + m.facets[1]          # edges by their (sorted) ends
    want = rm.facets[0].astype(np.int64) * m.p.shape[1] + rm.facets[1]
    order = np.argsort(key)
    at = order[np.minimum(np.searchsorted(key, want, sorter=order), key.size - 1)]
    if not np.array_equal(key[at], want):
        return None
    rb = rim.model.basis
    out = np.empty(rb.N, np.int64)
    out[rb.nodal_dofs] = basis.nodal_dofs[:, :nv]
    out[rb.facet_dofs] = basis.facet_dofs[:, at]
    return out

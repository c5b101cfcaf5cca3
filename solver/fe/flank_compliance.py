"""Bulk compliance of a gear body between points of its drive flanks: the FE influence
coefficients that the FE reference (`solver.fe.ltca`) and the coupling fits read.

Each gear body is the plane-stress FE model of `solver.fe.body` (clamped at the bore, thickness
field, one factorisation). Its *bulk compliance* is the matrix of influence coefficients
between candidate contact points on the + (drive) flanks of the teeth near the mesh:

    G[(a, ua), (b, ub)] = d(a, ua) . u(C(a, ua))  under a unit load at (b, ub)      [m/N]

a, b tooth indices, ua, ub roll parameters on a grid along the profile, d the load direction
(along the line of action, into the tooth) and C the point where the load line crosses the
tooth axis. Every load acts on the whole body, so the coupling between teeth through the rim
and web (the "foundation") is in the off-diagonal blocks. Loads are spread over the Hertz
half-width as in `solver.fe.body` (a 2D point load is log-singular), with the patch ends at their
exact positions on the flank so that G is smooth in the roll parameter. Reading at the centreline C,
as `solver.fe.body.tooth_stiffness` does, keeps the local flattening out of G: that part comes from
the contact law ``F = k_con*delta**m1`` in series, exactly as in the pseudo-rigid model, so the
two differ only in how the bodies deform. G is symmetric by Maxwell-Betti up to the small
local difference between the load point and C; the symmetric part is used.

Rotational symmetry: a solid body needs only the columns of one tooth
(G[(a, .), (b, .)] = G[(a - b, .), (0, .)]); a lightened body's compliance depends on the hole
positions, so its columns are computed for every tooth that meets the mesh.

Units: SI (m, N, rad).
"""
from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from solver.fe.body import BodyModel, LoadCase, load_case, sparse_columns
from solver.geometry import GearGeometry


@dataclass(frozen=True)
class BodyCompliance:
    """Bulk influence coefficients of one gear body between + flank points [m/N].

    ``g[ia, i, ib, j]``: read on tooth ``read_teeth[ia]`` at roll ``u[i]`` under a unit load on
    tooth ``load_teeth[ib]`` at roll ``u[j]``. ``symmetric_body``: the body is rotationally
    symmetric, ``load_teeth == [0]`` and ``read_teeth`` are offsets -R..R from the loaded tooth.
    """

    u: np.ndarray            # (n_u,) roll parameters of the grid [-]
    read_teeth: np.ndarray   # (n_r,) tooth indices (or offsets)
    load_teeth: np.ndarray   # (n_l,)
    g: np.ndarray            # (n_r, n_u, n_l, n_u) [m/N]
    symmetric_body: bool
    teeth: int               # number of teeth of the gear

    def block(self, a: int, b: int) -> np.ndarray:
        """(n_u, n_u) compliance block: read on tooth a, load on tooth b (absolute indices)."""
        if self.symmetric_body:
            off = (a - b + self.teeth // 2) % self.teeth - self.teeth // 2
            ia = np.flatnonzero(self.read_teeth == off)
            if ia.size == 0:
                return np.zeros((self.u.size, self.u.size))   # farther than any computed offset
            return self.g[ia[0], :, 0, :]
        ia = np.flatnonzero(self.read_teeth == a % self.teeth)
        ib = np.flatnonzero(self.load_teeth == b % self.teeth)
        if ia.size == 0 or ib.size == 0:
            raise KeyError(f"compliance of tooth pair ({a}, {b}) was not computed")
        return self.g[ia[0], :, ib[0], :]

    def matrix(self, teeth, rolls) -> np.ndarray:
        """Symmetric compliance [m/N] between points (teeth[i], rolls[i]) by cubic interpolation."""
        n = len(teeth)
        w = [lagrange_weights(self.u, r) for r in rolls]
        out = np.empty((n, n))
        for i in range(n):
            for j in range(n):
                bl = self.block(int(teeth[i]), int(teeth[j]))
                (ii, wi), (jj, wj) = w[i], w[j]
                out[i, j] = wi @ bl[np.ix_(ii, jj)] @ wj
        return 0.5 * (out + out.T)


def lagrange_weights(grid: np.ndarray, x: float):
    """Indices and weights of cubic Lagrange interpolation on a uniform grid (clamped to it)."""
    n = grid.size
    h = (grid[-1] - grid[0]) / (n - 1)
    x = min(max(float(x), grid[0]), grid[-1])
    k = int(min(max(math.floor((x - grid[0]) / h) - 1, 0), n - 4))
    idx = np.arange(k, k + 4)
    xs = grid[idx]
    w = np.ones(4)
    for i in range(4):
        for j in range(4):
            if i != j:
                w[i] *= (x - xs[j]) / (xs[i] - xs[j])
    return idx, w


def profile_grid(g: GearGeometry, n_u: int, u_start: float | None = None) -> np.ndarray:
    """Roll-parameter grid [-] along the + flank from ``u_start`` (default: the form circle)
    to the tip."""
    lo = g.u_form if u_start is None else max(g.u_form, u_start)
    return np.linspace(lo, g.u_tip, n_u)


def flank_load_vector(model: BodyModel, g: GearGeometry, case: LoadCase, u: float, force: float,
                      patch: float, samples: int = 33) -> np.ndarray:
    """Nodal forces [N] of ``force`` spread uniformly over the flank within ``patch`` [m] (arc
    length) either side of roll ``u``, along the load direction of ``case``.

    Unlike `solver.fe.body.load_vector`, which loads whole boundary edges, the patch ends sit at
    their exact positions on the involute (``samples`` points, each distributed by the quadratic
    edge shape functions of the facet it lies on), so the load and its resultant move
    continuously with u: the influence coefficients are smooth in u and can be interpolated.
    """
    m = model.basis.mesh
    rb = g.base_radius
    s0 = 0.5 * rb * u * u                       # involute arc length from the base circle
    s = s0 + patch * ((np.arange(samples) + 0.5) / samples * 2.0 - 1.0)
    s = np.clip(s, 0.5 * rb * g.u_form**2, 0.5 * rb * g.u_tip**2)
    ui = np.sqrt(2.0 * s / rb)
    x, y = g.flank_point(ui, 1)
    a = math.atan2(case.point[1], case.point[0]) - math.atan2(*g.flank_point(u, 1)[::-1])
    c, sn = math.cos(a), math.sin(a)
    pts = np.stack([c * x - sn * y, sn * x + c * y])             # (2, samples) on tooth's flank
    bf = m.boundary_facets()
    e0 = m.p[:, m.facets[0, bf]]
    e1 = m.p[:, m.facets[1, bf]]
    mid = 0.5 * (e0 + e1)
    near = np.argsort(np.hypot(mid[0] - case.point[0], mid[1] - case.point[1]))[:max(8, samples)]
    # each sample point on its nearest facet (distances to the facets near the load, all
    # samples at once); the forces added in the order of the samples, as one loop over them would
    d0, d1 = e0[:, near], e1[:, near]
    L2 = ((d1 - d0) ** 2).sum(axis=0)
    rel = pts[:, :, None] - d0[:, None, :]                         # (2, samples, near)
    t = np.clip((rel * (d1 - d0)[:, None, :]).sum(axis=0) / L2, 0.0, 1.0)
    dist = np.hypot(*(d0[:, None, :] + t * (d1 - d0)[:, None, :] - pts[:, :, None]))
    j = np.argmin(dist, axis=1)
    tj = t[np.arange(samples), j]
    fac = bf[near[j]]
    n0, n1 = m.facets[0, fac], m.facets[1, fac]
    w = np.stack([(1 - tj) * (1 - 2 * tj), tj * (2 * tj - 1), 4 * tj * (1 - tj)], axis=1)        # (samples, 3)
    nd, fd = model.basis.nodal_dofs, model.basis.facet_dofs
    q = force / samples
    dofs = np.stack([np.stack([nd[comp, n0], nd[comp, n1], fd[comp, fac]], axis=1) for comp in range(2)], axis=1)
    vals = np.stack([(q * case.direction[comp]) * w for comp in range(2)], axis=1)              # (samples, 2, 3)
    f = np.zeros(model.basis.N)
    np.add.at(f, dofs.ravel(), vals.ravel())
    return f


def products_key(u: np.ndarray, load_teeth, read_teeth, patch: float) -> str:
    """Name of a compliance load set (roll grid, loaded and read teeth, patch [m]) among a
    condensed rim's products (`solver.fe.condense.RimBlock.products`)."""
    import json
    return "compliance:" + json.dumps({"u": [float(x) for x in u], "load": [int(t) for t in load_teeth],
                                       "read": [int(t) for t in read_teeth], "patch": float(patch)})


@dataclass(frozen=True)
class FlankLoads:
    """The load set of a body's compliance: a unit load on the + flank of every tooth of
    ``load_teeth`` at every roll parameter of ``u`` [-], spread over ``patch`` [m] of arc either
    side of its point, each read along its load direction at the centreline point of every
    (read tooth, u). Tooth indices count modulo the tooth count; ``symmetric_body``: a
    rotationally symmetric body, ``load_teeth == [0]`` and ``read_teeth`` offsets from it."""

    u: np.ndarray
    load_teeth: np.ndarray
    read_teeth: np.ndarray
    patch: float
    symmetric_body: bool = False

    def __post_init__(self):
        object.__setattr__(self, "u", np.asarray(self.u, float))
        object.__setattr__(self, "load_teeth", np.asarray(self.load_teeth, dtype=int))
        object.__setattr__(self, "read_teeth", np.asarray(self.read_teeth, dtype=int))

    @property
    def key(self) -> str:
        """`products_key` of this load set."""
        return products_key(self.u, self.load_teeth, self.read_teeth, self.patch)


def body_compliance(model: BodyModel, g: GearGeometry, loads: FlankLoads, block: int = 48,
                    timings: dict | None = None) -> BodyCompliance:
    """Influence coefficients [m/N] of a factorised body under the load set ``loads``: unit
    loads at every (load tooth, u), displacement along the load direction read at the
    centreline point of every (read tooth, u).

    One factorisation; all load cases at once through `solver.fe.factor.influence` (triangular solves
    restricted to the DOFs the loads and reads reach), right-hand sides in blocks of ``block``;
    a body solved through its condensed rim through the rim's products of the load set, which
    serve every web of the rim (made, with the loads and reads in the rim's numbering, once).
    ``timings``: if given, wall and CPU seconds of building the load vectors and of the solves
    are added to it (keys ``loads_wall_s``, ``loads_cpu_s``, ``solve_wall_s``, ``solve_cpu_s``).
    """
    from solver.fe.factor import influence

    clock = _Clock(timings)
    condensed = model.condensed
    if condensed is not None and loads.key in condensed.rim.products:
        with clock("solve"):
            G = condensed.influence(None, None, loads.key)
        return _compliance(G, loads, g.teeth)
    target = condensed.rim.model if condensed is not None else model
    with clock("loads"):
        R, F = _reads_and_loads(target, g, loads)
    with clock("solve"):
        G = condensed.influence(R, F, loads.key) if condensed is not None else influence(model, R, F, block)
    return _compliance(G, loads, g.teeth)


def _reads_and_loads(target: BodyModel, g: GearGeometry, loads: FlankLoads) -> tuple:
    """(R (m, N): the reads along the load directions at the centreline points [1], F (N, k):
    the unit flank loads [N]) of ``loads`` in the DOF numbering of ``target``, CSR and CSC."""
    import scipy.sparse as sp

    z, u = g.teeth, loads.u
    read_cases = [load_case(g, int(a) % z, 0.0, ui) for a in loads.read_teeth for ui in u]
    P = target.basis.probes(np.column_stack([c.centre_point for c in read_cases])).tocsr()   # (2 m, N)
    m = len(read_cases)
    dx = np.array([c.direction[0] for c in read_cases])
    dy = np.array([c.direction[1] for c in read_cases])
    R = sp.diags(dx) @ P[:m] + sp.diags(dy) @ P[m:]        # displacement along d at C
    cols = []
    for b in loads.load_teeth:
        for ui in u:
            f = flank_load_vector(target, g, load_case(g, int(b) % z, 0.0, ui), ui, 1.0, loads.patch)
            nz = np.flatnonzero(f)
            cols.append((nz, f[nz]))
    F = sparse_columns(cols, target.basis.N)
    return R, F


def _compliance(G, loads: FlankLoads, z: int) -> BodyCompliance:
    n_u = loads.u.size
    G = G.reshape(loads.read_teeth.size, n_u, loads.load_teeth.size, n_u)
    return BodyCompliance(loads.u, loads.read_teeth, loads.load_teeth, G, loads.symmetric_body, z)


class _Clock:
    """Adds the wall and CPU seconds of a ``with clock(name):`` block to ``timings`` (if any)."""

    def __init__(self, timings: dict | None):
        self.timings = timings

    @contextmanager
    def __call__(self, name: str):
        if self.timings is None:
            yield
            return
        w, c = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self.timings[f"{name}_wall_s"] = self.timings.get(f"{name}_wall_s", 0.0) + time.perf_counter() - w
            self.timings[f"{name}_cpu_s"] = self.timings.get(f"{name}_cpu_s", 0.0) + time.process_time() - c

"""Plain numpy + scipy peer of the static solver: `scipy.optimize.root` at each driver angle.

What a Python user would write first: every tooth of both gears is an unknown (no active
set), the residual is the vector of generalised forces of `reference.PairEquations` (load
torque on gear 2, contacts by the closed forms, eq. (1.2) springs) at rest, and
`scipy.optimize.root` (MINPACK Levenberg-Marquardt, analytic Jacobian without the geometric
stiffness) solves it at each angle, starting from the previous angle's solution. (MINPACK's
hybrid Powell, root's default, stalls on this residual: the 130-odd unloaded teeth make the
Jacobian nearly singular.)

Unloaded teeth sit at phi = 0 where the spring tangent n*k*|phi|^(n-1) vanishes (n > 1):
as in `kernels/statics.py`, 1e-9 of each tooth's k_phi is added to the Jacobian's diagonal
(the residual, and so the solution, stays exact).

SI units. Entry points: `static_te_root`; `solve_static_scipy` (MINPACK hybrd on the loaded
teeth only).
"""
from __future__ import annotations

import numpy as np
from scipy import optimize

from solver.mbs.model import Model
from solver.mbs.statics import StaticResult
from solver.peers.pair_equations import PairEquations


def _residual(eq: PairEquations, theta1: float, x: np.ndarray, zeros: np.ndarray):
    """Generalised forces on [theta2, phi...] at rest [N m] and the contacts."""
    phi = x[1:]
    cons = eq.contacts(theta1, x[0], phi, 0.0, 0.0, zeros)
    q = np.empty(eq.n)
    q[0] = eq.torque
    q[1:] = eq.spring_torques(phi, zeros)
    for c in cons:
        q[1 + c.ia] -= c.force * c.g[1]
        q[0] -= c.force * c.g[2]
        q[1 + c.ib] -= c.force * c.g[3]
    return q, cons


def _jacobian(eq: PairEquations, theta1: float, x: np.ndarray, zeros: np.ndarray) -> np.ndarray:
    """d residual / dx [N m/rad]: spring tangents plus k_t G G^T of each contact (negated)."""
    phi = x[1:]
    cons = eq.contacts(theta1, x[0], phi, 0.0, 0.0, zeros)
    return eq.tangents(phi, zeros, cons, spring_floor=1e-9)[0]


def static_te_root(model: Model, angles, torque: float, tol: float = 1e-12) -> StaticResult:
    """Equilibrium under ``torque`` [N m] on gear 2 at driver angles ``angles`` [rad], one
    `scipy.optimize.root` call per angle (``tol`` passed to it: relative step tolerance).

    Returns a `StaticResult` (iterations = residual evaluations, negative when root failed).
    """
    angles = np.ascontiguousarray(angles, dtype=float)
    if angles.ndim != 1 or angles.size == 0:
        raise ValueError("angles: need a non-empty 1-D array of driver angles")
    eq = PairEquations(model, 0.0, 1.0, torque, 1.0)
    zeros = np.zeros(eq.nt)
    rb1, rb2 = model.base_radii
    x = np.zeros(eq.n)
    sgn = 1.0 if torque >= 0 else -1.0
    n = angles.size
    te = np.empty(n)
    th2 = np.empty(n)
    ncon = np.zeros(n, dtype=np.int64)
    f1 = np.zeros((n, model.teeth[0]))
    it = np.zeros(n, dtype=np.int64)
    for a, theta1 in enumerate(angles):
        if a == 0:
            # start in contact: the backlash closed plus the contact-only penetration under
            # the load (a start without contact has a zero row in the Jacobian)
            k_con, m1 = eq.law[0], eq.law[1]
            pen = (abs(torque) / rb2 / k_con) ** (1.0 / m1)
            x[0] = model.theta2_for_te(theta1, sgn * (model.backlash_offset + pen))
        else:
            x[0] -= rb1 / rb2 * (theta1 - angles[a - 1])
        sol = optimize.root(lambda y: _residual(eq, theta1, y, zeros)[0], x,
                            jac=lambda y: _jacobian(eq, theta1, y, zeros), method="lm", tol=tol)
        x = sol.x
        _q, cons = _residual(eq, theta1, x, zeros)
        te[a] = rb1 * theta1 + rb2 * x[0]
        th2[a] = x[0]
        for c in cons:
            if c.force > 0.0:
                ncon[a] += 1
                f1[a, c.ia] += c.force
        it[a] = sol.nfev if sol.success else -sol.nfev
    return StaticResult(angles, te, th2, ncon, f1, it, float(torque), x[1:].copy())


def solve_static_scipy(model: Model, angles, torque: float, xtol: float = 1e-13) -> np.ndarray:
    """Static TE [m] at driver angles [rad] under ``torque`` [N·m] with `scipy.optimize.root`
    (MINPACK hybrd, finite-difference Jacobian) on the plain-Python contact and spring forces.

    An independent check of the numba static kernel: unknowns are theta2 and the rotations of
    the teeth in loaded contact (an unloaded tooth rests at phi = 0 exactly, where the spring
    tangent of n_k > 1 vanishes); the set is updated until it no longer changes. The first
    angle starts from rigid teeth closing the backlash, the others from the previous angle's
    solution (continuation, as the static kernel does: where corner contacts make the
    equilibrium non-unique, both then follow the same branch).
    """
    eq = PairEquations(model, 0.0, 1.0, torque, 1.0)
    rb1, rb2 = model.base_radii
    z = eq.nt
    out = np.empty(len(angles))
    sgn = 1.0 if torque >= 0 else -1.0
    k, m1 = eq.law[0], eq.law[1]
    te = sgn * (model.backlash_offset + (abs(torque) / rb2 / k) ** (1.0 / m1))
    phi = np.zeros(z)
    for a, th1 in enumerate(angles):
        theta2 = float(model.theta2_for_te(th1, te))
        teeth: list[int] = []
        for _ in range(20):
            cons = eq.contacts(th1, theta2, phi, 0.0, 0.0, np.zeros(z))
            new = sorted({c.ia for c in cons if c.force > 0} | {c.ib for c in cons if c.force > 0})
            if new == teeth and _:
                break
            teeth = new
            keep = np.zeros(z, bool)
            keep[teeth] = True
            phi[~keep] = 0.0

            def residual(u, teeth=teeth):
                p = np.zeros(z)
                p[teeth] = u[1:] * 1e-3
                q = np.empty(len(teeth) + 1)
                q[0] = torque
                tq = eq.spring_torques(p, np.zeros(z))
                qt = {t: tq[t] for t in teeth}
                for c in eq.contacts(th1, u[0], p, 0.0, 0.0, np.zeros(z)):
                    q[0] -= c.force * c.g[2]
                    if c.ia in qt:
                        qt[c.ia] -= c.force * c.g[1]
                    if c.ib in qt:
                        qt[c.ib] -= c.force * c.g[3]
                q[1:] = [qt[t] for t in teeth]
                return q

            sol = optimize.root(residual, np.r_[theta2, phi[teeth] * 1e3], method="hybr",
                                options={"xtol": xtol})
            theta2 = float(sol.x[0])
            phi[teeth] = sol.x[1:] * 1e-3
        out[a] = te = rb1 * th1 + rb2 * theta2
    return out

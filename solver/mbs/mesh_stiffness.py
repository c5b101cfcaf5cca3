"""Tangent mesh stiffness of the loaded pair over driver angle, from the linearisation the
modes use (`solver.mbs.linearization.linearize`), and the tooth loads at the same equilibria.

At each driver angle the pair is solved to static equilibrium under the torque (continuation
from the previous angle, as the STE), linearised there, and the tangent stiffness matrix K
over the free DOFs (the driven hub, the teeth near the mesh and, for a body-coupled model, the
rims on their body springs) is condensed onto the driven hub with the driver hub prescribed:
every other DOF takes its static response x_r = -K_rr^-1 K_rh to a unit rotation of the hub,
and K_hh* = K_hh + K_hr x_r [N·m/rad] is dT2/dtheta2. The transmission error moves by rb2 per
radian of the driven hub, and the load along the line of action is T2/rb2, so the mesh
stiffness is

    k_m = dF/dTE = K_hh* / rb2**2  [N/m],

the body springs of a coupled model included in series, so that k_m is the slope of the hubs'
static TE.

The same response split by contacts gives each loaded tooth pair's share,
k_p = sum over its contacts of g2 * kt * (g . x) / rb2**2 (the pairs act in parallel between
the driver and the driven rim, and the whole rim moment reaches the hub, so the shares sum to
k_m): where the pair is alone in mesh, its stiffness with the bodies in series (ISO 6336-1's
single stiffness c' is its largest value).
DOFs with no stiffness (an unloaded tooth on a spring with n_k > 1, which has no tangent at
rest) carry no load and are left out of the condensation.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.model import Model


@dataclass
class MeshStates:
    """Linearised mesh and tooth loads at static equilibrium over driver angles."""
    angle: np.ndarray          # driver angle [rad]
    stiffness: np.ndarray      # (angle,) tangent mesh stiffness dF/dTE along the line of action [N/m]
    pair_stiffness: np.ndarray  # (angle, Z1) each loaded pair's share, by its driver tooth [N/m] (0: unloaded)
    tooth_force: np.ndarray    # (angle, Z1 + Z2) normal contact force on each tooth, gear-1 teeth first [N]
    mate: np.ndarray           # (angle, Z1) driven tooth in contact with each driver tooth (-1: none)
    te: np.ndarray             # (angle,) static TE at the hubs [m]
    converged: np.ndarray      # (angle,) bool

    def loaded_pairs(self, threshold: float = 1e-6) -> np.ndarray:
        """(angle,) number of driver teeth carrying more than ``threshold`` [N]."""
        z1 = self.mate.shape[1]
        return np.sum(self.tooth_force[:, :z1] > threshold, axis=1)


def condense(K: np.ndarray) -> tuple[float, np.ndarray]:
    """(K00* [K units], response x (n,) with x[0] = 1) of a symmetric tangent matrix condensed
    onto DOF 0: the other DOFs at their static response to a unit DOF 0. DOFs without
    stiffness (zero diagonal) stay at 0."""
    n = K.shape[0]
    x = np.zeros(n)
    x[0] = 1.0
    diag = np.abs(np.diag(K))
    live = np.flatnonzero(diag[1:] > 1e-12 * max(diag.max(), 1e-300)) + 1
    if live.size:
        x[live] = -np.linalg.solve(K[np.ix_(live, live)], K[live, 0])
    return float(K[0] @ x), x


def mesh_states(model: Model, angles, torque: float) -> MeshStates:
    """Tangent mesh stiffness, pair shares and tooth forces at static equilibrium under
    ``torque`` [N·m] on the driven gear (1 N·m if zero) at driver angles ``angles`` [rad]
    (see the module docstring). Angles where the statics do not converge hold NaN."""
    from solver.mbs.kernels.gearmesh import mesh_contacts, new_contact_buffer
    from solver.mbs.linearization import linearize
    from solver.mbs.statics import solve_static
    angles = np.asarray(angles, dtype=float)
    load = torque if abs(torque) > 1e-9 else 1.0
    z1, z2 = model.teeth
    n = angles.size
    k = np.full(n, np.nan)
    kp = np.zeros((n, z1))
    force = np.zeros((n, z1 + z2))
    mate = np.full((n, z1), -1, dtype=np.int64)
    te = np.full(n, np.nan)
    ok = np.zeros(n, bool)
    kb1, kb2 = model.body_stiffness
    rb1, rb2 = model.base_radii
    gp = model.gear_par
    tz2 = int(gp[1, L.TOOTH0])
    rec, pairs = new_contact_buffer()
    zeros = np.zeros(model.n_teeth)
    phi, te0 = None, None
    for i, theta1 in enumerate(angles):
        st = solve_static(model, np.array([theta1]), load, phi0=phi, te0=te0, raise_on_failure=False)
        if not st.converged[0]:
            force[i] = np.nan
            continue
        phi, te0 = st.phi_last, float(st.te[0])
        ok[i], te[i] = True, te0
        # a coupled model's mesh sits at the rim angles: the hubs less the body wind-up
        rim1 = theta1 - (load * rb1 / rb2 / kb1 if math.isfinite(kb1) else 0.0)
        rim2 = float(st.theta2[0]) - (load / kb2 if math.isfinite(kb2) else 0.0)
        lin = linearize(model, rim1, rim2, phi)
        hub = int(np.flatnonzero(lin.te)[0])            # the driven hub: theta2, or h2 when coupled
        order = [hub] + [j for j in range(lin.K.shape[0]) if j != hub]
        k00, xo = condense(lin.K[np.ix_(order, order)])
        x = np.empty_like(xo)
        x[order] = xo
        nb = lin.n_body
        th2 = lin.dofs.index("theta2")
        r1 = lin.dofs.index("r1") if "r1" in lin.dofs else None
        pos = {t: nb + j for j, t in enumerate(lin.teeth)}
        nc, _np = mesh_contacts((rim1, rim2, 0.0, 0.0), phi, zeros, (gp, model.pair_par, model.law_par), (rec, pairs))
        for c in range(nc):
            a, b = int(rec[c, L.C_TOOTH1]), int(rec[c, L.C_TOOTH2])
            f = rec[c, L.C_FORCE]
            force[i, a] += f
            force[i, tz2 + b] += f
            if f > 0 and (mate[i, a] < 0 or f > force[i, tz2 + mate[i, a]]):
                mate[i, a] = b
            g = [rec[c, L.C_G2], rec[c, L.C_GA], rec[c, L.C_GB]]
            dx = [x[th2], x[pos[a]] if a in pos else 0.0, x[pos[tz2 + b]] if tz2 + b in pos else 0.0]
            if r1 is not None:
                g.append(rec[c, L.C_G1])
                dx.append(x[r1])
            # its part of the driven rim's moment (all of it reaches the hub): lever g2 times the
            # contact's force change
            kp[i, a] += rec[c, L.C_G2] * rec[c, L.C_KT] * float(np.dot(g, dx)) / rb2**2
        km = k00 / rb2**2
        k[i] = km
    return MeshStates(angles, k, kp, force, mate, te, ok)


def pitch_lever(model: Model, g: int) -> float:
    """Lever arm [m] of a load at the pitch point along the line of action about the tooth
    pivot of gear ``g`` (0 driver, 1 driven): the line is tangent to the base circle at the
    polar angle psi_b - tan(alpha) from the tooth axis (the involute's roll angle at the pitch
    circle is tan(alpha)), so it passes the pivot on the axis at r_pv by
    |r_b - r_pv cos(psi_b - tan(alpha))|."""
    gp = model.gear_par[g]
    alpha = model.pair_par[L.ALPHA]
    return abs(gp[L.RB] - gp[L.R_PV] * math.cos(gp[L.PSI_B] - math.tan(alpha)))


def pitch_point_stiffness(model: Model, force: float) -> np.ndarray:
    """(Z1 + Z2,) linear stiffness [N/m] of each tooth at the pitch point along the line of
    action: the tangent dF/d(delta) of its spring T = k_phi phi^n_k under ``force`` [N] there
    (the moment F h about the pivot, h = `pitch_lever`), n_k k_phi phi^(n_k - 1) / h**2
    (independent of the force for a linear spring); gear-1 teeth first."""
    out = np.zeros(model.n_teeth)
    gp = model.gear_par
    for g in range(2):
        h = pitch_lever(model, g)
        t0, z, n = int(gp[g, L.TOOTH0]), int(gp[g, L.NZ]), float(gp[g, L.N_K])
        k = model.k_phi[t0:t0 + z]
        phi = (abs(force) * h / k) ** (1.0 / n)
        out[t0:t0 + z] = n * k * phi ** (n - 1.0) / h**2
    return out

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

The mesh alone (``stiffness_mesh``, ``pair_stiffness_mesh``): the same tangent with both
bodies' wind-up from the bore taken out, what ISO 6336-1's c' and c_gamma_alpha describe.
* A body-coupled model carries the wind-up as its body springs (hub -> rim, k_body): the
  tangent matrix without them, condensed onto the driven rim with the driver rim prescribed
  (the bodies rigid below the rim). The body springs sit in series with the rest, so where the
  contacts act along the line of action (flank contacts, levers rb1 and rb2 on the rims),
  1/k_m = 1/k_mesh + rb1**2/k_body1 + rb2**2/k_body2; a tip corner's other lever departs from it.
* The plain model lumps the wind-up into every tooth spring (a spring fitted to a bore-clamped
  body). Given the bodies' wind-up as compliances c_w along the line of action [m/N]
  (``windup``), each loaded tooth spring's tangent k_t [N·m/rad] is replaced by that of the
  tooth alone at the pitch point, 1 / (1/k_t - c_w/h**2), h the pitch lever (`pitch_lever`;
  the split of `solver.identify.coupling.body_torsion_fit` with a rigid body). Without
  ``windup`` the plain model's mesh alone is unknown (NaN); so it is at an angle where a
  loaded spring is stiffer than the wind-up alone (c_w/h**2 >= 1/k_t: it cannot hold it).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

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
    # the mesh alone, both bodies' wind-up from the bore taken out (NaN: a plain model given no windup)
    stiffness_mesh: np.ndarray = None        # (angle,) [N/m]
    pair_stiffness_mesh: np.ndarray = None   # (angle, Z1) [N/m]

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


def condense_onto(K: np.ndarray, dof: int, prescribed=()) -> tuple[float, np.ndarray]:
    """`condense` of ``K`` onto DOF ``dof`` with the DOFs ``prescribed`` held at 0 (left out):
    (K* [K units], response x (n,) with x[dof] = 1 and 0 at the prescribed DOFs)."""
    order = [dof] + [j for j in range(K.shape[0]) if j != dof and j not in prescribed]
    k00, xo = condense(K[np.ix_(order, order)])
    x = np.zeros(K.shape[0])
    x[order] = xo
    return k00, x


def mesh_states(model: Model, angles, torque: float, windup=None) -> MeshStates:
    """Tangent mesh stiffness, pair shares and tooth forces at static equilibrium under
    ``torque`` [N·m] on the driven gear (1 N·m if zero) at driver angles ``angles`` [rad]
    (see the module docstring), with the mesh alone beside them. ``windup``: (gear 1, gear 2)
    compliance along the line of action [m/N] of the body wind-up from the bore that the plain
    model's tooth springs hold (a body-coupled model carries its own: refused there). Angles
    where the statics do not converge hold NaN."""
    from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
    from solver.mbs.linearization import linearize
    from solver.mbs.statics import solve_static
    windup = _checked_windup(model, windup)
    angles = np.asarray(angles, dtype=float)
    load = torque if abs(torque) > 1e-9 else 1.0
    z1, z2 = model.teeth
    n = angles.size
    k = np.full(n, np.nan)
    kp = np.zeros((n, z1))
    k_mesh = np.full(n, np.nan)
    kp_mesh = np.zeros((n, z1)) if model.coupled or windup is not None else np.full((n, z1), np.nan)
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
            kp_mesh[i] = np.nan
            continue
        phi, te0 = st.phi_last, float(st.te[0])
        ok[i], te[i] = True, te0
        # a coupled model's mesh sits at the rim angles: the hubs less the body wind-up
        rim1 = theta1 - (load * rb1 / rb2 / kb1 if math.isfinite(kb1) else 0.0)
        rim2 = float(st.theta2[0]) - (load / kb2 if math.isfinite(kb2) else 0.0)
        lin = linearize(model, rim1, rim2, phi)
        hub = int(np.flatnonzero(lin.te)[0])            # the driven hub: theta2, or h2 when coupled
        k00, x = condense_onto(lin.K, hub)
        dofs = _Dofs(lin.dofs.index("theta2"), lin.dofs.index("r1") if "r1" in lin.dofs else None,
                     {t: lin.n_body + j for j, t in enumerate(lin.teeth)}, tz2)
        nc, _np = mesh_contacts((rim1, rim2, 0.0, 0.0), phi, zeros, contact_geo(gp, model.pair_par, model.law_par), (rec, pairs))
        _tooth_forces(rec, nc, force[i], mate[i], tz2)
        kp[i] = _pair_shares(rec, nc, x, dofs, rb2, z1)
        k[i] = k00 / rb2**2
        alone = _mesh_alone(model, lin, dofs, phi, windup)
        if alone is None:           # the plain model without the wind-up: no mesh alone
            continue
        if alone is False:          # a spring stiffer than the wind-up alone: it cannot hold it
            kp_mesh[i] = np.nan
            continue
        km, xm = alone
        k_mesh[i] = km / rb2**2
        kp_mesh[i] = _pair_shares(rec, nc, xm, dofs, rb2, z1)
    return MeshStates(angles, k, kp, force, mate, te, ok, k_mesh, kp_mesh)


def _checked_windup(model: Model, windup):
    """``windup`` of `mesh_states` as two floats [m/N] (None as is); ValueError where it is no
    pair of finite compliances >= 0, or the model carries its own wind-up."""
    if windup is None:
        return None
    if model.coupled:
        raise ValueError("windup: a body-coupled model carries the bodies' wind-up as its body springs "
                         "(give it for the plain model only)")
    windup = tuple(float(w) for w in windup)
    if len(windup) != 2 or not all(math.isfinite(w) and w >= 0 for w in windup):
        raise ValueError(f"windup: need two finite compliances >= 0 [m/N] (gear 1, gear 2), got {windup}")
    return windup


class _Dofs(NamedTuple):
    """Where a linearization's degrees of freedom sit: the driven rim ``th2``, the driver rim
    ``r1`` (None without body coupling), each tooth's by tooth index (``pos``), and the index
    of the driven gear's first tooth (``tz2``)."""
    th2: int
    r1: int | None
    pos: dict
    tz2: int


def _tooth_forces(rec, nc: int, force: np.ndarray, mate: np.ndarray, tz2: int) -> None:
    """Add the ``nc`` contacts' forces [N] to each tooth's ``force`` (driver teeth first, the
    driven from ``tz2``) and keep in ``mate`` each driver tooth's most loaded driven tooth."""
    for c in range(nc):
        a, b = int(rec[c, L.C_TOOTH1]), int(rec[c, L.C_TOOTH2])
        f = rec[c, L.C_FORCE]
        force[a] += f
        force[tz2 + b] += f
        if f > 0 and (mate[a] < 0 or f > force[tz2 + mate[a]]):
            mate[a] = b


def _mesh_alone(model: Model, lin, dofs: _Dofs, phi: np.ndarray, windup):
    """(condensed stiffness, static response) of the mesh alone at the linearization ``lin``:
    a coupled model without its body springs, the driver rim prescribed; the plain model with
    ``windup`` [m/N], each loaded tooth spring without the wind-up it holds (False where a
    spring is stiffer than the wind-up alone: it cannot hold it); None for the plain model
    without it."""
    from solver.mbs.kernels.gearmesh import tooth_spring_tangent
    gp, th2, r1 = model.gear_par, dofs.th2, dofs.r1
    if model.coupled:           # the body springs out, the driver rim prescribed, onto the driven rim
        K = lin.K.copy()
        K[r1, r1] -= gp[0, L.K_BODY]
        h2 = lin.dofs.index("h2")
        d = np.zeros(K.shape[0])
        d[th2], d[h2] = 1.0, -1.0
        K -= gp[1, L.K_BODY] * np.outer(d, d)
        return condense_onto(K, th2, prescribed=(r1, h2))
    if windup is None:
        return None
    levers = (pitch_lever(model, 0), pitch_lever(model, 1))
    K = lin.K.copy()
    held = True
    for t, j in dofs.pos.items():
        g = 1 if t >= dofs.tz2 else 0
        kt = tooth_spring_tangent(t, phi, model.k_phi, gp)
        if kt > 0:
            rest = 1.0 / kt - windup[g] / levers[g] ** 2
            held = held and rest > 0
            K[j, j] += 1.0 / rest - kt if rest > 0 else 0.0
    if not held:
        return False
    return condense_onto(K, th2)


def _pair_shares(rec, nc: int, x: np.ndarray, dofs: _Dofs, rb2: float, z1: int) -> np.ndarray:
    """(Z1,) each loaded pair's share [N/m] of the condensed stiffness whose static response
    is ``x``, by driver tooth: over its contacts, the contact's part of the driven rim's moment
    (all of it reaches the hub), lever g2 times the contact's force change, over rb2**2."""
    th2, r1, pos, tz2 = dofs
    out = np.zeros(z1)
    for c in range(nc):
        a, b = int(rec[c, L.C_TOOTH1]), int(rec[c, L.C_TOOTH2])
        g = [rec[c, L.C_G2], rec[c, L.C_GA], rec[c, L.C_GB]]
        dx = [x[th2], x[pos[a]] if a in pos else 0.0, x[pos[tz2 + b]] if tz2 + b in pos else 0.0]
        if r1 is not None:
            g.append(rec[c, L.C_G1])
            dx.append(x[r1])
        out[a] += rec[c, L.C_G2] * rec[c, L.C_KT] * float(np.dot(g, dx)) / rb2**2
    return out


def pitch_lever(model: Model, g: int) -> float:
    """Lever arm [m] of a load at the pitch point along the line of action about the tooth
    pivot of gear ``g`` (0 driver, 1 driven): the line is tangent to the base circle at the
    polar angle psi_b - tan(alpha) from the tooth axis (the involute's roll angle at the pitch
    circle is tan(alpha)), so it passes the pivot on the axis at r_pv by
    |r_b - r_pv cos(psi_b - tan(alpha))|."""
    gp = model.gear_par[g]
    alpha = model.pair_par[L.ALPHA]
    return abs(gp[L.RB] - gp[L.R_PV] * math.cos(gp[L.PSI_B] - math.tan(alpha)))


def pitch_point_stiffness(model: Model, force: float, windup=(0.0, 0.0)) -> np.ndarray:
    """(Z1 + Z2,) each tooth's own linear stiffness [N/m] at the pitch point along the line of
    action, its body rigid below the rim; gear-1 teeth first. The tangent dF/d(delta) of its
    spring T = k_phi phi^n_k under ``force`` [N] there (the moment F h about the pivot, h =
    `pitch_lever`), n_k k_phi phi^(n_k - 1) / h**2 (independent of the force for a linear
    spring), in series with the local compliance c_loc at the pitch point where the model has
    one (the compliance model: its tooth loaded alone then has the FE tooth's compliance there).
    A plain model's spring holds its body's wind-up from the bore: ``windup`` (gear 1, gear 2)
    [m/N] along the line of action is taken out of it, 1 / (1/k - c_w) (0: the spring as is)."""
    from solver.mbs.kernels.gearmesh import local_compliance
    if model.coupled and any(w != 0 for w in windup):
        raise ValueError("windup: a body-coupled model's tooth springs hold no body wind-up")
    out = np.zeros(model.n_teeth)
    gp = model.gear_par
    u = math.tan(model.pair_par[L.ALPHA])
    for g in range(2):
        h = pitch_lever(model, g)
        t0, z, n = int(gp[g, L.TOOTH0]), int(gp[g, L.NZ]), float(gp[g, L.N_K])
        k = model.k_phi[t0:t0 + z]
        phi = (abs(force) * h / k) ** (1.0 / n)
        c = h**2 / (n * k * phi ** (n - 1.0)) - windup[g]
        if gp[g, L.CLOC_ON]:
            c = c + local_compliance.py_func(gp, g, u)[0]
        if not np.all(c > 0):
            raise ValueError(f"windup: gear {g + 1}'s body wind-up {windup[g]:.4g} m/N is more than its tooth springs "
                             f"hold at the pitch point ({float(np.min(c + windup[g])):.4g} m/N)")
        out[t0:t0 + z] = 1.0 / c
    return out


def body_windup_compliance(model: Model, windup=None) -> tuple[float, float]:
    """(gear 1, gear 2) compliance [m/N] along the line of action of each body's wind-up from
    the bore to the rim: rb**2 / k_body of a body-coupled model (its body springs); for the
    plain model, whose tooth springs hold it, ``windup`` as given (None: 0, unknown)."""
    if model.coupled:
        return tuple(rb**2 / kb if math.isfinite(kb) else 0.0 for rb, kb in zip(model.base_radii, model.body_stiffness))
    return (0.0, 0.0) if windup is None else tuple(float(w) for w in windup)

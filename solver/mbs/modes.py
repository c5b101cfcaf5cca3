"""Modes of the loaded pair and damping given as a ratio of critical (numpy, no kernels).

The pair is linearised (`solver.mbs.linearization`: the DOFs the kernels integrate, the rims,
hubs and body springs of a coupled model included) at static equilibrium under the mean load
at ``positions`` driver angles across one angular pitch (one mesh period). At each position
the eigenvalues lambda of M x'' + C x' + K x = 0 (C: body, tooth-spring and contact dampers
linearised at rest), from its state-space form, give the natural frequency |lambda| and the
damping ratio -Re(lambda)/|lambda| of each mode. They are exact for the linearised pair where
the modal estimate x^T C x / (2 w) on undamped modes is not: a heavily damped tooth joint
holds the mesh mode's shape (at 5 % that estimate reads twice the ratio the free decay
shows). The mesh mode is the mode that puts the most into the TE at the hubs under a force at
the mesh (`te_participation`): in the plain model the driven gear rotating on the mesh
spring against the prescribed driver; in a coupled model the rims and the driven hub
against the mesh and the body springs together. The others are named by where their kinetic
energy lies: body modes (coupled models: mostly on the rims and hubs), or tooth modes of the
gear whose teeth carry most of it. Modes of teeth near the mesh that carry no load (a spring
with n_k > 1 has no stiffness at zero deflection) and overdamped modes are left out.

Damping as a ratio (`joint_damping_for_ratio`, `tooth_damping_for_ratio`):
* tooth dampers: zeta_t of the tooth's own mode, the tooth on its spring about its pivot:
  c_phi = 2 zeta_t sqrt(k_t I_P), k_t the spring tangent of the most deflected tooth of that
  gear at the mean-load equilibria (mean over the mesh positions), I_P the tooth's inertia
  about its pivot (needs n_c = 1);
* mesh mode: zeta_m, carried by the joint dampers of both gears (`joint_damping_for_ratio`):
  the mesh mode of the linearised pair (mesh stiffness: the contact tangents in series with
  the tooth-spring tangents; its mass from the mode shape) deflects mostly the tooth springs,
  so the dampers across them damp it; one scale of c_phi (both gears at the same ratio of
  their own modes) is found by root finding on the state-space eigenvalues so that the mesh
  mode's ratio, averaged over the mesh positions, equals zeta_m. A contact damper
  (c*ddelta*delta^m3, in series with the tooth springs) could not do it without overdamping
  the tooth-on-contact modes (see `study.scene_model.damping_from_ratios`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from solver.mbs.equilibria import Equilibrium, loaded_equilibria
from solver.mbs.kernels import layout as L
from solver.mbs.linearization import LinearSystem, at_equilibrium
from solver.mbs.model import Model


def with_damping(model: Model, c_con: float | None = None, c_phi: tuple | None = None,
                 c_body: tuple | None = None) -> Model:
    """A copy of ``model`` with the contact damping c_con [SI], the tooth dampers c_phi
    (gear 1, gear 2) [N·m·s/rad] and/or the body dampers c_body (gear 1, gear 2) [N·m·s/rad]
    replaced (the arrays are copied, the rest shared)."""
    gp, lp = model.gear_par, model.law_par
    if c_phi is not None or c_body is not None:
        gp = gp.copy()
    if c_phi is not None:
        gp[:, L.C_PHI] = c_phi
    if c_body is not None:
        gp[:, L.C_BODY] = c_body
    if c_con is not None:
        lp = lp.copy()
        lp[L.C_CON] = c_con
    return dataclasses.replace(model, gear_par=gp, law_par=lp)


def _system(model: Model, eq: Equilibrium) -> LinearSystem:
    return at_equilibrium(model, eq)


def _modes(M, K):
    """(w [rad/s], mass-normalised modes) of the modes with stiffness."""
    lam, x = scipy.linalg.eigh(K, M)
    keep = lam > 1e-8 * max(K[0, 0] / M[0, 0], 0.0)      # (see `_damped_modes`)
    return np.sqrt(lam[keep]), x[:, keep]


def te_participation(M, C, lam, u, te, mesh) -> np.ndarray:
    """How much each mode (eigenvalue lam, shape u of M x'' + C x' + K x = 0) puts into the TE
    at the hubs under a force at the mesh: |(te.u)(mesh.u)| / |a lam|, a = u^T (2 lam M + C) u
    (the residue of the receptance; for an undamped mode of unit modal mass (te.x)(mesh.x) /
    (2 w^2), its static share). Independent of the shapes' scaling."""
    a = np.array([u[:, k] @ ((2 * lam[k]) * M + C) @ u[:, k] for k in range(u.shape[1])])
    return np.abs((te @ u) * (mesh @ u)) / np.maximum(np.abs(a * lam), 1e-300)


def _state_parts(sy: LinearSystem) -> tuple:
    """(M^-1, -M^-1 K) of ``sy``: the parts of the state-space matrix of `_damped_modes` that do
    not depend on the damping, made once for the many dampings a ratio search tries on it."""
    mi = np.linalg.inv(sy.M)
    return mi, -mi @ sy.K


def _damped_modes(sy: LinearSystem, C, parts: tuple | None = None):
    """(natural frequency |lambda| [rad/s], damping ratio -Re(lambda)/|lambda| [1], kinetic-energy
    shares (dof, mode), index of the mesh mode) of the oscillating modes of
    M x'' + C x' + K x = 0 (the state-space eigenproblem: exact for non-proportional damping,
    where a heavily damped tooth joint holds the mesh mode's shape); overdamped and rigid
    modes are left out. The mesh mode is the one whose resonance puts the most into the TE at
    the hubs under a force at the mesh: `te_participation` over the damping ratio (the peak of
    a lightly damped mode; at least 1e-3 counted, so that an undamped pair falls back on the
    static share), the resonance a run-up shows. ``parts``: `_state_parts` of ``sy`` when
    already made."""
    M, K = sy.M, sy.K
    n = M.shape[0]
    mi, mik = parts or _state_parts(sy)
    lam, v = np.linalg.eig(np.block([[np.zeros((n, n)), np.eye(n)], [mik, -mi @ C]]))
    wn = np.abs(lam)
    # rigid-like modes (unloaded teeth on their regularised springs) are left out by comparison
    # with the driven hub on its own stiffness, not with the highest mode: with very stiff
    # tooth springs the tooth modes lie 1e4 above the mesh mode, which must stay in
    w_ref = math.sqrt(max(K[0, 0] / M[0, 0], 0.0)) or max(wn.max(), 1.0)
    keep = (lam.imag > 1e-9 * max(wn.max(), 1.0)) & (wn > 1e-4 * w_ref)
    lam, u = lam[keep], v[:n, keep]
    share = np.real(np.conj(u) * (M @ u))
    share = share / share.sum(0)
    zeta = -lam.real / np.abs(lam)
    mesh = int(np.argmax(te_participation(M, C, lam, u, sy.te, sy.mesh) / np.maximum(zeta, 1e-3)))
    return np.abs(lam), zeta, share, mesh


def _mesh_damping(sy: LinearSystem, C, parts: tuple | None = None) -> float:
    w, z, share, i = _damped_modes(sy, C, parts)
    return float(z[i])


@dataclass
class Modes:
    """Natural frequencies and damping ratios over mesh positions (mode 0 is the mesh mode;
    then the other modes by rising frequency, NaN where a position has fewer)."""
    position: np.ndarray       # driver angle [rad] of each mesh position
    frequency: np.ndarray      # (mode, position) [Hz]
    damping: np.ndarray        # (mode, position) ratio of critical [1]
    gear: np.ndarray           # (mode, position) gear whose teeth carry most of the mode's energy (0: the mesh mode, 3: a body mode)
    kind: tuple                # per mode: 'mesh', 'body', 'tooth gear1', 'tooth gear2' (most frequent over positions)


def modal_analysis(model: Model, torque: float, positions: int = 12, equilibria=None) -> Modes:
    """Modes of the pair linearised at static equilibrium under ``torque`` [N·m] at
    ``positions`` driver angles across one mesh period (see the module docstring); solved once
    per model and load (`solver.mbs.memo`). ``equilibria``: the model's loaded equilibria under
    ``torque`` at ``positions`` when already solved (`solver.mbs.equilibria.loaded_equilibria`:
    the same numbers, not solved again)."""
    from solver.mbs.memo import kept
    return kept("modal_analysis", model, (float(torque), int(positions)),
                lambda: _modal_analysis(model, torque, positions, equilibria))


def _modal_analysis(model: Model, torque: float, positions: int, equilibria) -> Modes:
    eqs = equilibria or loaded_equilibria(model, torque, positions)
    rows = []
    tz2 = int(model.gear_par[1, L.TOOTH0])
    for eq in eqs:
        sy = _system(model, eq)
        w, zeta, share, im = _damped_modes(sy, sy.damping())
        nb = sy.n_body
        g2 = np.array([t >= tz2 for t in sy.teeth], dtype=bool)
        tooth = share[nb:]
        gear = np.where(tooth[g2].sum(0) > tooth[~g2].sum(0), 2, 1)
        if nb > 1:      # body-coupled: a mode whose energy lies mostly on the rims and hubs
            gear[share[:nb].sum(0) > 0.5] = 3
        gear[im] = 0
        order = [im] + [j for j in np.argsort(w) if j != im]
        rows.append((w[order] / (2 * math.pi), zeta[order], gear[order]))
    n = max(len(r[0]) for r in rows)

    def pad(k, fill):
        return np.array([np.pad(r[k].astype(float), (0, n - len(r[k])), constant_values=fill) for r in rows]).T

    gear = pad(2, -1).astype(int)
    kind = ["mesh"]
    for row in gear[1:]:
        vals = row[row > 0]
        top = np.bincount(vals).argmax() if vals.size else 0
        kind.append("body" if top == 3 else f"tooth gear{top}" if top else "tooth")
    return Modes(np.array([e.theta1 for e in eqs]), pad(0, np.nan), pad(1, np.nan), gear, tuple(kind))


def tooth_damping_for_ratio(model: Model, equilibria, zeta: float, gear: int) -> float:
    """Tooth damper c_phi [N·m·s/rad] giving ratio ``zeta`` on gear ``gear``'s (1, 2) tooth
    mode: 2 zeta sqrt(k_t I_P), k_t the spring tangent of its most deflected tooth at the
    equilibria (mean), I_P the tooth's inertia about its pivot."""
    from solver.mbs.kernels.gearmesh import tooth_spring_tangent
    gp = model.gear_par
    g = gear - 1
    t0 = int(gp[g, L.TOOTH0])
    z = model.teeth[g]
    if model.teeth_coupled:   # the tooth's own spring: the inverse of its compliance
        ks = [1.0 / model.tooth_compliance[t0 + int(np.argmax(np.abs(e.phi[t0:t0 + z]))),
                                           t0 + int(np.argmax(np.abs(e.phi[t0:t0 + z])))] for e in equilibria]
    else:
        ks = [tooth_spring_tangent(t0 + int(np.argmax(np.abs(e.phi[t0:t0 + z]))), e.phi, model.k_phi, gp)
              for e in equilibria]
    return 2.0 * zeta * math.sqrt(float(np.mean(ks)) * gp[g, L.I_P])


def _solve_scale(parts, zeta: float, what: str) -> float:
    """The scale s >= 0 of the damper C1 in C = C0 + s C1 for which the mesh mode's ratio,
    mean over the positions ``parts`` [(LinearSystem, C0, C1)], is ``zeta``. The ratio grows
    with s from that of C0 up to a largest value (a very stiff damper locks its joint) and
    falls after it: the root below that largest value is taken."""
    state = [_state_parts(sy) for sy, _, _ in parts]

    def mean(s):
        return float(np.mean([_mesh_damping(sy, C0 + s * C1, st) for (sy, C0, C1), st in zip(parts, state)]))
    z0 = mean(0.0)
    if z0 > zeta:
        raise ValueError(f"the other dampers alone give the mesh mode {z0:.4g} of critical, more than {zeta:.4g}")
    if zeta == z0:
        return 0.0
    # first guess: the proportional-damping estimate x^T C1 x / (2 w), linear in s, on the
    # undamped mode nearest the damped mesh mode
    est = []
    for (sy, C0, C1), st in zip(parts, state):
        w, x = _modes(sy.M, sy.K)
        wd, _z, _share, i = _damped_modes(sy, C0, st)
        j = int(np.argmin(np.abs(w - wd[i])))
        est.append(0.5 * x[:, j] @ C1 @ x[:, j] / w[j])
    unit = float(np.mean(est))
    if not unit > 0:
        raise ValueError(f"the {what} do not damp the mesh mode (check the exponents and the load)")
    lo, hi, z_lo = 0.0, (zeta - z0) / unit, z0
    best = z0
    for _ in range(40):
        z_hi = mean(hi)
        if z_hi >= zeta:
            return float(scipy.optimize.brentq(lambda s: mean(s) - zeta, lo, hi, xtol=1e-12 * hi, rtol=1e-10))
        if z_hi < z_lo:       # past the largest ratio the damper can give
            break
        best = max(best, z_hi)
        lo, z_lo, hi = hi, z_hi, 2.0 * hi
    raise ValueError(f"the {what} cannot damp the mesh mode to {zeta:.4g} of critical (at most about {best:.3g})")


def joint_damping_for_ratio(model: Model, equilibria, zeta: float) -> tuple[float, float]:
    """Tooth-root joint dampers (c_phi gear 1, gear 2) [N·m·s/rad] that alone (no contact
    damper; the body dampers of a coupled model stay) give the mesh mode the ratio ``zeta`` on
    average over the equilibria; both gears' teeth at the same ratio of their own mode. The
    mesh mode deflects mostly the tooth springs (the contact is stiff in series with them),
    so this damps it at a small price on the local modes; a contact damper that did it alone
    would overdamp the tooth-on-contact modes far above and cut the explicit step by some
    fifty times. The linearisation is that of the model integrated (`solver.mbs.linearization`),
    made once per equilibrium."""
    unit = (tooth_damping_for_ratio(model, equilibria, 1.0, 1), tooth_damping_for_ratio(model, equilibria, 1.0, 2))
    parts = []
    for eq in equilibria:
        sy = _system(model, eq)
        parts.append((sy, sy.c_body, unit[0] * sy.joint_unit[0] + unit[1] * sy.joint_unit[1]))
    s = _solve_scale(parts, zeta, "tooth-root joint dampers")
    return unit[0] * s, unit[1] * s


def joint_and_body_damping_for_ratio(model: Model, equilibria, zeta: float) -> tuple[tuple, tuple]:
    """((c_phi gear 1, gear 2), (c_body gear 1, gear 2)) [N·m·s/rad]: the tooth-root joint
    dampers and the body dampers of a body-coupled model, all at the same ratio of their own
    modes (the tooth on its spring, the rim on its body spring), that give the mesh mode the
    ratio ``zeta`` on average over the equilibria. For a pair whose joint dampers alone cannot
    (`joint_damping_for_ratio`): a coupled mesh mode also winds up the bodies, so their
    dampers carry the rest."""
    from solver.mbs.model import body_critical_damping
    unit_j = (tooth_damping_for_ratio(model, equilibria, 1.0, 1), tooth_damping_for_ratio(model, equilibria, 1.0, 2))
    unit_b = tuple(body_critical_damping(model.gear_par, i) for i in (0, 1))
    bodies = with_damping(model, c_body=unit_b)
    parts = []
    for eq in equilibria:
        sy = _system(bodies, eq)
        parts.append((sy, np.zeros_like(sy.M), sy.c_body + unit_j[0] * sy.joint_unit[0] + unit_j[1] * sy.joint_unit[1]))
    s = _solve_scale(parts, zeta, "tooth-root joint and body dampers")
    return (unit_j[0] * s, unit_j[1] * s), (unit_b[0] * s, unit_b[1] * s)

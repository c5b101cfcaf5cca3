"""The pair linearised at a loaded static equilibrium: the one linear model behind the step
bound (`solver.mbs.stability`), the modes and the damping conversion (`solver.mbs.modes`).

Degrees of freedom are those the explicit kernels integrate:

* plain model (`kernels/explicit.py`): the driven hub theta2, then the teeth of the
  pre-search candidates (the driver hub is prescribed);
* body-coupled models (`kernels/explicit_coupled.py`): the driver rim r1 (on its body
  spring k_body1 to the prescribed hub), the driven rim theta2 and the driven hub h2 (joined
  by k_body2), then the candidates' teeth, each on its rim.

Mass: the arrowhead of each gear (hub or rim row coupled to its teeth by I_CPL); a rim carries
I_TOT - I_HUB, a driven hub I_HUB. Stiffness: the contact tangents along the penetration
gradients, the tooth-spring tangents or, with teeth coupled through the body (the compliance
model), K_S = (C[S, S])^-1 over the candidates' teeth S, exactly as the kernel's coupled set
(`kernels/toothcoupling.py`; the kernel's S is the teeth of the pre-search candidates, the
same pairs as here), and the body springs. Damping at rest, kept by origin so that a damping
conversion can scale one part without linearising again: the body dampers C_BODY, the
tooth-root dampers (per gear, as a pattern per unit c_phi), the contact dampers, the flank
friction's slope at zero sliding.

Teeth outside the candidates carry no load and sit at rest on their hub: they are rigid in
the linearisation (their inertia is in I_TOT), as in the kernels until they are named. With
``all_teeth`` they are free instead, each on its own spring and root damper (k_phi; the
compliance model's 1/C[a, a], as the kernels give a tooth outside the coupled set), as in a run
with every tooth free or an active set that has grown to all teeth: the step bound of the
all-explicit scheme needs them (`solver.mbs.stability`), since their root dampers together,
against the rim, damp a mode faster than any one tooth's.

The loaded equilibria are solved once per model and load (`solver.mbs.equilibria` keeps
them), however many of the step bound, the modes and the damping conversion ask for them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer, tooth_spring_tangent
from solver.mbs.kernels.laws import contact_damping_tangents, spring_damping_tangent
from solver.mbs.model import Model


@dataclass
class LinearSystem:
    """M x'' + C x' + K x = f over the free DOFs (SI: kg·m², N·m·s/rad, N·m/rad with angle
    DOFs). ``dofs``: names of the body DOFs ('theta2'; or 'r1', 'theta2', 'h2'), then one per
    tooth of ``teeth`` (tooth indices). The damping parts add up to C (`damping`)."""
    M: np.ndarray
    K: np.ndarray
    c_body: np.ndarray          # body-spring dampers
    c_joint: tuple              # (gear 1, gear 2) tooth-root dampers of the model
    joint_unit: tuple           # (gear 1, gear 2) the tooth-root damper pattern per unit c_phi (n_c = 1; 0 else)
    c_contact: np.ndarray       # contact dampers dF/d(ddelta) = c delta^m3 (m2 = 1; 0 at rest else)
    c_friction: np.ndarray      # flank friction's slope at zero sliding, along the lever arms
    dofs: tuple
    teeth: list
    te: np.ndarray              # TE at the hubs [m] per unit DOF displacement
    mesh: np.ndarray            # generalised force of a unit normal force at every loaded contact [m]

    @property
    def n_body(self) -> int:
        return len(self.dofs) - len(self.teeth)

    def damping(self, joint: bool = True, contact: bool = True, friction: bool = False, body: bool = True):
        """C [N·m·s/rad] of the parts asked for."""
        c = np.zeros_like(self.M)
        if body:
            c = c + self.c_body
        if joint:
            c = c + self.c_joint[0] + self.c_joint[1]
        if contact:
            c = c + self.c_contact
        if friction:
            c = c + self.c_friction
        return c


def linearize(model: Model, rim1: float, rim2: float, phi: np.ndarray, all_teeth: bool = False) -> LinearSystem:
    """The pair linearised about the driver rim angle ``rim1`` [rad] (the hub in the plain
    model), the driven rim angle ``rim2`` [rad] and the tooth rotations ``phi`` [rad], at rest
    (see the module docstring; ``all_teeth``: every tooth free, not only the candidates').
    The damping laws run as plain Python here (``.py_func``, a few dozen calls): compiling
    them would add to the first run's compile time for nothing."""
    rec, pairs = new_contact_buffer()
    zeros = np.zeros(model.n_teeth)
    gp, lp = model.gear_par, model.law_par
    nc, npair = mesh_contacts((rim1, rim2, 0.0, 0.0), phi, zeros, contact_geo(gp, model.pair_par, lp), (rec, pairs))
    tz2 = int(gp[1, L.TOOTH0])
    cand = sorted({int(pairs[p, 0]) for p in range(npair)} | {tz2 + int(pairs[p, 1]) for p in range(npair)})
    teeth = list(range(model.n_teeth)) if all_teeth else cand
    coupled_set = set(cand)
    coupled = model.coupled
    body = ("r1", "theta2", "h2") if coupled else ("theta2",)
    nb = len(body)
    r1, th2, h2 = (0, 1, 2) if coupled else (None, 0, None)
    pos = {t: nb + i for i, t in enumerate(teeth)}
    n = nb + len(teeth)
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    cb = np.zeros((n, n))
    cj = [np.zeros((n, n)), np.zeros((n, n))]
    ju = [np.zeros((n, n)), np.zeros((n, n))]
    cc = np.zeros((n, n))
    cf = np.zeros((n, n))
    te = np.zeros(n)
    if coupled:
        M[r1, r1] = gp[0, L.I_TOT] - gp[0, L.I_HUB]
        M[th2, th2] = gp[1, L.I_TOT] - gp[1, L.I_HUB]
        M[h2, h2] = gp[1, L.I_HUB]
        K[r1, r1] += gp[0, L.K_BODY]            # to the prescribed driver hub
        cb[r1, r1] += gp[0, L.C_BODY]
        d = np.zeros(n)
        d[th2], d[h2] = 1.0, -1.0
        K += gp[1, L.K_BODY] * np.outer(d, d)
        cb += gp[1, L.C_BODY] * np.outer(d, d)
        te[h2] = gp[1, L.RB]
    else:
        M[th2, th2] = gp[1, L.I_TOT]
        te[th2] = gp[1, L.RB]
    for t, i in pos.items():
        g = 1 if t >= tz2 else 0
        M[i, i] = gp[g, L.I_P]
        rim = th2 if g == 1 else r1         # the plain driver's hub is prescribed: no coupling row
        if rim is not None:
            M[rim, i] = M[i, rim] = gp[g, L.I_CPL]
        if not model.teeth_coupled or t not in coupled_set:     # its own spring: outside the coupled set
            K[i, i] += tooth_spring_tangent(t, phi, model.k_phi, gp)
        cj[g][i, i] += spring_damping_tangent.py_func(0.0, gp[g, L.C_PHI], gp[g, L.N_C])
        ju[g][i, i] += 1.0 if gp[g, L.N_C] == 1.0 else 0.0
    if model.teeth_coupled:     # the springs of the candidates' teeth: (C[S, S])^-1
        idx = [pos[t] for t in cand]
        K[np.ix_(idx, idx)] += np.linalg.inv(model.tooth_compliance[np.ix_(cand, cand)])
    mesh = np.zeros(n)
    for c in range(nc):
        ia = int(rec[c, L.C_TOOTH1])
        ib = tz2 + int(rec[c, L.C_TOOTH2])
        idx = [th2, pos[ia], pos[ib]]
        g = [rec[c, L.C_G2], rec[c, L.C_GA], rec[c, L.C_GB]]
        hv = [rec[c, L.C_H2], rec[c, L.C_HA], rec[c, L.C_HB]]
        if coupled:
            idx.append(r1)
            g.append(rec[c, L.C_G1])
            hv.append(rec[c, L.C_H1])
        g, hv = np.array(g), np.array(hv)
        K[np.ix_(idx, idx)] += rec[c, L.C_KT] * np.outer(g, g)
        _kd, cd = contact_damping_tangents.py_func(rec[c, L.C_DELTA], 0.0, max(rec[c, L.C_FORCE], 1e-300),
                                                   lp[L.C_CON], lp[L.M2], lp[L.M3])
        cc[np.ix_(idx, idx)] += cd * np.outer(g, g)
        if lp[L.MU] > 0:
            # flank friction at rest: its slope mu*F/v_reg in the sliding speed, a stiff damper
            # along the lever arms H (the symmetric part; it sets the explicit step)
            cf[np.ix_(idx, idx)] += rec[c, L.C_DFT] * np.outer(hv, hv)
        if rec[c, L.C_FORCE] > 0:
            mesh[idx] += g
    return LinearSystem(M, K, cb, tuple(cj), tuple(ju), cc, cf, body + tuple(f"tooth {t}" for t in teeth),
                        teeth, te, mesh)


def at_equilibrium(model: Model, eq) -> LinearSystem:
    """`linearize` at a loaded equilibrium (`solver.mbs.equilibria.Equilibrium`)."""
    return linearize(model, eq.rim1, eq.rim2, eq.phi)

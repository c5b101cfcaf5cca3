"""Loaded static equilibria of the pair across one mesh period: where the pair is linearised
(`solver.mbs.linearization`; the step bound, the modes and the damping conversion).

A run asks for them several times (the damping conversion, the modes, the step bound, the
method choice, the free decay's step): they are solved once per model and load and kept
(`loaded_equilibria`), keyed by what they depend on, so that a model that only differs in its
dampers (`solver.mbs.modes.with_damping`) shares them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.model import Model
from solver.store import STORE, digest

KEEP = 32           # equilibrium sets kept (a study point asks for one or two)
KEPT = STORE.shelf("loaded equilibria", KEEP)


@dataclass
class Equilibrium:
    """A loaded static equilibrium of the pair, where it is linearised."""
    theta1: float          # driver hub angle [rad]
    rim1: float            # driver rim angle (hub less the body wind-up) [rad]
    rim2: float            # driven rim angle [rad]
    phi: np.ndarray        # tooth rotations [rad]


def statics_key(model: Model, torque: float, positions: int) -> str:
    """Digest of everything a static equilibrium depends on: the model's arrays less its
    dampers (gear_par C_PHI, N_C, C_BODY; law_par C_CON, M2, M3), the load and the positions."""
    gp = model.gear_par.copy()
    gp[:, [L.C_PHI, L.N_C, L.C_BODY]] = 0.0
    lp = model.law_par.copy()
    lp[[L.C_CON, L.M2, L.M3]] = 0.0
    return digest(*(np.asarray(a, dtype=float) for a in (
        gp, model.pair_par, lp, model.k_phi, model.tooth_compliance, np.array([torque, positions], float))))


def loaded_equilibria(model: Model, torque: float, positions: int = 12) -> list[Equilibrium]:
    """Static equilibria under ``torque`` [N·m] (1 N·m if zero) at ``positions`` driver angles
    across one angular pitch, by one sweep with continuation; positions that do not converge
    are left out. Solved once per `statics_key` (the last KEEP sets are kept); the caller
    gets copies of the tooth rotations."""
    kept = KEPT.kept(statics_key(model, torque, positions), lambda: _solve(model, torque, positions))
    return [Equilibrium(e.theta1, e.rim1, e.rim2, e.phi.copy()) for e in kept]


def _solve(model: Model, torque: float, positions: int) -> list[Equilibrium]:
    from solver.mbs.statics import solve_static
    angles = np.linspace(0.0, model.geometry[0].pitch_angle, positions, endpoint=False)
    load = torque if abs(torque) > 1e-9 else 1.0
    out, phi, te0 = [], None, None
    kb1, kb2 = model.body_stiffness
    rb1, rb2 = model.base_radii
    for theta1 in angles:
        st = solve_static(model, np.array([theta1]), load, phi0=phi, te0=te0, raise_on_failure=False)
        if not st.converged[0]:
            continue
        phi, te0 = st.phi_last, float(st.te[0])
        # a coupled model's mesh sits at the rim angles: the hubs less the body wind-up
        out.append(Equilibrium(float(theta1), theta1 - load * rb1 / rb2 / kb1, float(st.theta2[0]) - load / kb2, phi.copy()))
    if not out:
        raise ValueError(f"no static equilibrium under {load} N·m found to linearise the pair")
    return out

"""Loaded static equilibria of the pair across one mesh period: where the pair is linearised
(`solver.mbs.stability` for the step bound, `solver.mbs.modes` for its modes)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.mbs.model import Model


@dataclass
class Equilibrium:
    """A loaded static equilibrium of the pair, where it is linearised."""
    theta1: float          # driver hub angle [rad]
    rim1: float            # driver rim angle (hub less the body wind-up) [rad]
    rim2: float            # driven rim angle [rad]
    phi: np.ndarray        # tooth rotations [rad]


def loaded_equilibria(model: Model, torque: float, positions: int = 12) -> list[Equilibrium]:
    """Static equilibria under ``torque`` [N·m] (1 N·m if zero) at ``positions`` driver angles
    across one angular pitch, by one sweep with continuation; positions that do not converge
    are left out."""
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

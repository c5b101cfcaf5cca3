"""Step bound of the explicit integrator: the pair linearised at static equilibrium
(`solver.mbs.linearization`: the DOFs the kernel integrates, the body modes of a coupled
model included), its natural frequencies and modal damping.

`stable_time_step` gives ``dt = safety * 2 / omega_max`` (velocity Verlet is stable for
omega*dt < 2), reduced where the modal damping of the loaded contacts asks for it
(`stability_limit`); the model is linearised at several positions across one mesh cycle
under the full load.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from solver.mbs.kernels import layout as L
from solver.mbs.linearization import at_equilibrium, linearizations, linearize
from solver.mbs.model import Model


def implicit_dampers_apply(model: Model) -> bool:
    """Whether the explicit kernels can take the tooth-root dampers implicitly (IMEX, see
    `solver.mbs.kernels.explicit`; the body-coupled kernel the same way): linear dampers
    (n_c = 1) on both gears, at least one of them nonzero."""
    gp = model.gear_par
    return bool(np.all(gp[:, L.N_C] == 1.0)) and bool(np.any(gp[:, L.C_PHI] != 0.0))


def linearized_system(model: Model, theta1: float, theta2: float, phi: np.ndarray, damping: bool = False,
                      friction: bool = False, spring_dampers: bool = True):
    """Mass and tangent stiffness over the free DOFs of `solver.mbs.linearization.linearize`
    (the body DOFs first: theta2, or r1, theta2, h2 for a body-coupled model; then the teeth
    near the mesh), about the rim angles theta1, theta2 [rad] and the tooth rotations phi.

    Returns (M, K, dof_teeth) in SI. With ``damping`` also the damping tangent at rest,
    (M, K, C, dof_teeth): body, spring and contact dampers; with ``friction``, also the flank
    friction's slope at zero sliding (the step bound wants it; a modal damping would not:
    the flanks slide but at the pitch point); without ``spring_dampers`` the tooth-root
    dampers are left out (those the explicit kicks take implicitly).
    """
    s = linearize(model, theta1, theta2, phi)
    if damping:
        return s.M, s.K, s.damping(joint=spring_dampers, friction=friction), s.teeth
    return s.M, s.K, s.teeth


def stability_limit(model: Model, torque: float, positions: int = 12,
                    implicit_dampers: bool = False, equilibria=None) -> tuple[float, float]:
    """(critical Verlet step [s], highest natural frequency [rad/s]) of the loaded pair over one
    mesh cycle.

    The pair is linearised at static equilibrium under ``torque`` [N·m] (1 N·m if zero) at
    ``positions`` driver angles across one angular pitch; the generalised eigenproblem
    K x = w² M x gives the frequencies. Each mode i, with its modal damping ratio
    zeta_i = x_i^T C x_i / (2 w_i) (mass-normalised x_i), limits the step to
    2/w_i * (sqrt(1 + zeta_i²) - zeta_i): velocity Verlet with damping forces evaluated at the
    predicted velocity is stable up to there (2/w_i undamped). Flank friction enters C with
    its slope at zero sliding (the stiffest it gets, near the pitch point). A deep, damped contact (m3 > 1)
    can make a lower but overdamped mode the limit. The equilibria come from one static sweep
    with continuation (tooth rotations carried from angle to angle); positions where it does
    not converge are left out. ``implicit_dampers``: the tooth-root dampers are taken implicitly
    (IMEX kicks, `implicit_dampers_apply`), which are stable at any damping: only the contact
    and body dampers count then. Solved once per model and arguments (`solver.mbs.memo`: a
    run asks for it in its method choice and again in `simulate`; a study's points of one body
    share it). ``equilibria``: the model's loaded equilibria under ``torque`` at ``positions``
    when already solved (`solver.mbs.equilibria.loaded_equilibria`: the same numbers).
    """
    from solver.mbs.memo import kept
    args = (float(torque), int(positions), bool(implicit_dampers))
    return kept("stability_limit", model, args, lambda: _stability_limit(model, *args, equilibria))


def _stability_limit(model: Model, torque: float, positions: int, implicit_dampers: bool,
                     equilibria=None) -> tuple[float, float]:
    wmax = 0.0
    dt_crit = math.inf
    systems = (linearizations(model, torque, positions) if equilibria is None
               else [at_equilibrium(model, eq) for eq in equilibria])
    for sy in systems:
        M, K, C = sy.M, sy.K, sy.damping(joint=not implicit_dampers, friction=True)
        lam, x = scipy.linalg.eigh(K, M)
        w = np.sqrt(np.maximum(lam, 0.0))
        h = 0.5 * np.einsum("ij,ik,kj->j", x, C, x)          # zeta_i * w_i [1/s]
        lim = 2.0 / np.maximum(np.hypot(w, h) + h, 1e-300)    # = 2/w (sqrt(1+zeta²) - zeta)
        wmax = max(wmax, float(w.max()))
        dt_crit = min(dt_crit, float(lim.min()))
    return dt_crit, wmax


def highest_frequency(model: Model, torque: float, positions: int = 12) -> float:
    """Highest natural frequency [rad/s] of the loaded pair over one mesh cycle (see
    `stability_limit`)."""
    return stability_limit(model, torque, positions)[1]


def stable_time_step(model: Model, torque: float, safety: float | None = None,
                     implicit_dampers: bool = False, equilibria=None) -> tuple[float, float]:
    """(dt [s], omega_max [rad/s]) for the explicit integrator: safety times the critical step
    of `stability_limit` (2/omega_max without damping); ``implicit_dampers`` as there.
    ``safety`` None: SAFETY, or IMEX_SAFETY with implicit dampers (see there); ``equilibria``
    as there."""
    if safety is None:
        safety = IMEX_SAFETY if implicit_dampers else SAFETY
    dt_crit, w = stability_limit(model, torque, implicit_dampers=implicit_dampers, equilibria=equilibria)
    if not w > 0:
        raise ValueError("no loaded contact found to estimate the highest natural frequency")
    return safety * dt_crit, w


# Fraction of the critical step the explicit kernel runs at by default. Every force explicit:
# half of it (the damped bound is an estimate of a damped, nonlinear system). Tooth-root
# dampers implicit: the bound is the undamped 2/omega_max of the loaded, linearised pair, and
# `load_covered` checks after the run that the contact forces reached keep the step below it.
SAFETY = 0.5
IMEX_SAFETY = 0.9


def stiffening_exponent(model: Model) -> float:
    """e [-] such that every tangent stiffness of the pair grows at most as (force ratio)^e:
    the contact tangent k*m1*delta^(m1-1) as F^((m1-1)/m1), a tooth spring's as
    T^((n_k-1)/n_k); 0 for linear laws."""
    gp, lp = model.gear_par, model.law_par
    laws = [lp[L.M1]] + [float(n) for n in gp[:, L.N_K]]
    return max([0.0] + [(n - 1.0) / n for n in laws if n > 0])


def load_covered(model: Model, torque: float, safety: float, force_max: float) -> bool:
    """Whether a step of ``safety`` times the critical step estimated under ``torque`` [N·m]
    (1 N·m if zero) stays below the critical step of a run whose largest contact force was
    ``force_max`` [N].

    The estimate's largest contact force is about |torque|/r_b2 (one pair carrying the load,
    at the positions of single contact). Where the run's forces exceed it by a ratio r, every
    tangent stiffness grows at most by r^e (`stiffening_exponent`), so by the Rayleigh quotient
    omega_max by at most r^(e/2): the step stays stable (omega*dt < 2 for the linearised pair)
    while safety * r^(e/2) < 1.
    """
    load = abs(torque) if abs(torque) > 1e-9 else 1.0
    ratio = max(1.0, force_max * model.base_radii[1] / load)
    return safety * ratio ** (0.5 * stiffening_exponent(model)) < 1.0

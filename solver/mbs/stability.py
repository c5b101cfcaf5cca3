"""Step bound of the explicit integrator: the pair linearised at static equilibrium
(`solver.mbs.linearization`: the DOFs the kernel integrates, the body modes of a coupled
model included), its natural frequencies and damping.

`stable_time_step` gives ``dt = safety * dt_crit``, the model linearised at several positions
across one mesh cycle under the full load (`stability_limit`). dt_crit is the critical step of
the scheme the kernel runs on that linear system:

* every force explicit (dampers at the predicted velocity v + dt*a): the smallest dt at which
  the amplification matrix of the step has the eigenvalue -1, ``verlet_damped_limit``; every
  tooth free in the linearisation (a run with every tooth free, or an active set grown to all
  teeth: freezing teeth only lowers the bound's frequencies, see there);
* tooth-root dampers implicit (IMEX kicks): 2/omega_max reduced by the modal damping of the
  explicit (contact, body, friction) dampers; the implicit dampers only raise the critical
  step (measured 1.0-1.9 x this bound).
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from solver.mbs.kernels import layout as L
from solver.mbs.linearization import at_equilibrium, linearize
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
    K x = w² M x gives the frequencies. Every force explicit: the critical step of the scheme
    with its dampers (`verlet_damped_limit`, every tooth free): below 2/w where the tooth-root
    dampers take the highest modes near or beyond critical (there a modal estimate
    2/w_i (sqrt(1 + zeta_i²) - zeta_i) read 1.1-2.4 x the step that runs). ``implicit_dampers``:
    the tooth-root dampers are taken implicitly (IMEX kicks, `implicit_dampers_apply`), which
    are stable at any damping: each mode i, with its modal damping ratio of the contact and
    body dampers zeta_i = x_i^T C x_i / (2 w_i) (mass-normalised x_i), limits the step to
    2/w_i (sqrt(1 + zeta_i²) - zeta_i) (2/w_i undamped). Flank friction enters C with its
    slope at zero sliding (the stiffest it gets, near the pitch point). The equilibria come
    from one static sweep with continuation (tooth rotations carried from angle to angle);
    positions where it does not converge are left out. Solved once per model and arguments
    (`solver.mbs.memo`: a run asks for it in its method choice and again in `simulate`; a
    study's points of one body share it). ``equilibria``: the model's loaded equilibria under
    ``torque`` at ``positions`` when already solved
    (`solver.mbs.equilibria.loaded_equilibria`: the same numbers).
    """
    from solver.mbs.memo import kept
    args = (float(torque), int(positions), bool(implicit_dampers))
    return kept("stability_limit", model, args, lambda: _stability_limit(model, *args, equilibria))


def _stability_limit(model: Model, torque: float, positions: int, implicit_dampers: bool,
                     equilibria=None) -> tuple[float, float]:
    from solver.mbs.equilibria import loaded_equilibria
    wmax = 0.0
    dt_crit = math.inf
    for eq in loaded_equilibria(model, torque, positions) if equilibria is None else equilibria:
        if implicit_dampers:
            sy = at_equilibrium(model, eq)
            M, K, C = sy.M, sy.K, sy.damping(joint=False, friction=True)
            lam, x = scipy.linalg.eigh(K, M)
            w = np.sqrt(np.maximum(lam, 0.0))
            h = 0.5 * np.einsum("ij,ik,kj->j", x, C, x)          # zeta_i * w_i [1/s]
            lim = float((2.0 / np.maximum(np.hypot(w, h) + h, 1e-300)).min())   # = 2/w (sqrt(1+zeta²) - zeta)
        else:
            sy = linearize(model, eq.rim1, eq.rim2, eq.phi, all_teeth=True)
            M, K = sy.M, sy.K
            w = np.sqrt(np.maximum(scipy.linalg.eigh(K, M, eigvals_only=True), 0.0))
            lim = verlet_damped_limit(M, K, sy.damping(friction=True))
        wmax = max(wmax, float(w.max()))
        dt_crit = min(dt_crit, lim)
    return dt_crit, wmax


def verlet_damped_limit(M: np.ndarray, K: np.ndarray, C: np.ndarray) -> float:
    """Critical step [s] of velocity Verlet with every damper at the predicted velocity
    v + dt*a (the all-explicit kernels) on M x'' + C x' + K x = 0 (SI; M positive definite,
    K and C symmetric positive semidefinite).

    A solution that flips sign each step (x, v, a) -> -(x, v, a) needs v = 0, a = -4x/dt² and
    (dt² K + 4 dt C - 4 M) x = 0: with mu = 1/dt, the quadratic eigenproblem
    (4 mu² M - 4 mu C - K) x = 0. It is hyperbolic (its discriminant 16 (x'Cx)² + 16 x'Mx x'Kx
    is positive), so its eigenvalues are real and the largest is the largest of
    p(x) = (x'Cx + sqrt((x'Cx)² + x'Mx x'Kx)) / (2 x'Mx) over all x: the critical step is
    1/mu_max, for one DOF 2/w (sqrt(1 + 4 zeta²) - 2 zeta) (half of the undamped 2/w for an
    overdamped mode: 1/(2 zeta w)). As a maximum over x, it can only grow when DOFs are added
    (free teeth) and only shrink when they are held (frozen teeth). Checked against the
    spectral radius of the step's amplification matrix on the paper and small pairs, both
    models: the step turns unstable at 1/mu_max to 1e-9, with no other eigenvalue leaving
    the unit circle first (`tests/solver/mbs/test_step_bound_models.py`).
    """
    n = M.shape[0]
    Mi = np.linalg.inv(M)
    # the linearisation y = mu x: mu (x, y) = (y, M^-1 (K x / 4 + C y))
    A = np.block([[np.zeros((n, n)), np.eye(n)], [0.25 * Mi @ K, Mi @ C]])
    mu = float(np.linalg.eigvals(A).real.max())
    return 1.0 / mu if mu > 0 else math.inf


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


def pair_frequency_estimate(model: Model, torque: float) -> float:
    """Highest natural frequency [rad/s] of the loaded plain pair estimated from its laws alone,
    with no static equilibrium and nothing compiled: one tooth pair carrying the whole load
    ``torque`` [N·m] (1 N·m if zero) at the pitch point, each tooth on its stiffest root
    spring (tangent n_k T/phi at the moment it carries) about its pivot, the contact's tangent
    m1 F/delta between them, the hubs held (hundreds of times the teeth's inertia). The normal
    force acts on a tooth with the lever r_b - r_pv cos(alpha) about its pivot (the pitch
    point's line of action, the pivot on the tooth's centre line). The top mode of the
    linearised pair is this pair's: within 5 % of `stability_limit`'s (the tooth-root dampers
    implicit, as the runs step) on the shipped pairs and their stiff variants (contact, springs, load, law exponents, pressure angle;
    `tests/solver/mbs/test_stability_estimate.py`), a little below it. For the plain model
    only (``model.coupled`` and coupled teeth: ValueError)."""
    if model.coupled or model.teeth_coupled:
        raise ValueError("pair_frequency_estimate: the plain model only (no body coupling, no tooth compliance)")
    gp, lp = model.gear_par, model.law_par
    load = abs(torque) if abs(torque) > 1e-9 else 1.0
    force = load / model.geometry[1].base_radius                  # N, along the line of action
    m1 = float(lp[L.M1])
    delta = (force / lp[L.K_CON]) ** (1.0 / m1)                    # m
    k_con = m1 * force / delta                                     # contact tangent [N/m]
    z1 = model.geometry[0].teeth
    lever, k_tooth = np.zeros(2), np.zeros(2)
    for g, geo in enumerate(model.geometry):
        lever[g] = max(geo.base_radius - gp[g, L.R_PV] * math.cos(geo.spec.pressure_angle), 0.25 * geo.spec.module)
        k_phi = float(np.max(model.k_phi[:z1] if g == 0 else model.k_phi[z1:]))     # N·m/rad^n_k
        n_k, moment = float(gp[g, L.N_K]), force * lever[g]
        k_tooth[g] = n_k * moment / (moment / k_phi) ** (1.0 / n_k)                # N·m/rad
    K = np.diag(k_tooth) + k_con * np.outer(lever, lever)
    I_P = gp[:, L.I_P]
    return float(math.sqrt(scipy.linalg.eigh(K, np.diag(I_P), eigvals_only=True).max()))

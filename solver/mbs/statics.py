"""Static transmission error: equilibrium at each driver angle (no inertia, no time).

`solve_static` runs Newton with continuation over a sequence of driver angles (kernel in
`kernels/statics.py`). Angles are driver hub rotations [rad] from the nominal position.

Body-torsion coupling (``Model.coupled``): the teeth sit on a rigid rim joined to the hub by
the body spring k_body. In statics the spring carries the whole gear torque (T on gear 2,
T*rb1/rb2 on the driver under flank contact), so the rims stand at the hub angles less the
constant wind-ups: the kernel solves the mesh in rim angles and the hubs' TE adds
rb1*M1/k_body1 + rb2*T/k_body2. Teeth coupled through the body (``Model.teeth_coupled``,
the compliance model) take their spring moments from the compliance matrix of the teeth
near the mesh (`kernels.toothcoupling`).

Flank friction (``ContactLaw.mu`` > 0): the equilibrium of a pair whose driver turns in its
positive sense at ``friction_speed`` [rad/s] (the friction's direction and regularisation are
those of the rigid rolling kinematics at that speed; the contact damping is left out, as it
sees no motion in statics). The driver's torque (`driver_torque`) then exceeds the output's
rb1/rb2 share by the friction loss.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.mbs import interrupt
from solver.mbs.kernels import layout as L
from solver.mbs.kernels.gearmesh import contact_parts
from solver.mbs.kernels.statics import static_sweep, static_work
from solver.mbs.model import Model

# Largest elastic approach of the flanks along the line of action at an equilibrium, as a
# fraction of the module: beyond it the pseudo-rigid teeth are bent by a sizeable part of
# their height and a Newton "equilibrium" is no result (the scene check
# `study.plausibility.check_loads` refuses such loads up front with the same fraction).
DEFLECTION_FRACTION = 0.2


class StaticSolveError(RuntimeError):
    """Newton failed to reach equilibrium at some angles, or reached one beyond the deflection bound."""


@dataclass
class StaticResult:
    angle: np.ndarray          # driver rotation [rad]
    te: np.ndarray             # transmission error [m]
    theta2: np.ndarray         # driven hub angle [rad]
    n_contacts: np.ndarray     # loaded contacts [-]
    tooth_force: np.ndarray    # (angle, gear-1 tooth) normal force [N]
    iterations: np.ndarray     # Newton iterations (negative: not converged)
    torque: float              # resisting torque [N·m]
    phi_last: np.ndarray       # tooth rotations at the last angle [rad] (Z1 + Z2)
    message: str = "ok"        # why angles count as not converged ("ok": all converged)
    driver_torque: np.ndarray | None = None    # torque the driver applies [N·m] (None: not computed)

    @property
    def converged(self) -> np.ndarray:
        return self.iterations > 0


@dataclass(frozen=True)
class StaticSolver:
    """Newton with continuation over driver angles, and its settings; `run` finds the loaded
    equilibria of a model.

    ``tol`` is relative to the torque (residual torques below tol*|torque| count as converged);
    ``max_iter`` Newton iterations an angle. ``raise_on_failure``: an angle not converged raises
    `StaticSolveError` (else the result says so). ``friction_speed`` [rad/s]: the driver speed
    whose rigid kinematics set the sliding speed of the flank friction (unused without
    friction).
    """
    tol: float = 1e-10
    max_iter: int = 60
    raise_on_failure: bool = True
    friction_speed: float = 1.0

    def run(self, model: Model, angles, torque: float, phi0: np.ndarray | None = None,
            te0: float | None = None) -> StaticResult:
        """Equilibrium under ``torque`` [N·m] on gear 2 at driver angles ``angles`` [rad], from
        the tooth rotations ``phi0`` [rad] and the TE ``te0`` [m] (None: unloaded teeth, and the
        backlash offset on the loaded flank)."""
        return _solve(self, model, angles, torque, phi0, te0)


def solve_static(model: Model, angles, torque: float, phi0: np.ndarray | None = None, te0: float | None = None,
                 **settings) -> StaticResult:
    """The static solver in one call: ``StaticSolver(**settings).run(model, angles, torque,
    phi0, te0)``."""
    return StaticSolver(**settings).run(model, angles, torque, phi0, te0)


def sweep_arguments(model: Model, angles: np.ndarray, torque: float, theta2: float, tol: float = StaticSolver.tol,
                    max_iter: int = StaticSolver.max_iter, friction_speed: float = StaticSolver.friction_speed,
                    phi: np.ndarray | None = None) -> tuple:
    """The arguments of `kernels.statics.static_sweep` for ``model`` at the rim angles
    ``angles`` [rad] under ``torque`` [N·m], from the driven rim angle ``theta2`` [rad] and the
    tooth rotations ``phi`` [rad] (None: zeros; changed in place by the sweep): (mdl, ctooth,
    ctl, angles, phi, out, f1, sw). What a model's static sweep is compiled for (the
    `layout.ContactParts` variant, a coupled set or None) is in their types, which
    `study.stand_in` reads without running the sweep."""
    n = angles.size
    # teeth coupled through the bodies: their springs act through the compliance matrix alone
    kphi = np.zeros_like(model.k_phi) if model.teeth_coupled else model.k_phi
    ctooth = model.tooth_compliance if model.teeth_coupled else None    # None: the plain kernel
    lp, w1 = model.law_par, 0.0
    if lp[L.MU] > 0:
        if not friction_speed > 0:
            raise ValueError(f"friction_speed: the driver speed of the friction's kinematics must be positive, got {friction_speed}")
        lp, w1 = lp.copy(), float(friction_speed)
        lp[L.C_CON] = 0.0
    mdl = (model.gear_par, model.pair_par, lp, kphi, contact_parts(model.gear_par, model.pair_par, lp))
    ctl = (np.array([float(torque), theta2, tol, w1, 0.0]), np.array([max_iter], dtype=np.int64))
    phi = np.zeros(model.n_teeth) if phi is None else phi
    sw = static_work(model.n_teeth, ctooth is not None)
    return mdl, ctooth, ctl, angles, phi, np.zeros((n, L.N_S_OUT)), np.zeros((n, model.teeth[0])), sw


def _solve(settings: StaticSolver, model: Model, angles, torque: float, phi0, te0) -> StaticResult:
    """`StaticSolver.run`."""
    tol, max_iter = settings.tol, settings.max_iter
    raise_on_failure, friction_speed = settings.raise_on_failure, settings.friction_speed
    angles = np.ascontiguousarray(angles, dtype=float)
    if angles.ndim != 1 or angles.size == 0:
        raise ValueError("angles: need a non-empty 1-D array of driver angles")
    n = angles.size
    phi = np.zeros(model.n_teeth) if phi0 is None else np.array(phi0, dtype=float)
    sgn = 1.0 if torque >= 0 else -1.0
    te_start = sgn * model.backlash_offset if te0 is None else te0
    theta2 = float(model.theta2_for_te(angles[0], te_start))
    kb1, kb2 = model.body_stiffness
    rb1, rb2 = model.base_radii
    windup1 = torque * rb1 / rb2 / kb1          # driver rim lags its hub [rad]
    windup2 = torque / kb2                      # driven hub lags its rim [rad]
    rim_angles = angles - windup1 if model.coupled else angles
    if model.coupled:
        theta2 -= windup2
    args = sweep_arguments(model, rim_angles, torque, theta2, tol, max_iter, friction_speed, phi)
    ctl, out, f1 = args[2], args[5], args[6]
    # stoppable by Ctrl-C / SIGTERM before the next angle (KeyboardInterrupt raised here)
    interrupt.call(static_sweep, args, ctl[0], L.S_ABORT)
    te, th2 = out[:, L.S_TE].copy(), out[:, L.S_TH2].copy()
    nc, it = out[:, L.S_NC].astype(np.int64), out[:, L.S_ITER].astype(np.int64)
    if model.coupled:
        th2 += windup2
        te[:] = rb1 * angles + rb2 * th2
    # an equilibrium whose flanks approach beyond the bound is no result: not converged
    bound = DEFLECTION_FRACTION * min(g.spec.module for g in model.geometry)
    approach = np.abs(te - sgn * model.backlash_offset)
    deep = (it > 0) & ~(approach <= bound)
    it[deep] = -it[deep]
    bad = np.flatnonzero(it < 0)
    res = StaticResult(angles, te, th2, nc, f1, it, float(torque), phi, driver_torque=out[:, L.S_T1].copy())
    if bad.size:
        res.message = f"static equilibrium not reached at {bad.size} of {n} angles, first at {np.degrees(angles[bad[0]]):.3f} deg"
        if deep.any():
            res.message += (f"; at {int(deep.sum())} of them the flanks approach by up to {np.nanmax(approach[deep]) * 1e3:.3g} mm, "
                            f"beyond {DEFLECTION_FRACTION:g} x module = {bound * 1e3:.3g} mm (teeth bent out of the model's range)")
        if raise_on_failure:
            raise StaticSolveError(res.message)
    return res

"""Implicit time integration (HHT-alpha, Newton on the analytic tangent).

`ImplicitIntegrator` (`simulate_implicit` in one call) has the settings and the `DynamicResult`
contract of `solver.mbs.dynamics.ExplicitIntegrator`, plus the HHT parameter alpha (0:
trapezoidal rule, no numerical damping; down to -1/3: more damping of the high frequencies)
and the Newton controls. Its
result also carries the Newton counts and the numerical dissipation of the scheme.
The choice between this integrator and the explicit one is `solver.mbs.method.choose_method`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.mbs.dynamics import (
    ENERGY_TOL,
    Drive,
    DynamicResult,
    accuracy_check,
    check_positive,
    contact_records,
    result_fields,
    run_kernel,
    run_loads,
    status_message,
    step_grid,
)
from solver.mbs.kernels import layout as L
from solver.mbs.kernels.implicit import hht
from solver.mbs.model import Model
from solver.mbs.stability import stable_time_step


@dataclass
class ImplicitResult(DynamicResult):
    """`DynamicResult` of the HHT-alpha integrator plus its Newton counts.

    ``newton_max``: most Newton iterations in one step of each output interval [-];
    ``newton_total``: Newton iterations over the run [-].
    """
    alpha: float = 0.0
    newton_max: np.ndarray | None = None
    newton_total: int = 0

    @property
    def numerical_dissipation(self) -> np.ndarray:
        """Energy removed by the scheme itself [J]: work - (kinetic + potential - initial)
        - dissipated. Zero to O(dt^2) for alpha = 0; positive for alpha < 0."""
        return self.energy_error


@dataclass(frozen=True)
class ImplicitIntegrator:
    """The HHT-alpha integrator and its settings; `run` integrates a model under a `Drive`
    (loads, outputs and guards as `solver.mbs.dynamics.ExplicitIntegrator`).

    ``dt`` [s] defaults to four times the explicit stability step; it is rounded down so that
    output_step [s] is a whole number of steps (then the end of a ramp that is a multiple of
    output_step falls on a step boundary). ``alpha`` in [-1/3, 0]. ``newton_tol`` [m]: Newton
    stops when its last correction moves no flank point by more than this; ``max_iter``
    Newton iterations per step before the run stops with "Newton failure".
    ``all_teeth``: integrate every tooth from the start and never freeze one (the model of
    the scipy peer `solver.peers.scipy_dynamics`, for like-for-like error figures).
    """
    dt: float | None = None
    output_step: float = 1e-5
    alpha: float = 0.0
    newton_tol: float = 1e-13
    max_iter: int = 12
    delta_max: float | None = None
    raise_on_failure: bool = False
    phi_quiet: float = 1e-9
    energy_tol: float = ENERGY_TOL
    all_teeth: bool = False

    def run(self, model: Model, drive: Drive, progress=None) -> ImplicitResult:
        """Integrate ``model`` from rest under ``drive``. ``progress``: a callable taking the
        time reached [s] while the run goes (`run_kernel`)."""
        return _run_implicit(self, model, drive, progress)


def simulate_implicit(model: Model, speed: float, speed_ramp: float, torque: float, torque_ramp: float,
                      duration: float, *, progress=None, **settings) -> ImplicitResult:
    """The implicit integrator in one call: ``ImplicitIntegrator(**settings).run(model,
    Drive(speed, speed_ramp, torque, torque_ramp, duration, load_table), progress)``, with
    ``load_table`` taken from ``settings``."""
    drive = Drive(speed, speed_ramp, torque, torque_ramp, duration, settings.pop("load_table", None))
    return ImplicitIntegrator(**settings).run(model, drive, progress)


def _run_implicit(settings: ImplicitIntegrator, model: Model, drive: Drive, progress) -> ImplicitResult:
    """`ImplicitIntegrator.run`."""
    speed, speed_ramp, torque, torque_ramp = drive.speed, drive.speed_ramp, drive.torque, drive.torque_ramp
    duration, load_table = drive.duration, drive.load_table
    dt, output_step, alpha, newton_tol, max_iter = (settings.dt, settings.output_step, settings.alpha,
                                                    settings.newton_tol, settings.max_iter)
    delta_max, raise_on_failure, phi_quiet = settings.delta_max, settings.raise_on_failure, settings.phi_quiet
    energy_tol, all_teeth = settings.energy_tol, settings.all_teeth
    check_positive(duration=duration, speed_ramp=speed_ramp, torque_ramp=torque_ramp, output_step=output_step,
                   newton_tol=newton_tol)
    if not -1.0 / 3.0 <= alpha <= 0.0:
        raise ValueError(f"alpha: must lie in [-1/3, 0] (HHT), got {alpha}")
    if model.coupled:
        raise ValueError("dynamic.method: the implicit integrator has no body-torsion coupling "
                         "(coupling.model); use the explicit integrator for a coupled model")
    if max_iter < 1:
        raise ValueError(f"max_iter: must be at least 1, got {max_iter}")
    table, torque, side = run_loads(load_table, torque)
    omega_max = float("nan")
    if dt is None or dt <= 0:
        dt, omega_max = stable_time_step(model, torque)
        dt *= 4.0
    grid = step_grid(dt, output_step, duration)
    if delta_max is None:
        delta_max = 0.1 * model.geometry[0].spec.module
    par = dict(DELTA_MAX=float(delta_max), PHI_QUIET=phi_quiet, ENERGY_TOL=float(energy_tol), HHT_ALPHA=float(alpha),
               NEWTON_TOL=float(newton_tol), MAX_ITER=int(max_iter))
    (status, step, max_act, total), out = run_kernel(hht, model, (float(speed), float(speed_ramp), float(torque),
                                                     float(torque_ramp), table, side), grid, par, all_teeth,
                                                     progress)
    msg = status_message(status, step, grid[0], delta_max, raise_on_failure)
    res = ImplicitResult(*result_fields(out), grid[0], int(step), int(status), msg, omega_max, int(max_act),
                         alpha=float(alpha), newton_max=out[:, L.O_NEWTON].astype(np.int64), newton_total=int(total))
    res.contacts = contact_records(out)
    return accuracy_check(res, alpha)

"""What the work-precision study runs (`study.verify.precision`): the shortened cases of a
scene, the solver ladders on them (one `Spec` per solver setting) and their references.

Dynamic case (DTE over a window of a few ms, SI units): velocity Verlet at fractions of its
stability step, HHT-alpha at multiples of it, the scipy stiff solvers at several relative
tolerances, every one on the scipy peer's equations (every tooth free); plus ``explicit,
active set`` (every force explicit, quiet threshold 1e-9 rad: the production path before the
implicit tooth-root dampers), and where the scene's tooth-root dampers are linear ``explicit,
implicit dampers`` (every tooth free, IMEX kicks, at fractions of their stability step) and
``explicit, production`` (`simulate` with its defaults: IMEX kicks, its own step and active set). Reference: DOP853 at rtol 1e-10; cross-check: Verlet at
1/32 of the stability step.

Quasi-static case (STE over a rotation of the driver): the static Newton solver at several
tolerances and the slow-ramp transient with both integrators. Reference: static Newton at
tol 1e-13; cross-check: `scipy.optimize.root` on the plain-Python forces.

A body-coupled model (``Model.coupled``: the default compliance model, or body-torsion) has
neither the implicit integrator nor the scipy peer: its ladders are the explicit ones (all
forces explicit, implicit tooth-root dampers, the production path) and the static Newton
solver; its dynamic reference is all-explicit Verlet at 1/32 of its stability step (every
tooth free), cross-checked by the same at 1/16 (three times the reference's error), and its
static cross-check is Newton at tol 1e-13 over the angles taken in reverse order (every
angle started from another solution). Its slow-ramp transient runs at fractions of the
production step (implicit dampers), the all-explicit step being about 20x smaller.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver import units
from solver.mbs.dynamics import at_driver_angles, simulate, slow_ramp_window, step_grid
from solver.mbs.implicit import simulate_implicit
from solver.mbs.model import Model
from solver.mbs.stability import implicit_dampers_apply, stable_time_step
from solver.mbs.statics import solve_static
from solver.peers.scipy_dynamics import simulate_explicit_all_teeth, simulate_scipy
from solver.peers.scipy_statics import solve_static_scipy
from study.scene import Scene


@dataclass(frozen=True)
class Spec:
    """One run of the study: method name, step [s] (fixed-step) or rtol [-] (adaptive), and
    the callable returning (TE [m] on the output grid, steps, status, message)."""
    method: str
    step: float
    rtol: float
    run: object
    warmup: bool = True      # False: nothing to compile (the scipy peer), no warm-up run



def fixed_step_specs(method: str, steps, run) -> list[Spec]:
    """One `Spec` of a fixed-step method per time step [s] of ``steps``; ``run(dt)`` returns
    (TE [m] on the output grid, steps, status, message)."""
    return [Spec(method, dt, math.nan, lambda dt=dt: run(dt)) for dt in steps]


def _dyn(res) -> tuple:
    """(TE [m], steps, status, message) of a dynamic run's result."""
    return res.te, res.steps, res.status, res.message


# ------------------------------------------------------------------ dynamic scene

@dataclass(frozen=True)
class DynamicCase:
    """Loads of the shortened dynamic window (SI): the paper's 0 -> speed and 0 -> torque
    ramps, scaled to end at ``ramp`` [s], over ``duration`` [s], TE sampled every
    ``output_step`` [s]."""
    speed: float
    torque: float
    ramp: float
    duration: float
    output_step: float

    @property
    def loads(self) -> tuple:
        return self.speed, self.ramp, self.torque, self.ramp, self.duration


def dynamic_case(scene: Scene, duration: float = 0.002, ramp_fraction: float = 0.5,
                 output_step: float = 1e-5) -> DynamicCase:
    """The scene's dynamic loads over a window of ``duration`` [s], the ramps ending at
    ``ramp_fraction`` of it (the paper's 10 ms ramp of a 0.2 s run, scaled down)."""
    if not duration > 0:
        raise ValueError(f"duration: must be positive, got {duration}")
    if not 0 < ramp_fraction <= 1:
        raise ValueError(f"ramp_fraction: must lie in (0, 1], got {ramp_fraction}")
    d = scene.dynamic
    ramp = round(duration * ramp_fraction / output_step) * output_step
    return DynamicCase(d.speed, d.torque, ramp, duration, output_step)


@dataclass(frozen=True)
class ScipyRuns:
    """The scipy runs of the dynamic study: each of ``methods`` at each of ``rtols``; a run
    taking longer than ``max_wall_time`` [s] stops and stays in the study as a failed run with
    its message."""
    methods: tuple = ("Radau", "LSODA")
    rtols: tuple = (1e-3, 1e-5)
    max_wall_time: float = 120.0


def dynamic_specs(model: Model, case: DynamicCase, explicit_fractions=(1, 2, 4, 8),
                  implicit_multiples=(8, 4, 2, 1, 0.5), alphas=(0.0, -0.1), active_set: bool = True,
                  scipy: ScipyRuns = ScipyRuns()) -> tuple[list[Spec], float]:
    """The runs of the dynamic study and the explicit stability step [s] they are scaled by:
    the explicit runs at the stability step over ``explicit_fractions`` (the active set too with
    ``active_set``), the implicit ones at ``implicit_multiples`` of it for each HHT alpha of
    ``alphas``, and the ``scipy`` runs."""
    dt_b, _w = stable_time_step(model, case.torque)
    L, o = case.loads, case.output_step
    if model.coupled:       # the implicit integrator and the scipy peer are the plain model's
        alphas, scipy = (), ScipyRuns(methods=())
    explicit_steps = [dt_b / f for f in explicit_fractions]
    specs = fixed_step_specs("explicit", explicit_steps,
                             lambda dt: _dyn(simulate_explicit_all_teeth(model, *L, dt=dt, output_step=o)))
    if active_set:
        specs += fixed_step_specs("explicit, active set", explicit_steps,
                                  lambda dt: _dyn(simulate(model, *L, dt=dt, output_step=o, phi_quiet=1e-9,
                                                           implicit_dampers=False)))
    if implicit_dampers_apply(model):
        dt_i, _w = stable_time_step(model, case.torque, implicit_dampers=True)
        specs += fixed_step_specs("explicit, implicit dampers", [dt_i / f for f in explicit_fractions],
                                  lambda dt: _dyn(simulate_explicit_all_teeth(model, *L, dt=dt, output_step=o,
                                                                              implicit_dampers=True)))
        if active_set:
            specs.append(Spec("explicit, production", step_grid(dt_i, o, case.duration)[0], math.nan,
                              lambda: _dyn(simulate(model, *L, output_step=o))))
    for a in alphas:
        specs += fixed_step_specs(f"implicit alpha={a:g}", [min(dt_b * k, o) for k in implicit_multiples],
                                  lambda dt, a=a: _dyn(simulate_implicit(model, *L, dt=dt, output_step=o,
                                                                         alpha=a, all_teeth=True)))
    for m in scipy.methods:
        for tol in scipy.rtols:
            specs.append(Spec(m, math.nan, tol,
                              lambda m=m, tol=tol: _dyn(simulate_scipy(model, *L, method=m, rtol=tol, output_step=o,
                                                                       max_wall_time=scipy.max_wall_time)),
                              warmup=False))
    return specs, dt_b


def dynamic_reference(model: Model, case: DynamicCase, dt_bound: float):
    """(reference TE [m], cross-check TE [m], names): DOP853 at rtol 1e-10 and Verlet at
    dt_bound/32 [s], both with every tooth free; a body-coupled model `coupled_reference`."""
    if model.coupled:
        return coupled_reference(model, case, dt_bound)
    ref = simulate_scipy(model, *case.loads, method="DOP853", rtol=1e-10, output_step=case.output_step)
    chk = simulate_explicit_all_teeth(model, *case.loads, dt=dt_bound / 32, output_step=case.output_step)
    for r, name in ((ref, "DOP853 reference"), (chk, "explicit cross-check")):
        if r.status:
            raise RuntimeError(f"{name} failed: {r.message}")
    return ref.te, chk.te, ("scipy DOP853, rtol 1e-10, every tooth free",
                            f"explicit Verlet at dt = {dt_bound / 32 * 1e9:.4g} ns (1/32 of the stability step), every tooth free")


def coupled_reference(model: Model, case: DynamicCase, dt_bound: float):
    """(reference TE [m], cross-check TE [m], names) of a body-coupled model, which has no scipy
    peer: all-explicit Verlet at dt_bound/32 and at dt_bound/16 [s], every tooth free. The
    scheme being second order, their difference is three times the reference's own error.
    (That the ladders converge to it at second order, the implicit-damper scheme's included,
    shows it is the answer of the equations, not of one scheme.)"""
    ref = simulate_explicit_all_teeth(model, *case.loads, dt=dt_bound / 32, output_step=case.output_step)
    chk = simulate_explicit_all_teeth(model, *case.loads, dt=dt_bound / 16, output_step=case.output_step)
    for r, name in ((ref, "explicit reference"), (chk, "explicit cross-check")):
        if r.status:
            raise RuntimeError(f"{name} failed: {r.message}")
    return ref.te, chk.te, tuple(f"explicit Verlet at dt = {dt_bound / k * 1e9:.4g} ns (1/{k} of the stability step), "
                                 "every tooth free" for k in (32, 16))


# ------------------------------------------------------------------ quasi-static scene

@dataclass(frozen=True)
class StaticCase:
    """The quasi-static analysis over ``rotation`` [rad] of the driver at ``angle_step`` [rad]:
    torque [N·m], and the slow-ramp transient's speed [rad/s] and ramp time [s]."""
    torque: float
    rotation: float
    angle_step: float
    speed: float
    ramp: float

    @property
    def angles(self) -> np.ndarray:
        n = int(math.floor(self.rotation / self.angle_step + 1e-9)) + 1
        return np.arange(n) * self.angle_step


def static_case(scene: Scene, rotation_deg: float = 6.0) -> StaticCase:
    """The scene's quasi-static analysis over ``rotation_deg`` [deg] (one mesh cycle is
    360/Z1 deg) instead of the scene's rotation."""
    qs = scene.quasi_static
    if not rotation_deg > 0:
        raise ValueError(f"rotation_deg: must be positive, got {rotation_deg}")
    return StaticCase(qs.torque, rotation_deg * units.DEG, qs.angle_step * units.DEG, qs.speed, qs.ramp_time)


def _transient_te(res, case: StaticCase) -> np.ndarray:
    """Transient TE [m] interpolated at the case's driver angles (NaN past the run's end)."""
    return at_driver_angles(res, case.speed, case.ramp, case.angles)[0]


def static_specs(model: Model, case: StaticCase, tols=(1e-2, 1e-4, 1e-6, 1e-8),
                 explicit_fractions=(1, 2, 4), implicit_multiples=(256, 64, 16, 4),
                 alphas=(0.0, -0.1)) -> tuple[list[Spec], float]:
    """The runs of the quasi-static study (static Newton at ``tols``, the slow-ramp transient
    explicit at fractions and implicit at multiples of the stability step) and that step [s]
    (a body-coupled model: no implicit runs, the step of its production integrator)."""
    angles = case.angles
    specs = []
    for tol in tols:
        def run(tol=tol):
            r = solve_static(model, angles, case.torque, tol=tol, raise_on_failure=False)
            bad = int(np.sum(r.iterations < 0))
            return r.te, int(np.sum(np.abs(r.iterations))), int(bad > 0), f"not converged at {bad} angles" if bad else "ok"
        specs.append(Spec("static Newton", math.nan, tol, run))
    if model.coupled:       # no implicit integrator; the transient at the production step
        alphas = ()
        dt_b, _w = stable_time_step(model, case.torque, implicit_dampers=implicit_dampers_apply(model))
    else:
        dt_b, _w = stable_time_step(model, case.torque)
    dt_out, t_end = slow_ramp_window(angles, case.angle_step, case.speed, case.ramp)
    L = (case.speed, case.ramp, case.torque, case.ramp, t_end)

    def transient(res):
        return _transient_te(res, case), res.steps, res.status, res.message
    specs += fixed_step_specs("slow-ramp transient, explicit", [dt_b / f for f in explicit_fractions],
                              lambda dt: transient(simulate(model, *L, dt=dt, output_step=dt_out)))
    for a in alphas:
        specs += fixed_step_specs(f"slow-ramp transient, implicit alpha={a:g}",
                                  [min(dt_b * k, dt_out) for k in implicit_multiples],
                                  lambda dt, a=a: transient(simulate_implicit(model, *L, dt=dt, output_step=dt_out,
                                                                              alpha=a)))
    return specs, dt_b


def static_reference(model: Model, case: StaticCase):
    """(reference TE [m], cross-check TE [m], names): static Newton at tol 1e-13 and
    `scipy.optimize.root` on the plain-Python forces (a body-coupled model, which the scipy
    peer lacks: Newton at tol 1e-13 over the angles in reverse order)."""
    ref = solve_static(model, case.angles, case.torque, tol=1e-13)
    if model.coupled:
        chk = solve_static(model, case.angles[::-1].copy(), case.torque, tol=1e-13).te[::-1]
        return ref.te, chk, ("static Newton (numba), tol 1e-13",
                             "static Newton (numba), tol 1e-13, the angles in reverse order (each started from "
                             "another solution)")
    chk = solve_static_scipy(model, case.angles, case.torque)
    return ref.te, chk, ("static Newton (numba), tol 1e-13",
                         "scipy.optimize.root (MINPACK hybrd) on the plain-Python forces, xtol 1e-13")

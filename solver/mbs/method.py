"""The choice of time integrator and step for a dynamic run: `choose_method` picks the
explicit (`solver.mbs.dynamics.simulate`) or the implicit integrator
(`solver.mbs.implicit.simulate_implicit`) and the step [s] from the loaded pair's highest
natural frequency: explicit at its stability step when that step is affordable, implicit
otherwise.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from solver.mbs.model import Model
from solver.mbs.stability import implicit_dampers_apply, stable_time_step


@dataclass(frozen=True)
class MethodChoice:
    """Integrator and step for a dynamic run, and why."""
    method: str          # 'explicit' or 'implicit'
    dt: float            # s
    omega_max: float     # highest natural frequency of the loaded pair [rad/s]
    reason: str
    estimated: bool = False     # explicit at the estimated stability step: `simulate` may check it


@dataclass(frozen=True)
class MethodLimits:
    """What `choose_method` weighs: the most explicit steps a run may take before 'auto' goes
    implicit (``max_explicit_steps``), the implicit step as a multiple of the explicit bound
    (``implicit_factor``), and the fraction of the stability bound (``safety``; None: the
    default of `solver.mbs.stability`)."""
    max_explicit_steps: float = math.inf
    implicit_factor: float = 4.0
    safety: float | None = None


def choose_method(model: Model, torque: float, duration: float, method: str = "auto",
                  dt: float | None = None, alpha: float = 0.0, limits: MethodLimits = MethodLimits(),
                  equilibria=None) -> MethodChoice:
    """Method and step [s] for a run of ``duration`` [s] under ``torque`` [N·m] (``alpha``, the
    HHT parameter of an implicit run, does not change its step).

    'explicit' and 'implicit' are kept; a given ``dt`` [s] > 0 is kept. 'auto' computes the
    explicit stability step safety*2/omega_max and takes explicit when duration/step is at
    most ``max_explicit_steps``, implicit at ``implicit_factor`` times that step otherwise.
    The default bound is none, so 'auto' takes explicit: a step of HHT costs about 20 steps of
    Verlet (Newton on the tangent; 68 us against 3.5 us on the paper pair), so at 4 x the step
    the implicit run is about 5 x slower per simulated second, and with a stiff penalty
    contact (k_con x 1000) the trapezoidal rule at 4 x the explicit step gains energy at the
    contact events and is stopped by the guard, while Verlet at its stability step completes.
    The run-time bound of a long explicit run is `study.estimate` (``--max-time``).
    The explicit step takes the tooth-root dampers implicitly where `simulate` does
    (`solver.mbs.stability.implicit_dampers_apply`; ``safety`` None: that default); the
    implicit step is a multiple of the all-explicit bound (safety 0.5 by default), as before.
    ``equilibria``: the model's loaded equilibria under ``torque`` when already solved
    (`solver.mbs.equilibria.loaded_equilibria`; the step bound linearises there).
    """
    max_explicit_steps, implicit_factor, safety = limits.max_explicit_steps, limits.implicit_factor, limits.safety
    if method not in ("explicit", "implicit", "auto"):
        raise ValueError(f"method: must be 'explicit', 'implicit' or 'auto', got {method!r}")
    given = dt is not None and dt > 0
    if method != "auto" and given:
        return MethodChoice(method, float(dt), float("nan"), "method and step given")
    if method == "implicit":
        dt_stable, w = stable_time_step(model, torque, safety, equilibria=equilibria)
        return MethodChoice("implicit", implicit_factor * dt_stable, w,
                            f"implicit at {implicit_factor:g} x the explicit stability step")
    imex = implicit_dampers_apply(model)
    dt_stable, w = stable_time_step(model, torque, safety, implicit_dampers=imex, equilibria=equilibria)
    how = "tooth-root dampers implicit, " if imex else ""
    if method == "explicit":
        return MethodChoice("explicit", dt_stable, w, f"explicit ({how}the default fraction of the stability step)"
                            if safety is None else f"explicit ({how}{safety} x the stability step)", estimated=True)
    n = duration / dt_stable
    if model.coupled:     # only the explicit kernel carries the body-torsion DOFs
        return MethodChoice("explicit", float(dt) if given else dt_stable, w,
                            "auto: explicit, the only integrator of the body-torsion coupling")
    if n <= max_explicit_steps:
        bound = f" <= {max_explicit_steps:.3g}" if math.isfinite(max_explicit_steps) else \
            " (a step of the implicit integrator costs about 20 explicit ones)"
        return MethodChoice("explicit", float(dt) if given else dt_stable, w,
                            f"auto: explicit, {n:.3g} steps at the stability step ({dt_stable * 1e9:.4g} ns){bound}",
                            estimated=not given)
    if imex:
        dt_stable = stable_time_step(model, torque, safety, equilibria=equilibria)[0]
    return MethodChoice("implicit", float(dt) if given else implicit_factor * dt_stable, w,
                        f"auto: implicit, the explicit run would take {n:.3g} steps > {max_explicit_steps:.3g}")

"""Free decay of the mesh mode, simulated: the damping ratio and frequency a run really has.

The driver is held (speed 0) at a driver angle of the mesh period (``driver_angle``; the
pair is turned there by its tooth-axis angles, `turned`); the resisting torque ramps slowly to 90 % of the load
(10 periods of the mesh mode, little left ringing) and then steps to the full load in a
quarter period. The pair then rings freely about the loaded equilibrium with an amplitude of
about a tenth of the static deflection (the contact and spring laws nearly linear there);
a damped cosine a + exp(-s t) (b cos(wd t) + c sin(wd t)) fitted by least squares to the TE
from one period after the step gives zeta = s / sqrt(s² + wd²) and the natural frequency
sqrt(s² + wd²) / 2 pi. The tooth modes, tens of kHz and heavily damped, are gone within a
period of the mesh mode.
"""
from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from solver.mbs.dynamics import DivergenceError, Drive, ExplicitIntegrator
from solver.mbs.kernels import layout as L
from solver.mbs.kernels.status import COMPLETED, OK
from solver.mbs.model import Model
from solver.mbs.stability import IMEX_SAFETY, SAFETY, implicit_dampers_apply, stable_time_step


@dataclass
class RingDown:
    frequency: float       # natural frequency of the fitted decay [Hz]
    damping: float         # damping ratio [1]
    time: np.ndarray       # s, of the fitted part
    te: np.ndarray         # m, the fitted TE
    fit: np.ndarray        # m, the fitted damped cosine


def turned(model: Model, driver_angle: float) -> Model:
    """A copy of ``model`` whose zero position (both hubs at 0) is the original's pair at the
    driver angle ``driver_angle`` [rad] on the nominal conjugate position: both gears' tooth
    axes turned (gear 2 by -driver_angle rb1/rb2). TE reads the same."""
    gp = model.gear_par.copy()
    gp[0, L.GAMMA0] += driver_angle
    gp[1, L.GAMMA0] -= driver_angle * model.base_radii[0] / model.base_radii[1]
    return dataclasses.replace(model, gear_par=gp)


def ring_down(model: Model, torque: float, frequency: float, damping: float, cycles: float | None = None,
              driver_angle: float = 0.0) -> RingDown:
    """Simulated free decay of the mesh mode under ``torque`` [N·m] with the driver held at
    ``driver_angle`` [rad]; ``frequency`` [Hz] and ``damping`` [1] (from the modal analysis
    there) set the time scales and start the fit. ``cycles``: periods fitted (default: until
    the amplitude falls to ~5 %, 6 to 40 periods). Solved once per model and arguments
    (`solver.mbs.memo`): a study's points of one body share it."""
    from solver.mbs.memo import kept
    args = (float(torque), float(frequency), float(damping), cycles, float(driver_angle))
    return kept("ring_down", model, args, lambda: _ring_down(model, *args))


def _ring_down(model: Model, torque: float, frequency: float, damping: float, cycles: float | None,
               driver_angle: float) -> RingDown:
    load = torque if abs(torque) > 1e-9 else 1.0
    # the default step of a run, from the model's own loaded equilibria (kept: the turned
    # pair has the same bound and needs no statics of its own); where a guard or the energy
    # check catches it near the bound, half the bound, as `simulate` does
    imex = implicit_dampers_apply(model)
    dt = stable_time_step(model, load, implicit_dampers=imex)[0]
    steps = (dt, dt * SAFETY / IMEX_SAFETY) if imex else (dt,)
    if driver_angle:
        model = turned(model, driver_angle)
    period = 1.0 / frequency
    cycles = cycles or float(np.clip(3.0 / (2 * math.pi * max(damping, 1e-6)), 6.0, 40.0))
    t_ramp, t_step = 10 * period, 0.25 * period
    table = [[0.0, 0.0], [t_ramp, 0.9 * load], [t_ramp + t_step, load]]
    t_fit = t_ramp + t_step + period
    drive = Drive(0.0, 1.0, load, t_ramp, t_fit + cycles * period, table)
    for dt in steps:
        res = ExplicitIntegrator(dt=dt, output_step=period / 40).run(model, drive)
        if res.status == OK:
            break
    if res.status not in COMPLETED:     # stopped by a guard (an inaccurate decay is still fitted)
        raise DivergenceError(f"free decay of the mesh mode: {res.message}")
    sel = res.time >= t_fit
    t = res.time[sel] - t_fit
    x = res.te[sel]
    wd0 = 2 * math.pi * frequency * math.sqrt(max(1 - damping ** 2, 1e-6))

    def model_fn(tt, a, b, c, s, wd):
        e = np.exp(-s * tt)
        return a + e * (b * np.cos(wd * tt) + c * np.sin(wd * tt))

    amp = float(np.ptp(x)) / 2 or 1e-12
    p0 = (float(x[-1]), amp, 0.0, damping * 2 * math.pi * frequency, wd0)
    scale = amp
    with warnings.catch_warnings():
        # an undamped decay fits exactly, and its covariance (unused here) cannot be estimated
        warnings.simplefilter("ignore", scipy.optimize.OptimizeWarning)
        p, _cov = scipy.optimize.curve_fit(lambda tt, *q: model_fn(tt, *q) / scale, t, x / scale, p0=p0, maxfev=20000)
    s, wd = abs(p[3]), abs(p[4])
    wn = math.hypot(s, wd)
    return RingDown(wn / (2 * math.pi), s / wn, t + t_fit, x, model_fn(t, *p))

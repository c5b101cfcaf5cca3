"""Plain numpy + scipy peer of the dynamic solver: the same equations, no numba.

scipy's `solve_ivp` solvers (their `OdeSolver` classes, stepped directly so that steps are
counted and TE is read from their dense output) integrate the equations of
`solver.peers.pair_equations` (every tooth free)

    y = [theta2, phi_1..phi_N, w2, dphi_1..dphi_N, W, D]

with W the work done on the pair by the driver and the load torque [J] and D the energy
dissipated by the dampers [J] (two quadrature states, so the energy balance can be checked).
Integration is split at the ramp ends, where the forcing has a kink. Stiff methods (Radau,
BDF, LSODA) get the analytic Jacobian (`PairEquations.jac`).

Model difference from the explicit integrator: there, teeth away from the mesh are frozen
rigid to their hub; here every tooth is free, so the driver's speed ramp also winds up the
idle driver teeth (I_cpl * theta1'' on k_phi). The resulting TE difference is of order
1e-4 um on the paper pair; `simulate_explicit_all_teeth` runs the explicit kernel on this
model for like-for-like comparisons.

SI units throughout. Entry point: `ScipyIntegrator` (`simulate_scipy` in one call).
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass

import numpy as np
from scipy import integrate

from solver.mbs.dynamics import DivergenceError, Drive, DynamicResult, check_positive, run_loads, simulate
from solver.mbs.kernels import layout as L
from solver.mbs.kernels.status import INTERRUPTED, NONFINITE, OK, PENETRATION
from solver.mbs.model import Model
from solver.peers.pair_equations import PairEquations, driver_motion

METHODS = ("RK45", "DOP853", "Radau", "BDF", "LSODA")
STIFF_METHODS = ("Radau", "BDF", "LSODA")


@dataclass
class ScipyResult(DynamicResult):
    """`DynamicResult` of the scipy peer, plus the solver's counters.

    ``force_max`` is the largest contact force at each output instant (not over the interval);
    ``dt`` is the mean step [s]; ``steps`` the accepted steps; ``max_active_teeth`` all teeth.
    """
    method: str = ""
    rtol: float = float("nan")
    atol: float = float("nan")
    nfev: int = 0
    njev: int = 0
    nlu: int = 0
    wall_time: float = float("nan")     # s, integration only


@dataclass(frozen=True)
class ScipyIntegrator:
    """A `scipy.integrate` ODE solver on the pair (all teeth free) and its settings; `run`
    integrates a model from rest under a `solver.mbs.dynamics.Drive` (the loads of the
    explicit integrator), TE [m] and the energies sampled every output_step [s].

    ``method``: one of RK45, DOP853 (non-stiff; use DOP853 for tight references), Radau, BDF,
    LSODA (stiff; analytic Jacobian). ``rtol`` [-]; ``atol`` absolute tolerance on angles
    [rad] and rates [rad/s] (default rtol * 1e-6, i.e. rtol times about a micrometre of flank
    motion; rates get atol scaled by the highest tooth frequency). ``max_step`` [s]: the
    solver's largest step (None: its own). ``delta_max`` [m] (default a tenth of the module)
    bounds the penetration.
    A failure of the solver or a guard gives a status other than OK (`solver.mbs.kernels.status`)
    and a message (or raises `DivergenceError` with ``raise_on_failure``). ``max_wall_time`` [s]
    stops a run that takes longer (status INTERRUPTED, "wall-time limit").
    """
    method: str = "LSODA"
    rtol: float = 1e-6
    atol: float | None = None
    output_step: float = 1e-5
    max_step: float | None = None
    delta_max: float | None = None
    raise_on_failure: bool = False
    max_wall_time: float | None = None

    def run(self, model: Model, drive: Drive) -> ScipyResult:
        """Integrate ``model`` from rest under ``drive``."""
        method, rtol, atol, output_step = self.method, self.rtol, self.atol, self.output_step
        speed, speed_ramp, torque, torque_ramp = drive.speed, drive.speed_ramp, drive.torque, drive.torque_ramp
        duration = drive.duration
        if method not in METHODS:
            raise ValueError(f"method: must be one of {', '.join(METHODS)}, got {method!r}")
        check_positive(duration=duration, speed_ramp=speed_ramp, torque_ramp=torque_ramp, output_step=output_step,
                       rtol=rtol)
        table, _step_torque, side = run_loads(drive.load_table, torque)
        eq = PairEquations(model, speed, speed_ramp, torque, torque_ramp, table)
        n = eq.n
        if atol is None:
            atol = rtol * 1e-6
        omega_tooth = math.sqrt(float(np.max(model.k_phi)) / float(np.min(model.gear_par[:, L.I_P])))
        atol_vec = np.r_[np.full(n, atol), np.full(n, atol * omega_tooth), 1e-3 * atol, 1e-3 * atol]
        delta_max = self.delta_max
        if delta_max is None:
            delta_max = 0.1 * model.geometry[0].spec.module
        y = np.zeros(2 * n + 2)
        y[0] = model.theta2_for_te(0.0, (1.0 if side >= 0 else -1.0) * model.backlash_offset)
        n_out = int(math.floor(duration / output_step + 1e-9)) + 1
        t_out = np.arange(n_out) * output_step
        kinks = (speed_ramp, *table[:, 0]) if table.shape[0] else (speed_ramp, torque_ramp)
        breaks = sorted({0.0, duration, *(float(b) for b in kinks if 0 < b < duration)})
        kw = {"rtol": rtol, "atol": atol_vec}
        if self.max_step is not None:
            kw["max_step"] = self.max_step
        if method in STIFF_METHODS:
            kw["jac"] = eq.jac
        ys, status, msg, counts = self._step(eq, y, t_out, breaks, kw)
        steps, t_reached, wall = counts["steps"], counts["t_reached"], counts["wall"]
        good = np.all(np.isfinite(ys), axis=1)
        m = int(np.argmin(good)) if not good.all() else n_out
        t_out, ys = t_out[:m], ys[:m]
        status, msg, (te, fmax, ncon, react, ke, pe) = _sampled(model, eq, drive, t_out, ys, status, msg, delta_max)
        if status and self.raise_on_failure:
            raise DivergenceError(msg)
        mean_dt = t_reached / steps if steps else float("nan")
        return ScipyResult(t_out, te, ys[:, 0], fmax, ncon, react, ke, pe, ys[:, 2 * n], ys[:, 2 * n + 1],
                           np.zeros_like(t_out), mean_dt, steps, status, msg, float("nan"), eq.nt,
                           method=method, rtol=rtol, atol=float(atol), nfev=counts["nfev"], njev=counts["njev"],
                           nlu=counts["nlu"], wall_time=wall)

    def _step(self, eq: PairEquations, y: np.ndarray, t_out: np.ndarray, breaks: list, kw: dict):
        """Step the solver from one break (ramp end) to the next, reading the state at the
        output instants t_out [s] from its dense output: (states, status, message, counters:
        steps, nfev, njev, nlu, t_reached [s], wall [s] of the integration)."""
        method, max_wall_time = self.method, self.max_wall_time
        ys = np.full((t_out.size, y.size), np.nan)
        status, msg = OK, "ok"
        nfev = njev = nlu = steps = 0
        t_reached = 0.0
        cls = getattr(integrate, method)
        ys[0] = y
        t0 = _time.perf_counter()
        for a, b in zip(breaks[:-1], breaks[1:]):
            solver = cls(eq.rhs, a, y, b, **kw)
            while solver.status == "running":
                t_old = solver.t
                err = solver.step()
                if solver.status == "failed" or not np.all(np.isfinite(solver.y)):
                    status = NONFINITE
                    msg = (f"{method} failed at t = {t_old:.6g} s (step {steps + 1}): "
                           f"{err or 'non-finite state'}")
                    break
                steps += 1
                if max_wall_time is not None and _time.perf_counter() - t0 > max_wall_time:
                    status = INTERRUPTED
                    msg = (f"{method}: wall-time limit {max_wall_time:g} s reached at t = {solver.t:.6g} s "
                           f"(step {steps})")
                    solver.status = "failed"
                sel = np.flatnonzero((t_out > t_old) & (t_out <= solver.t))
                if sel.size:
                    ys[sel] = solver.dense_output()(t_out[sel]).T
                t_reached = solver.t
            nfev += solver.nfev
            njev += solver.njev
            nlu += solver.nlu
            if status:
                break
            y = solver.y
        wall = _time.perf_counter() - t0
        return ys, status, msg, dict(steps=steps, nfev=nfev, njev=njev, nlu=nlu, t_reached=t_reached, wall=wall)


def _sampled(model: Model, eq: PairEquations, drive: Drive, t_out: np.ndarray, ys: np.ndarray, status: int,
             msg: str, delta_max: float):
    """The outputs at the instants t_out [s] of the states ys: (status, message, (TE [m],
    largest contact force [N], contacts in force, driver torque [N·m], kinetic and potential
    energy [J])); a penetration beyond delta_max [m] sets the status where none was set."""
    n, m = eq.n, t_out.size
    rb1, rb2 = model.base_radii
    te = np.empty(m)
    fmax = np.zeros(m)
    ncon = np.zeros(m, int)
    react = np.empty(m)
    ke = np.empty(m)
    pe = np.empty(m)
    for i, (t, yy) in enumerate(zip(t_out, ys)):
        x, v = yy[:n], yy[n:2 * n]
        q, q1, cons, a1 = eq.forces(t, x, v)
        acc = eq.solve_mass(q, a1)
        th1 = driver_motion(t, drive.speed, drive.speed_ramp)[0]
        te[i] = rb1 * th1 + rb2 * x[0]
        fmax[i] = max((c.force for c in cons), default=0.0)
        ncon[i] = sum(1 for c in cons if c.force > 0.0)
        react[i] = eq.driver_torque(q1, acc, a1)
        ke[i], pe[i] = eq.energies(t, x, v, cons)
        if status == OK and max((c.delta for c in cons), default=0.0) > delta_max:
            status, msg = PENETRATION, f"penetration beyond the bound {delta_max * 1e6:.4g} um at t = {t:.6g} s"
    return status, msg, (te, fmax, ncon, react, ke, pe)


def simulate_scipy(model: Model, speed: float, speed_ramp: float, torque: float, torque_ramp: float,
                   duration: float, **settings) -> ScipyResult:
    """The scipy peer in one call: ``ScipyIntegrator(**settings).run(model, Drive(speed,
    speed_ramp, torque, torque_ramp, duration, load_table))``, with ``load_table`` (a torque
    profile instead of the torque ramp, as in `solver.mbs.dynamics.Drive`) taken from
    ``settings``."""
    drive = Drive(speed, speed_ramp, torque, torque_ramp, duration, settings.pop("load_table", None))
    return ScipyIntegrator(**settings).run(model, drive)


def simulate_explicit_all_teeth(model: Model, speed: float, speed_ramp: float, torque: float,
                                torque_ramp: float, duration: float, dt: float, **settings) -> DynamicResult:
    """The explicit Verlet kernel on the same model as the scipy peer: every tooth free.

    `solver.mbs.dynamics.simulate` freezes idle teeth rigid to their hub (its active set); here
    all teeth start active (phi = 1e-300 rad, numerically zero) and none is ever frozen, so
    the two solvers integrate identical equations and can be compared step against
    tolerance. ``dt`` [s] is rounded down to divide ``output_step`` [s] (default 1e-5 s);
    ``settings``: those of `solver.mbs.dynamics.ExplicitIntegrator` and ``load_table``, as in
    `solver.mbs.dynamics.simulate`. Every force explicit by default (the scheme the reference
    runs have always used); ``implicit_dampers``: the IMEX kicks of `simulate`.
    """
    settings.setdefault("implicit_dampers", False)
    return simulate(model, speed, speed_ramp, torque, torque_ramp, duration, dt=dt, all_teeth=True, **settings)

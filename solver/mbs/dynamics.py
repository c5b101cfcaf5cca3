"""Time integration of the pair under the prescribed speed ramp and the load-torque ramp.

`ExplicitIntegrator` (its settings; `simulate` in one call) runs the explicit velocity-Verlet kernel (`kernels/explicit.py`, or
`kernels/explicit_coupled.py` for a body-torsion coupled model) with a fixed step, by default
the stability bound of `solver.mbs.stability`. Shared by every fixed-step integrator (the
implicit one and the peers too): the step grid (`step_grid`), the load inputs
(`run_loads`), the kernel call (`run_kernel`), the guard messages, and the reading of a run
at driver angles (`at_driver_angles`, the slow-ramp quasi-static transient).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.mbs.energy_guard import ENERGY_ERROR_RATIO, ENERGY_FLOW_RATIO, energy_error_limit
from solver.mbs.kernels import layout as L
from solver.mbs.kernels.explicit import verlet
from solver.mbs.kernels.gearmesh import contact_parts
from solver.mbs.kernels.mechanics import driver_motion
from solver.mbs.kernels.status import ENERGY, INACCURATE, PENETRATION, STATUS_TEXT
from solver.mbs.kernels.stepping import work_arrays
from solver.mbs.model import Model
from solver.mbs.stability import IMEX_SAFETY, SAFETY, implicit_dampers_apply, load_covered, stable_time_step

ENERGY_TOL = 0.05   # relative energy growth that stops a run (see `simulate`)
# Quiet threshold of the active set [rad] (a tooth outside the mesh freezes below it): 1e-9 by
# default; 1e-7 where every tooth-root joint is damped to at least QUIET_ZETA of critical (the
# mesh damping ratio puts 0.7-0.9 there), since a frozen tooth there would have stopped ringing
# within about a period anyway. Measured on the paper's 0.2 s case against the all-teeth model:
# 0.0019 um (solid) and 0.0019 um (lightened) at 1e-7 with the default damping, 0.0031 um with
# the tooth joints at 0.36 of critical; the lightly damped raw coefficients (0.016 of
# critical) would move TE by 0.06-0.17 um at 1e-7, so they keep 1e-9.
PHI_QUIET = 1e-9
PHI_QUIET_DAMPED = 1e-7
QUIET_ZETA = 0.3


def default_phi_quiet(model: Model) -> float:
    """The active set's quiet threshold [rad] for ``model`` (see PHI_QUIET_DAMPED): the
    damping ratio of each tooth's own mode, c_phi/(2*sqrt(k_phi*I_P)) with the largest k_phi of
    its gear (the lowest ratio; n_k > 1 softens the spring near rest, which only raises it)."""
    gp = model.gear_par
    for g in range(2):
        t0, nz = int(gp[g, L.TOOTH0]), int(gp[g, L.NZ])
        k = float(np.max(model.k_phi[t0:t0 + nz]))
        if not gp[g, L.C_PHI] >= QUIET_ZETA * 2.0 * math.sqrt(k * gp[g, L.I_P]):
            return PHI_QUIET
    return PHI_QUIET_DAMPED


class DivergenceError(RuntimeError):
    """The integration stopped on a guard; the message names the cause, time and step."""


@dataclass
class DynamicResult:
    time: np.ndarray            # s
    te: np.ndarray              # transmission error [m]
    theta2: np.ndarray          # driven hub angle [rad]
    force_max: np.ndarray       # largest contact force over each output interval [N]
    n_contacts: np.ndarray      # loaded contacts at the output instant [-]
    driver_torque: np.ndarray   # torque the driver applies [N·m]
    kinetic: np.ndarray         # J
    potential: np.ndarray       # J
    work: np.ndarray            # work done by driver and load torque since t = 0 [J]
    dissipated: np.ndarray      # J, by the dampers
    switched: np.ndarray        # J taken out by the coupled set's switches (compliance model; 0 otherwise)
    dt: float                   # integration step [s]
    steps: int                  # steps taken
    status: int                 # 0 ok (see STATUS_TEXT)
    message: str
    omega_max: float            # highest natural frequency used for the step [rad/s]
    max_active_teeth: int
    # (record, slot, `layout` OC_* column): the loaded contacts at each output instant (gear-1
    # tooth, gear-2 tooth, normal force [N], moment on the driven gear [N m]); set by the
    # runs (`contact_records`), None where a result has none
    contacts = None

    @property
    def energy_error(self) -> np.ndarray:
        """work - (kinetic + potential - initial) - dissipated - switched [J]."""
        e = self.kinetic + self.potential
        return self.work - (e - e[0]) - self.dissipated - self.switched


def status_message(status: int, step: int, dt: float, delta_max: float, raise_on_failure: bool = False) -> str:
    """'ok', or the guard's cause with the time [s], the step and dt [s]; raises if asked."""
    if not status:
        return "ok"
    msg = f"{STATUS_TEXT[status]} at t = {step * dt:.6g} s (step {step}, dt = {dt:.3g} s)"
    if status == PENETRATION:
        msg += f"; bound {delta_max * 1e6:.4g} um"
    if status in (PENETRATION, ENERGY):
        msg += "; a step too coarse for the contact forces reached does this: try a smaller dynamic.time_step"
    if raise_on_failure:
        raise DivergenceError(msg)
    return msg


def accuracy_check(res: DynamicResult, alpha: float = 0.0) -> DynamicResult:
    """Flag (status INACCURATE, message with the figures) a run that completed although its
    energy balance error exceeds `energy_error_limit`: the step is too coarse for the contact
    events (forces and TE are then wrong while no guard stopped the run). For HHT with
    ``alpha`` < 0, whose numerical damping removes energy by design, only energy created
    counts. Returns ``res``."""
    if res.status or res.time.size < 2:
        return res
    err = res.energy_error
    err = -err if alpha < 0 else np.abs(err)
    pe = float(np.max(res.potential))
    limit = energy_error_limit(res)
    worst = int(np.argmax(err / np.maximum(limit, 1e-300)))
    if pe > 0 and err[worst] > limit[worst]:
        res.status = INACCURATE
        res.message = (f"inaccurate: energy balance error {err[worst]:.3g} J at t = {res.time[worst]:.4g} s, "
                       f"{err[worst] / pe:.2g} x the largest potential energy of the mesh ({pe:.3g} J) with "
                       f"{abs(res.dissipated[worst]):.3g} J dissipated (a converged run stays under "
                       f"{ENERGY_ERROR_RATIO:g} x the one + {ENERGY_FLOW_RATIO:g} x the other, {limit[worst]:.3g} J), "
                       f"largest contact force {np.max(res.force_max):.4g} N: the step (dt = {res.dt:.3g} s) misses "
                       "the contact events; set a smaller dynamic.time_step")
    return res


def load_profile(table) -> np.ndarray:
    """A resisting-torque profile as the kernels take it: (n, 2) [time s, torque N·m], times
    from 0, strictly increasing; ``None`` or an empty table -> (0, 2) (the ramp)."""
    if table is None:
        return np.zeros((0, 2))
    a = np.array(table, dtype=float)
    if a.size == 0:
        return np.zeros((0, 2))
    if a.ndim != 2 or a.shape[1] != 2 or a.shape[0] < 2:
        raise ValueError(f"load_table: need rows of (time s, torque N·m), at least two, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("load_table: times and torques must be finite")
    if a[0, 0] < 0 or np.any(np.diff(a[:, 0]) <= 0):
        raise ValueError("load_table: times must start at or after 0 s and increase strictly")
    if a[0, 0] > 0:
        a = np.vstack([[0.0, 0.0], a])          # from rest: the load starts from zero
    if a[0, 1] != 0:
        raise ValueError(f"load_table: the run starts from rest, so the torque at t = 0 must be 0, got {a[0, 1]} N·m")
    return a


def run_loads(load_table, torque: float) -> tuple[np.ndarray, float, float]:
    """(profile for the kernels, torque for the step estimate [N·m], torque whose sign picks
    the initial flank side [N·m]) of a run with ramp target ``torque`` or a profile: with a
    profile, its largest torque in magnitude and its first nonzero torque."""
    table = load_profile(load_table)
    if not table.shape[0]:
        return table, torque, torque
    nz = np.flatnonzero(table[:, 1])
    side = float(table[nz[0], 1]) if nz.size else 0.0
    return table, float(table[np.argmax(np.abs(table[:, 1])), 1]), side


def step_grid(dt: float, output_step: float, duration: float) -> tuple[float, int, int, int]:
    """(dt [s], steps per output, steps, output records) of a fixed-step run: ``dt`` rounded
    down so that ``output_step`` [s] is a whole number of steps (a step within 1e-9 of a
    divisor is kept: the ends of ramps that are multiples of output_step then fall on step
    boundaries), steps to cover ``duration`` [s], records including t = 0."""
    out_every = max(1, int(math.ceil(output_step / dt - 1e-9)))
    dt = output_step / out_every
    n_steps = int(round(duration / dt))
    return dt, out_every, n_steps, n_steps // out_every + 1


def check_positive(**values: float) -> None:
    """Raise ValueError naming the first of ``values`` that is not positive and finite."""
    for name, v in values.items():
        if not (v > 0 and math.isfinite(v)):
            raise ValueError(f"{name}: must be positive, got {v}")


def start_te(model: Model, side: float) -> float:
    """TE [m] at t = 0: the rigid teeth touching on the flank side of the first load (sign).
    Perfect gears touch at +-jn/2; with pitch errors or eccentricity (`solver.pitch_errors`) the first
    touch at theta1 = 0 is found by bisection on the contact search within the errors' bound, so
    that the run starts in contact without penetration (a penetration of microns would start it
    with a kick)."""
    s = 1.0 if side >= 0 else -1.0
    te0 = s * model.backlash_offset
    if model.pair_par.size <= L.N_PAIR_PAR:
        return te0
    from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
    rec, pairs = new_contact_buffer()
    zeros = np.zeros(model.n_teeth)
    geo = contact_geo(model.gear_par, model.pair_par, model.law_par)

    def touching(te):
        nc, _ = mesh_contacts((0.0, model.theta2_for_te(0.0, te), 0.0, 0.0), zeros, zeros, geo, (rec, pairs))
        return any(rec[c, L.C_KIND] * s > 0 for c in range(nc))

    clear, touch = 0.0, 2.0 * model.pair_par[L.E_BOUND]    # approach from jn/2 - bound along side s
    for _ in range(48):
        mid = 0.5 * (clear + touch)
        if touching(te0 - s * model.pair_par[L.E_BOUND] + s * mid):
            touch = mid
        else:
            clear = mid
    return te0 - s * model.pair_par[L.E_BOUND] + s * clear


def run_kernel(kernel, model: Model, loads: tuple, grid: tuple, par: dict, all_teeth: bool = False,
               progress=None):
    """Run a stepping kernel from rest; returns (its 4 return values, output records).

    loads: (speed [rad/s], speed ramp [s], torque [N·m], torque ramp [s], profile (n x 2),
    initial flank side (sign)); grid: `step_grid`; par: the remaining control values by
    `layout` column name (DELTA_MAX, PHI_QUIET, ENERGY_TOL, HHT_ALPHA, NEWTON_TOL, MAX_ITER,
    IMEX).
    ``all_teeth``: every tooth active from the start (phi = 1e-300 rad) and none frozen.
    ``progress``: None, or a callable taking the time reached [s], called about every
    PROGRESS_PERIOD_S while the kernel runs. The kernel stops at the end of its step on
    Ctrl-C or SIGTERM (`solver.mbs.interrupt`: KeyboardInterrupt raised here).
    """
    from solver.mbs import interrupt
    args = kernel_arguments(model, loads, grid, par, all_teeth)
    p, out = args[1][0], args[4]
    poll = None if progress is None else (lambda: progress(float(out[last_record(out), L.O_TIME])))
    ret = interrupt.call(kernel, args, p, L.ABORT, poll, PROGRESS_PERIOD_S)
    return ret, out[:min(grid[3], ret[1] // grid[1] + 1)]


def kernel_arguments(model: Model, loads: tuple, grid: tuple, par: dict, all_teeth: bool = False,
                     theta2: float | None = None) -> tuple:
    """The arguments of a stepping kernel (`run_kernel`'s ``loads``, ``grid``, ``par``,
    ``all_teeth``): (mdl, (par, ipar, load table), hub, teeth, out, work arrays), the run
    from rest, the driven hub at ``theta2`` [rad] (None: where the flanks touch, `start_te`).
    What a model's stepping kernel is compiled for (the `layout.ContactParts` variant, the
    work tuples) is in their types, which `study.stand_in` reads without a run."""
    speed, speed_ramp, torque, torque_ramp, table, side = loads
    dt, out_every, n_steps, n_out = grid
    phi_quiet = 0.0 if all_teeth else par["PHI_QUIET"]
    omega_tooth = math.sqrt(model.k_phi.max() / model.gear_par[:, L.I_P].min())
    p = np.zeros(L.N_PAR)
    rate_quiet = 0.0 if all_teeth else par.get("RATE_QUIET", phi_quiet)
    for name, v in dict(par, SPEED=speed, SPEED_RAMP=speed_ramp, TORQUE=torque, TORQUE_RAMP=torque_ramp, DT=dt,
                        PHI_QUIET=phi_quiet, DPHI_QUIET=rate_quiet * omega_tooth).items():
        if name == "RATE_QUIET":
            continue
        if name != "MAX_ITER":
            p[getattr(L, name)] = v
    ip = np.zeros(L.N_IPAR, dtype=np.int64)
    ip[[L.N_STEPS, L.OUT_EVERY, L.MAX_ITER]] = n_steps, out_every, par.get("MAX_ITER", 0)
    hub = np.zeros((3, L.N_HUB))
    if theta2 is None:
        theta2 = model.theta2_for_te(0.0, start_te(model, side))
    hub[L.POS, L.H_TH2] = hub[L.POS, L.H_H2] = theta2
    teeth = np.zeros((3, model.n_teeth))
    if all_teeth:
        teeth[L.POS] = 1e-300
    out = np.zeros((n_out, L.N_OUT + L.CONTACT_SLOTS * L.O_CONTACT_COLS))
    # contact_parts: which parts of the contact search the model has, so which compiled variant runs
    mdl = (model.gear_par, model.pair_par, model.law_par, model.k_phi, model.tooth_compliance,
           contact_parts(model.gear_par, model.pair_par, model.law_par))
    return (mdl, (p, ip, np.ascontiguousarray(table, dtype=float)), hub, teeth, out,
            work_arrays(model.n_teeth, model.tooth_compliance))


PROGRESS_PERIOD_S = 0.25


def last_record(out: np.ndarray) -> int:
    """Index of the last output record a running kernel has written: records fill ``out`` in
    order and their times are positive, the rows not yet written are zero (bisection)."""
    lo, hi = 0, out.shape[0] - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if out[mid, L.O_TIME] > 0.0:
            lo = mid
        else:
            hi = mid - 1
    return lo


def result_fields(out: np.ndarray) -> tuple:
    """The `DynamicResult` arrays time .. switched of a run's output records."""
    cols = (L.O_TIME, L.O_TE, L.O_THETA2, L.O_FMAX, L.O_NC, L.O_REACT, L.O_KE, L.O_PE, L.O_WORK, L.O_DISS, L.O_SWITCH)
    fields = [out[:, c].copy() for c in cols]
    fields[4] = fields[4].astype(int)
    return tuple(fields)


def contact_records(out: np.ndarray) -> np.ndarray:
    """The loaded contacts of a run's output records, (record, slot, `layout` OC_* column)."""
    return out[:, L.N_OUT:].reshape(out.shape[0], -1, L.O_CONTACT_COLS).copy()


def at_driver_angles(res: DynamicResult, speed: float, ramp: float, angles) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(TE [m], driven hub angle [rad], loaded contacts) of a run under the speed ramp
    0 -> speed [rad/s] over ramp [s], interpolated at driver angles [rad] (TE and angle NaN
    past the run's end): how a slow-ramp transient gives the quasi-static STE."""
    th1 = np.array([driver_motion(t, speed, ramp)[0] for t in res.time])
    te = np.interp(angles, th1, res.te, right=np.nan)
    th2 = np.interp(angles, th1, res.theta2, right=np.nan)
    nc = np.round(np.interp(angles, th1, res.n_contacts)).astype(np.int64)
    return te, th2, nc


def slow_ramp_window(angles, angle_step: float, speed: float, ramp: float) -> tuple[float, float]:
    """(output step [s], duration [s]) of the slow-ramp transient that samples driver angles
    [rad] up to angles[-1] at angle_step [rad]: four records per angle step, to the last
    angle plus two records (the driver's angle lags speed*t by speed*ramp/2)."""
    dt_out = angle_step / speed / 4
    return dt_out, ramp / 2 + angles[-1] / speed + 2 * dt_out


@dataclass(frozen=True)
class Drive:
    """What a run is driven by, from rest: the driver speed ramp 0 -> ``speed`` [rad/s] over
    ``speed_ramp`` [s] and the resisting torque ramp 0 -> ``torque`` [N·m] over
    ``torque_ramp`` [s], for ``duration`` [s]. ``load_table``: a resisting-torque profile (rows
    of time [s], torque [N·m], from 0 N·m at t = 0; `load_profile`) instead of the ramp to
    ``torque``; the step estimate then uses the profile's largest torque in magnitude, and the
    initial flank side its first nonzero torque."""
    speed: float
    speed_ramp: float
    torque: float
    torque_ramp: float
    duration: float
    load_table: object = None


@dataclass(frozen=True)
class ExplicitIntegrator:
    """The explicit velocity-Verlet integrator and its settings; `run` integrates a model
    under a `Drive`.

    ``dt`` [s] defaults to ``safety`` times the stability bound (`solver.mbs.stability`; safety
    None: 0.5, or 0.9 with implicit dampers); it is rounded down so that output_step [s] is a
    whole number of steps. A step of the default is checked after the run against the largest
    contact force reached (`solver.mbs.stability.load_covered`): where that force makes the
    pair stiffer than the estimate allows, the step is estimated again under the load that
    force stands for (x 1.25) and the run repeated (at most three times; then status
    "inaccurate"); a default step above half the bound that a guard stops or the energy check
    (`accuracy_check`) flags is repeated at half the bound (impacts, rattle). ``delta_max`` [m] (default: a tenth of the module) bounds the
    penetration; the run stops there with a message naming time and step.
    ``phi_quiet`` [rad]: a tooth outside the mesh window is frozen once its rotation is below
    this (1e-9 rad moves the flank by about 3e-6 um) and its rate below phi_quiet times its
    natural frequency; None: `default_phi_quiet` (1e-7 rad with well-damped tooth joints).
    ``energy_tol`` [-]: the run stops ("energy growth") when the energy balance shows more
    energy in the pair than the work put in, by more than this fraction of the larger of the
    work and the stored energy: the signature of an unstable step.
    ``all_teeth``: integrate every tooth from the start and never freeze one (the model of
    the scipy peer `solver.peers.scipy_dynamics`, for like-for-like error figures).
    ``implicit_dampers``: take the tooth-root dampers implicitly in the Verlet kicks (IMEX,
    `solver.mbs.kernels.explicit`), so that they no longer limit the step; None (default):
    wherever they can be (`solver.mbs.stability.implicit_dampers_apply`: linear dampers);
    False: every force explicit (the scheme before, kept as the reference).
    ``raise_on_failure``: a run stopped by a guard raises `DivergenceError` instead of
    returning its status.
    """
    dt: float | None = None
    output_step: float = 1e-5
    safety: float | None = None
    delta_max: float | None = None
    raise_on_failure: bool = False
    phi_quiet: float | None = None
    energy_tol: float = ENERGY_TOL
    all_teeth: bool = False
    implicit_dampers: bool | None = None

    def run(self, model: Model, drive: Drive, progress=None) -> DynamicResult:
        """Integrate ``model`` from rest under ``drive``. ``progress``: a callable taking the
        time reached [s] while the run goes (`run_kernel`)."""
        return _run_explicit(self, model, drive, progress)


def simulate(model: Model, speed: float, speed_ramp: float, torque: float, torque_ramp: float,
             duration: float, *, progress=None, **settings) -> DynamicResult:
    """The explicit integrator in one call: ``ExplicitIntegrator(**settings).run(model,
    Drive(speed, speed_ramp, torque, torque_ramp, duration, load_table), progress)``, with
    ``load_table`` taken from ``settings`` (see `Drive` and `ExplicitIntegrator`)."""
    drive = Drive(speed, speed_ramp, torque, torque_ramp, duration, settings.pop("load_table", None))
    return ExplicitIntegrator(**settings).run(model, drive, progress)


def explicit_kernel(model: Model):
    """The explicit stepping loop of ``model``: `verlet_coupled` where the teeth are coupled
    through the bodies (`Model.coupled`), else `verlet`."""
    if model.coupled:
        from solver.mbs.kernels.explicit_coupled import verlet_coupled
        return verlet_coupled
    return verlet


def _run_explicit(settings: ExplicitIntegrator, model: Model, drive: Drive, progress) -> DynamicResult:
    """`ExplicitIntegrator.run`."""
    speed, speed_ramp, torque, torque_ramp = drive.speed, drive.speed_ramp, drive.torque, drive.torque_ramp
    duration, load_table = drive.duration, drive.load_table
    dt, output_step, safety, delta_max = settings.dt, settings.output_step, settings.safety, settings.delta_max
    phi_quiet, energy_tol, all_teeth = settings.phi_quiet, settings.energy_tol, settings.all_teeth
    implicit_dampers, raise_on_failure = settings.implicit_dampers, settings.raise_on_failure
    check_positive(duration=duration, speed_ramp=speed_ramp, torque_ramp=torque_ramp, output_step=output_step)
    table, torque, side = run_loads(load_table, torque)
    applies = implicit_dampers_apply(model)
    imex = applies if implicit_dampers is None else bool(implicit_dampers)
    rate = {}
    if phi_quiet is None:
        phi_quiet = default_phi_quiet(model)
        # the rate bound stays PHI_QUIET * omega_tooth: a tooth frozen while it still moves
        # relative to its hub takes its share of the kinetic energy (I_cpl*w*dphi at hub speed
        # w) out of the balance unbooked
        rate = dict(RATE_QUIET=PHI_QUIET)
    if imex and not applies:
        raise ValueError("implicit_dampers: needs linear tooth-root dampers (n_c = 1, c_phi > 0)")
    omega_max = float("nan")
    auto = dt is None or dt <= 0
    step_torque = torque
    if auto:
        dt, omega_max = stable_time_step(model, step_torque, safety, implicit_dampers=imex)
    if delta_max is None:
        delta_max = 0.1 * model.geometry[0].spec.module
    if model.teeth_coupled and not model.coupled:
        raise ValueError("tooth_compliance: the dynamics of teeth coupled through the body need the body "
                         "springs too (coupling.model = 'compliance' identifies both)")
    kernel = explicit_kernel(model)
    par = dict(DELTA_MAX=float(delta_max), PHI_QUIET=phi_quiet, ENERGY_TOL=float(energy_tol), IMEX=float(imex), **rate)
    fraction = safety if safety is not None else (IMEX_SAFETY if imex else SAFETY)
    for attempt in range(4):
        grid = step_grid(dt, output_step, duration)
        (status, step, max_act, _n), out = run_kernel(kernel, model, (float(speed), float(speed_ramp), float(torque),
                                                      float(torque_ramp), table, side), grid, par, all_teeth,
                                                      progress)
        peak = float(np.max(out[:, L.O_FMAX])) if out.shape[0] else 0.0
        covered = not auto or status or load_covered(model, step_torque, fraction, peak)
        if not covered and attempt < 3:
            raised = math.copysign(1.25 * peak * model.base_radii[1], step_torque if step_torque else 1.0)
            try:
                dt, omega_max = stable_time_step(model, raised, fraction, implicit_dampers=imex)
            except ValueError:
                # no static equilibrium under the load reached (more than the pair carries statically,
                # e.g. far above its critical speeds): no bound to tighten the step to; the run is kept
                # and marked inaccurate below
                pass
            else:
                step_torque = raised
                continue
        res = DynamicResult(*result_fields(out), grid[0], int(step), int(status),
                            status_message(status, step, grid[0], delta_max), omega_max, int(max_act))
        res.contacts = contact_records(out)
        if not covered:
            res.status = INACCURATE
            res.message = (f"inaccurate: the largest contact force {peak:.4g} N makes the pair stiffer than the step "
                           f"(dt = {res.dt:.3g} s, {fraction:g} x the bound under {step_torque:.4g} N·m) allows; "
                           "set a smaller dynamic.time_step")
        res = accuracy_check(res)
        if auto and res.status and fraction > SAFETY and attempt < 3:
            # a guard or the energy balance caught the step near the bound (impacts, rattle): the
            # all-explicit fraction of the same bound
            dt *= SAFETY / fraction
            fraction = SAFETY
            continue
        break
    if raise_on_failure and status:
        status_message(status, step, res.dt, delta_max, raise_on_failure=True)
    return res

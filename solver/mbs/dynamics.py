"""Time integration of the pair under the prescribed speed ramp and the load-torque ramp.

`simulate` runs the explicit velocity-Verlet kernel (`kernels/explicit.py`, or
`kernels/explicit_coupled.py` for a body-torsion coupled model) with a fixed step. By default
the step comes from the scene's highest natural frequency: the model is linearised at static equilibrium at several positions across one mesh cycle under the full
load, and ``dt = safety * 2 / omega_max`` (Verlet is stable for omega*dt < 2), reduced where
the modal damping of the loaded contacts asks for it (`stability_limit`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.explicit import verlet
from solver.mbs.kernels.gearmesh import mesh_contacts, new_contact_buffer, tooth_spring_tangent
from solver.mbs.kernels.laws import contact_damping_tangents, spring_damping_tangent
from solver.mbs.model import Model
from solver.mbs.statics import solve_static

STATUS_TEXT = {0: "ok", 1: "non-finite state", 2: "penetration beyond the bound", 3: "energy growth",
               4: "Newton failure"}
ENERGY_TOL = 0.05   # relative energy growth that stops a run (see `simulate`)


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
    dissipated: np.ndarray      # J
    dt: float                   # integration step [s]
    steps: int                  # steps taken
    status: int                 # 0 ok (see STATUS_TEXT)
    message: str
    omega_max: float            # highest natural frequency used for the step [rad/s]
    max_active_teeth: int

    @property
    def energy_error(self) -> np.ndarray:
        """work - (kinetic + potential - initial) - dissipated [J]."""
        e = self.kinetic + self.potential
        return self.work - (e - e[0]) - self.dissipated


def status_message(status: int, step: int, dt: float, delta_max: float, raise_on_failure: bool = False) -> str:
    """'ok', or the guard's cause with the time [s], the step and dt [s]; raises if asked."""
    if not status:
        return "ok"
    msg = f"{STATUS_TEXT[status]} at t = {step * dt:.6g} s (step {step}, dt = {dt:.3g} s)"
    if status == 2:
        msg += f"; bound {delta_max * 1e6:.4g} um"
    if raise_on_failure:
        raise DivergenceError(msg)
    return msg


def linearized_system(model: Model, theta1: float, theta2: float, phi: np.ndarray, damping: bool = False):
    """Mass and tangent stiffness over the free DOFs (theta2, then the teeth near the mesh).

    Returns (M, K, dof_teeth) in SI; the driver hub is prescribed and not a DOF. With
    ``damping`` also the damping tangent at rest, (M, K, C, dof_teeth): spring dampers and
    contact dampers dF/d(ddelta) = c*delta^m3 (for m2 = 1; 0 at rest for m2 > 1).
    The damping laws run as plain Python here (``.py_func``, a few dozen calls): compiling
    them would add to the first run's compile time for nothing.
    """
    rec, pairs = new_contact_buffer()
    zeros = np.zeros(model.n_teeth)
    gp = model.gear_par
    nc, npair = mesh_contacts(theta1, theta2, phi, 0.0, 0.0, zeros, gp, model.pair_par, model.law_par, pairs, rec)
    tz2 = int(gp[1, L.TOOTH0])
    teeth = sorted({int(pairs[p, 0]) for p in range(npair)} | {tz2 + int(pairs[p, 1]) for p in range(npair)})
    pos = {t: i + 1 for i, t in enumerate(teeth)}
    n = len(teeth) + 1
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    M[0, 0] = gp[1, L.I_TOT]
    lp = model.law_par
    for t, i in pos.items():
        g = 1 if t >= tz2 else 0
        M[i, i] = gp[g, L.I_P]
        if g == 1:
            M[0, i] = M[i, 0] = gp[1, L.I_CPL]
        if not model.teeth_coupled:
            K[i, i] += tooth_spring_tangent(t, phi, model.k_phi, gp)
        C[i, i] += spring_damping_tangent.py_func(0.0, gp[g, L.C_PHI], gp[g, L.N_C])
    if model.teeth_coupled:     # the springs of the teeth near the mesh: (C[S, S])^-1
        K[1:, 1:] += np.linalg.inv(model.tooth_compliance[np.ix_(teeth, teeth)])
    for c in range(nc):
        kt = rec[c, L.C_KT]
        ia = int(rec[c, L.C_TOOTH1])
        ib = tz2 + int(rec[c, L.C_TOOTH2])
        idx = [0, pos[ia], pos[ib]]
        g = np.array([rec[c, L.C_G2], rec[c, L.C_GA], rec[c, L.C_GB]])
        K[np.ix_(idx, idx)] += kt * np.outer(g, g)
        _kd, cd = contact_damping_tangents.py_func(rec[c, L.C_DELTA], 0.0, max(rec[c, L.C_FORCE], 1e-300),
                                           lp[L.C_CON], lp[L.M2], lp[L.M3])
        C[np.ix_(idx, idx)] += cd * np.outer(g, g)
    if damping:
        return M, K, C, teeth
    return M, K, teeth


def stability_limit(model: Model, torque: float, positions: int = 12) -> tuple[float, float]:
    """(critical Verlet step [s], highest natural frequency [rad/s]) of the loaded pair over one
    mesh cycle.

    The pair is linearised at static equilibrium under ``torque`` [N·m] (1 N·m if zero) at
    ``positions`` driver angles across one angular pitch; the generalised eigenproblem
    K x = w² M x gives the frequencies. Each mode i, with its modal damping ratio
    zeta_i = x_i^T C x_i / (2 w_i) (mass-normalised x_i), limits the step to
    2/w_i * (sqrt(1 + zeta_i²) - zeta_i): velocity Verlet with damping forces evaluated at the
    predicted velocity is stable up to there (2/w_i undamped). A deep, damped contact (m3 > 1)
    can make a lower but overdamped mode the limit. The equilibria come from one static sweep
    with continuation (tooth rotations carried from angle to angle); positions where it does
    not converge are left out.
    """
    angles = np.linspace(0.0, model.geometry[0].pitch_angle, positions, endpoint=False)
    load = torque if abs(torque) > 1e-9 else 1.0
    wmax = 0.0
    dt_crit = math.inf
    phi, te0, used = None, None, 0
    for theta1 in angles:
        st = solve_static(model, np.array([theta1]), load, phi0=phi, te0=te0, raise_on_failure=False)
        if not st.converged[0]:
            continue
        phi, te0 = st.phi_last, float(st.te[0])
        # a coupled model's mesh sits at the rim angles: the hubs less the body wind-up
        kb1, kb2 = model.body_stiffness
        rb1, rb2 = model.base_radii
        rim1 = theta1 - load * rb1 / rb2 / kb1
        rim2 = st.theta2[0] - load / kb2
        M, K, C, _t = linearized_system(model, rim1, rim2, phi, damping=True)
        lam, x = scipy.linalg.eigh(K, M)
        w = np.sqrt(np.maximum(lam, 0.0))
        h = 0.5 * np.einsum("ij,ik,kj->j", x, C, x)          # zeta_i * w_i [1/s]
        lim = 2.0 / np.maximum(np.hypot(w, h) + h, 1e-300)    # = 2/w (sqrt(1+zeta²) - zeta)
        wmax = max(wmax, float(w.max()))
        dt_crit = min(dt_crit, float(lim.min()))
        used += 1
    if used == 0:
        raise ValueError(f"no static equilibrium under {load} N·m found to estimate the highest natural frequency")
    return dt_crit, wmax


def highest_frequency(model: Model, torque: float, positions: int = 12) -> float:
    """Highest natural frequency [rad/s] of the loaded pair over one mesh cycle (see
    `stability_limit`)."""
    return stability_limit(model, torque, positions)[1]


def body_frequency(model: Model) -> float:
    """Highest natural frequency [rad/s] of the body springs alone (hub against rim and teeth);
    the tooth modes of `highest_frequency` are usually far above it."""
    gp = model.gear_par
    w = 0.0
    for g in range(2):
        if gp[g, L.K_BODY] > 0:
            i_rim = gp[g, L.I_TOT] - gp[g, L.I_HUB]
            inv = 1.0 / i_rim + (1.0 / gp[g, L.I_HUB] if g == 1 else 0.0)   # the driver's hub is prescribed
            w = max(w, math.sqrt(gp[g, L.K_BODY] * inv))
    return w


def stable_time_step(model: Model, torque: float, safety: float = 0.5) -> tuple[float, float]:
    """(dt [s], omega_max [rad/s]) for the explicit integrator: safety times the critical step
    of `stability_limit` (2/omega_max without damping)."""
    dt_crit, w = stability_limit(model, torque)
    if model.coupled:   # the body modes are not in the mesh linearisation
        wb = body_frequency(model)
        w = max(w, wb)
        dt_crit = min(dt_crit, 2.0 / wb)
    if not w > 0:
        raise ValueError("no loaded contact found to estimate the highest natural frequency")
    return safety * dt_crit, w


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


def simulate(model: Model, speed: float, speed_ramp: float, torque: float, torque_ramp: float,
             duration: float, dt: float | None = None, output_step: float = 1e-5,
             safety: float = 0.5, delta_max: float | None = None, raise_on_failure: bool = False,
             phi_quiet: float = 1e-9, energy_tol: float = ENERGY_TOL, load_table=None) -> DynamicResult:
    """Integrate from rest with the driver speed ramp 0 -> speed [rad/s] over speed_ramp [s]
    and the resisting torque ramp 0 -> torque [N·m] over torque_ramp [s], for duration [s].

    ``dt`` defaults to the stability bound; it is rounded down so that output_step [s] is a
    whole number of steps. ``delta_max`` [m] (default: a tenth of the module) bounds the
    penetration; the run stops there with a message naming time and step.
    ``phi_quiet`` [rad]: a tooth outside the mesh window is frozen once its rotation is below
    this (1e-9 rad moves the flank by about 3e-6 um) and its rate below phi_quiet times its
    natural frequency.
    ``load_table``: a resisting-torque profile (rows of time [s], torque [N·m], from 0 N·m at
    t = 0; `load_profile`) instead of the ramp to ``torque``; the step estimate then uses the
    profile's largest torque in magnitude, and the initial flank side its first nonzero torque.
    ``energy_tol`` [-]: the run stops ("energy growth") when the energy balance shows more
    energy in the pair than the work put in, by more than this fraction of the larger of the
    work and the stored energy: the signature of an unstable step.
    """
    for name, v in (("duration", duration), ("speed_ramp", speed_ramp), ("torque_ramp", torque_ramp), ("output_step", output_step)):
        if not (v > 0 and math.isfinite(v)):
            raise ValueError(f"{name}: must be positive, got {v}")
    table, torque, side = run_loads(load_table, torque)
    omega_max = float("nan")
    if dt is None or dt <= 0:
        dt, omega_max = stable_time_step(model, torque, safety)
    out_every = max(1, int(math.ceil(output_step / dt)))
    dt = output_step / out_every
    n_steps = int(round(duration / dt))
    n_out = n_steps // out_every + 1
    if delta_max is None:
        delta_max = 0.1 * model.geometry[0].spec.module
    o = [np.zeros(n_out) for _ in range(10)]
    theta2 = float(model.theta2_for_te(0.0, (1.0 if side >= 0 else -1.0) * model.backlash_offset))
    phi = np.zeros(model.n_teeth)
    dphi = np.zeros(model.n_teeth)
    omega_tooth = math.sqrt(model.k_phi.max() / model.gear_par[:, L.I_P].min())
    if model.teeth_coupled and not model.coupled:
        raise ValueError("tooth_compliance: the dynamics of teeth coupled through the body need the body "
                         "springs too (coupling.model = 'compliance' identifies both)")
    if model.coupled:
        from solver.mbs.kernels.explicit_coupled import verlet_coupled
        status, step, max_act = verlet_coupled(model.gear_par, model.pair_par, model.law_par, model.k_phi,
                                               model.tooth_compliance,
                                               float(speed), float(speed_ramp), float(torque), float(torque_ramp),
                                               table, dt, n_steps, out_every, 0.0, 0.0, theta2, 0.0, theta2, 0.0, phi, dphi,
                                               phi_quiet, phi_quiet * omega_tooth, float(delta_max), float(energy_tol), *o)
    else:
        status, step, max_act = verlet(model.gear_par, model.pair_par, model.law_par, model.k_phi,
                                       float(speed), float(speed_ramp), float(torque), float(torque_ramp),
                                       table, dt, n_steps, out_every, theta2, 0.0, phi, dphi,
                                       phi_quiet, phi_quiet * omega_tooth, float(delta_max), float(energy_tol), *o)
    n = min(n_out, step // out_every + 1)
    t, te, fmax, nc, react, ke, pe, work, diss, th2 = (a[:n] for a in o)
    msg = status_message(status, step, dt, delta_max, raise_on_failure)
    return DynamicResult(t, te, th2, fmax, nc.astype(int), react, ke, pe, work, diss, dt, step,
                         int(status), msg, omega_max, int(max_act))

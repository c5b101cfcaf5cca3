"""Time integration of the pair under the prescribed speed ramp and the load-torque ramp.

`simulate` runs the explicit velocity-Verlet kernel (`kernels/explicit.py`, or
`kernels/explicit_coupled.py` for a body-torsion coupled model) with a fixed step. By default the step comes from the scene's highest natural frequency: the model is
linearised at static equilibrium at several positions across one mesh cycle under the full
load, and ``dt = safety * 2 / omega_max`` (Verlet is stable for omega*dt < 2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from .kernels import layout as L
from .kernels.explicit import verlet
from .kernels.mesh import mesh_contacts, new_contact_buffer, tooth_spring_tangent
from .model import Model
from .statics import solve_static

STATUS_TEXT = {0: "ok", 1: "non-finite state", 2: "penetration beyond the bound", 3: "energy balance drift"}


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


def linearized_system(model: Model, theta1: float, theta2: float, phi: np.ndarray):
    """Mass and tangent stiffness over the free DOFs (theta2, then the teeth near the mesh).

    Returns (M, K, dof_teeth) in SI; the driver hub is prescribed and not a DOF.
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
    M[0, 0] = gp[1, L.I_TOT]
    for t, i in pos.items():
        g = 1 if t >= tz2 else 0
        M[i, i] = gp[g, L.I_P]
        if g == 1:
            M[0, i] = M[i, 0] = gp[1, L.I_CPL]
        K[i, i] += tooth_spring_tangent(t, phi, model.k_phi, gp)
    for c in range(nc):
        kt = rec[c, L.C_KT]
        ia = int(rec[c, L.C_TOOTH1])
        ib = tz2 + int(rec[c, L.C_TOOTH2])
        idx = [0, pos[ia], pos[ib]]
        g = np.array([rec[c, L.C_G2], rec[c, L.C_GA], rec[c, L.C_GB]])
        K[np.ix_(idx, idx)] += kt * np.outer(g, g)
    return M, K, teeth


def highest_frequency(model: Model, torque: float, positions: int = 12) -> float:
    """Highest natural frequency [rad/s] of the loaded pair over one mesh cycle.

    The pair is linearised at static equilibrium under ``torque`` [N·m] (1 N·m if zero) at
    ``positions`` driver angles across one angular pitch; the generalised eigenproblem
    K x = w² M x gives the frequencies.
    """
    angles = np.linspace(0.0, model.geometry[0].pitch_angle, positions, endpoint=False)
    load = torque if abs(torque) > 1e-9 else 1.0
    st = solve_static(model, angles, load, raise_on_failure=False)
    wmax = 0.0
    for a, theta1 in enumerate(angles):
        phi = _phi_at(model, theta1, load, st.te[a])
        # a coupled model's mesh sits at the rim angles: the hub less the body wind-up
        rim2 = st.theta2[a] - load / model.body_stiffness[1]
        M, K, _t = linearized_system(model, theta1, rim2, phi)
        lam = scipy.linalg.eigh(K, M, eigvals_only=True)
        wmax = max(wmax, math.sqrt(max(lam.max(), 0.0)))
    return wmax


def _phi_at(model: Model, theta1: float, torque: float, te0: float) -> np.ndarray:
    from .kernels.statics import static_sweep
    phi = np.zeros(model.n_teeth)
    out = [np.zeros(1), np.zeros(1, dtype=np.int64), np.zeros((1, model.teeth[0])), np.zeros(1, dtype=np.int64), np.zeros(1)]
    static_sweep(np.array([theta1]), float(torque), float(model.theta2_for_te(theta1, te0)), phi,
                 model.gear_par, model.pair_par, model.law_par, model.k_phi, 1e-10, 60, *out)
    return phi


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
    """(dt [s], omega_max [rad/s]) for the explicit integrator: safety * 2 / omega_max."""
    w = highest_frequency(model, torque)
    if model.coupled:
        w = max(w, body_frequency(model))
    if not w > 0:
        raise ValueError("no loaded contact found to estimate the highest natural frequency")
    return safety * 2.0 / w, w


def simulate(model: Model, speed: float, speed_ramp: float, torque: float, torque_ramp: float,
             duration: float, dt: float | None = None, output_step: float = 1e-5,
             safety: float = 0.5, delta_max: float | None = None, raise_on_failure: bool = False,
             phi_quiet: float = 1e-9) -> DynamicResult:
    """Integrate from rest with the driver speed ramp 0 -> speed [rad/s] over speed_ramp [s]
    and the resisting torque ramp 0 -> torque [N·m] over torque_ramp [s], for duration [s].

    ``dt`` defaults to the stability bound; it is rounded down so that output_step [s] is a
    whole number of steps. ``delta_max`` [m] (default: a tenth of the module) bounds the
    penetration; the run stops there with a message naming time and step.
    ``phi_quiet`` [rad]: a tooth outside the mesh window is frozen once its rotation is below
    this (1e-9 rad moves the flank by about 3e-6 um) and its rate below phi_quiet times its
    natural frequency.
    """
    for name, v in (("duration", duration), ("speed_ramp", speed_ramp), ("torque_ramp", torque_ramp), ("output_step", output_step)):
        if not (v > 0 and math.isfinite(v)):
            raise ValueError(f"{name}: must be positive, got {v}")
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
    theta2 = float(model.theta2_for_te(0.0, (1.0 if torque >= 0 else -1.0) * model.backlash_offset))
    phi = np.zeros(model.n_teeth)
    dphi = np.zeros(model.n_teeth)
    omega_tooth = math.sqrt(model.k_phi.max() / model.gear_par[:, L.I_P].min())
    if model.coupled:
        from .kernels.explicit_coupled import verlet_coupled
        status, step, max_act = verlet_coupled(model.gear_par, model.pair_par, model.law_par, model.k_phi,
                                               float(speed), float(speed_ramp), float(torque), float(torque_ramp),
                                               dt, n_steps, out_every, 0.0, 0.0, theta2, 0.0, theta2, 0.0, phi, dphi,
                                               phi_quiet, phi_quiet * omega_tooth, float(delta_max), *o)
    else:
        status, step, max_act = verlet(model.gear_par, model.pair_par, model.law_par, model.k_phi,
                                       float(speed), float(speed_ramp), float(torque), float(torque_ramp),
                                       dt, n_steps, out_every, theta2, 0.0, phi, dphi,
                                       phi_quiet, phi_quiet * omega_tooth, float(delta_max), *o)
    n = min(n_out, step // out_every + 1)
    t, te, fmax, nc, react, ke, pe, work, diss, th2 = (a[:n] for a in o)
    msg = "ok"
    if status:
        msg = f"{STATUS_TEXT[status]} at t = {step * dt:.6g} s (step {step}, dt = {dt:.3g} s)"
        if status == 2:
            msg += f"; bound {delta_max * 1e6:.4g} um"
        if raise_on_failure:
            raise DivergenceError(msg)
    return DynamicResult(t, te, th2, fmax, nc.astype(int), react, ke, pe, work, diss, dt, step,
                         int(status), msg, omega_max, int(max_act))

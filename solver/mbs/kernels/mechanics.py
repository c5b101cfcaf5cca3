"""The pair's mechanics that every time-stepping loop shares (numba): the prescribed driver
motion, the load torque, the arrowhead accelerations, the energies and the dissipation power.

``act[:nact]`` are the active (integrated) teeth; ``rec[:nc]`` the contact records
(`layout` C_* columns); ``mdl`` the model arrays (gear_par, pair_par, law_par, k_phi,
tooth_compliance, `layout.ContactParts`) as the stepping kernels take them. SI units.
"""
from solver.mbs.kernels import layout as L
from solver.mbs.kernels import njit
from solver.mbs.kernels.laws import contact_energy, series_contact, series_energy, signed_pow, spring_energy


@njit(cache=True, no_cfunc_wrapper=True)
def driver_motion(t, speed, ramp):
    """Driver angle [rad], speed [rad/s] and acceleration [rad/s²] of the speed ramp."""
    if t < ramp:
        acc = speed / ramp
        return 0.5 * acc * t * t, acc * t, acc
    return speed * (t - 0.5 * ramp), speed, 0.0


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def driver_acc_left(t, speed, ramp):
    """Left limit of the driver acceleration at t [rad/s²]."""
    return speed / ramp if t <= ramp else 0.0


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def driver_speed(t, speed, ramp):
    """Driver speed [rad/s] of the ramp (continuous, with a kink at the ramp end)."""
    return speed * t / ramp if t < ramp else speed


@njit(cache=True, no_cfunc_wrapper=True)
def load_torque(t, torque, ramp, table):
    """Resisting torque on gear 2 [N m] at time t [s]: ramped from zero to ``torque`` over
    ``ramp`` [s], or, when ``table`` (n x 2: time [s], torque [N m], times increasing) has
    rows, linear between its points and held at its ends."""
    n = table.shape[0]
    if n == 0:
        if t < ramp:
            return torque * t / ramp
        return torque
    if t <= table[0, 0]:
        return table[0, 1]
    for k in range(1, n):
        if t <= table[k, 0]:
            t0 = table[k - 1, 0]
            return table[k - 1, 1] + (table[k, 1] - table[k - 1, 1]) * (t - t0) / (table[k, 0] - t0)
    return table[n - 1, 1]


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def drive(t, par, table):
    """The loads at t [s] of the controls par (`layout` SPEED, SPEED_RAMP, TORQUE, TORQUE_RAMP)
    and the load profile ``table`` (`load_torque`): driver angle [rad], speed [rad/s] and
    acceleration [rad/s²], and the resisting torque on gear 2 [N m]."""
    th1, w1, acc1 = driver_motion(t, par[L.SPEED], par[L.SPEED_RAMP])
    return th1, w1, acc1, load_torque(t, par[L.TORQUE], par[L.TORQUE_RAMP], table)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def kick_gear_par(gp, dt, imex):
    """The gear_par of the Verlet kicks' arrowhead solve: a copy of gp, with the tooth inertia
    I_P + dt/4*c_phi [kg m²] where the tooth-root dampers are taken implicitly (imex; step dt
    [s], `explicit`)."""
    gpk = gp.copy()
    if imex:
        for g in range(2):
            gpk[g, L.I_P] += 0.25 * dt * gp[g, L.C_PHI]
    return gpk


@njit(cache=True, no_cfunc_wrapper=True)
def arrowhead_accelerations(q, act, nact, gp, acc):
    """Solve the arrowhead systems of the plain pair for the force part of the accelerations.

    Gear-1 teeth get (Q_phi)/I_P only: the prescribed driver's inertial coupling
    -I_cpl/I_P * theta1'' is the caller's (the explicit loop applies it as exact velocity
    increments, since theta1'' jumps at the end of the speed ramp). Fills acc of the active
    teeth; returns (theta2'', S1, R1) with the driver torque T = S1*theta1'' + R1.
    """
    tz2 = int(gp[1, L.TOOTH0])
    s = gp[1, L.I_TOT]
    rhs = q[1]
    for a in range(nact):
        i = act[a]
        if i >= tz2:
            c = gp[1, L.I_CPL]
            s -= c * c / gp[1, L.I_P]
            rhs -= c * q[2 + i] / gp[1, L.I_P]
    a2 = rhs / s
    s1 = gp[0, L.I_TOT]
    r1 = -q[0]
    for a in range(nact):
        i = act[a]
        if i >= tz2:
            acc[i] = (q[2 + i] - gp[1, L.I_CPL] * a2) / gp[1, L.I_P]
        else:
            acc[i] = q[2 + i] / gp[0, L.I_P]
            s1 -= gp[0, L.I_CPL] * gp[0, L.I_CPL] / gp[0, L.I_P]
            r1 += gp[0, L.I_CPL] * acc[i]
    return a2, s1, r1


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def mesh_energies(ke, pe, w1, w2, teeth, act, nact, mdl, rec, nc):
    """(kinetic, potential) energy [J]: ``ke`` and ``pe`` of the bodies plus the active teeth,
    their springs and the contacts. w1, w2 [rad/s]: rates of the bodies that carry the teeth
    of gear 1 and 2; ``teeth`` rows: rotations, rates. The plain pair's bodies are the rigid
    gears: ke = I_tot1*w1²/2 + I_tot2*w2²/2, pe = 0."""
    gp, lp, kphi = mdl[0], mdl[2], mdl[3]
    tz2 = int(gp[1, L.TOOTH0])
    phi = teeth[0]
    dphi = teeth[1]
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        w = w2 if g == 1 else w1
        ke += gp[g, L.I_CPL] * w * dphi[i] + 0.5 * gp[g, L.I_P] * dphi[i] * dphi[i]
        pe += spring_energy(phi[i], kphi[i], gp[g, L.N_K])
    for c in range(nc):
        if rec[c, L.C_CLOC] == 0.0:
            pe += contact_energy(rec[c, L.C_DELTA], lp[L.K_CON], lp[L.M1])
        else:
            pe += series_energy(rec[c, L.C_DCON], rec[c, L.C_CLOC], lp[L.K_CON], lp[L.M1])
    return ke, pe


@njit(cache=True, no_cfunc_wrapper=True)
def dissipation_power(dphi, act, nact, mdl, rec, nc, series=None):
    """Power [W] of the tooth-spring dampers at the rates dphi, of the contact dampers and of
    the flank friction (F_t*v_s >= 0, where a friction force F_t is recorded). ``series``: the
    model's `ContactParts` series part (the contact law in series with a local compliance,
    whose elastic force then is the series law's); None or left out: the plain law (numba
    compiles no series code for it)."""
    gp, lp = mdl[0], mdl[2]
    tz2 = int(gp[1, L.TOOTH0])
    p = 0.0
    for a in range(nact):
        i = act[a]
        g = 1 if i >= tz2 else 0
        if gp[g, L.C_PHI] != 0.0:
            p += gp[g, L.C_PHI] * signed_pow(dphi[i], gp[g, L.N_C]) * dphi[i]
    damped = lp[L.C_CON] != 0.0     # without a contact damper the force is the elastic one, exactly
    for c in range(nc):
        d = rec[c, L.C_DELTA]
        if damped and d > 0.0:
            fel = lp[L.K_CON] * d ** lp[L.M1]
            if series is not None:
                # the elastic part of a contact in series with the local compliance: the series law's
                if rec[c, L.C_CLOC] != 0.0:
                    fel = series_contact(d, rec[c, L.C_CLOC], lp[L.K_CON], lp[L.M1])[1]
            p += (rec[c, L.C_FORCE] - fel) * rec[c, L.C_DDELTA]
        ft = rec[c, L.C_FT]
        if ft != 0.0:
            p += ft * rec[c, L.C_VS]
    return p

"""Pieces shared by the time-stepping loops (explicit, coupled explicit, implicit; numba):
status codes, the active-tooth set, output records and the output-time guards.

Status codes: 0 ok, 1 non-finite state, 2 penetration beyond the bound, 3 energy growth.

Teeth away from the mesh are left out of the integration, rigid to their hub; a tooth joins
the set when the pre-search names it a candidate and leaves it once it is outside the
candidates and at rest (rotation below ``phi_quiet`` [rad], rate below ``dphi_quiet``
[rad/s]). Arrays: ``act`` the active tooth indices (first ``nact`` valid), ``active`` and
``incand`` per-tooth 0/1 flags, ``q`` the generalised forces (hubs first, then the teeth).
The flags are int64 arrays, not bool: numba then reuses the int64 allocation it compiles
anyway instead of compiling np.zeros once more for bool.
"""
from numba import njit

from solver.mbs.kernels.layout import C_FORCE

OK = 0
NONFINITE = 1
PENETRATION = 2
ENERGY = 3


@njit(cache=True)
def freeze_quiet_teeth(act, nact, active, incand, phi, dphi, acc, q, phi_quiet, dphi_quiet):
    """Set the quiet teeth outside the candidates exactly to rest and drop them from the set.

    Their rotation, rate, acceleration and generalised force become zero (rigid to the hub,
    whose inertia already holds them). Returns the new number of active teeth.
    """
    a = 0
    while a < nact:
        i = act[a]
        if not incand[i] and abs(phi[i]) < phi_quiet and abs(dphi[i]) < dphi_quiet:
            phi[i] = 0.0
            dphi[i] = 0.0
            acc[i] = 0.0
            q[2 + i] = 0.0
            active[i] = False
            nact -= 1
            act[a] = act[nact]
        else:
            a += 1
    return nact


@njit(cache=True)
def clear_candidates(incand, pairs, npair, tz2):
    """Reset the candidate flags of this step's pre-search pairs (gear-2 teeth offset by tz2)."""
    for p in range(npair):
        incand[int(pairs[p, 0])] = False
        incand[tz2 + int(pairs[p, 1])] = False


@njit(cache=True)
def loaded_contacts(rec, nc):
    """Number of the nc contact records that carry a positive normal force."""
    n = 0
    for c in range(nc):
        if rec[c, C_FORCE] > 0.0:
            n += 1
    return n


@njit(cache=True)
def record_output(o, t, te, fmax, n_loaded, react, ke, pe, work, diss, theta2,
                  o_time, o_te, o_fmax, o_nc, o_react, o_ke, o_pe, o_work, o_diss, o_theta2):
    """Write output record o: time [s], TE [m], largest contact force over the interval [N],
    loaded contacts, driver torque [N m], kinetic, potential, input and dissipated energy [J],
    driven hub angle [rad]."""
    o_time[o] = t
    o_te[o] = te
    o_fmax[o] = fmax
    o_nc[o] = n_loaded
    o_react[o] = react
    o_ke[o] = ke
    o_pe[o] = pe
    o_work[o] = work
    o_diss[o] = diss
    o_theta2[o] = theta2


@njit(cache=True)
def checked_status(status, finite, ke, pe, e0, work, diss, energy_tol):
    """Status after the checks at an output instant: NONFINITE when the state is not finite,
    ENERGY when the balance shows a growth kinetic + potential - initial + dissipated - work
    [J] above energy_tol times the energy scale, else ``status`` unchanged."""
    if not finite:
        return NONFINITE
    if status == OK and ke + pe - e0 + diss - work > energy_tol * max(abs(work), ke + pe, diss):
        return ENERGY
    return status

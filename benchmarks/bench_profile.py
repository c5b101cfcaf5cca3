"""Where the explicit solver's time goes: one velocity-Verlet step of the paper's dynamic case
against its parts, each timed in a numba loop at a loaded state of the solid Table 1 pair.

Parts: the contact search (pre-search + closed forms, `kernels/gearmesh.py mesh_contacts`), the
generalised forces, the arrowhead solve and the energy/dissipation bookkeeping, for a small
active set (the teeth near the mesh) and for every tooth active. The whole step comes from
`simulate` runs of 20 ms at 100 rad/s (CPU time per step, best of 3).
Run: python benchmarks/bench_profile.py   (writes results/benchmarks/profile.csv)
"""
from __future__ import annotations

import sys
import time

import common  # noqa: I001  (first: pins BLAS to one thread before numpy loads)
import numpy as np
from numba import njit

from solver.mbs.kernels.gearmesh import generalized_forces, mesh_contacts
from solver.mbs.kernels.mechanics import arrowhead_accelerations, dissipation_power

COLUMNS = ("part", "active_teeth", "ns_per_call", "note")
N_CALLS = 200_000


@njit(cache=False)
def _loop_contacts(n, state, mdl, buf):
    """``n`` contact searches at the angles and tooth states ``state`` (theta1, theta2, phi,
    dphi) of the contact search's arrays ``mdl`` (`gearmesh.contact_geo`), into the buffers ``buf`` (rec, pairs)."""
    th1, th2, phi, dphi = state
    s = 0
    for k in range(n):
        nc, npair = mesh_contacts((th1 + 1e-12 * k, th2, 100.0, 100.0), phi, dphi, mdl, buf)
        s += nc
    return s


@njit(cache=False)
def _loop_forces(n, contacts, state, mdl, out):
    """``n`` force evaluations and arrowhead solves: the ``contacts`` (rec, nc), the tooth
    ``state`` (phi, dphi, active teeth, their count), the model arrays ``mdl`` (k_phi, gear)
    and the outputs ``out`` (q, acc)."""
    rec, nc = contacts
    phi, dphi, act, nact = state
    kphi, gp = mdl
    q, acc = out
    s = 0.0
    for _k in range(n):
        generalized_forces(rec, nc, phi, dphi, act, nact, kphi, gp, 50.0, q)
        a2, _s1, _r1 = arrowhead_accelerations(q, act, nact, gp, acc)
        s += a2
    return s


@njit(cache=False)
def _loop_bookkeeping(n, dphi, act, nact, mdl, rec, nc):
    s = 0.0
    for _k in range(n):
        s += dissipation_power(dphi, act, nact, mdl, rec, nc)
    return s


def per_call(fn, *args) -> float:
    fn(10, *args)
    best = float("inf")
    for _ in range(3):
        c0 = time.process_time()
        fn(N_CALLS, *args)
        best = min(best, time.process_time() - c0)
    return best / N_CALLS * 1e9


def main(argv=None) -> int:
    from solver.mbs.dynamics import simulate
    from solver.mbs.kernels import layout as L
    from solver.mbs.kernels.gearmesh import contact_geo, new_contact_buffer
    from solver.mbs.stability import stable_time_step
    from solver.mbs.statics import solve_static
    m = common.model("solid", "paper")     # the plain contact search and forces
    gp, pp, lp = m.gear_par, m.pair_par, m.law_par
    geo = contact_geo(gp, pp, lp)
    mdl = (gp, pp, lp, m.k_phi, m.tooth_compliance, geo[3])
    tz2 = int(gp[1, L.TOOTH0])
    theta1 = np.radians(2.0)
    st = solve_static(m, np.array([theta1]), 50.0)
    phi = st.phi_last
    dphi = np.zeros(m.n_teeth)
    rec, pairs = new_contact_buffer()
    nc, npair = mesh_contacts((theta1, st.theta2[0], 100.0, 100.0), phi, dphi, geo, (rec, pairs))
    rows = [dict(part="contact search (mesh_contacts)", active_teeth=None,
                 ns_per_call=per_call(_loop_contacts, (theta1, st.theta2[0], phi, dphi), geo, (rec, pairs)),
                 note=f"{npair} candidate pairs, {nc} contacts")]
    near = sorted({int(pairs[p, 0]) for p in range(npair)} | {tz2 + int(pairs[p, 1]) for p in range(npair)})
    q = np.zeros(m.n_teeth + 2)
    acc = np.zeros(m.n_teeth)
    for label, act in (("near the mesh", np.array(near, dtype=np.int64)), ("all teeth", np.arange(m.n_teeth, dtype=np.int64))):
        rows.append(dict(part="forces + arrowhead solve", active_teeth=act.size,
                         ns_per_call=per_call(_loop_forces, (rec, nc), (phi, dphi, act, act.size), (m.k_phi, gp), (q, acc)),
                         note=label))
        rows.append(dict(part="dissipation power (energy balance)", active_teeth=act.size,
                         ns_per_call=per_call(_loop_bookkeeping, dphi, act, act.size, mdl, rec, nc), note=label))
    dt, _w = stable_time_step(m, 50.0)
    for pq in (1e-9, 1e-6):
        simulate(m, 100.0, 0.01, 50.0, 0.01, 1e-3, dt=dt)
        tim, r = common.best_of(lambda: simulate(m, 100.0, 0.01, 50.0, 0.01, 0.02, dt=dt, phi_quiet=pq), 3)
        rows.append(dict(part=f"whole step (simulate, phi_quiet {pq:g})", active_teeth=r.max_active_teeth,
                         ns_per_call=tim["cpu_min_s"] / r.steps * 1e9, note=f"{r.steps} steps; active = most at once"))
    common.write_table("profile", "Explicit step profile, solid Table 1 pair (CPU ns per call, best of 3)", rows, COLUMNS)
    return 0


if __name__ == "__main__":
    sys.exit(main())

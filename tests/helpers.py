"""Shared test scenes and checks, imported by the tests as ``from helpers import ...`` (pytest puts
tests/ on the path): the solid paper pair, the scenes as overrides, the raw damping, and checks of
the mechanics. The small pairs are embedded scenes: load_scene("small_pair"), load_scene("small_lightened")."""
from study.scene import load_scene

# the raw damping coefficients the scenes had before the damping ratio (mesh mode at 0.14 %)
RAW_DAMPING = {"contact.c_con": 3640.0, "gear1.spring.c_phi": 0.062, "gear2.spring.c_phi": 0.062}


def solid_scene(**overrides):
    """The paper pair with a solid driven gear (the embedded scene paper_solid) on the paper's plain
    model (no FE needed), plus overrides."""
    return load_scene("paper_solid").replace(**{"coupling.model": "paper", **overrides})


def scene_overrides(name: str) -> dict:
    """The fields an embedded scene sets over the paper example, by dotted path (its title
    aside): ``--set`` or a study's [scene] table that give the scene on the paper example."""
    import tomllib

    from study.scene import scene_path

    def flat(table, prefix=""):
        for k, v in table.items():
            if isinstance(v, dict):
                yield from flat(v, f"{prefix}{k}.")
            elif prefix or k != "title":
                yield f"{prefix}{k}", v
    return dict(flat(tomllib.loads(scene_path(name).read_text())))


def assert_energy_closes_at_second_order(model, torque=50.0):
    """Undamped run from the paper's ramps (4 ms, no tooth frozen, so the balance measures the
    integrator alone): the energy residual stays bounded (no secular drift) and falls about
    4x per halved step."""
    import numpy as np

    from solver.mbs.dynamics import simulate
    from solver.mbs.stability import stable_time_step
    dt0, _ = stable_time_step(model, torque)
    errs = []
    for dt in (dt0, dt0 / 2):
        r = simulate(model, 100.0, 0.01, torque, 0.01, 0.004, dt=dt, output_step=1e-5, phi_quiet=0.0)
        assert r.status == 0 and np.all(r.dissipated == 0)
        errs.append(np.max(np.abs(r.energy_error)))
        assert errs[-1] < 1e-5 * np.max(np.abs(r.work))
    assert 3.0 < errs[0] / errs[1] < 5.5


def slow_transient_against_statics(model, torque=50.0):
    """Dynamics at 1 rad/s (1 ms ramps, 50 ms) against the static STE at the same driver
    angles past 1.5 deg: (TE difference [m], the run, the static result)."""
    import math

    import numpy as np

    from solver.mbs.dynamics import simulate
    from solver.mbs.kernels.mechanics import driver_motion
    from solver.mbs.statics import solve_static
    r = simulate(model, 1.0, 0.001, torque, 0.001, 0.05, output_step=1e-4)
    assert r.status == 0
    th1 = np.array([driver_motion(t, 1.0, 0.001)[0] for t in r.time])
    sel = th1 > math.radians(1.5)
    st = solve_static(model, th1[sel], torque)
    return r.te[sel] - st.te, r, st


def loaded_mesh_state(m, angle_deg: float, phi_scale: float, seed: int = 3):
    """(theta1, theta2 [rad], tooth rotations phi [rad], teeth near the mesh, contact records,
    their count) of model ``m`` at driver angle ``angle_deg``, 5 um into the mesh, the teeth near
    the mesh turned at random by about ``phi_scale`` [rad]."""
    import math

    import numpy as np

    from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
    th1 = math.radians(angle_deg)
    th2 = m.theta2_for_te(th1, m.backlash_offset + 5.0e-6)
    phi = np.zeros(m.n_teeth)
    rec, pairs = new_contact_buffer()
    _nc, npair = mesh_contacts((th1, th2, 0.0, 0.0), phi, phi, contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
    teeth = sorted({int(p) for p in pairs[:npair, 0]} | {m.teeth[0] + int(p) for p in pairs[:npair, 1]})
    phi[teeth] = np.random.default_rng(seed).normal(scale=phi_scale, size=len(teeth))
    nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, np.zeros_like(phi), contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
    return th1, th2, phi, teeth, rec, nc


def mesh_potential(m, th1, th2, phi) -> float:
    """Plain-Python potential energy [J] of model ``m``: the tooth springs and the contacts, from
    the kernel's contact records: k delta^(m1+1)/(m1+1) of the penetration, or with a local
    compliance in series the law's share plus c F^2/2 (`laws.series_energy`)."""
    import numpy as np

    from solver.mbs.kernels import layout as L
    from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
    from solver.mbs.kernels.laws import series_energy
    rec, pairs = new_contact_buffer()
    nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, np.zeros_like(phi), contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
    n = m.gear_par[:, L.N_K]
    z1 = m.teeth[0]
    e = sum(m.k_phi[i] * abs(phi[i]) ** (n[0 if i < z1 else 1] + 1) / (n[0 if i < z1 else 1] + 1) for i in range(len(phi)))
    k, m1 = m.law_par[L.K_CON], m.law_par[L.M1]
    return e + sum(series_energy.py_func(rec[c, L.C_DCON], rec[c, L.C_CLOC], k, m1) if rec[c, L.C_CLOC] != 0.0
                   else k * rec[c, L.C_DELTA] ** (m1 + 1) / (m1 + 1) for c in range(nc))


def assert_forces_are_minus_the_energy_gradient(m, th1, th2, phi, teeth, rec, nc):
    """The kernel's generalised forces on both hubs and the teeth near the mesh equal
    -d(mesh_potential)/dq by central differences."""
    import numpy as np
    import pytest

    from solver.mbs.kernels.gearmesh import generalized_forces
    act = np.array(teeth, dtype=np.int64)
    q = np.zeros(m.n_teeth + 2)
    generalized_forces(rec, nc, phi, np.zeros_like(phi), act, len(act), m.k_phi, m.gear_par, 0.0, q)
    h = 1e-8  # rad: central differences of energies ~1e-3 J lose digits below this
    fd1 = -(mesh_potential(m, th1 + h, th2, phi) - mesh_potential(m, th1 - h, th2, phi)) / (2 * h)
    fd2 = -(mesh_potential(m, th1, th2 + h, phi) - mesh_potential(m, th1, th2 - h, phi)) / (2 * h)
    assert q[0] == pytest.approx(fd1, rel=1e-5)
    assert q[1] == pytest.approx(fd2, rel=1e-5)
    for i in teeth:
        p1, p0 = phi.copy(), phi.copy()
        p1[i] += h
        p0[i] -= h
        fd = -(mesh_potential(m, th1, th2, p1) - mesh_potential(m, th1, th2, p0)) / (2 * h)
        assert q[2 + i] == pytest.approx(fd, rel=1e-5, abs=1e-6)


def small_scene(**kw):
    """The small 24-tooth pair (the small_pair scene, contact ratio 1.6), one mesh pitch of rotation."""
    return load_scene("small_pair").replace(**{"quasi_static.rotation": 15.0, "quasi_static.angle_step": 0.25,
                                               "quasi_static.torque": 100.0, **kw})


# the small pair's driven gear lightened: a web of 8 mm with 4 holes
LIGHT = {"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4, "gear2.body.hole_radius": 3.0,
         "gear2.body.hole_circle_radius": 19.5}


def compiled_call(kernel):
    """A compiled function that calls ``kernel`` with the arguments it is given and returns what
    it returns: a kernel that only other kernels call is compiled without its Python wrapper,
    so a test reaches its machine code through a compiled caller, as the loops do. The caller
    names the kernel's own arguments (numba inlines a kernel marked ``inline="always"`` into its
    caller, which it cannot do through ``*args``)."""
    import inspect

    import numba
    names = ", ".join(inspect.signature(kernel.py_func).parameters)
    space = {"kernel": kernel}
    exec(f"def call({names}):\n    return kernel({names})\n", space)
    return numba.njit(space["call"])


def series_force(delta: float, c: float, k: float, m1: float) -> float:
    """F [N] with (F/k)^(1/m1) + c F = delta [m] (bisection: independent of the kernels' Halley
    iteration; c >= 0)."""
    lo, hi = 0.0, k * delta**m1
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if (mid / k) ** (1 / m1) + c * mid < delta:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)

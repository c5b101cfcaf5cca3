"""Shared fixtures: small solid scenes that need no FE, and their models."""
import os

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pytest  # noqa: E402

from study.scene import default_scene  # noqa: E402

# 24 teeth, m = 3 mm, small solid bodies: a coarse, fast FE body (about 1 s)
SMALL_PAIR = {"pair.backlash": 0.1}
for _g in (1, 2):
    SMALL_PAIR.update({f"gear{_g}.module": 3.0, f"gear{_g}.teeth": 24, f"gear{_g}.fillet_radius": 0.9,
                       f"gear{_g}.face_width": 20.0, f"gear{_g}.body.rim_height": 4.0,
                       f"gear{_g}.body.web_height": 14.0, f"gear{_g}.body.hub_height": 6.0,
                       f"gear{_g}.body.web_thickness": 20.0, f"gear{_g}.body.holes": 0})


# a small lightened pair (24 teeth, m 2 mm, a coarse FE body) whose driven gear has a thin web
# with 8 holes
SMALL_LIGHTENED = {
    "gear1.module": 2.0, "gear1.teeth": 24, "gear2.module": 2.0, "gear2.teeth": 24,
    "gear1.body.rim_height": 3.0, "gear1.body.web_height": 12.0, "gear1.body.hub_height": 3.0,
    "gear1.body.web_thickness": 17.0, "gear1.body.holes": 0,
    "gear2.body.rim_height": 3.0, "gear2.body.web_height": 12.0, "gear2.body.hub_height": 3.0,
    "gear2.body.web_thickness": 8.0, "gear2.body.holes": 8, "gear2.body.hole_radius": 3.0,
    "gear2.body.hole_circle_radius": 12.5, "fe.mesh_size": 1.0,
}


# the raw damping coefficients the scenes had before the damping ratio (mesh mode at 0.14 %)
RAW_DAMPING = {"contact.c_con": 3640.0, "gear1.spring.c_phi": 0.062, "gear2.spring.c_phi": 0.062}


def solid_scene(**overrides):
    """The paper pair with a solid driven gear (no FE needed), plus overrides."""
    from study import setup
    return setup.solid_scene(default_scene(), gears=(2,)).replace(**overrides)


@pytest.fixture
def private_fe_cache(tmp_path, monkeypatch):
    """FE results of the test go to a fresh disk cache, and nothing the FE cache holds in
    memory (spring maps, influence coefficients, factorised bodies, coupling fits) leaks in or out."""
    from study.inputs.cache import FE_CACHE
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "cache"))
    FE_CACHE.clear()
    yield FE_CACHE
    FE_CACHE.clear()


@pytest.fixture(scope="session")
def paper_solid_scene():
    return solid_scene()


@pytest.fixture(scope="session")
def paper_solid_model(paper_solid_scene):
    from study.setup import build_scene_model
    return build_scene_model(paper_solid_scene)


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

"""The loaded pair's highest natural frequency from its laws alone (`pair_frequency_estimate`:
no static equilibrium, nothing compiled; what a study's ``--max-time`` estimate steps with)
against the pair linearised at static equilibrium over a mesh cycle (`stability_limit`, the
tooth-root dampers implicit, as the runs step): the shipped pairs and variants stiffer or
softer in each law the estimate reads."""
import math

import pytest

from solver.mbs.stability import pair_frequency_estimate, stability_limit
from study.scene import load_scene
from study.scene_model import build_scene_model, flankless_model
from study.sweep.cost import estimate_choice

PLAIN = {"gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform", "coupling.model": "none"}

CASES = [
    ("paper", {}),
    ("small_pair", {}),
    ("small_pair", {"dynamic.torque": 200.0}),                                    # a stiffer contact tangent
    ("small_pair", {"contact.m1": 1.2, "gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0}),
    ("small_pair", {"gear1.spring.k_phi": 1.06e7, "gear2.spring.k_phi": 1.06e7}),   # stiff roots
    ("small_pair", {"gear1.pressure_angle": 25.0, "gear2.pressure_angle": 25.0}),
]


@pytest.mark.parametrize("name,over", CASES, ids=[f"{n}-{'-'.join(o) or 'as shipped'}" for n, o in CASES])
def test_estimate_within_five_percent_of_the_linearised_pair(name, over):
    scene = load_scene(name).replace(**PLAIN, **over)
    torque = scene.dynamic.torque
    exact = stability_limit(build_scene_model(scene), torque, implicit_dampers=True)[1]
    est = pair_frequency_estimate(flankless_model(scene), torque)
    assert 0.95 * exact < est < 1.01 * exact


def test_estimate_grows_with_the_load_as_the_contact_tangent():
    """The contact tangent m1 F/delta grows as F^((m1-1)/m1): the estimate rises with the load
    and is the same for the coast flanks (a negative torque)."""
    m = flankless_model(load_scene("small_pair").replace(**PLAIN))
    w = [pair_frequency_estimate(m, t) for t in (5.0, 50.0, 500.0)]
    assert w[0] < w[1] < w[2]
    assert pair_frequency_estimate(m, -50.0) == w[1]


def test_estimate_refuses_a_coupled_model():
    import dataclasses

    from solver.mbs.kernels import layout as L
    m = flankless_model(load_scene("small_pair").replace(**PLAIN))
    gear_par = m.gear_par.copy()
    gear_par[1, L.K_BODY] = 1e5                              # a body-torsion spring [N·m/rad]
    with pytest.raises(ValueError, match="plain model only"):
        pair_frequency_estimate(dataclasses.replace(m, gear_par=gear_par), 10.0)


def test_study_estimate_solves_no_statics_where_the_bound_is_undamped(monkeypatch):
    """The sweep's estimate steps a plain, undamped-contact scene from the laws (no static
    sweep); a scene with a contact damper keeps the linearised bound, a given step is kept."""
    import solver.mbs.equilibria as equilibria

    calls = []
    real = equilibria.loaded_equilibria
    monkeypatch.setattr(equilibria, "loaded_equilibria", lambda *a, **k: calls.append(a) or real(*a, **k))
    scene = load_scene("small_pair")
    model, choice = estimate_choice(scene)
    assert calls == [] and choice.reason == "estimated from the pair's laws"
    assert choice.dt == pytest.approx(0.9 * 2.0 / pair_frequency_estimate(model, scene.dynamic.torque))
    _, given = estimate_choice(scene.replace(**{"dynamic.time_step": 1e-6}))
    assert calls == [] and given.dt == 1e-6 and math.isnan(given.omega_max)
    _, damped = estimate_choice(scene.replace(**{"contact.c_con": 2917.0}))     # (a value no other test builds)
    assert calls and damped.reason != "estimated from the pair's laws"

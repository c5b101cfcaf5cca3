"""The body-coupled models in dynamics agree with themselves: the modes, critical speeds and
damping their linearisation reports are those their time integration shows, and their
energy balance closes, as for the plain model. The paper pair (lightened driven gear) in
each model; its FE body is computed once (about 40 s from an empty cache) and cached."""
import math

import numpy as np
import pytest

import study
from solver.mbs.dynamics import energy_error_limit, simulate
from solver.mbs.kernels import layout as L
from solver.mbs.modes import modal_analysis
from solver.mbs.ringdown import ring_down
from study.archive.order_tracking import order_cut, order_map
from study.scene_model import build_scene_model

MODELS = ("none", "body-torsion", "compliance")
TORQUE = 50.0
RUNUP_S = 0.3          # 0 -> 1.3 x the 1Z critical speed: ~0.4 % of it per decay time at 5 %


@pytest.fixture(scope="module")
def models():
    return {cm: build_scene_model(study.default_scene().replace(**{"coupling.model": cm})) for cm in MODELS}


@pytest.fixture(scope="module")
def modes(models):
    return {cm: modal_analysis(m, TORQUE) for cm, m in models.items()}


def critical_1z(model, md) -> float:
    """The modal 1Z critical speed [rad/s] of the driver: mesh frequency = Z2 x driven speed."""
    z1, z2 = model.teeth
    return 2 * math.pi * float(np.nanmean(md.frequency[0])) * z2 / (z1 * z2)


@pytest.fixture(scope="module")
def runups(models, modes):
    """A coarse run-up of each model through its 1Z critical speed, at the default step."""
    out = {}
    for cm, m in models.items():
        w_end = 1.3 * critical_1z(m, modes[cm])
        out[cm] = (w_end, simulate(m, w_end, RUNUP_S, TORQUE, 0.01, RUNUP_S, output_step=5e-6))
    return out


def test_coupled_linearisation_has_the_body_dofs(models, modes):
    """A coupled model's modes hold its body modes (rims and hubs on the body springs) and the
    mesh mode below them; the plain model has none."""
    assert "body" not in modes["none"].kind
    for cm in ("body-torsion", "compliance"):
        md = modes[cm]
        assert md.kind[0] == "mesh" and "body" in md.kind
        body = [i for i, k in enumerate(md.kind) if k == "body"]
        assert np.nanmean(md.frequency[0]) < min(np.nanmean(md.frequency[i]) for i in body)
        assert models[cm].gear_par[0, L.K_BODY] > 0


@pytest.mark.slow
@pytest.mark.parametrize("cm", MODELS)
def test_mesh_mode_critical_speed_is_the_runup_peak(cm, models, modes, runups):
    """The modal 1Z critical speed within 3 % of where the run-up's mesh-order DTE peaks
    (computed order tracking, blocks of half a driven revolution)."""
    m = models[cm]
    w_end, r = runups[cm]
    assert r.status in (0, 6) and r.time[-1] == pytest.approx(RUNUP_S)
    z1, z2 = m.teeth
    crit = critical_1z(m, modes[cm])
    speed, order, amp = order_map(r.time, r.te * 1e6, (w_end, RUNUP_S), (z1, z2), revs=0.5, speed_min=0.5 * crit,
                                  hop=1 / 32)
    cut = order_cut(speed, order, amp, float(z2), 1.0)
    peak = speed[int(np.argmax(cut))]
    assert peak == pytest.approx(crit, rel=0.03)
    # a resonance, not the edge of the window
    assert cut.max() > 2.0 * cut[speed > 1.2 * crit].max()


@pytest.mark.parametrize("cm", MODELS)
def test_free_decay_shows_the_modal_and_the_requested_ratio(cm, models, modes):
    """The simulated free decay, where the modal ratio is nearest its mean over the mesh
    period, within 5 % of the modal ratio there and of the requested 5 %."""
    md = modes[cm]
    assert np.nanmean(md.damping[0]) == pytest.approx(0.05, rel=1e-4)
    j = int(np.nanargmin(np.abs(md.damping[0] - np.nanmean(md.damping[0]))))
    rd = ring_down(models[cm], TORQUE, float(md.frequency[0, j]), float(md.damping[0, j]),
                   driver_angle=float(md.position[j]))
    assert rd.damping == pytest.approx(md.damping[0, j], rel=0.05)
    assert rd.damping == pytest.approx(0.05, rel=0.05)
    assert rd.frequency == pytest.approx(md.frequency[0, j], rel=0.01)


@pytest.mark.slow
@pytest.mark.parametrize("cm", ("body-torsion", "compliance"))
def test_coupled_energy_balance_closes_within_the_plain_margin(cm, runups):
    """Through the resonance at the default step: the coupled model's energy-balance error,
    against the mesh's potential energy and against the guard's limit, no larger than the
    plain model's (the compliance model's set switches booked)."""
    plain = runups["none"][1]
    r = runups[cm][1]
    assert r.status == 0 and plain.status == 0

    def ratios(res):
        e = np.abs(res.energy_error)
        return e.max() / res.potential.max(), np.max(e / energy_error_limit(res))
    assert ratios(r)[0] <= ratios(plain)[0]
    assert ratios(r)[1] <= ratios(plain)[1]


def test_coupled_step_is_the_stiffness_bound_with_implicit_tooth_dampers(models):
    """The coupled kernels take the linear tooth-root dampers implicitly, as the plain one:
    its default step is 0.9 of the undamped bound, not the bound of the (heavily damped)
    tooth joints."""
    from solver.mbs.stability import implicit_dampers_apply, stability_limit, stable_time_step
    m = models["compliance"]
    assert implicit_dampers_apply(m)
    dt_imex, _w = stable_time_step(m, TORQUE, implicit_dampers=True)
    dt_free, w = stability_limit(m, TORQUE, implicit_dampers=True)
    assert dt_imex == pytest.approx(0.9 * dt_free) and dt_free <= 2.0 / w * (1 + 1e-12)
    assert dt_imex > 3.0 * stable_time_step(m, TORQUE)[0]


def test_a_run_solves_its_loaded_equilibria_once(monkeypatch):
    """The damping conversion, the modes, the free decay, the method choice and the step bound
    of one run share one set of loaded equilibria (solved once; a load the run's forces
    exceed may ask for a second set under that load)."""
    import solver.mbs.equilibria as eqm
    from study.run import run_scene
    loads = []
    solve = eqm._solve

    def counted(model, torque, positions):
        loads.append(torque)
        return solve(model, torque, positions)
    monkeypatch.setattr(eqm, "_solve", counted)
    sc = study.default_scene().replace(**{"coupling.model": "compliance", "dynamic.torque": 47.0,
                                          "dynamic.duration": 0.004, "dynamic.ramp_time": 0.002,
                                          "quasi_static.enabled": False})
    ds = run_scene(sc)
    assert ds.attrs["dynamic_status"] == "ok" and "mesh_mode_damping_decay" in ds.attrs
    assert loads.count(47.0) == 1

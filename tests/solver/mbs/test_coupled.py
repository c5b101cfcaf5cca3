"""Body-torsion coupling: limits, the static wind-up, identification, and the gain against the
FE reference in double contact."""
import dataclasses
import math

import numpy as np
import pytest
from helpers import LIGHT, assert_energy_closes_at_second_order, slow_transient_against_statics, small_scene, solid_scene

from solver.fe.ltca import mesh_points
from solver.identify.coupling import body_torsion_fit, body_windup
from solver.mbs.model import build_model
from solver.mbs.statics import solve_static
from study.scene import SceneError
from study.scene_model import build_scene_model
from study.verify import fe_reference as ref_mod

# (the shared FE cache: what these tests check reads the FE bodies, not how they were cached,
# and a body's bits do not depend on which test filled the cache, tests/study/inputs/test_condensed_inputs.py)


def with_body_springs(model, k_body, ratio=0.02):
    g1, g2, law, mat = model.inputs
    return build_model(dataclasses.replace(g1, body_stiffness=k_body[0], body_damping_ratio=ratio),
                       dataclasses.replace(g2, body_stiffness=k_body[1], body_damping_ratio=ratio), law, mat)


def test_plain_model_is_unchanged_and_stiff_body_springs_recover_it(paper_solid_model):
    angles = np.radians(np.arange(0.0, 12.0, 0.25))
    plain = solve_static(paper_solid_model, angles, 50.0)
    assert not paper_solid_model.coupled
    again = solve_static(with_body_springs(paper_solid_model, (math.inf, math.inf)), angles, 50.0)
    assert np.array_equal(plain.te, again.te)                      # coupling off: bit-identical
    stiff = solve_static(with_body_springs(paper_solid_model, (1e15, 1e15)), angles, 50.0)
    assert stiff.te == pytest.approx(plain.te, abs=1e-13)


def test_static_body_windup_is_a_constant_shift(paper_solid_model):
    """With a rigid rim the body springs carry the gear torques: the hubs' TE is the plain
    model's (mesh phase moved by the driver's wind-up) plus rb1*M1/k1 + rb2*T/k2."""
    angles = np.radians(np.arange(0.0, 12.0, 0.25))
    kb = (1.5e6, 0.9e6)
    T = 50.0
    coupled = solve_static(with_body_springs(paper_solid_model, kb), angles, T)
    rb1, rb2 = paper_solid_model.base_radii
    shift = T * rb1 / rb2 / kb[0]
    plain = solve_static(paper_solid_model, angles - shift, T)
    expected = plain.te + rb1 * shift + body_windup(T, (rb1, rb2), kb) - rb1 * shift
    assert coupled.te == pytest.approx(expected, abs=1e-13)
    assert body_windup(T, (rb1, rb2), kb) == pytest.approx(rb1 * (T * rb1 / rb2) / kb[0] + rb2 * T / kb[1])


def test_body_torsion_fit_splits_the_shared_compliance():
    c_tot = np.array([2.5, 2.6, 2.4]) * 1e-9
    c_adj = np.array([1.4, 1.5, 1.3]) * 1e-9
    fit = body_torsion_fit(c_tot, c_adj, 2e-3, 0.05)
    assert fit.c_body == pytest.approx(1.4e-9)
    assert fit.k_body == pytest.approx(0.05**2 / 1.4e-9)
    assert 1 / fit.k_tooth + 1 / (fit.k_body * (2e-3 / 0.05) ** 2) == pytest.approx(1 / fit.k_total)
    with pytest.raises(ValueError, match="body compliance"):
        body_torsion_fit(c_tot, c_adj * 3, 2e-3, 0.05)
    prof = body_torsion_fit(c_tot, c_adj, 2e-3, 0.05, 0.047, k_profile=3000.0)
    c_tooth = c_tot - 1.4e-9
    assert prof.k_tooth[0] == 3000.0 and prof.k_tooth == pytest.approx(3000.0 * c_tooth[0] / c_tooth)
    assert prof.k_body == fit.k_body and prof.pivot_radius == 0.047


def test_coupling_model_is_validated():
    with pytest.raises(SceneError, match="coupling.model"):
        solid_scene(**{"coupling.model": "full"})


UNDAMPED = {"gear1.spring.c_phi": 0.0, "gear2.spring.c_phi": 0.0, "contact.c_con": 0.0}
K_BODY = (1.5e6, 1.0e6)    # N m/rad, about the FE values of the paper's solid body


def test_coupled_dynamics_conserve_energy_at_second_order():
    assert_energy_closes_at_second_order(with_body_springs(build_scene_model(solid_scene(**UNDAMPED)), K_BODY, ratio=0.0))


def test_coupled_slow_transient_follows_coupled_statics(paper_solid_model):
    """At 1 rad/s the coupled dynamics settle on the coupled static STE, which is the plain
    STE plus the body wind-up: the rims really carry the teeth and the hubs the TE."""
    m = with_body_springs(paper_solid_model, K_BODY)
    diff, r, st = slow_transient_against_statics(m)
    # ringing of the lightly damped modes after each contact change: the rims alone (without
    # the hubs) ring against the mesh, so more than the plain pair's 0.1-0.15 um (0.29 um seen)
    assert abs(diff.mean()) < 0.03e-6 and np.abs(diff).max() < 0.4e-6
    assert np.max(np.abs(r.energy_error)) < 1e-3 * r.work[-1]
    plain = solve_static(paper_solid_model, st.angle, 50.0)
    assert (st.te - plain.te).mean() == pytest.approx(body_windup(50.0, m.base_radii, K_BODY), rel=0.02)


def _double_contact_errors(scene, coupling="body-torsion"):
    """(plain-FE, coupled) STE errors [m] against the FE reference where the rigid geometry has
    two pairs in the path of contact, and the single-contact errors."""
    from solver import units
    from study.inputs.coupling import plain_fe_springs
    from study.scene_model import gear_setup
    angles = np.radians(np.arange(0.0, scene.quasi_static.rotation, 0.25))
    res, model, _ = ref_mod.reference(scene, angles)
    nominal = np.array([np.count_nonzero(mesh_points(model, a).kind == 1) for a in angles])
    lin = scene.replace(**{"gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0, "coupling.model": "paper"})
    sp = []
    for g in (1, 2):
        k = plain_fe_springs(gear_setup(scene, g)) / units.spring_stiffness_to_si(1.0)
        sp.append((k, np.ones_like(k)))
    plain = solve_static(build_scene_model(lin, tuple(sp)), angles, scene.quasi_static.torque).te - res.te
    coupled = solve_static(build_scene_model(scene.replace(**{"coupling.model": coupling})), angles,
                           scene.quasi_static.torque).te - res.te
    two, one = nominal == 2, nominal == 1
    assert two.any() and one.any()
    return plain[two], coupled[two], plain[one], coupled[one]


@pytest.mark.slow
@pytest.mark.parametrize("coupling", ["body-torsion", "compliance"])
@pytest.mark.parametrize("body", ["solid", "lightened"])
def test_coupled_model_closes_the_double_contact_gap(body, coupling):
    """Per-tooth FE springs count the body wind-up once per loaded tooth: too stiff in double
    contact. Both coupled models, from the same FE body, are closer to the FE reference."""
    s = small_scene(**{"fe.mesh_size": 1.2, **(LIGHT if body == "lightened" else {})})
    p2, c2, p1, c1 = _double_contact_errors(s, coupling)
    assert p2.mean() < 0                                      # plain: too stiff in double contact
    assert np.sqrt(np.mean(c2**2)) < 0.5 * np.sqrt(np.mean(p2**2))
    assert np.sqrt(np.mean(c1**2)) < np.sqrt(np.mean(p1**2)) + 2e-8


def test_coupled_step_above_the_stability_bound_is_caught(paper_solid_model):
    """Twice the critical step of the coupled pair: the guard stops the run and names why."""
    from solver.mbs.dynamics import DivergenceError, simulate
    from solver.mbs.stability import stable_time_step
    m = with_body_springs(paper_solid_model, K_BODY)
    dt, _w = stable_time_step(m, 50.0)          # half the critical step
    ok = simulate(m, 100.0, 0.002, 50.0, 0.002, 0.002, dt=dt)
    assert ok.status == 0
    with pytest.raises(DivergenceError) as e:
        simulate(m, 100.0, 0.002, 50.0, 0.002, 0.004, dt=4 * dt, raise_on_failure=True)
    msg = str(e.value)
    assert ("non-finite" in msg or "penetration" in msg or "energy growth" in msg) and "t = " in msg


def test_scipy_peer_refuses_a_coupled_model(paper_solid_model):
    from solver.peers.scipy_dynamics import simulate_scipy
    with pytest.raises(ValueError, match="coupling"):
        simulate_scipy(with_body_springs(paper_solid_model, K_BODY), 100.0, 0.01, 50.0, 0.01, 1e-4)


def test_implicit_integrator_refuses_and_auto_picks_explicit_for_a_coupled_model(paper_solid_model):
    from solver.mbs.implicit import simulate_implicit
    from solver.mbs.method import choose_method
    coupled = with_body_springs(paper_solid_model, (1.5e6, 0.9e6))
    with pytest.raises(ValueError, match="dynamic.method"):
        simulate_implicit(coupled, 100.0, 0.002, 50.0, 0.002, 0.001, dt=1e-6)
    choice = choose_method(coupled, 50.0, 10.0, "auto")     # 10 s: plain would go implicit
    assert choice.method == "explicit" and "coupling" in choice.reason


def test_validation_workflow_writes_archive_and_figures(tmp_path):
    import xarray as xr

    from study.verify.validation import MODELS
    from workflows import validation
    s = small_scene(**{"fe.mesh_size": 1.8, **LIGHT})
    path = tmp_path / "s.toml"
    path.write_text(s.to_toml())
    out = tmp_path / "v" / "validation.nc"
    assert validation.main([str(path), "-o", str(out), "--step", "0.5"]) == 0
    with xr.open_dataset(out) as ds:
        assert list(ds["model"].values) == list(MODELS)
        assert ds["error_mean"].sel(model="fe-reference").values.tolist() == [0.0, 0.0]
        assert np.isnan(ds["hole_amplitude"].sel(pair="solid", model="fe-reference"))
        # 15 deg of the driver turn the driven gear through less than one period of its 4 holes
        # (90 deg): the hole order is not resolved, and the archive says so instead of a fit
        assert np.isnan(ds["hole_amplitude"].sel(pair="lightened", model="fe-reference"))
        assert "undefined (NaN)" in ds["hole_amplitude"].attrs["comment"]
        assert ds["ste"].attrs["units"] == "um"
        root = s.gear2.module * (s.gear2.teeth / 2 - s.gear2.dedendum)
        piv = ds["compliance_pivot_radius"].values
        assert np.all((root - s.gear2.body.rim_height <= piv) & (piv <= root))
        assert np.all(ds["compliance_k_body"].values > 0) and np.all(ds["compliance_fit_rms"].values < 0.2)
    assert {p.name for p in out.parent.glob("*.png")} == {"ste_solid.png", "ste_lightened.png", "load_sharing_solid.png",
                                                          "load_sharing_lightened.png", "errors.png"}


def test_compliance_scene_runs_statics_and_dynamics_from_its_fe_body(tmp_path):
    """`coupling.model = "compliance"` end to end on the small lightened pair: the FE fit, the
    static STE and a short dynamic run, recorded in the archive."""
    from study.run import run_scene
    s = small_scene(**{"fe.mesh_size": 1.8, **LIGHT, "coupling.model": "compliance",
                       "dynamic.duration": 0.004, "dynamic.ramp_time": 0.002, "dynamic.speed": 100.0,
                       "dynamic.torque": 100.0})
    ds = run_scene(s)
    assert ds.attrs["coupling"] == "compliance" and ds.attrs["teeth_coupled"] == 1
    assert ds.attrs["dynamic_status"] == "ok"
    assert np.all(ds.attrs["body_stiffness_N_m_rad"] > 0)
    root = s.gear2.module * (s.gear2.teeth / 2 - s.gear2.dedendum)
    assert root - s.gear2.body.rim_height <= ds.attrs["pivot_radius_mm"][1] <= root
    assert np.all(np.isfinite(ds["ste"])) and np.all(np.isfinite(ds["dte"]))
    # the DTE after the ramp oscillates about the STE level
    late = ds["dte"].sel(time=slice(0.003, None))
    assert abs(float(late.mean()) - float(ds["ste"].mean())) < 0.1 * float(ds["ste"].mean() - ds.attrs["backlash_offset_um"])


@pytest.mark.parametrize("name, torque", [("small_pair", 1500.0), ("small_lightened", 300.0)])
def test_compliance_statics_converge_well_above_the_nominal_load(name, torque):
    """Loads of 6 to 30 x the nominal, flanks well within the model's range: every position of a
    pitch is in equilibrium (a Newton iterate that lost contact once restarted from the deflected
    teeth and cycled), and the mesh deflects further under the full load than under half of it."""
    from study.scene import load_scene
    m = build_scene_model(load_scene(name))
    angles = np.linspace(0.0, m.geometry[0].pitch_angle, 12, endpoint=False)
    full = solve_static(m, angles, torque, raise_on_failure=False)
    half = solve_static(m, angles, 0.5 * torque, raise_on_failure=False)
    assert full.converged.all() and half.converged.all(), full.message + "; " + half.message
    assert np.all(full.te > half.te)

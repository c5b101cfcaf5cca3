"""Per-tooth FE springs: symmetry of the map, independent checks (ISO 6336-1, energy method), cache."""
import dataclasses
import math

import numpy as np
import pytest

from solver.fe import body as fe
from solver.geometry import gear_geometry
from solver.identify.weber import pitch_point_depth, weber_deflection
from solver.peers.energy_method import tooth_compliance
from solver.peers.iso6336 import blank_factor, single_stiffness
from study.inputs import springs
from study.inputs.gearsetup import gear_setup
from study.scene import default_scene, load_scene

pytestmark = pytest.mark.usefixtures("private_fe_cache")


def small_scene(**kw):
    """The small 24-tooth pair (the small_pair scene), the driven gear with a web of 8 mm and 4 holes."""
    return load_scene("small_pair").replace(**{"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4,
                                               "gear2.body.hole_radius": 3.0, "gear2.body.hole_circle_radius": 19.5, **kw})


def test_solid_body_gives_the_same_stiffness_to_every_tooth():
    s = small_scene().solid()
    k = springs.fe_stiffness(gear_setup(s, 2), teeth=[0, 5, 11, 17])
    assert np.ptp(k) / k.mean() < 2e-3


def test_map_has_the_hole_symmetry_and_rotates_with_the_holes():
    s = small_scene()
    k = springs.fe_stiffness(gear_setup(s, 2))     # 4 holes, 24 teeth: period 6 teeth
    assert np.ptp(k) / k.mean() > 0.01            # the holes do show
    assert np.allclose(k, np.roll(k, 6), rtol=3e-3)
    # moving the holes by one tooth pitch moves the map by one tooth
    k_rot = springs.fe_stiffness(gear_setup(small_scene(**{"gear2.body.hole_phase": 15.0}), 2))
    assert np.allclose(k_rot, np.roll(k, 1), rtol=3e-3)


def test_ratio_converges_under_mesh_refinement():
    s = small_scene()
    _, r0, _ = springs.fe_ratio(gear_setup(s, 2))
    _, r1, _ = springs.fe_ratio(gear_setup(s.replace(**{"fe.mesh_size": 3.0 / 6}), 2))   # default is module / 4
    assert np.max(np.abs(r1 / r0 - 1)) < 5e-3


def test_solid_gear_needs_no_fe(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("FE called for a solid gear")
    monkeypatch.setattr(springs, "fe_stiffness", boom)
    s = small_scene()
    k, r = springs.tooth_springs(gear_setup(s, 1))
    assert np.all(k == s.gear1.spring.k_phi) and np.all(r == 1.0)
    k, r = springs.tooth_springs(gear_setup(s.replace(**{"gear2.spring.stiffness": "uniform"}), 2))
    assert np.all(k == s.gear2.spring.k_phi)


def test_spring_options_and_cache(monkeypatch, tmp_path, private_fe_cache):
    s = small_scene()
    k, r = springs.tooth_springs(gear_setup(s, 2))
    assert np.allclose(k, s.gear2.spring.k_phi * r)
    assert 0.5 < r.min() < r.max() < 1.0          # thinner web and holes: softer than solid
    files = list((tmp_path / "cache" / "fe").glob("*.nc"))
    assert len(files) == 2                        # the lightened body and its solid reference
    private_fe_cache.clear()
    calls = []
    monkeypatch.setattr("solver.fe.mesh.mesh_body", lambda *a, **kw: calls.append(1))
    k2, r2 = springs.tooth_springs(gear_setup(s, 2))   # from disk, no mesh
    assert not calls and np.array_equal(k2, k)
    # 'fe': the nonlinear spring passes through the FE point at the reference moment
    s_fe = s.replace(**{"gear2.spring.stiffness": "fe"})
    k_nl, _ = springs.tooth_springs(gear_setup(s_fe, 2))
    g = gear_geometry(s.tooth_spec(2))
    lever = fe.load_case(g, 0, g.root_radius).lever
    m_ref = s.quasi_static.torque / g.base_radius * lever
    k_lin = springs.fe_stiffness(gear_setup(s, 2))
    phi_fe = m_ref / k_lin
    phi_nl = (m_ref / (k_nl * 1e-3)) ** (1 / s.gear2.spring.n_k)   # N·mm -> N·m
    assert np.allclose(phi_nl, phi_fe, rtol=1e-10)


# ---------------------------------------------------------------- Table 1, independent checks

@pytest.fixture(scope="module")
def table1():
    import os
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        old = os.environ.get("LIGHTGEAR_CACHE")
        os.environ["LIGHTGEAR_CACHE"] = d
        s = default_scene()
        g = gear_geometry(s.tooth_spec(1))
        body = s.body_spec(1)
        setup = gear_setup(s, 1)
        k = {t: springs.fe_stiffness(dataclasses.replace(setup, body=dataclasses.replace(body, web_thickness=t * 1e-3)), teeth=[0])[0]
             for t in (17.0, 10.0, 5.0)}
        if old is None:
            del os.environ["LIGHTGEAR_CACHE"]
        else:
            os.environ["LIGHTGEAR_CACHE"] = old
    lever = fe.load_case(g, 0, g.root_radius).lever
    compliance = {t: lever**2 / kt for t, kt in k.items()}       # m/N along the line of action
    return s, g, body, compliance


def test_solid_tooth_against_the_energy_method_with_sainsot_body(table1):
    s, g, body, c = table1
    pe = tooth_compliance(g, s.material_spec(), g.root_radius - body.rim_height - body.web_height - body.hub_height)
    # the two 2D models agree within the spread of the analytic formula (about 10 %)
    assert pe["total"] / c[17.0] == pytest.approx(1.0, abs=0.12)
    assert pe["foundation"] > pe["bending"]    # a 67-tooth gear: the body dominates at the pitch point


def contact_compliance(s, g):
    f = s.quasi_static.torque / g.base_radius
    R = g.base_radius * math.tan(g.spec.pressure_angle) / 2
    h = pitch_point_depth(g)   # to the centreline, where the FE spring is read
    return weber_deflection(f, g.spec.face_width, R, (h, h), s.material_spec()) / f


def test_solid_pair_against_iso_6336_single_stiffness(table1):
    s, g, body, c = table1
    G = s.material_spec().youngs_modulus / 2.6
    r_web = g.root_radius - body.rim_height
    r_bore = r_web - body.web_height - body.hub_height
    # ISO's c' has no bore: take out the torsion of web and hub down to the bore (exact for an annulus)
    windup = g.base_radius**2 / (4 * math.pi * G * body.web_thickness) * (1 / r_bore**2 - 1 / r_web**2)
    pair = 2 * (c[17.0] - windup) + contact_compliance(s, g)
    c_fe = 1 / (pair * 1e6) / (g.spec.face_width * 1e3)       # N/(mm·um)
    c_iso = single_stiffness(67, 67, 1.25, 20.0)
    assert c_fe / c_iso == pytest.approx(1.0, abs=0.2)       # ISO's stated spread


def test_web_thickness_trend_follows_iso_blank_factor(table1):
    s, g, body, c = table1
    cc = contact_compliance(s, g)
    ratios = []
    for t in (10.0, 5.0):
        fe_ratio = (2 * c[17.0] + cc) / (c[17.0] + c[t] + cc)     # pair with one thinned gear
        iso = blank_factor(t, 17.0, body.rim_height * 1e3, 1.5)
        ratios.append(fe_ratio)
        assert fe_ratio == pytest.approx(iso, abs=0.06)
    assert 1.0 > ratios[0] > ratios[1]


def test_identification_recovers_a_known_spring_and_reads_the_fe():
    from solver.identify.pivot import fit_pivot, fit_power_law, lever
    rb, r_q, k = 0.047, 0.0445, 9.0e3
    t = np.linspace(-0.45, -0.2, 6)
    c = lever(rb, t, r_q) ** 2 / k
    r_fit, k_fit, err = fit_pivot(rb, t, c)
    assert r_fit == pytest.approx(r_q, rel=1e-10) and k_fit == pytest.approx(k, rel=1e-10) and err < 1e-10
    phi = np.array([1e-4, 3e-4, 1e-3])
    assert fit_power_law(1060.0 * phi**1.1, phi) == pytest.approx((1060.0, 1.1), rel=1e-10)
    fit, u, comp = springs.identify_spring(gear_setup(small_scene(), 1), radii=5)
    assert np.all(np.diff(comp) > 0)                     # higher load point: more compliant
    assert fit.n == pytest.approx(1.0, abs=1e-9)          # the body FE is linear
    g = gear_geometry(small_scene().tooth_spec(1))
    assert 0.5 * g.root_radius < fit.pivot_radius < g.pitch_radius
    assert fit.rms_rel_error < 0.1


def test_lightened_scene_runs_with_its_fe_springs_in_the_archive():
    from study.run import run_scene
    # the paper's model: its springs are k_phi scaled by the FE ratio (the default, the
    # compliance model, takes its tooth springs from the coupling fit instead)
    lite = small_scene(**{"quasi_static.rotation": 15.0, "quasi_static.angle_step": 0.5, "coupling.model": "paper"})
    solid = lite.solid()
    ds = run_scene(lite, static=True, dynamic=False)
    assert ds.attrs["coupling_model"] == "paper"
    k = ds["tooth_stiffness"].sel(gear=2).values
    r = ds["stiffness_ratio"].sel(gear=2).values
    assert ds["tooth_stiffness"].attrs["units"] == "N mm" and ds["tooth_stiffness"].attrs["unit_symbol"] == "N·mm/rad^n_k"
    assert np.allclose(k, lite.gear2.spring.k_phi * r) and r.max() < 1.0
    assert np.all(ds["stiffness_ratio"].sel(gear=1).values == 1.0)
    ste_solid = run_scene(solid, static=True, dynamic=False)["ste"].values
    # softer driven teeth: more transmission error at every angle
    assert np.all(ds["ste"].values > ste_solid)


def test_a_run_stores_the_body_fields_its_render_draws_and_the_render_factorises_no_body(private_fe_cache, monkeypatch,
                                                                                          tmp_path):
    """`lightgear run` then `lightgear render`: the run, holding the factorised body (its
    coupling fit and strength), stores the fields of the render's two teeth; the render (a new
    process: nothing held) reads them and meshes, assembles and factorises nothing, and they are
    bit for bit what the render would have solved itself. A study's point stores none, and a run
    that factorises no body (all its FE read from the disk cache) does not factorise one for them."""
    from solver.fe import condense
    from study.plan import RunOptions
    from study.run import run_fields, run_scene
    lite = small_scene(**{"quasi_static.rotation": 15.0, "quasi_static.angle_step": 0.5})    # the default model
    stored = lambda: sorted((tmp_path / "cache" / "fe").glob("fields-*.npz"))    # noqa: E731

    def refuse(*a, **k):
        raise AssertionError("a body was assembled and factorised")

    run_fields(lite, None, RunOptions(warn=False, archive=False))     # a study's point: its speed first
    assert stored() == []
    ds = run_scene(lite, dynamic=False, warn=False)                    # the body still held from the point
    assert len(stored()) == 1
    teeth = springs.render_teeth(ds["tooth_stiffness"].sel(gear=2).values)
    k2 = ds["tooth_stiffness"].sel(gear=2).values[:lite.gear2.teeth]
    assert teeth == [int(np.argmax(k2)), int(np.argmin(k2))] and k2[teeth[0]] > k2[teeth[1]]

    private_fe_cache.clear()                                          # the render's own process
    with monkeypatch.context() as m:
        m.setattr(fe, "assemble", refuse)
        m.setattr(condense, "assemble_condensed", refuse)
        fields = springs.archive_body_fields(ds)
        assert list(fields) == [2] and [f.tooth for f in fields[2]] == teeth
        stored()[0].unlink()                                          # a run with every FE result on disk
        run_scene(lite, dynamic=False, warn=False)
        assert stored() == []                                         # ... holds no body: none made for the fields

    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "empty"))
    private_fe_cache.clear()
    solved = springs.body_fields(gear_setup(lite, 2), teeth)           # what the render solved without them
    for a, b in zip(fields[2], solved, strict=True):
        assert a.tooth == b.tooth and a.load_N == b.load_N
        for name in ("points", "triangles", "thickness", "web", "displacement", "von_mises", "load_point"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert np.abs(fields[2][0].displacement).max() > 0 and fields[2][0].von_mises.max() > 0

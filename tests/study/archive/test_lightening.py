"""Mass, inertia and root stress of each gear in run archives and sweep scalars."""
import math

import numpy as np
import pytest

from solver.inertia import gear_mass
from study.inputs import springs
from study.inputs.gearsetup import gear_setups
from study.inputs.springs import lightening_dataset
from study.scene import load_scene


def small_scene(**kw):
    """The small 24-tooth pair (the small_pair scene), the driven gear with a web of 8 mm and 4 holes."""
    return load_scene("small_pair").replace(**{"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4,
                                               "gear2.body.hole_radius": 3.0, "gear2.body.hole_circle_radius": 19.5, **kw})


def _no_fe(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("FE started")
    monkeypatch.setattr("solver.fe.mesh.mesh_body", boom)


def test_lightened_gear_root_stress_from_the_spring_fe_cached_with_the_map(private_fe_cache, monkeypatch):
    scene = small_scene()
    ds = lightening_dataset(scene)
    s1, s2 = gear_setups(scene)
    for g, s in ((1, s1), (2, s2)):
        mp = gear_mass(s.geometry, s.body, s.material.density)
        assert float(ds["mass"].sel(gear=g)) == pytest.approx(mp.mass, rel=1e-12)
        assert float(ds["inertia"].sel(gear=g)) == pytest.approx(mp.inertia * 1e6, rel=1e-12)   # kg mm2
    assert float(ds["mass_saving"].sel(gear=1)) == 0.0 and float(ds["mass_saving"].sel(gear=2)) > 10.0
    sigma = ds["root_stress"].sel(gear=2).values
    assert np.all(np.isfinite(sigma)) and np.all(sigma > 0)
    assert np.allclose(sigma, np.roll(sigma, 6), rtol=0.03)           # 4 holes on 24 teeth: period 6
    assert float(ds["root_stress_max"].sel(gear=2)) == sigma.max()
    solid = float(springs.root_stress(s2.solid(), teeth=[0])[0]) / 1e6
    assert float(ds["root_stress_ratio"].sel(gear=2)) == pytest.approx(sigma.max() / solid, rel=1e-12)
    # the solid driver runs no FE for its springs: no stress (NaN and the reason), but it is its
    # own stress reference, ratio 1 by definition
    assert np.isnan(ds["root_stress"].sel(gear=1)).all() and np.isnan(float(ds["root_stress_max"].sel(gear=1)))
    assert float(ds["root_stress_ratio"].sel(gear=1)) == 1.0
    assert "gear 1: solid body" in ds["root_stress_max"].attrs["not_computed"]
    assert "1 by definition for a solid gear" in ds["root_stress_ratio"].attrs["comment"]
    for v in ds.data_vars:
        assert ds[v].attrs["source"] and ds[v].attrs["units"]
    assert ds["mass"].attrs["source"].startswith("geometry") and ds["root_stress"].attrs["source"].startswith("FE")
    # stored with the stiffness map: read back from disk without any FE
    private_fe_cache.clear()
    _no_fe(monkeypatch)
    again = lightening_dataset(scene)
    np.testing.assert_array_equal(again["root_stress"].values, ds["root_stress"].values)


def test_no_fe_is_started_for_the_root_stress_alone(monkeypatch, private_fe_cache):
    _no_fe(monkeypatch)
    ds = lightening_dataset(small_scene(**{"gear2.spring.stiffness": "uniform", "gear1.spring.stiffness": "uniform"}))
    assert np.isnan(ds["root_stress_max"]).all()
    assert "gear 2: springs 'uniform'" in ds["root_stress_max"].attrs["not_computed"]
    # a lightened gear is not its own reference: without the FE its ratio is unknown
    assert ds["root_stress_ratio"].values.tolist()[0] == 1.0 and np.isnan(float(ds["root_stress_ratio"].sel(gear=2)))
    assert float(ds["mass_saving"].sel(gear=2)) > 10.0


def test_run_archive_summary_and_sweep_scalars_carry_the_gear_outputs(capsys, monkeypatch):
    """A run archive (solid driver, lightened driven gear on uniform springs: no FE) holds
    the per-gear variables; `summarize` gives them as the sweep scalars of the same names and
    `print_summary` prints them; a study that asks for geometry outputs only runs no solve."""
    import study.run
    from study.archive.summary import summarize
    from study.report.summary import print_summary
    from study.sweep import engine
    from study.sweep.outputs import SCALARS, outputs_from_table
    scene = small_scene(**{"gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform", "quasi_static.rotation": 2.0,
                           "quasi_static.angle_step": 0.5})
    ds = study.run.run_scene(scene, static=True, dynamic=False)
    s = summarize(ds)
    for g in (1, 2):
        for name in ("mass", "mass_saving", "inertia", "root_stress_max", "root_stress_ratio"):
            key = f"{name}_gear{g}"
            assert key in SCALARS
            np.testing.assert_equal(s[key], float(ds[name].sel(gear=g)))
            assert SCALARS[key].units == ds[name].attrs["units"]
    print_summary(ds, "x.nc", 1.0)
    out = capsys.readouterr().out
    assert f"gear 2: mass {s['mass_gear2']:.4f} kg ({s['mass_saving_gear2']:.1f} % saved" in out
    assert "root stress not computed" in out
    # geometry-only outputs: no model, no solve, no FE
    monkeypatch.setattr(study.run, "run_scene", lambda *a, **k: (_ for _ in ()).throw(AssertionError("solve")))
    _no_fe(monkeypatch)
    r = engine.run_point(scene, outputs_from_table({"scalars": ["mass_gear2", "mass_saving_gear2", "inertia_gear2",
                                                                "root_stress_max_gear2"]}))
    assert r["status"] == "ok", r["message"]
    assert r["scalars"]["mass_saving_gear2"] == pytest.approx(s["mass_saving_gear2"], rel=1e-12)
    assert math.isnan(r["scalars"]["root_stress_max_gear2"])

"""What each analysis reads, the tasks a study runs (one static analysis for the points that
differ only in dynamic fields) and the archive layout that follows from it."""
import dataclasses
from collections import Counter

import numpy as np
import pytest
import xarray as xr
from sweep_cases import tiny_study

from study.scene import default_scene
from study.sweep.engine import run_sweep
from study.sweep.outputs import ANALYSES, STATUS, outputs_from_table, reads
from study.sweep.tasks import flat_fields, plan, point_result, task_key

FIELDS = list(flat_fields(dataclasses.asdict(default_scene())))


def test_the_analyses_read_nested_sets_of_scene_fields():
    read = {a: {f for f in FIELDS if reads(a, f)} for a in ANALYSES}
    assert read["geometry"] < read["fe"] < read["static"] < read["dynamic"]
    assert read["dynamic"] == set(FIELDS) - {"title"}
    assert read["static"] == {f for f in read["dynamic"] if not f.startswith("dynamic.")}
    assert {"gear2.body.holes", "gear2.body.web_thickness", "pair.backlash", "material.density"} <= read["geometry"]
    assert not {"gear2.spring.k_phi", "material.youngs_modulus", "quasi_static.torque"} & read["geometry"]
    assert {"quasi_static.torque", "fe.mesh_size", "gear2.spring.stiffness"} <= read["fe"]
    assert not {"contact.k_con", "quasi_static.rotation", "dynamic.speed"} & read["fe"]


def test_a_task_key_changes_with_the_fields_its_outputs_read_only():
    sc = default_scene()
    static = outputs_from_table({"scalars": ["ste_p2p", "mass_gear2"]})
    geometry = outputs_from_table({"scalars": ["mass_gear2"]})
    dynamic = outputs_from_table({"scalars": ["dte_rms"]})
    other_run = sc.replace(**{"dynamic.speed": 250.0, "dynamic.duration": 0.05})
    other_load = sc.replace(**{"quasi_static.torque": 80.0})
    assert task_key(other_run, static) == task_key(sc, static)
    assert task_key(other_run, dynamic) != task_key(sc, dynamic)
    assert task_key(other_load, static) != task_key(sc, static)
    assert task_key(other_load, geometry) == task_key(sc, geometry)
    assert task_key(sc, static) != task_key(sc, geometry)        # other outputs, another task


def test_points_share_the_static_task_and_a_point_record_joins_its_tasks():
    st = tiny_study('[grid]\ngear2.body.holes = [0, 4]\n"dynamic.speed" = [50.0, 60.0, 70.0]\n'
                    '[outputs]\nscalars = ["ste_p2p", "dte_rms"]')
    points = st.points()
    tasks, of_point = plan(st, points)
    shared = Counter(k for keys in of_point.values() for k in keys)
    assert len(tasks) == 2 + 6 and len(of_point) == 6
    assert sorted(shared.values()) == [1] * 6 + [3, 3]               # a static task serves the 3 speeds
    assert [tasks[k].outputs.scalars for k in of_point[(0, 0)]] == [("ste_p2p",), ("dte_rms",)]
    static, dyn = of_point[(1, 2)]
    results = {static: {"status": "diverged", "message": "static equilibrium not reached", "wall_time": 3.0,
                        "scalars": {"ste_p2p": np.nan}, "curves": {}},
               dyn: {"status": "ok", "message": "ok", "wall_time": 2.0, "scalars": {"dte_rms": 0.4}, "curves": {}}}
    r = point_result(of_point[(1, 2)], results, shared)
    assert r["status"] == "diverged" and r["message"] == "static equilibrium not reached"
    assert r["wall_time"] == pytest.approx(3.0 / 3 + 2.0) and r["scalars"]["dte_rms"] == 0.4
    assert point_result(of_point[(1, 1)], results, shared) is None   # its dynamic run is missing: pending
    # a static-only study over the speed runs the statics once per body
    st = tiny_study('[grid]\ngear2.body.holes = [0, 4]\n"dynamic.speed" = [50.0, 60.0]\n[outputs]\nscalars = ["ste_p2p"]')
    assert len(plan(st, st.points())[0]) == 2


def test_a_point_invalid_for_its_dynamics_only_keeps_the_statics_of_its_body(tmp_path):
    """Too short a run is invalid (no steady window), yet the body's STE is archived once, over
    the hole count only; renders draw the static output against the one dimension it lies over."""
    from study.report.figures import make_figures
    st = tiny_study('[grid]\n"dynamic.duration" = [0.003, 0.01]\ngear2.body.holes = [0, 4]\n'
                    '[outputs]\nscalars = ["ste_p2p", "dte_rms"]')
    res = run_sweep(st, tmp_path / "short.nc", workers=0, progress=False)
    ds = res.dataset
    assert res.invalid == 2 and res.computed == 2 + 2
    status = ds["status"].sel(dynamic_duration=0.003)
    assert (status == STATUS.index("invalid")).all() and "steady" in str(ds["message"].values[0, 0])
    assert (ds["status"].sel(dynamic_duration=0.01) == STATUS.index("ok")).all()
    assert ds["ste_p2p"].dims == ("n_holes",) and np.isfinite(ds["ste_p2p"]).all()
    assert np.isnan(ds["dte_rms"].sel(dynamic_duration=0.003)).all() and np.isfinite(ds["dte_rms"].sel(dynamic_duration=0.01)).all()
    assert (ds["wall_time"].sel(dynamic_duration=0.003) == 0).all() and (ds["wall_time"].sel(dynamic_duration=0.01) > 0).all()
    with xr.open_dataset(tmp_path / "short.nc", engine="netcdf4") as back:
        xr.testing.assert_identical(back.load(), ds)
    pngs = {p.name for p in make_figures(ds, tmp_path / "fig")}
    assert {"sweep_ste_p2p.png", "sweep_dte_rms.png", "main_effects_ste_p2p.png"} <= pngs

"""What each analysis reads, the tasks a study runs (one static analysis for the points that
differ only in dynamic fields) and the archive layout that follows from it."""
import dataclasses
from collections import Counter

import numpy as np
import pytest
import xarray as xr
from sweep_cases import swept, tiny_study  # noqa: F401  (swept: the sweep, run once per session)

from study.scene import default_scene
from study.sweep.engine import run_point, run_sweep
from study.sweep.outputs import ANALYSES, SCALARS, STATUS, analysis_of, outputs_from_table, reads
from study.sweep.tasks import WORST_FIRST, flat_fields, plan, point_result, scene_fields, task_key

FIELDS = list(flat_fields(dataclasses.asdict(default_scene())))


def test_the_analyses_read_nested_sets_of_scene_fields():
    read = {a: {f for f in FIELDS if reads(a, f)} for a in ANALYSES}
    assert read["geometry"] < read["fe"] < read["static"] < read["modes"] < read["dynamic"]
    # the modes are linearised at the mean load: the dynamic run's torque, when it runs
    assert read["modes"] - read["static"] == {"dynamic.torque", "dynamic.enabled"}
    assert read["dynamic"] == set(FIELDS) - {"title"}
    assert read["static"] == {f for f in read["dynamic"] if not f.startswith("dynamic.")}
    assert {"gear2.body.holes", "gear2.body.web_thickness", "pair.backlash", "material.density"} <= read["geometry"]
    assert not {"gear2.spring.k_phi", "material.youngs_modulus", "quasi_static.torque"} & read["geometry"]
    assert {"quasi_static.torque", "fe.mesh_size", "gear2.spring.stiffness"} <= read["fe"]
    assert not {"contact.k_con", "quasi_static.rotation", "dynamic.speed"} & read["fe"]


def test_scene_fields_are_the_flattened_scene():
    """The task key's flattening (no deep copy) gives the paths and values of the flattened
    dataclasses.asdict, containers (pitch deviations, profile tables) included."""
    sc = default_scene()
    changed = sc.replace(**{"gear1.errors.pitch": (1.0, -2.0, 0.5) * 22 + (11.0,), "gear2.modification.tip_relief": 5.0,
                            "gear2.modification.tip_length": 1.0, "dynamic.speed": 120.0})
    for scene in (sc, changed):
        flat = scene_fields(scene)
        ref = flat_fields(dataclasses.asdict(scene))
        assert list(flat) == list(ref) and flat == ref
    assert scene_fields(changed)["gear1.errors.pitch"] == (1.0, -2.0, 0.5) * 22 + (11.0,)
    assert scene_fields(changed)["dynamic.speed"] == 120.0 and scene_fields(sc)["dynamic.speed"] != 120.0


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
    the hole count only; renders draw an output of the body against the one dimension it lies
    over, and none of an output that takes one value (the STE of uniform springs)."""
    from study.report.figures import make_figures
    st = tiny_study('[grid]\n"dynamic.duration" = [0.003, 0.01]\ngear2.body.holes = [0, 4]\n'
                    '[outputs]\nscalars = ["ste_p2p", "dte_rms", "mass_gear2"]')
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
    assert {"sweep_mass_gear2.png", "sweep_dte_rms.png", "main_effects_mass_gear2.png"} <= pngs
    assert float(np.ptp(ds["ste_p2p"].values)) == 0.0 and not {"sweep_ste_p2p.png", "main_effects_ste_p2p.png"} & pngs


def test_modal_outputs_follow_the_dynamic_torque_and_join_the_dynamic_task():
    modal = [k for k, v in SCALARS.items() if v.analysis == "modes"]
    assert set(modal) == {"mesh_mode_frequency", "mesh_mode_damping", "critical_speed_z", "critical_speed_2z",
                          "critical_speed_3z"} and analysis_of("mesh_mode_damping_decay") == "dynamic"
    out = outputs_from_table({"scalars": ["ste_p2p", "mass_gear2", "critical_speed_z", "dte_rms"]})
    assert out.parts() == (outputs_from_table({"scalars": ["ste_p2p", "mass_gear2"]}),
                           outputs_from_table({"scalars": ["critical_speed_z", "dte_rms"]}))
    sc = default_scene()
    alone = outputs_from_table({"scalars": ["mesh_mode_frequency", "mesh_mode_damping"]})
    assert alone.widest == "modes"
    for field, value, same in (("dynamic.speed", 250.0, True), ("dynamic.torque", 80.0, False),
                               ("contact.damping_ratio", 0.08, False), ("quasi_static.torque", 80.0, False)):
        assert (task_key(sc.replace(**{field: value}), alone) == task_key(sc, alone)) == same, field


def test_a_modal_scalar_is_computed_per_dynamic_torque_not_shared_across_torques(tmp_path):
    st = tiny_study('[grid]\ngear2.body.holes = [0, 4]\n"dynamic.torque" = [10.0, 150.0]\n"dynamic.speed" = [50.0, 100.0]\n'
                    '[outputs]\nscalars = ["ste_p2p", "mesh_mode_frequency", "mesh_mode_damping", "critical_speed_z"]')
    tasks, _ = plan(st, st.points())
    assert len(tasks) == 2 + 4               # statics per body; modes per body and torque, shared by the speeds
    res = run_sweep(st, tmp_path / "modes.nc", workers=0, progress=False)
    ds = res.dataset
    assert (ds["status"] == STATUS.index("ok")).all() and res.computed == 6
    f = ds["mesh_mode_frequency"]
    assert f.dims == ("n_holes", "torque") and ds["ste_p2p"].dims == ("n_holes",)
    assert f.attrs["analysis"] == "modes" and np.isfinite(f).all()
    assert (abs(f.sel(torque=150.0) - f.sel(torque=10.0)) > 1e-3 * f.sel(torque=10.0)).all()
    for p in st.points():
        if p.values["dynamic.speed"] != 100.0:
            continue
        ref = run_point(p.scene, st.outputs)["scalars"]
        here = {d: p.values[a.path] for d, a in zip(ds["status"].dims, st.axes) if d in f.dims}
        for k in ("mesh_mode_frequency", "mesh_mode_damping", "critical_speed_z"):
            np.testing.assert_allclose(float(ds[k].sel(here)), ref[k], rtol=1e-12, err_msg=k)


def test_an_inaccurate_run_ranks_between_ok_and_diverged():
    assert WORST_FIRST.index("diverged") < WORST_FIRST.index("inaccurate") < WORST_FIRST.index("ok")
    assert set(WORST_FIRST) == set(STATUS) - {"pending"}
    rec = {"message": "ok", "wall_time": 1.0, "scalars": {}, "curves": {}}
    results = {"s": {**rec, "status": "ok"}, "d": {**rec, "status": "inaccurate", "message": "inaccurate: energy"}}
    r = point_result(("s", "d"), results, Counter({"s": 2, "d": 1}))
    assert r["status"] == "inaccurate" and r["message"] == "inaccurate: energy"
    results["s"] = {**rec, "status": "diverged", "message": "static equilibrium not reached"}
    assert point_result(("s", "d"), results, Counter({"s": 2, "d": 1}))["status"] == "diverged"


def test_the_merge_reads_each_task_part_once_per_position_of_its_curves(swept, tmp_path, monkeypatch):
    """The archive's curves come from the part file of the task that produced them: the static
    ``ste`` from the static task (once per body, whatever the speeds), ``dte_amplitude`` from each
    dynamic run; each part is read when the sweep finds it, for its curves' axes and into its block."""
    import study.sweep.engine as sweep
    from study.sweep.engine import PartStore
    res, _ = swept
    out = tmp_path / "again.nc"
    run_sweep(tiny_study(), out, workers=0, progress=False, keep_parts=True)
    out.unlink()
    monkeypatch.setattr(sweep, "run_point", lambda *a: pytest.fail("a stored task was computed again"))
    reads = []
    real_get = PartStore.get
    monkeypatch.setattr(PartStore, "get", lambda self, key: reads.append(key) or real_get(self, key))
    again = run_sweep(tiny_study(), out, workers=0, progress=False)
    tasks, _ = plan(tiny_study(), tiny_study().points())
    assert again.computed == 0 and again.reused == len(tasks) == 4 + 8
    assert Counter(reads) == {k: 3 for k in tasks}
    drop = ["wall_time"]
    xr.testing.assert_identical(again.dataset.drop_vars(drop).load().assign_attrs(created="", history=""),
                                res.dataset.drop_vars(drop).load().assign_attrs(created="", history=""))
    assert again.dataset["ste"].dims == ("n_holes", "web_thickness", "angle")


def test_cheap_tasks_go_to_dask_in_batches_of_one_model_dearest_first():
    from study.sweep.cost import task_seconds
    from study.sweep.grid import check_points
    from study.sweep.tasks import BATCH_S, batches, model_group
    st = tiny_study(grid='[grid]\ngear2.body.holes = [0, 4]\n"dynamic.speed" = {start = 50.0, stop = 100.0, num = 40}\n'
                         '"dynamic.duration" = [0.01, 0.05]\n[outputs]\nscalars = ["ste_p2p", "dte_rms"]\n')
    tasks, _ = plan(st, check_points(st))
    assert len(tasks) == 2 + 160
    out = batches(list(tasks.values()), workers=2)
    # every task once; a batch holds tasks of one model only, within BATCH_S unless alone, at most
    # len / (4 x workers) tasks; the longer runs cost more and go first
    assert Counter(t.key for b in out for t in b) == Counter(tasks.keys())
    assert all(len({model_group(t.scene) for t in b}) == 1 for b in out)
    cost = [[task_seconds(t.scene, t.outputs) for t in b] for b in out]
    assert all(len(c) == 1 or sum(c) <= BATCH_S for c in cost)
    assert max(len(b) for b in out) <= len(tasks) // 8 and len(out) >= 8
    assert [sum(c) for c in cost] == sorted((sum(c) for c in cost), reverse=True)
    assert task_seconds(*max(((t.scene, t.outputs) for t in tasks.values()), key=lambda so: so[0].dynamic.duration)) > \
        3 * task_seconds(*min(((t.scene, t.outputs) for t in tasks.values() if t.outputs.dynamic),
                              key=lambda so: so[0].dynamic.duration))
    # a small study: one task a batch (its tasks spread over the workers as before)
    small, _ = plan(tiny_study(), check_points(tiny_study()))
    assert all(len(b) == 1 for b in batches(list(small.values()), workers=2))

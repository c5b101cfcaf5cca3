"""The sweep engine: a sweep equals its points run alone, resume, failures, dask, the CLI and
the sensitivity workflow."""
import math

import numpy as np
import pytest
import xarray as xr
from sweep_cases import BASE, count_points, ctrl_c_after_stored, swept, tiny_study  # noqa: F401  (swept: the sweep, run once per session)

import study.sweep.engine as sweep
from study.archive.summary import summarize
from study.run import run_scene
from study.scene import default_scene
from study.sweep.engine import parts_folder, run_sweep
from study.sweep.outputs import SCALARS, STATUS, STRENGTH_SCALARS
from study.sweep.tasks import plan

# ---------------------------------------------------------------- the sweep

def test_sweep_equals_each_point_run_alone(swept):
    res, _ = swept
    ds = res.dataset
    # dotted keys nest (TOML): gear2.* fields come first, then the quoted "dynamic.speed"
    assert ds["status"].dims == ("n_holes", "web_thickness", "speed") and (ds["status"] == STATUS.index("ok")).all()
    # 4 bodies: 4 static analyses, each shared by both speeds; 8 dynamic runs
    assert res.points == 8 and res.computed == 4 + 8 and res.reused == 0
    base = default_scene().replace(**{k: v for k, v in _flat(loads_scene_data()).items()})
    for h in (0, 4):
        for w in (50.0, 100.0):
            for t in (12.0, 17.0):
                sc = base.replace(**{"gear2.body.holes": h, "dynamic.speed": w, "gear2.body.web_thickness": t})
                alone = run_scene(sc)
                s = summarize(alone)
                pt = ds.sel(n_holes=h, speed=w, web_thickness=t)
                for k in (k for k in SCALARS if k not in STRENGTH_SCALARS):     # (the default outputs)
                    np.testing.assert_allclose(float(pt[k]), s.get(k, math.nan), rtol=1e-12, equal_nan=True, err_msg=k)
                np.testing.assert_allclose(pt["ste"].values, alone["ste"].values, rtol=1e-12)
                np.testing.assert_allclose(pt["dte_amplitude"].values, alone["dte_amplitude"].values, rtol=1e-12)
    assert (ds["ste_p2p"] > 0).all() and (ds["dte_rms"] > 0).all()
    # the static outputs do not lie over the speed (the points above each ran their own statics
    # at their own speed: the shared one equals them), the dynamic ones do
    assert ds["ste"].dims == ("n_holes", "web_thickness", "angle") and ds["ste_p2p"].dims == ("n_holes", "web_thickness")
    assert ds["mass_gear2"].dims == ("n_holes", "web_thickness")
    assert ds["dte_rms"].dims == ds["status"].dims and ds["dte_amplitude"].dims[:-1] == ds["status"].dims
    assert ds["ste_p2p"].attrs["analysis"] == "static" and ds["dte_rms"].attrs["analysis"] == "dynamic"


def loads_scene_data():
    import tomllib
    return tomllib.loads(BASE)["scene"]


def _flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        p = f"{prefix}.{k}" if prefix else k
        out.update(_flat(v, p) if isinstance(v, dict) else {p: v})
    return out


def test_rerunning_a_complete_study_computes_nothing(swept, monkeypatch):
    res, out = swept
    monkeypatch.setattr(sweep, "run_point", lambda *a: pytest.fail("recomputed"))
    again = run_sweep(tiny_study(), out, workers=0, progress=False)
    assert again.computed == 0
    xr.testing.assert_identical(again.dataset, res.dataset)


def test_changed_code_recomputes_every_point(swept, tmp_path, monkeypatch):
    """Finished points of another version of the code are never reused, neither from the
    part files nor from a complete archive."""
    from study.archive import netcdf
    res, out = swept
    keys = set(plan(tiny_study(), tiny_study().points())[0])
    monkeypatch.setattr(netcdf, "code_fingerprint", lambda: "another-version")
    assert not keys & set(plan(tiny_study(), tiny_study().points())[0])
    calls = []
    monkeypatch.setattr(sweep, "run_point", lambda s, o: calls.append(s) or {"status": "failed", "message": "new code",
                                                                               "wall_time": 0.0, "scalars": {}, "curves": {}})
    copy = tmp_path / "copy.nc"
    copy.write_bytes(out.read_bytes())
    again = run_sweep(tiny_study(), copy, workers=0, progress=False)
    assert again.reused == 0 and len(calls) == 12


def test_interrupt_and_resume_give_the_same_archive(swept, tmp_path, monkeypatch):
    res, _ = swept
    out = tmp_path / "resumed.nc"
    count_points(monkeypatch, stop_after=4)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(tiny_study(), out, workers=0, progress=False)
    assert not out.exists()  # no half archive
    parts = sorted(parts_folder(out).glob("*.pkl"))
    assert len(parts) == 4
    # a process killed while writing leaves a temporary file; a damaged record is recomputed
    (parts_folder(out) / ".junk.123.tmp").write_bytes(b"\0" * 10)
    parts[0].write_bytes(b"not a pickle")
    monkeypatch.undo()
    calls = count_points(monkeypatch)
    again = run_sweep(tiny_study(), out, workers=0, progress=False)
    assert len(calls) == 9 and again.computed == 9 and again.reused == 3
    drop = ["wall_time"]
    xr.testing.assert_identical(again.dataset.drop_vars(drop).assign_attrs(created="", history=""),
                                res.dataset.drop_vars(drop).assign_attrs(created="", history=""))


def test_failing_points_are_recorded_and_the_sweep_goes_on(tmp_path, monkeypatch):
    points = """
[[points]]
dynamic.speed = 60.0
[[points]]
gear2.body.holes = 4
gear2.body.hole_radius = 2.5
[[points]]
dynamic.speed = 77.0
[[points]]
dynamic = {output_step = 1e-4, time_step = 5e-5}
[outputs]
scalars = ["ste_p2p", "dte_rms"]
"""
    import study.run
    real = study.run.run_fields

    def boom(scene, *args):
        if scene.dynamic.speed == 77.0:
            raise RuntimeError("boom")
        return real(scene, *args)

    monkeypatch.setattr(study.run, "run_fields", boom)
    res = run_sweep(tiny_study(points), tmp_path / "p.nc", workers=0, progress=False)
    ds = res.dataset
    assert ds["status"].dims == ("point",) and ds.sizes["point"] == 4
    assert ds["hole_radius"].attrs["scene_field"] == "gear2.body.hole_radius"
    np.testing.assert_array_equal(ds["speed"], [60.0, 100.0, 77.0, 100.0])  # base value where not set
    st = [STATUS[i] for i in ds["status"].values]
    msg = list(ds["message"].values)
    assert st == ["ok", "invalid", "failed", "diverged"], msg
    assert "gear2.body.hole_radius" in msg[1] and "cut the rim" in msg[1]
    assert msg[2].startswith("RuntimeError: boom")
    assert "dynamic run stopped" in msg[3]
    # one static analysis (the three valid points differ only in dynamic.*) and three dynamic runs
    assert res.invalid == 1 and res.computed == 1 + 3
    # diverged: the dynamic numbers are withheld, the static ones kept
    assert np.isnan(ds["dte_rms"][3]) and np.isfinite(ds["ste_p2p"][3]) and np.isfinite(ds["dte_rms"][0])
    assert np.isnan(ds["dte_rms"][1:3]).all()
    assert "dte" not in ds and "ste" not in ds
    with xr.open_dataset(tmp_path / "p.nc", engine="netcdf4") as back:
        xr.testing.assert_identical(back.load(), ds)


def test_only_the_asked_analyses_run(monkeypatch):
    import study.run
    from study.plan import RunOptions
    seen = []
    real = study.run.run_fields
    monkeypatch.setattr(study.run, "run_fields", lambda s, *args: seen.append(args) or real(s, *args))
    st = tiny_study("[grid]\ndynamic.speed = [50.0]\n[outputs]\nscalars = ['ste_p2p']")
    r = sweep.run_point(st.points()[0].scene, st.outputs)
    # the sweep warns once; keeps the model; reads the run without its archive's documentation,
    # per-gear and modal variables: the statics alone
    lean = RunOptions(warn=False, keep_model=True, archive=False)
    assert r["status"] == "ok" and seen == [(frozenset({"static"}), lean)]
    assert set(r["scalars"]) == {"ste_p2p"} and r["curves"] == {}
    # a mesh scalar asks for the linearised mesh over the STE
    st = tiny_study("[grid]\ndynamic.speed = [50.0]\n[outputs]\nscalars = ['mesh_stiffness_mean']")
    r = sweep.run_point(st.points()[0].scene, st.outputs)
    assert seen[-1] == ({"static", "mesh"}, lean) and r["scalars"]["mesh_stiffness_mean"] > 0
    st = tiny_study("[grid]\ndynamic.speed = [50.0]\n[outputs]\nscalars = ['ste_p2p']\ncurves = ['mesh_stiffness']")
    r = sweep.run_point(st.points()[0].scene, st.outputs)
    assert "mesh" in seen[-1][0] and r["curves"]["mesh_stiffness"][0] == "angle"


# ---------------------------------------------------------------- dask

def test_dask_sweep_is_interruptible_closes_its_cluster_and_resumes(swept, tmp_path, monkeypatch):
    """One LocalCluster (2 workers) started by the code; Ctrl-C after two stored points."""
    from distributed.deploy.spec import SpecCluster
    res, _ = swept
    out = tmp_path / "dask.nc"
    import distributed
    started = []
    real_cluster = distributed.LocalCluster
    monkeypatch.setattr(distributed, "LocalCluster", lambda **kw: started.append(kw) or real_cluster(**kw))
    with ctrl_c_after_stored(monkeypatch, 2), pytest.raises(KeyboardInterrupt):
        run_sweep(tiny_study(), out, workers=2, progress=False)
    assert SpecCluster._instances and all(c.status.name == "closed" for c in SpecCluster._instances)
    (kw,) = started
    assert kw["n_workers"] == 2 and kw["threads_per_worker"] == 1 and kw["processes"]
    assert kw["env"]["NUMBA_NUM_THREADS"] == "1"
    # the workers' log lines (a heartbeat that finds the scheduler closing on a loaded machine)
    # stay off the terminal: a point's failure reaches the user through its recorded cause
    assert kw["silence_logs"] >= __import__("logging").CRITICAL
    # the two points computed on the workers are kept; the rest is computed here
    calls = count_points(monkeypatch)
    again = run_sweep(tiny_study(), out, workers=0, progress=False)
    assert again.reused == 2 and len(calls) == 10
    xr.testing.assert_identical(again.dataset.drop_vars("wall_time").assign_attrs(created="", history=""),
                                res.dataset.drop_vars("wall_time").assign_attrs(created="", history=""))


# ---------------------------------------------------------------- CLI, workflow, scheduling

def test_cli_sweep_of_the_example_study(tmp_path, capsys):
    from study.cli import main
    out = tmp_path / "ex.nc"
    assert main(["sweep", "study/scenes/example_study.toml", "-o", str(out), "--workers", "0", "--no-progress"]) == 0
    assert "4 points; analyses computed 6" in capsys.readouterr().out     # 2 static, 4 dynamic
    with xr.open_dataset(out, engine="netcdf4") as ds:
        assert ds["dte"].dims == ("n_holes", "speed", "time") and ds["time"].attrs["units"] == "s"
        assert (ds["status"] == STATUS.index("ok")).all()
    bad = tmp_path / "bad.toml"
    bad.write_text("[grid]\ngear2.body.holes = [1.5]\n")
    assert main(["sweep", str(bad), "-o", str(tmp_path / "bad.nc"), "--workers", "0"]) == 2
    assert "gear2.body.holes" in capsys.readouterr().err and not (tmp_path / "bad.nc").exists()


def test_sensitivity_workflow_shrunk_to_a_tiny_grid(tmp_path, capsys):
    from study.sweep.grid import loads_study
    from workflows.sensitivity_sweep import STUDY, main, sensitivity_study
    full = sensitivity_study(STUDY)
    assert [a.name for a in full.axes] == ["n_holes", "hole_radius", "rim_thickness", "web_thickness", "speed"]
    assert full.axes[0].values == (0, 3, 6, 9, 12) and all(p.scene is not None for p in full.points())
    out = tmp_path / "s.nc"
    assert main(["--study", "study/scenes/example_study.toml", "--grid", "gear2.body.holes=0,3",
                 "--grid", "dynamic.speed=60", "--set", "dynamic.duration=0.008", "-o", str(out),
                 "--workers", "0", "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "2 points: n_holes 2 x speed 1" in text and "dte_rms" in text
    with xr.open_dataset(out, engine="netcdf4") as ds:
        assert loads_study(ds.attrs["study"]).base["dynamic"]["duration"] == 0.008
        assert ds["time"].values[-1] == pytest.approx(0.008)


def test_in_one_process_the_tasks_of_a_model_follow_each_other_and_build_it_once(tmp_path, monkeypatch):
    """A study run in this process takes its tasks model by model (`by_model`), whatever the
    grid's order: the kept model (springs, model, damping conversion) serves them in a row.
    Spread over the queue (`interleave`, for dask workers), more bodies than the process keeps
    models for (`scene_model.MODEL_SLOTS`) had each task build its model again."""
    import study.scene_model as scene_model
    from study.sweep.schedule import by_model
    from study.sweep.tasks import model_group
    holes = [0, 2, 4, 6, 8]
    assert len(holes) > scene_model.MODEL_SLOTS
    st = tiny_study(f'[grid]\n"dynamic.speed" = [50.0, 60.0]\ngear2.body.holes = {holes}\n')
    todo = {p.index: p.scene for p in st.points()}
    assert [s.gear2.body.holes for s in todo.values()] == holes * 2      # the grid's order alternates
    ordered = by_model(todo)
    assert [s.gear2.body.holes for s in ordered.values()] == sorted(holes * 2)
    assert list(ordered)[:2] == [(0, 0), (1, 0)]           # first seen first, the grid's order within
    assert len({model_group(s) for s in ordered.values()}) == len(holes)
    built = []
    real = scene_model._damped_model
    monkeypatch.setattr(scene_model, "_damped_model", lambda *a: built.append(a[0]) or real(*a))
    res = run_sweep(st, tmp_path / "s.nc", workers=0, progress=False)
    assert res.computed == 3 * len(holes)       # a static task (shared by the speeds) and two dynamic ones a body
    assert sorted(s.gear2.body.holes for s in built) == holes


def test_points_sharing_a_body_are_queued_apart():
    st = tiny_study("[grid]\ngear2.body.holes = [0, 4]\n\"dynamic.speed\" = [50.0, 60.0, 70.0]")
    todo = {str(p.index): p.scene for p in st.points()}
    order = list(sweep.interleave(todo).values())
    holes = [s.gear2.body.holes for s in order]
    assert sorted(holes) == [0, 0, 0, 4, 4, 4]
    assert all(a != b for a, b in zip(holes, holes[1:]))

"""`lightgear` exit codes: clear errors (2) before any work, a diverged run (3), the backstop (1)."""
import netCDF4
import numpy as np
import pytest
import xarray as xr

import study
from study import cli
from study.cli import main

STUDY = "study/scenes/example_study.toml"


@pytest.mark.parametrize("overrides, field, words", [
    (["gear1.module=1e6", "gear2.module=1e6"], "gear1.module", "<= 100"),
    (["fe.mesh_size=100"], "fe.mesh_size", "module = 1.5 mm"),
    (["gear2.body.rim_height=0"], "gear2.body.rim_height", ">= 0.75 mm"),       # 2 elements of module/4
    (["gear2.body.rim_height=0.3", "fe.mesh_size=0.2"], "gear2.body.rim_height", ">= 0.4 mm"),
    (["dynamic.speed=-100"], "dynamic.speed", ">= 0"),
    (["dynamic.duration=0.015"], "dynamic.duration", "twice dynamic.ramp_time"),
    (["dynamic.torque=1e6"], "dynamic.torque", "implausible load"),
    (["quasi_static.torque=1e9", "dynamic.enabled=false"], "quasi_static.torque", "implausible load"),
    (["gear1.spring.k_phi=1060", "gear2.spring.k_phi=1060", "coupling.model=paper"], "quasi_static.torque",
     "implausible load"),
])
def test_bad_scenes_exit_2_naming_the_field_before_any_output(overrides, field, words, tmp_path, capsys):
    out = tmp_path / "x.nc"
    args = ["run", "-o", str(out)] + [a for o in overrides for a in ("--set", o)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert field in err and words in err and "Traceback" not in err
    assert not out.exists()


def test_the_rim_criterion_follows_the_mesh_size():
    # the paper's rim (6.075 mm) and a 1 mm rim with a fine mesh are fine; 1 mm at module/4 is not
    study.load_scene(None, ["gear2.body.rim_height=1.0", "fe.mesh_size=0.3"])
    with pytest.raises(study.SceneError, match="rim_height"):
        study.load_scene(None, ["gear2.body.rim_height=0.7"])
    # the load bound passes the paper's range of torques and keeps two decades of margin
    study.load_scene(None, ["quasi_static.torque=500", "dynamic.torque=-500"])


@pytest.mark.parametrize("make, words", [
    (lambda p: p.mkdir() or p, "is a directory"),
    (lambda p: p.with_suffix(".txt"), "ending in .nc"),
    (lambda p: p.parent / "file" / "x.nc", "is a file, not a directory"),
])
def test_output_path_is_checked_before_the_work(make, words, tmp_path, capsys, example_scene_file):
    (tmp_path / "file").write_text("x")
    out = make(tmp_path / "out.nc")
    for args in (["run", str(example_scene_file)], ["stiffness", str(example_scene_file)], ["reference", str(example_scene_file)],
                 ["precision", str(example_scene_file)], ["sweep", STUDY, "--workers", "0", "--no-progress"]):
        assert main(args + ["-o", str(out)]) == 2, args
        err = capsys.readouterr().err
        assert "-o" in err and words in err and "Traceback" not in err


def test_unwritable_output_folder_is_refused(capsys, example_scene_file):
    # /proc refuses new files even to root (a chmod'ed folder would not stop root)
    assert main(["run", str(example_scene_file), "-o", "/proc/lightgear/run.nc"]) == 2
    assert "cannot write in /proc/lightgear" in capsys.readouterr().err


def test_sweep_refuses_negative_workers_and_an_unreachable_scheduler(tmp_path, capsys, monkeypatch):
    assert main(["sweep", STUDY, "-o", str(tmp_path / "s.nc"), "--workers", "-1"]) == 2
    assert "--workers: must be >= 0" in capsys.readouterr().err
    from study.sweep import cluster
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1.0)
    assert main(["sweep", STUDY, "-o", str(tmp_path / "s.nc"), "--scheduler", "tcp://127.0.0.1:1", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "--scheduler: no dask scheduler answered at tcp://127.0.0.1:1 within 1 s" in err and "Traceback" not in err


def test_render_refuses_what_is_not_a_lightgear_archive(tmp_path, capsys):
    (tmp_path / "text.nc").write_text("not a netcdf file\n")
    (tmp_path / "empty.nc").write_bytes(b"")
    xr.Dataset({"x": ("n", np.arange(4.0))}).to_netcdf(tmp_path / "other.nc")
    full = tmp_path / "other.nc"
    (tmp_path / "truncated.nc").write_bytes(full.read_bytes()[: full.stat().st_size // 2])
    (tmp_path / "folder.nc").mkdir()
    for name, words in (("text.nc", "not a readable NetCDF"), ("empty.nc", "not a readable NetCDF"),
                        ("truncated.nc", "not a readable NetCDF"), ("folder.nc", "not a file"),
                        ("other.nc", "not a lightgear archive"), ("missing.nc", "no such file")):
        assert main(["render", str(tmp_path / name), "--no-renders"]) == 2, name
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err, (name, err)
    assert not list(tmp_path.glob("*.png"))


def test_unexpected_errors_are_one_line_with_exit_1(monkeypatch, capsys, example_scene_file, tmp_path):
    def boom(*a, **k):
        raise RuntimeError("disk on fire\nsecond line")
    monkeypatch.setattr(study, "run_scene", boom)
    assert main(["run", str(example_scene_file), "-o", str(tmp_path / "r.nc")]) == 1
    err = capsys.readouterr().err
    assert err.strip() == ("lightgear run: error: RuntimeError: disk on fire (LIGHTGEAR_DEBUG=1 shows the traceback)")
    monkeypatch.setenv("LIGHTGEAR_DEBUG", "1")
    with pytest.raises(RuntimeError, match="disk on fire"):
        main(["run", str(example_scene_file), "-o", str(tmp_path / "r.nc")])


def test_a_diverged_run_exits_3_with_its_cause_and_keeps_the_archive(example_scene_file, tmp_path, capsys):
    out = tmp_path / "div.nc"
    assert main(["run", str(example_scene_file), "-o", str(out), "--no-static", "--set", "dynamic.time_step=1e-5"]) == 3
    err = capsys.readouterr().err
    assert "dynamic run diverged: energy growth" in err
    with netCDF4.Dataset(out) as nc:
        assert nc.getncattr("dynamic_status").startswith("energy growth")


def test_help_documents_the_exit_codes(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    for code in ("0    done", "2    invalid input", "3    a run that diverged", "130  interrupted"):
        assert code in text
    assert cli.EXIT_CODES.splitlines()[0] == "exit codes:"

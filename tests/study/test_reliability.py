"""What a careless user or script meets: every bad input is exit 2 with the field or option
named, before any work; every refusal names the lever that helps. Here: files and output
names, options and the messages; the estimates in test_reliability_estimates.py, results
that would pass as ok in test_reliability_results.py."""
from pathlib import Path

import numpy as np
import pytest
from reliability_cases import dynamic_fields, paper_pair, run_cli

from study.inputs.cache import FE_CACHE

# ---------------------------------------------------------------- files and output names

def test_a_scene_or_study_file_that_is_not_utf8_is_named(tmp_path, capsys):
    bad = tmp_path / "latin1.toml"
    bad.write_bytes('title = "engrenage allégé"\n'.encode("latin-1"))
    code, _, err = run_cli(capsys, "run", bad, "-o", tmp_path / "r.nc")
    assert code == 2 and "scene: " in err and "not UTF-8" in err
    code, _, err = run_cli(capsys, "sweep", bad, "-o", tmp_path / "s.nc")
    assert code == 2 and "study: " in err and "not UTF-8" in err


def test_a_study_whose_scene_is_a_number_is_named(tmp_path, capsys):
    st = tmp_path / "s.toml"
    st.write_text('scene = 5\n[grid]\n"dynamic.speed" = [50.0]\n')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc")
    assert code == 2 and "scene: must be a file name or a table" in err


@pytest.mark.parametrize("command", ["run", "stiffness", "reference", "precision"])
def test_an_output_name_too_long_for_the_file_system_is_refused_up_front(tmp_path, capsys, command):
    code, _, err = run_cli(capsys, command, "-o", tmp_path / ("a" * 300 + ".nc"))
    assert code == 2 and "-o: a name of 303 bytes is too long" in err
    # and one that leaves no room for the temporary file of the atomic write
    code, _, err = run_cli(capsys, command, "-o", tmp_path / ("b" * 240 + ".nc"))
    assert code == 2 and "at most 215 bytes" in err


def test_a_file_where_the_parts_folder_goes_is_refused(tmp_path, capsys):
    (tmp_path / ".s.nc.parts").write_text("not a folder")
    code, _, err = run_cli(capsys, "sweep", "study/scenes/example_study.toml", "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and ".s.nc.parts is a file" in err


# ---------------------------------------------------------------- options

@pytest.mark.parametrize("option, value, says", [("--duration", "0", "must be a positive number"),
                                                 ("--rotation", "0", "must be a positive number"),
                                                 ("--duration", "nan", "must be a positive number"),
                                                 ("--ramp-fraction", "2", "must lie in (0, 1]"),
                                                 ("--repeats", "0", "at least 1")])
def test_precision_options_are_checked_before_any_work(tmp_path, capsys, option, value, says):
    code, out, err = run_cli(capsys, "precision", option, value, "-o", tmp_path / "p.nc")
    assert code == 2 and f"{option}: " in err and says in err and "study ..." not in out


def test_workflow_scripts_options_give_exit_2_not_a_traceback(tmp_path, capsys):
    from study.process import script_main
    from workflows import sensitivity_sweep, validation
    assert script_main("validation", lambda: validation.main(["--step", "0", "-o", str(tmp_path / "v.nc")])) == 2
    assert "--step: the driver angle step must be a positive number" in capsys.readouterr().err
    assert script_main("sweep", lambda: sensitivity_sweep.main(["--grid", "bad", "-o", str(tmp_path / "s.nc")])) == 2
    assert "a grid axis must look like field=v1,v2" in capsys.readouterr().err


def test_a_material_too_soft_for_weber_is_named_by_fit_contact(capsys):
    code, _, err = run_cli(capsys, "fit-contact", "--set", "material.youngs_modulus=1e-9")
    assert code == 2 and "material.youngs_modulus" in err and "LinAlgError" not in err
    code, _, err = run_cli(capsys, "fit-contact", "--set", "quasi_static.torque=0")
    assert code == 2 and "quasi_static.torque" in err


# ---------------------------------------------------------------- messages

def test_a_study_given_to_run_and_a_scene_given_to_sweep_are_told_apart(tmp_path, capsys):
    code, _, err = run_cli(capsys, "run", "example_study", "-o", tmp_path / "r.nc")
    assert code == 2 and "example_study is a study" in err and "lightgear sweep" in err and "unknown key" not in err
    code, _, err = run_cli(capsys, "run", "study/scenes/tolerance.toml", "-o", tmp_path / "r.nc")
    assert code == 2 and "is a study" in err
    code, _, err = run_cli(capsys, "sweep", "paper", "-o", tmp_path / "s.nc")
    assert code == 2 and "this file is a scene" in err and "lightgear run" in err and "unknown study key" not in err


def test_an_output_folder_is_not_made_at_the_root_of_the_file_system(tmp_path, capsys):
    missing = Path("/nonexistent-lightgear") / "dir"
    code, _, err = run_cli(capsys, "run", "-o", missing / "x.nc")
    assert code == 2 and "-o: the folder /nonexistent-lightgear does not exist" in err and not missing.parent.exists()
    # one new folder in an existing one is made, as is any folder under the working directory
    from study.cli import checked_output
    assert checked_output(tmp_path / "new" / "x.nc").parent.is_dir()


def test_the_documented_default_mesh_size_is_the_codes():
    from solver.fe.mesh import default_mesh_size
    assert default_mesh_size(1.0) == 0.25 and "default module/4" in Path("docs/cli.md").read_text()


def test_a_field_prefix_cut_short_suggests_the_fields_it_begins(capsys):
    code, _, err = run_cli(capsys, "fields", "gear2.bod")
    assert code == 2 and "did you mean 'gear2.body'?" in err
    code, out, _ = run_cli(capsys, "fields", "gear2.body")
    assert code == 0 and "gear2.body.holes" in out
    code, _, err = run_cli(capsys, "fields", "gear2.body.hol")
    assert code == 2 and "'gear2.body.holes' or 'gear2.body.hole_radius'" in err


def test_the_study_tables_render_writes_are_an_archive_export_takes(tmp_path, capsys):
    """(and the example study's DTE RMS is defined at each speed: its steady part covers more
    than a mesh period at 50 rad/s)"""
    import xarray as xr
    code, _, err = run_cli(capsys, "sweep", "example_study", "-o", tmp_path / "s.nc", "--workers", 0, "--no-progress")
    assert code == 0, err
    with xr.open_dataset(tmp_path / "s.nc") as ds:
        assert np.isfinite(ds["dte_rms"].values).all()
    code, _, err = run_cli(capsys, "render", tmp_path / "s.nc", "-o", tmp_path / "fig", "--no-renders")
    assert code == 0 and (tmp_path / "fig" / "s_study_tables.nc").is_file(), err      # named after the archive
    code, out, err = run_cli(capsys, "export", tmp_path / "fig" / "s_study_tables.nc", "-o", tmp_path / "csv")
    assert code == 0 and "csv:" in out, err


def test_a_full_disk_is_said_as_such(tmp_path, capsys, monkeypatch):
    """HDF5 reports a full disk as 'NetCDF: HDF error': the free space tells it."""
    import shutil
    from collections import namedtuple

    import xarray as xr

    from study.archive.netcdf import write_netcdf
    from study.cli import guarded

    def hdf_error(self, *a, **k):
        raise RuntimeError("NetCDF: HDF error")
    monkeypatch.setattr(xr.Dataset, "to_netcdf", hdf_error)
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1e9, 1e9, 1000))
    ds = xr.Dataset({"x": ("n", np.arange(10.0))})
    assert guarded("lightgear run", lambda: write_netcdf(ds, tmp_path / "r.nc")) == 1
    err = capsys.readouterr().err
    assert "no space left on device: 0.0 MiB free" in err and "HDF error" not in err
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1e12, 0, 1e12))     # room: the error as it is
    with pytest.raises(RuntimeError, match="HDF error"):
        write_netcdf(ds, tmp_path / "r.nc")


def test_an_override_that_invalidates_another_field_is_named(capsys):
    code, _, err = run_cli(capsys, "run", "--set", "gear2.module=2", "--set", "dynamic.speed=50")
    assert code == 2 and "invalid scene: gear2.module: 2 makes gear2.body.hole_radius invalid" in err
    assert "holes cut the hub" in err
    # an override that is itself at fault is named as before
    code, _, err = run_cli(capsys, "run", "--set", "gear2.body.hole_radius=30")
    assert code == 2 and "invalid scene: gear2.body.hole_radius: holes cut the rim" in err


def test_a_run_up_whose_teeth_lose_contact_says_its_critical_speeds_are_linear(capsys, tmp_path):
    from study.plan import RunOptions
    from study.report.summary import print_summary
    from study.run import run_fields

    def runup(speed_end):
        scene = paper_pair(**{"dynamic.speed_end": speed_end, "dynamic.torque": 20.0, "dynamic.ramp_time": 0.002,
                              "dynamic.duration": 0.1})      # (the tracked speeds from some 430 rad/s)
        return run_fields(scene, {"dynamic", "modes", "gear"}, RunOptions(warn=False)).dataset()
    rattles = runup(1500.0)         # through 2Z and 1Z (about 250 and 495 rad/s) at 20 N·m: the teeth separate
    lo, hi = rattles.attrs["contact_lost_speed_rad_s"]
    z1 = float(rattles["critical_speed"].sel(excitation="1Z", mode=0))
    assert rattles.attrs["contact_lost_fraction"] > 0 and 0 < lo <= hi < 1500.0
    capsys.readouterr()
    print_summary(rattles, tmp_path / "r.nc", 1.0)
    out = capsys.readouterr().out
    assert f"the teeth lost contact between {lo:.0f} and {hi:.0f} rad/s" in out and "linear estimates" in out
    assert "1Z measured" in out and f"modal {z1:.0f}" in out
    steady = dynamic_fields(paper_pair())       # 100 rad/s, far below the resonances: always in contact
    assert steady.attrs["contact_lost_fraction"] == 0.0 and "contact_lost_speed_rad_s" not in steady.attrs


def test_fe_bodies_beyond_the_memory_are_refused_before_any_fe_work(tmp_path, capsys, monkeypatch, private_fe_cache):
    """A 10000-tooth driven gear: some 1.9e6 elements, tens of GiB (`study.estimate.body_bytes`,
    29 kB an element measured at 40 000), refused naming the lever in run, sweep and reference alike,
    whatever --max-time; a body over half the memory is warned of."""
    from study import estimate
    monkeypatch.setattr(estimate, "available_memory", lambda: 16.0 * 2 ** 30)
    code, _, err = run_cli(capsys, "run", "small_pair", "--set", "gear2.teeth=10000", "--max-time", "1e9",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "fe.mesh_size: the FE bodies need about" in err and "GiB" in err
    assert "a coarser fe.mesh_size" in err and not FE_CACHE.folder.exists()
    code, _, err = run_cli(capsys, "reference", "small_pair", "--set", "gear2.teeth=10000", "--max-time", "1e9",
                           "-o", tmp_path / "f.nc")
    assert code == 2 and "fe.mesh_size: the FE bodies need about" in err
    st = tmp_path / "big.toml"
    st.write_text('scene = "small_pair"\n[grid]\n"gear2.teeth" = [24, 10000]\n[outputs]\nscalars = ["ste_p2p"]\n')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--max-time", "1e9")
    assert code == 2 and "fe.mesh_size: the FE bodies need about" in err and not FE_CACHE.folder.exists()
    # the small pair's bodies (some 170 MB each) pass; with 600 MB available they are warned of
    from study.inputs.gearsetup import gear_setups
    from tests.helpers import small_scene
    setups = gear_setups(small_scene())
    assert estimate.check_fe_memory(setups) is None
    monkeypatch.setattr(estimate, "available_memory", lambda: 600e6)
    assert "more than half of" in estimate.check_fe_memory(setups)


def test_precision_outputs_beyond_the_memory_are_refused_naming_its_option(tmp_path, capsys):
    code, out, err = run_cli(capsys, "precision", "--duration", "1e7", "-o", tmp_path / "p.nc")
    assert code == 2 and "--duration: the run's outputs need about" in err and "TiB" in err and "study ..." not in out
    code, _, err = run_cli(capsys, "precision", "--only", "static", "--rotation", "1e12", "-o", tmp_path / "p.nc")
    assert code == 2 and "--rotation: the static analysis needs about" in err

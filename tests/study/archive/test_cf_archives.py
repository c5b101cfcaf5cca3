"""Archives pass the CF-1.8 checker; the atomic write cleans what a killed writer left."""
import os
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from cf_check import cf_errors

import study
from study.archive.netcdf import clean_stale_temporaries, write_netcdf

pytest.importorskip("compliance_checker")


@pytest.fixture(scope="module")
def small_scene():
    """The example study's 20-tooth pair with uniform springs: 3 deg of STE, 4 ms of DTE."""
    base = study.load_study(os.path.join(os.path.dirname(study.__file__), "scenes", "example_study.toml")).base_scene()
    return base.replace(**{"quasi_static.rotation": 3.0, "dynamic.duration": 0.004, "dynamic.ramp_time": 0.001})


def test_run_archive_passes_cf_and_keeps_names_values_and_float_time(small_scene, tmp_path):
    ds = study.run_scene(small_scene)
    path = study.write(ds, tmp_path / "run.nc")
    assert cf_errors(path) == []
    with xr.open_dataset(path) as back:
        assert set(back.variables) == set(ds.variables)
        for name in ds.variables:
            np.testing.assert_array_equal(back[name].values, ds[name].values, err_msg=name)
        assert back["time"].dtype == np.float64 and back["time"].attrs["units"] == "s"   # no calendar axis
        assert back.attrs["history"] and back.attrs["Conventions"] == "CF-1.8"
    import netCDF4
    with netCDF4.Dataset(path) as nc:
        assert nc["driver_tooth"].dtype == np.int32 and nc["gear"].dtype == np.int32     # CF has no int64
        for dim in ("angle", "time", "frequency"):
            assert "_FillValue" not in nc[dim].ncattrs(), dim


def test_stiffness_and_reference_archives_pass_cf(private_fe_cache, tmp_path):
    from study.inputs.springs import stiffness_dataset
    from study.verify.fe_reference import reference_dataset
    scene = study.load_scene("small_pair").replace(**{"gear2.body.holes": 4, "gear2.body.hole_radius": 2.5,
                                                      "gear2.body.hole_circle_radius": 20.0})
    stiff = study.write(stiffness_dataset(scene), tmp_path / "stiffness.nc")
    assert cf_errors(stiff) == []
    ref = study.write(reference_dataset(scene, np.radians([0.0, 1.0, 2.0])), tmp_path / "ref.nc")
    assert cf_errors(ref) == []


def test_a_killed_writers_temporary_is_removed_on_the_next_write(tmp_path):
    ds = xr.Dataset({"x": ("n", np.arange(3.0), {"units": "m", "long_name": "x"})})
    out = tmp_path / "out.nc"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead_pid = int(dead.stdout)                                  # that process has exited
    from study.archive.netcdf import host_tag
    stale = tmp_path / f".out.nc.tmp{dead_pid}.{host_tag()}-0123abcd"
    legacy = tmp_path / f".out.nc.tmp{dead_pid}.89abcdef"       # the older name, without host tag
    live = tmp_path / f".out.nc.tmp{os.getppid()}.{host_tag()}-00000000"   # a running writer
    other_host = tmp_path / f".out.nc.tmp{dead_pid}.ffffff-00000000"        # maybe running elsewhere
    for f in (stale, legacy, live, other_host):
        f.write_bytes(b"half a file")
    write_netcdf(ds, out)
    assert not stale.exists() and not legacy.exists()
    assert live.exists() and other_host.exists()
    assert xr.open_dataset(out)["x"].values.tolist() == [0.0, 1.0, 2.0]
    assert clean_stale_temporaries(out) == []

"""`lightgear run`: the archive contract, overrides, and errors that name the field."""
import numpy as np
import pytest
import xarray as xr

from study.cli import main
from study.scene import loads_scene

TINY = ["gear2.body.holes=0", "gear2.body.web_thickness=17.0", "quasi_static.rotation=6.0",
        "dynamic.duration=0.03", "dynamic.ramp_time=0.005"]


@pytest.fixture(scope="module")
def archive(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "tiny.nc"
    args = ["run", "-o", str(out)]
    for s in TINY:
        args += ["--set", s]
    assert main(args) == 0
    with xr.open_dataset(out, engine="netcdf4") as ds:
        yield ds.load()


def test_archive_holds_ste_dte_and_spectrum_with_units(archive):
    ds = archive
    assert ds["ste"].dims == ("angle",) and ds["ste"].attrs["units"] == "um"
    assert ds["angle"].attrs["units"] == "degree" and float(ds["angle"][-1]) == pytest.approx(6.0)
    assert ds["dte"].dims == ("time",) and ds["time"].attrs["units"] == "s"
    assert ds["dte_amplitude"].dims == ("frequency",) and ds["frequency"].attrs["units"] == "Hz"
    assert "order" in ds.coords and ds["order"].attrs["units"] == "1"
    for v in ds.variables.values():
        assert "units" in v.attrs and "long_name" in v.attrs
    # the scene travels with the archive and reproduces the overrides
    sc = loads_scene(ds.attrs["scene"])
    assert sc.quasi_static.rotation == 6.0 and sc.gear2.body.holes == 0
    # order axis: driven gear at 100 rad/s (equal tooth counts) -> order = f / (100/2pi)
    np.testing.assert_allclose(ds["order"], ds["frequency"] * 2 * np.pi / 100.0)
    # STE sits above the backlash offset by a few um; DTE after the ramp around the same mean
    off = ds.attrs["backlash_offset_um"]
    assert 3 < float(ds["ste"].mean()) - off < 10
    after = ds["dte"].where(ds["time"] >= ds.attrs["spectrum_start_s"], drop=True)
    assert abs(float(after.mean()) - float(ds["ste"].mean())) < 0.5
    # the mesh order (67) stands well above the spectral floor
    a = ds["dte_amplitude"]
    near = a.where(abs(ds["order"] - 67) < 3, drop=True)
    assert float(near.max()) > 5 * float(a.median())


def test_bad_scene_value_is_reported_with_its_field(capsys, tmp_path):
    code = main(["run", "-o", str(tmp_path / "x.nc"), "--set", "gear2.body.hole_radius=12"])
    assert code == 2
    err = capsys.readouterr().err
    assert "gear2.body.hole_radius" in err and "cut the rim" in err
    assert not (tmp_path / "x.nc").exists()


def test_unknown_key_is_rejected(capsys, tmp_path):
    assert main(["run", "-o", str(tmp_path / "x.nc"), "--set", "dynamic.sped=3"]) == 2
    assert "dynamic.sped" in capsys.readouterr().err

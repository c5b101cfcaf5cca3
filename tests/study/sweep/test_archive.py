"""Study archives: labels and units, the NetCDF round trip, and split studies opening as one."""
import pytest
import xarray as xr
from sweep_cases import GRID, swept, tiny_study  # noqa: F401  (swept: the sweep, run once per session)

from study.sweep.engine import parts_folder, run_sweep
from study.sweep.grid import loads_study
from study.sweep.outputs import STATUS


def test_archive_labels_units_and_netcdf_round_trip(swept):
    res, out = swept
    ds = res.dataset
    for name, path, unit in (("n_holes", "gear2.body.holes", "1"), ("speed", "dynamic.speed", "rad s-1"),
                             ("web_thickness", "gear2.body.web_thickness", "mm")):
        assert ds[name].attrs["scene_field"] == path and ds[name].attrs["units"] == unit
        assert ds[name].attrs["long_name"]
    for name, v in ds.variables.items():
        assert "long_name" in v.attrs, name
        if v.dtype.kind in "fiu":
            assert "units" in v.attrs, name
    assert list(ds["status"].attrs["flag_meanings"].split()) == list(STATUS)
    assert ds["dte_amplitude"].dims[-1] == "frequency" and ds["ste"].dims[-1] == "angle"
    assert "dte" not in ds  # not asked for
    assert loads_study(ds.attrs["study"]).shape == (2, 2, 2)
    assert "software" in ds.attrs and "machine" in ds.attrs and "created" in ds.attrs
    assert not parts_folder(out).exists()  # complete: the per-point files are gone
    with xr.open_dataset(out, engine="netcdf4") as back:
        xr.testing.assert_identical(back.load(), ds)
        assert back["ste"].encoding.get("zlib")


def test_archive_passes_the_cf_checker(swept):
    pytest.importorskip("compliance_checker")
    from cf_check import cf_errors
    _, out = swept
    assert cf_errors(out) == []


def test_archives_of_split_studies_open_together(swept, tmp_path):
    res, _ = swept
    paths = []
    for w in (50.0, 100.0):
        grid = GRID.replace('{start = 50.0, stop = 100.0, num = 2}', f"[{w}]")
        p = tmp_path / f"w{w:g}.nc"
        run_sweep(tiny_study(grid), p, workers=0, progress=False)
        paths.append(p)
    # the static outputs do not lie over the split dimension (speed): taken once, checked equal
    with xr.open_mfdataset(paths, engine="netcdf4", combine="by_coords", data_vars="minimal", compat="no_conflicts") as both:
        both = both.load()
    assert both["ste_p2p"].dims == ("n_holes", "web_thickness")
    xr.testing.assert_equal(both.drop_vars("wall_time"), res.dataset.drop_vars("wall_time"))
    # with every variable concatenated they gain the split dimension, the same value along it
    with xr.open_mfdataset(paths, engine="netcdf4", combine="by_coords", data_vars="all", compat="no_conflicts") as every:
        every = every.load()
    ste = every["ste_p2p"].transpose("n_holes", "web_thickness", "speed")
    xr.testing.assert_equal(ste, res.dataset["ste_p2p"].broadcast_like(ste).transpose(*ste.dims))

"""The paper example's archive: the paper model's run, with the default model's STE and DTE
beside it (the default's run is also what fills the numba cache for `lightgear run`)."""
import numpy as np
import xarray as xr

import study
from workflows.paper_example import main

SETS = ("dynamic.duration=0.03", "quasi_static.rotation=15")


def test_the_default_models_dte_is_stored_beside_the_papers_and_is_its_own_run(tmp_path):
    out = tmp_path / "pe.nc"
    argv = ["small_lightened", "--no-figures", "--transient-rotation", "0", "-o", str(out)]
    for s in SETS:
        argv += ["--set", s]
    assert main(argv) == 0
    with xr.open_dataset(out) as ds:
        ds = ds.load()
    assert ds.attrs["coupling_model"] == "paper"
    assert ds.attrs["default_coupling_model"] == "compliance"
    dflt = ds["dte_default"]
    assert dflt.attrs["units"] == "um" and dflt.dims == ("time",)
    assert np.array_equal(dflt["time"].values, ds["dte"]["time"].values)
    # the default model's own run, to the last bit
    own = study.run_scene(study.load_scene("small_lightened", list(SETS)), static=False)
    np.testing.assert_array_equal(dflt.values, own["dte"].values)
    # and another model than the paper's: the lightened body's compliance moves the DTE
    assert np.max(np.abs(dflt.values - ds["dte"].values)) > 1e-3

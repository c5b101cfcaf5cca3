"""benchmarks/archive_diff.py: two study archives equal variable by variable, or told apart."""
import sys
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))
from archive_diff import differences, main  # noqa: E402


def archive(ste, status=(1, 1, 1), wall=(0.1, 0.2, 0.3)):
    return xr.Dataset({"ste_p2p": ("speed", np.array(ste, float)), "status": ("speed", np.array(status)),
                       "wall_time": ("speed", np.array(wall)), "title": ((), "x")},
                      coords={"speed": [1.0, 2.0, 3.0]})


def test_equal_archives_pass_and_a_changed_value_nan_or_missing_variable_fails(tmp_path):
    a = archive([1.0, 2.0, np.nan])
    same = archive([1.0, 2.0, np.nan], wall=(9.0, 9.0, 9.0))          # only the compute times differ
    assert [(n, r) for n, r, _ in differences(a, same)] == [("status", 0.0), ("ste_p2p", 0.0)]
    rel = dict((n, r) for n, r, _ in differences(a, archive([1.0, 2.0 + 2e-6, np.nan])))
    assert np.isclose(rel["ste_p2p"], 1e-6)                             # of the largest magnitude, 2
    assert differences(a, archive([1.0, 2.0, 3.0]))[1][2] == "NaNs differ"
    assert differences(a, a.drop_vars("status"))[0][2] == "missing"
    paths = []
    for name, ds in (("a", a), ("same", same), ("off", archive([1.0, 2.1, np.nan]))):
        ds.to_netcdf(tmp_path / f"{name}.nc")
        paths.append(str(tmp_path / f"{name}.nc"))
    assert main([paths[0], paths[1]]) == 0
    assert main([paths[0], paths[2]]) == 1
    assert main([paths[0], paths[2], "--rtol", "0.1"]) == 0

"""The run archive's schema: every variable a run writes is declared once, with the dimensions,
unit and long name it is written with; the status codes load no numba."""
import os
import subprocess
import sys

import pytest

import study
from study.archive.schema import GEAR_VARIABLES, RUN_VARIABLES, variable


@pytest.fixture(scope="module")
def run_archive():
    """The example study's 20-tooth pair, lightened, with the mesh outputs: 3 deg of STE, 4 ms of DTE."""
    base = study.load_study(os.path.join(os.path.dirname(study.__file__), "scenes", "example_study.toml")).base_scene()
    return study.run_scene(base.replace(**{"quasi_static.rotation": 3.0, "dynamic.duration": 0.004,
                                           "dynamic.ramp_time": 0.001, "gear2.body.holes": 4,
                                           "gear2.body.hole_radius": 1.8}))


def test_every_variable_of_a_run_archive_is_declared_as_written(run_archive):
    written = set(run_archive.variables)
    assert {"ste", "dte", "tooth_stiffness", "mass", "mode_frequency", "mesh_stiffness", "dte_contact_force"} <= written
    for name in written:
        assert name in RUN_VARIABLES, f"{name} is written but not declared in study.archive.schema"
        v, decl = run_archive[name], RUN_VARIABLES[name]
        assert v.dims == decl.dims, name
        assert v.attrs["units"] == decl.units and v.attrs["long_name"] == decl.long_name, name
        assert all(v.attrs[k] == a for k, a in decl.attrs.items()), name


def test_declared_variables_build_with_their_fixed_attributes_first():
    v = variable("ste_amplitude", [1.0, 2.0], resolution_orders=0.5)
    assert v.dims == ("ste_order",) and list(v.attrs) == ["units", "long_name", "window", "resolution_orders"]
    assert set(GEAR_VARIABLES) <= set(RUN_VARIABLES)
    with pytest.raises(KeyError):
        variable("not_an_archive_variable", [1.0])


def test_status_codes_and_archive_readers_load_no_numba():
    code = ("import sys; import solver.mbs.kernels.status, study.sweep.outputs, study.report.effects, "
            "study.archive.summary, study.archive.netcdf; print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"

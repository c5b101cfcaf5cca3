"""A study's task reads its run without building the run archive (`study.run.run_fields`, lean:
no documenting attributes, no per-gear variables it was not asked for): every scalar and curve it
gives must be the one the full run archive (`study.run.run_scene`, an xarray.Dataset) gives."""
import math
import tomllib

import numpy as np
import pytest
import xarray as xr
from sweep_cases import BASE

from study.archive.summary import summarize
from study.plan import RunOptions, scene_stages
from study.run import RunFields, run_fields, run_scene
from study.scene import scene_from_dict
from study.sweep.engine import point_values, run_point
from study.sweep.outputs import CURVES, MESH_SCALARS, SCALARS, Outputs

ALL = Outputs(tuple(SCALARS), tuple(CURVES))


def scene_of(**changes):
    """The sweep tests' tiny pair (uniform springs, a 4-hole driven gear), with ``changes``
    ({table: {field: value}}) over its fields."""
    data = tomllib.loads(BASE)["scene"]
    data["gear2"]["body"]["holes"] = 4
    for table, fields in changes.items():
        data.setdefault(table, {}).update(fields)
    return scene_from_dict(data)


def archive_values(scene, outputs: Outputs):
    """(status, message, scalars, curves) read from the full run archive, as a study's task
    read them before it took the lean path."""
    stages = scene_stages(scene, outputs.static, outputs.dynamic)
    if not set(outputs.scalars + outputs.curves) & set(MESH_SCALARS):
        stages -= {"mesh"}
    ds = run_fields(scene, stages, RunOptions(warn=False)).dataset()
    return point_values(ds, outputs)


def assert_same_values(lean, full):
    status, message, scalars, curves = lean
    assert (status, message) == full[:2]
    assert list(scalars) == list(full[2])
    for k, v in scalars.items():
        assert v == full[2][k] or (math.isnan(v) and math.isnan(full[2][k])), k
    assert list(curves) == list(full[3])
    for name, (axis, x, x_attrs, y, y_attrs) in curves.items():
        f_axis, f_x, f_x_attrs, f_y, f_y_attrs = full[3][name]
        assert axis == f_axis and x_attrs == f_x_attrs and y_attrs == f_y_attrs, name
        assert x.dtype == f_x.dtype and y.dtype == f_y.dtype, name
        np.testing.assert_array_equal(x, f_x)
        np.testing.assert_array_equal(y, f_y)


def test_run_fields_summarise_like_the_run_archive():
    """Every summary scalar of a full run (static, mesh outputs, modes, dynamic with friction:
    the efficiency; a lightened driven gear: the per-gear variables) read from the variables
    equals the one read from the archive they make."""
    scene = scene_of(contact={"friction": 0.05})
    run = run_fields(scene, options=RunOptions(warn=False))
    ds = run.dataset()
    a, b = summarize(run), summarize(ds)
    assert list(a) == list(b) and len(a) > 30
    assert {"mesh_efficiency", "critical_speed_z", "c_prime", "mass_gear2", "amp_mesh_order"} <= set(a)
    for k in a:
        assert a[k] == b[k] or (math.isnan(a[k]) and math.isnan(b[k])), k
    assert math.isfinite(a["mesh_efficiency"]) and 0 < a["mesh_efficiency"] < 1
    # what the archive holds is exactly the variables and attributes run_fields gave
    assert set(ds.variables) == set(run.variables) and ds.attrs == run.attrs
    assert "scene" in run.attrs and "code_fingerprint" in run.attrs


@pytest.mark.parametrize("outputs", [
    Outputs(("ste_mean", "ste_elastic_mean", "ste_p2p"), ("ste",)),                                      # static
    Outputs(("ste_p2p", "mesh_stiffness_mean", "c_prime", "loaded_contact_ratio"), ("mesh_stiffness",)),  # mesh
    Outputs(("ste_p2p", "mass_gear2", "inertia_gear1", "root_stress_ratio_gear2")),            # static + per gear
    Outputs(("dte_rms", "dte_p2p", "dte_mean", "tooth_force_max", "amp_mesh_order", "amp_hole_order",
             "mesh_mode_damping_decay"), ("dte", "dte_amplitude")),                                        # dynamic
    Outputs(("dte_rms", "dynamic_factor")),                                                   # dynamic + mesh
    Outputs(("mesh_mode_frequency", "mesh_mode_damping", "critical_speed_z", "critical_speed_3z")),       # modes
], ids=["static", "mesh", "gears", "dynamic", "dynamic-mesh", "modes"])
def test_a_task_gives_the_run_archives_scalars_and_curves(outputs):
    scene = scene_of()
    for part in outputs.parts():
        lean = run_point(scene, part)
        assert lean["status"] == "ok", lean["message"]
        full = archive_values(scene, part)
        assert_same_values((lean["status"], lean["message"], lean["scalars"], lean["curves"]), full)
        assert all(math.isfinite(v) for k, v in lean["scalars"].items() if k not in ("amp_hole_order",
                                                                                    "root_stress_ratio_gear2"))


def test_geometry_and_fe_only_points():
    """No solve: the per-gear variables alone, the same with or without a run."""
    scene = scene_of()
    out = Outputs(("mass_gear1", "mass_saving_gear2", "root_stress_max_gear2"))
    r = run_point(scene, out)
    full = archive_values(scene, Outputs(("ste_p2p", *out.scalars)))
    assert r["status"] == "ok" and r["scalars"] == {k: full[2][k] for k in out.scalars if k != "root_stress_max_gear2"} | \
        {"root_stress_max_gear2": r["scalars"]["root_stress_max_gear2"]}
    assert math.isnan(r["scalars"]["root_stress_max_gear2"])     # uniform springs: no FE


def test_a_stopped_dynamic_run_gives_the_archives_status_and_message():
    """A dynamic run that stops (an output step the time step cannot keep): diverged, its numbers
    withheld, the same message either way."""
    scene = scene_of(dynamic={"output_step": 1e-4, "time_step": 5e-5})
    out = Outputs(("dte_rms", "mesh_mode_frequency"), ("dte",))
    lean = run_point(scene, out)
    full = archive_values(scene, out)
    assert lean["status"] == "diverged" and "dynamic run stopped" in lean["message"]
    assert_same_values((lean["status"], lean["message"], lean["scalars"], lean["curves"]), full)
    assert math.isnan(lean["scalars"]["dte_rms"]) and lean["curves"] == {}
    assert math.isfinite(lean["scalars"]["mesh_mode_frequency"])


def test_an_invalid_run_is_refused_with_its_reason():
    """A run refused before it starts (outputs larger than the memory) is an invalid point whose
    message names the field."""
    scene = scene_of(dynamic={"duration": 1e4})
    r = run_point(scene, Outputs(("dte_rms",)))
    assert r["status"] == "invalid" and r["message"].startswith("dynamic.duration")
    assert math.isnan(r["scalars"]["dte_rms"]) and r["curves"] == {}
    with pytest.raises(Exception, match="memory available"):
        run_scene(scene, warn=False)


def test_a_dimension_without_coordinate_reads_as_its_positions():
    """As in the archive it makes: a dimension that has no coordinate variable reads as 0, 1, ..."""
    run = RunFields({"angle": xr.Variable(("angle",), [0.0, 0.5])},
                    {"force": xr.Variable(("angle", "slot"), np.ones((2, 3)), {"units": "N"})}, {"title": "t"})
    ds = run.dataset()
    assert "slot" not in run and "slot" not in ds
    np.testing.assert_array_equal(run["slot"].values, ds["slot"].values)
    np.testing.assert_array_equal(run["slot"].values, [0, 1, 2])
    assert float(run["angle"][1]) == 0.5 and run["force"].attrs == ds["force"].attrs == {"units": "N"}
    with pytest.raises(KeyError):
        run["no_such_variable"]


def test_points_of_one_model_share_its_springs_and_model_only():
    """A study's worker keeps the springs and model of the last scene: reused for a scene that
    differs only in its run's speed, made again when the mean load (the damping conversion's)
    or the body changes."""
    from study.plan import kept_springs_and_model
    base = scene_of()
    springs, model = kept_springs_and_model(base)
    faster = kept_springs_and_model(scene_of(dynamic={"speed": 180.0, "duration": 0.02}))
    assert faster[0] is springs and faster[1] is model
    loaded = kept_springs_and_model(scene_of(dynamic={"torque": 80.0}))
    assert loaded[1] is not model
    other = kept_springs_and_model(base.replace(**{"gear2.body.holes": 0}))
    assert other[1] is not model and other[1].body_inertia[1] > model.body_inertia[1]     # no holes: heavier
    # the FE cache cleared (or another one): the springs are read again, not kept from before
    from solver.store import STORE
    STORE.clear()
    again = kept_springs_and_model(base.replace(**{"gear2.body.holes": 0}))
    assert again[0] is not other[0]

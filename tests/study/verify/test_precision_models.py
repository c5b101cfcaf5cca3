"""Work-precision of the default (compliance) model beside the paper model's, and against the FE
mesh size, on the small pair (module 3, 24 teeth, solid bodies: its FE solves in seconds):
second-order fall of the error with the step in both models, each against its own converged
answer; the STE and DTE errors falling as the FE mesh is refined; the archives and the plot."""
import math

import numpy as np
import pytest

from study.verify.precision_cases import ScipyRuns


@pytest.fixture(scope="module")
def small():
    import study
    return study.load_scene("small_pair", ["dynamic.duration=0.004", "dynamic.ramp_time=0.001"])


@pytest.fixture(scope="module")
def models(small):
    """Both models of the small pair, the compliance model's FE solved in an empty cache."""
    from study.commands import precision_scene
    from study.scene_model import build_scene_model
    from study.verify.precision_mesh import empty_fe_cache
    out = {}
    with empty_fe_cache():
        for name in ("paper", "compliance"):
            sc = precision_scene(small.replace(**{"coupling.model": name}))
            out[name] = sc, build_scene_model(sc)
    return out


def _ladder(ds, method):
    return ds["te_error"].sel(norm="linf").values[ds["method"].values == method]


def test_the_step_error_falls_at_second_order_in_both_models(models):
    """1 ms window, ramps ending at 0.5 ms: the explicit schemes at 1/2 and 1/4 of their
    stability steps. Each model against its own reference (the paper model: DOP853; the
    compliance model, which has no scipy peer: all-explicit Verlet at 1/32 of its step, checked
    at 1/16); a halved step divides the error by about 4 in both schemes of both models (the
    implicit-damper scheme converging to the all-explicit reference: one answer of the
    equations), and the references agree far below the smallest error."""
    from study.verify.precision_study import dynamic_study
    ds = {name: dynamic_study(sc, m, duration=0.001, repeats=1, explicit_fractions=(2, 4), implicit_multiples=(1,),
                              alphas=(0.0,), scipy=ScipyRuns(methods=()), active_set=False)
          for name, (sc, m) in models.items()}
    c = ds["compliance"]
    assert c.attrs["model"] == "compliance model" and "compliance model" in c.attrs["title"]
    assert "1/32 of the stability step" in c.attrs["reference"]
    # no implicit integrator and no scipy peer for the coupled model: its ladders are the explicit ones
    assert set(c["method"].values) == {"explicit", "explicit, implicit dampers"}
    assert "implicit alpha=0" in set(ds["paper"]["method"].values)
    for name, d in ds.items():
        assert np.all(d["status"].values == "ok"), (name, d["message"].values)
        assert np.all(d["cpu_time"].values > 0) and d["cpu_time"].attrs["units"] == "s"
        for method in ("explicit", "explicit, implicit dampers"):
            e = _ladder(d, method)
            assert 3.0 < e[0] / e[1] < 5.5, (name, method, e)          # 4x per halved step
        assert d.attrs["reference_difference_linf_um"] < 0.05 * np.nanmin(d["te_error"].sel(norm="linf").values)


def test_the_compliance_statics_against_its_own_reference(models):
    """Static Newton at a loose and a tight tolerance against Newton at 1e-13, cross-checked by
    the same solver over the angles in reverse order (each angle started from another solution)."""
    from study.verify.precision_report import cheapest
    from study.verify.precision_study import static_study
    sc, m = models["compliance"]
    ds = static_study(sc, m, rotation_deg=1.0, repeats=1, tols=(1e-2, 1e-8), explicit_fractions=(1,))
    assert "reverse order" in ds.attrs["cross_check"] and ds.attrs["transient_step_bound_s"] > 0
    assert ds.attrs["reference_difference_linf_um"] < 1e-6
    st = _ladder(ds, "static Newton")
    assert st[1] < 1e-3 * st[0] and st[1] < 1e-6
    assert set(ds["method"].values) == {"static Newton", "slow-ramp transient, explicit"}
    assert cheapest(ds, 0.01)[0] == "static Newton"


@pytest.fixture(scope="module")
def mesh(small):
    """The compliance model of the small pair at fe.mesh_size 1.125, 0.75 and 0.45 mm, each
    size's FE from an empty cache, STE over one mesh cycle (15 deg), DTE of 4 ms."""
    import study
    return study.precision_mesh(small.replace(**{"coupling.model": "compliance"}), None, (1.5, 1.0, 0.6), 15.0, 1)


def test_the_error_falls_as_the_fe_mesh_is_refined(mesh):
    h = mesh["mesh_size"].values
    assert np.allclose(h, [1.125, 0.75, 0.45]) and mesh["mesh_size"].attrs["units"] == "mm"
    assert list(mesh["level"].values) == ["x1.5", "x1", "x0.6"]
    for k in ("ste_mean_error", "ste_error_linf", "dte_error_linf"):
        e = mesh[k].values
        assert mesh[k].attrs["units"] == "um"
        assert e[-1] == 0 and e[0] > e[1] > 0, (k, e)          # the finest is the reference
    # the errors are small beside what they measure: the mesh moves the STE by < 1 %
    assert mesh["ste_mean_error"].values[0] < 0.01 * mesh["ste_mean"].values[-1]
    # a finer body costs more FE time (both gears: the same solid body, solved once)
    fe = mesh["fe_cpu_time"].sum("gear").values
    assert fe[-1] > fe[0] > 0
    assert np.all(mesh["dynamic_cpu_time"].values > 0) and np.all(mesh["static_cpu_time"].values > 0)


def test_the_mesh_study_leaves_the_fe_cache_as_it_was_and_writes_its_archive(mesh, tmp_path):
    import os

    import xarray as xr

    from study.archive.netcdf import write_netcdf
    from study.verify.precision_mesh import mesh_plot, mesh_table
    assert mesh.attrs["fresh_fe_cache"] == 1
    assert "lightgear-fe-" not in os.environ.get("LIGHTGEAR_CACHE", "")
    write_netcdf(mesh, tmp_path / "m.nc")
    back = xr.open_dataset(tmp_path / "m.nc")
    assert np.allclose(back["ste_error_linf"].values, mesh["ste_error_linf"].values)
    assert list(back["level"].values) == list(mesh["level"].values)
    mesh_plot(mesh, tmp_path / "m.png")
    assert (tmp_path / "m.png").stat().st_size > 10_000
    text = mesh_table(mesh)
    assert "x0.6" in text and "errors [um] against the finest mesh" in text
    import importlib.util
    if importlib.util.find_spec("compliance_checker"):
        from cf_check import cf_errors
        assert cf_errors(tmp_path / "m.nc") == []


def test_mesh_options_are_refused_with_their_reason(small, tmp_path):
    import argparse

    import study
    from study.verify.precision_mesh import mesh_study
    for args, words in (((None,), "scene"), ((small, tmp_path / "m.nc", (1.0,)), "factors"),
                        ((small, None, (1.0, -0.5)), "factors"), ((small, None, (2, 1), -6.0), "rotation"),
                        ((small, None, (2, 1), 6.0, 1.5), "repeats"), ((small, 5), "output")):
        with pytest.raises(TypeError, match=f"precision_mesh: {words}"):
            study.precision_mesh(*args)
    assert not list(tmp_path.iterdir())        # refused before any work
    from workflows.work_precision import mesh_factors, model_output
    assert mesh_factors("2,1,0.5") == (2.0, 1.0, 0.5)
    for bad in ("1", "2,x", "1,-1", f"1,{math.inf}"):
        with pytest.raises(argparse.ArgumentTypeError):
            mesh_factors(bad)
    with pytest.raises(ValueError, match="factors"):
        mesh_study(None, (1.0,))
    assert model_output("r/wp.nc", "paper") == "r/wp.nc"
    assert model_output("r/wp.nc", "compliance") == "r/wp_compliance.nc"


def test_the_estimate_of_a_coupled_models_study_counts_no_scipy_runs(models):
    """`lightgear precision` estimates its time before any work: the compliance model has no scipy
    runs and no implicit ladder to count, the paper model both."""
    from study.estimate import precision_estimate
    est = {name: precision_estimate(sc, m, 0.001, 1.0, 1) for name, (sc, m) in models.items()}
    assert est["compliance"].seconds["dynamic: scipy reference and runs"] == 0
    assert est["paper"].seconds["dynamic: scipy reference and runs"] > 0
    assert est["compliance"].seconds["static"] < est["paper"].seconds["static"]
    assert est["compliance"].seconds["dynamic: numba runs"] > 0

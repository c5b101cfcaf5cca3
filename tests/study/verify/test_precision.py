"""Work-precision study on tiny cases: dataset contract, references that agree far below the
smallest error, errors that fall with the step or tolerance, failed runs kept as NaN with
their message, the plot."""
import importlib.util
import math

import numpy as np
import pytest
from helpers import solid_scene

from study.verify.precision_cases import ScipyRuns, Spec
from study.verify.precision_report import cheapest, plot
from study.verify.precision_study import dynamic_study, run_study, static_study


@pytest.fixture(scope="module")
def dyn(paper_solid_scene, paper_solid_model):
    """1 ms window (ramps end at 0.5 ms): explicit (all explicit, and with implicit tooth-root
    dampers) at 1 and 1/2 of its stability step, the production path, the
    implicit one at 1 and 4 times it (the scipy stiff solvers take minutes here: they run in
    the workflow, their code path is tested in tests/solver/peers/test_scipy_dynamics.py)."""
    return dynamic_study(paper_solid_scene, paper_solid_model, duration=0.001, repeats=1, explicit_fractions=(1, 2),
                           implicit_multiples=(4, 1), alphas=(0.0,), scipy=ScipyRuns(methods=()), active_set=True)


def test_dynamic_dataset_contract(dyn):
    assert dict(dyn.sizes) == {"run": 9, "norm": 3}
    assert list(dyn["norm"].values) == ["final", "l2", "linf"]
    assert dyn["te_error"].attrs["units"] == "um" and dyn["wall_time"].attrs["units"] == "s"
    assert dyn["step"].attrs["units"] == "s"
    for key in ("reference", "cross_check", "machine", "case", "reference_difference_linf_um"):
        assert key in dyn.attrs
    assert set(dyn["method"].values) == {"explicit", "explicit, active set", "implicit alpha=0",
                                         "explicit, implicit dampers", "explicit, production"}
    assert np.all(dyn["status"].values == "ok"), dyn["message"].values
    e = dyn["te_error"].values
    assert np.all(e[:, 1] <= e[:, 2] + 1e-15)          # rms <= max
    assert np.all(np.isfinite(dyn["wall_time"].values))
    # the first run of a method carries its compile/first-call time, apart from the wall time
    assert np.isfinite(dyn["first_call_time"].values[0])


def test_references_agree_far_below_the_smallest_error(dyn):
    """DOP853 at rtol 1e-10 and Verlet at 1/32 of its stability step: two different solvers
    whose difference lies two orders of magnitude below the smallest error in the study."""
    d = dyn.attrs["reference_difference_linf_um"]
    assert d < 0.01 * np.nanmin(dyn["te_error"].sel(norm="linf").values)


def test_errors_fall_with_the_step_at_least_at_second_order(dyn):
    e = dyn["te_error"].sel(norm="linf").values
    m = dyn["method"].values
    ex = e[m == "explicit"]
    im = e[m == "implicit alpha=0"]
    imex = e[m == "explicit, implicit dampers"]
    assert ex[0] / ex[1] > 3.0                          # halved step: error / 4 or better
    assert imex[0] / imex[1] > 3.0
    assert im[0] > 8 * im[1]                            # 4x smaller step: error / 16


def test_static_study_and_failed_run_kept(paper_solid_scene, paper_solid_model, tmp_path):
    ds = static_study(paper_solid_scene, paper_solid_model, rotation_deg=0.5, repeats=1, tols=(1e-2, 1e-8),
                        explicit_fractions=(1,), implicit_multiples=(4,), alphas=(0.0,))
    e = ds["te_error"].sel(norm="linf").values
    m = ds["method"].values
    st = e[m == "static Newton"]
    assert st[1] < st[0] and st[1] < 1e-6            # tighter Newton, smaller error [um]
    assert ds.attrs["reference_difference_linf_um"] < 1e-6
    # the slow-ramp transient differs from the static STE by its own ringing, not by the solver
    assert np.all(e[m != "static Newton"] > 1e-3)
    c = cheapest(ds, 0.01)
    assert c[0] == "static Newton"
    # a run whose solver raises, and one stopped by a guard, stay as NaN with their message
    bad = [Spec("broken", math.nan, 1e-3, lambda: 1 / 0),
           Spec("guarded", 1e-6, math.nan, lambda: (np.zeros(3), 10, 2, "penetration beyond the bound at t = 1e-06 s"))]
    ds2 = run_study(bad, np.zeros(3), np.zeros(3), ("a", "b"), repeats=1)
    assert np.all(np.isnan(ds2["te_error"].values))
    assert list(ds2["status"].values) == ["failed", "failed"]
    assert "ZeroDivisionError" in ds2["message"].values[0] and "penetration" in ds2["message"].values[1]
    plot(ds, tmp_path / "wp.png")
    assert (tmp_path / "wp.png").stat().st_size > 10_000
    from study.archive.netcdf import write_netcdf
    write_netcdf(ds2, tmp_path / "wp.nc")
    import xarray as xr
    back = xr.open_dataset(tmp_path / "wp.nc")
    assert list(back["message"].values) == list(ds2["message"].values)
    if importlib.util.find_spec("compliance_checker"):
        from cf_check import cf_errors
        write_netcdf(ds, tmp_path / "wp_static.nc")
        assert cf_errors(tmp_path / "wp.nc") == [] and cf_errors(tmp_path / "wp_static.nc") == []


def test_stability_suite_subset_ends_ok_or_named():
    """Stiff and extreme scenes (solid bodies, no FE): every run ends bounded and plausible or
    with a failure that names its cause, time and step; never a silent NaN. On a 30/30-tooth
    pair of module 3 (60 teeth against the Table 1 pair's 134): the integrators' method choice
    solves the eigenproblems of the linearised pair, whose cost grows with the cube of the
    teeth (about 4 s of CPU against 30 s), and ending bounded or named does not depend on them."""
    import re

    from study.verify import stability as S
    names = ["contact stiffness x100", "no damping", "teeth 100x lighter", "zero torque", "overload x10"]
    pair = {"gear1.module": 3.0, "gear1.teeth": 30, "gear2.module": 3.0, "gear2.teeth": 30}
    ds = S.run_suite(solid_scene(**pair), duration=0.002, methods=("explicit", "implicit alpha=-0.1", "LSODA"),
                     scipy_wall=1.0, names=names, progress=lambda *a: None)
    assert list(ds["scene"].values) == names
    st = ds["status"].values
    msg = ds["message"].values
    assert set(st.ravel()) <= {"ok", "failed"}, msg
    for i, j in zip(*np.nonzero(st == "failed")):
        assert re.search(r"at t = [0-9.e+-]+ s \(step \d+", msg[i, j]), msg[i, j]
    ok = st == "ok"
    assert np.all(np.isfinite(ds["te_min"].values[ok])) and np.all(np.isfinite(ds["te_max"].values[ok]))
    # the undamped pair under the explicit integrator conserves energy: it must run through
    assert st[names.index("no damping"), 0] == "ok"
    # zero torque rattles across the backlash: both flanks hit
    zt = names.index("zero torque")
    if st[zt, 0] == "ok":
        assert ds["te_min"].values[zt, 0] < 0 < ds["te_max"].values[zt, 0]
    # the scipy peer at 1 s of wall time stops with its named limit
    assert all(("wall-time limit" in m or s == "ok") for m, s in zip(msg[:, 2], st[:, 2]))


def test_precision_runs_the_papers_model_by_default_and_a_coupled_one_as_named():
    """The default 'auto' runs as 'paper' (every integrator the study compares exists for it); a
    coupled model named by the scene runs as named, with the explicit integrators it has."""
    from study.commands import precision_scene
    from study.scene import default_scene
    assert precision_scene(default_scene()).coupling_model == "none"
    assert precision_scene(default_scene().replace(**{"coupling.model": "compliance"})).coupling_model == "compliance"

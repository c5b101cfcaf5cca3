"""Main effects, the ANOVA sensitivity split and the Pareto set on synthetic grids (no solver)."""

import numpy as np
import pytest
import xarray as xr

from study.report.effects import main_effect, pareto_mask, pareto_table, sensitivity_table, with_study_tables

X = np.array([0.0, 1.0, 2.0, 4.0])
Y = np.array([-1.0, 0.5, 3.0])


def grid(f, status=None):
    xx, yy = np.meshgrid(X, Y, indexing="ij")
    data = {"f": (("x", "y"), f(xx, yy), {"units": "um"})}
    if status is not None:
        data["status"] = (("x", "y"), status)
    return xr.Dataset(data, coords={"x": X, "y": Y}, attrs={"outputs": "f"})


def share(tab, term):
    return float(tab["sensitivity_share"].sel(output="f", term=term))


def test_additive_function_splits_into_the_closed_form_variances_of_its_parts():
    a, b = np.sin(X) * 3.0, Y ** 2
    tab = sensitivity_table(grid(lambda x, y: np.sin(x) * 3.0 + y ** 2), ["x", "y"])
    total = a.var() + b.var()               # population variances over the grid values
    assert share(tab, "x") == pytest.approx(a.var() / total, rel=1e-12)
    assert share(tab, "y") == pytest.approx(b.var() / total, rel=1e-12)
    assert share(tab, "x x y") == pytest.approx(0.0, abs=1e-12)
    assert share(tab, "rest") == pytest.approx(0.0, abs=1e-12)
    assert int(tab["sensitivity_points"].sel(output="f")) == X.size * Y.size


def test_a_product_of_centred_parameters_is_all_interaction():
    xc, yc = X - X.mean(), Y - Y.mean()
    tab = sensitivity_table(grid(lambda x, y: (x - X.mean()) * (y - Y.mean())), ["x", "y"])
    assert share(tab, "x") == pytest.approx(0.0, abs=1e-12)
    assert share(tab, "y") == pytest.approx(0.0, abs=1e-12)
    assert share(tab, "x x y") == pytest.approx(1.0, rel=1e-12)
    # and x*y uncentred: main effects are the closed forms mean(y)*x and mean(x)*y
    tab = sensitivity_table(grid(lambda x, y: x * y), ["x", "y"])
    total = np.outer(X, Y).var()
    assert share(tab, "x") == pytest.approx((Y.mean() ** 2) * X.var() / total, rel=1e-12)
    assert share(tab, "x x y") == pytest.approx(xc.var() * yc.var() / total, rel=1e-12)


def test_three_parameters_rest_holds_the_three_way_interaction_and_unused_dims_get_zero():
    z = xr.DataArray([1.0, -1.0], dims="z", coords={"z": [0.0, 1.0]})
    base = grid(lambda x, y: (x - X.mean()) * (y - Y.mean()))
    ds = xr.Dataset({"f": base["f"] * z, "g": base["f"]}, attrs={"outputs": "f, g"})
    tab = sensitivity_table(ds, ["x", "y", "z"])
    assert float(tab["sensitivity_share"].sel(output="f", term="rest")) == pytest.approx(1.0)
    assert float(tab["sensitivity_share"].sel(output="g", term="z")) == 0.0
    assert float(tab["sensitivity_share"].sel(output="g", term="x x y")) == pytest.approx(1.0)


def test_points_not_ok_or_nan_are_left_out_not_counted_as_zero():
    status = np.ones((X.size, Y.size), np.int8)
    status[0, 0] = 4                                       # failed: its value is garbage
    f = lambda x, y: x + 0.0 * y                           # noqa: E731
    ds = grid(f, status)
    ds["f"][0, 0] = 1e9
    ds["f"][1, 1] = np.nan
    tab = sensitivity_table(ds, ["x", "y"])
    assert int(tab["sensitivity_points"].sel(output="f")) == X.size * Y.size - 2
    # y does nothing; the lost points unbalance the grid (means over fewer points), so the split
    # is approximate, but the failed point's garbage value does not enter it
    assert share(tab, "x") > 0.95 and share(tab, "y") < 0.03
    shares = tab["sensitivity_share"].sel(output="f").dropna("term")
    assert float(shares.sum()) == pytest.approx(1.0, rel=1e-12)
    me = main_effect(ds, "f", "x")
    np.testing.assert_allclose(me["mean"].values, X)
    assert me["count"].values.tolist() == [2, 2, 3, 3]


def test_pareto_set_equals_the_brute_force_non_dominated_set_within_the_stress_limit():
    rng = np.random.default_rng(3)
    gain = rng.uniform(0, 30, 60).round(1)                  # rounding makes ties happen
    cost = rng.uniform(1, 5, 60).round(1)
    ratio = rng.uniform(0.9, 1.4, 60)
    gain[5] = np.nan
    feasible = ratio <= 1.15
    got = pareto_mask(gain, cost, feasible)
    ok = feasible & np.isfinite(gain)
    brute = np.zeros(60, bool)
    for p in np.flatnonzero(ok):
        brute[p] = not any(gain[q] >= gain[p] and cost[q] <= cost[p] and (gain[q] > gain[p] or cost[q] < cost[p])
                           for q in np.flatnonzero(ok))
    np.testing.assert_array_equal(got, brute)
    assert got.sum() >= 2 and not got[~feasible].any()


def test_pareto_flags_over_the_grid_skip_failed_points_and_say_what_is_missing():
    dims = ("a", "b")
    coords = {"a": [1, 2, 3], "b": [0.0, 1.0]}
    saving = np.array([[0.0, 10.0], [20.0, 30.0], [40.0, 50.0]])
    ste = np.array([[1.0, 1.2], [1.1, 1.5], [2.0, 1.4]])
    ratio = np.array([[1.0, 1.0], [1.1, 1.1], [1.2, 1.1]])
    status = np.ones((3, 2), np.int8)
    status[2, 1] = 3                                   # invalid point: would otherwise dominate
    ds = xr.Dataset({"mass_saving_gear2": (dims, saving), "ste_p2p": (dims, ste),
                     "root_stress_ratio_gear2": (dims, ratio), "status": (dims, status)}, coords=coords)
    p = pareto_table(ds)["pareto_ste_p2p"]
    assert p.dtype == np.int8 and p.dims == dims
    assert [tuple(i) for i in np.argwhere(p.values)] == [(0, 0), (1, 0), (1, 1)]   # (0, 1) beaten by (1, 0)
    said = []
    assert not pareto_table(ds.drop_vars("mass_saving_gear2"), skip=lambda w, y: said.append(y)).data_vars
    assert said == ["the archive has no mass_saving_gear2"]
    assert set(with_study_tables(ds, ["a", "b"]).data_vars) >= {"pareto_ste_p2p", "sensitivity_share"}


def test_a_point_without_a_stress_ratio_is_not_in_the_pareto_set():
    """A ratio NaN (a lightened gear whose springs ran no FE) is unknown, not within the limit:
    the point is left out even with the least TE; a solid gear carries its ratio 1 in the archive."""
    dims = ("a",)
    ds = xr.Dataset({"mass_saving_gear2": (dims, [0.0, 20.0, 30.0, 25.0]), "ste_p2p": (dims, [0.5, 0.7, 0.6, 0.4]),
                     "root_stress_ratio_gear2": (dims, [1.0, 1.05, 1.3, np.nan]),
                     "status": (dims, np.ones(4, np.int8))}, coords={"a": [0, 1, 2, 3]})
    # the 30 % point is over the stress limit, the 25 % one has no known stress
    assert pareto_table(ds)["pareto_ste_p2p"].values.tolist() == [1, 1, 0, 0]

"""Sampled studies: draws reproducible from the seed and true to their distributions, bad
distributions refused before any work, Sobol indices against a closed form, resume after an
interruption, and the statistics of a sampled STE against its closed form."""
import math

import numpy as np
import pytest
import xarray as xr
from scipy import stats
from sweep_cases import BASE, assert_refused_before_any_work, count_points, ctrl_c_after_stored

from study.cli import main
from study.report.distributions import (
    exceedance,
    interval_note,
    min_builds,
    quantile_interval,
    sample_tables,
    sobol_indices,
    summary_statistics,
)
from study.scene import SceneError
from study.sweep.engine import parts_folder, run_sweep
from study.sweep.grid import loads_study, make_study
from study.sweep.sample import Distribution, Sample, unit_points

ECC = "gear1.errors.eccentricity"
# the tiny pair of the sweep tests (STE every 0.5 deg); with an eccentricity its statics cover one driver revolution
SCENE = BASE
assert "angle_step = 0.5" in SCENE


def sampled(sample: str, grid: str = "", outputs: str = '[outputs]\nscalars = ["ste_p2p"]\n'):
    return loads_study('title = "sampled"\n' + SCENE + grid + "\n[sample]\n" + sample + "\n" + outputs)


# ---------------------------------------------------------------- the sampler

@pytest.mark.parametrize("method", ["random", "lhs", "sobol"])
def test_the_draws_come_back_from_the_seed(method):
    spec = {"size": 64, "method": method, "seed": 7, ECC: {"uniform": [0.0, 6.0]},
            "gear1.errors.seed": {"integers": [0, 1000]}, "gear1.modification.tip_relief": {"normal": [2.0, 0.5]}}
    relief = {"gear1.modification.tip_length": 2.0}
    a = make_study(relief, sample=spec, outputs={"scalars": ["ste_p2p"]})
    b = loads_study(a.text)                       # the archived study text gives the same draws
    c = make_study(relief, sample={**spec, "seed": 8}, outputs={"scalars": ["ste_p2p"]})
    for path in a.sample.paths:
        np.testing.assert_array_equal(a.sample.values[path], b.sample.values[path])
        assert not np.array_equal(a.sample.values[path], c.sample.values[path])
    pts = a.points()
    assert len(pts) == 64 and pts[5].values[ECC] == a.sample.values[ECC][5]
    assert pts[5].scene.gear1.errors.eccentricity == a.sample.values[ECC][5]


def _dist(kind, params, bounds=None, integer=False):
    b = bounds or ((params[0], params[1]) if kind != "normal" else (-math.inf, math.inf))
    return Distribution("x", kind, params, b, integer)


@pytest.mark.parametrize("method", ["random", "lhs", "sobol"])
@pytest.mark.parametrize("dist, mean, var", [
    (_dist("uniform", (1.0, 7.0)), 4.0, 36.0 / 12.0),
    (_dist("normal", (2.0, 0.5)), 2.0, 0.25),
    # truncated to [0, inf): a field's range (tip_relief >= 0) cuts the normal's lower tail
    (_dist("normal", (0.5, 1.0), (0.0, math.inf)),
     *stats.truncnorm(-0.5, math.inf, loc=0.5, scale=1.0).stats("mv")),
    (_dist("integers", (3, 12), integer=True), 7.5, (10 ** 2 - 1) / 12.0),
])
def test_the_moments_of_each_distribution_within_sampling_error(method, dist, mean, var):
    n = 4096
    x = dist.ppf(unit_points(method, n, 1, seed=3)[:, 0])
    mean, var = float(mean), float(var)
    # standard errors of the mean and the variance of n independent draws (4 sigma: the
    # stratified methods sit far inside)
    kurt = np.mean((x - x.mean()) ** 4)
    assert abs(x.mean() - mean) < 4 * math.sqrt(var / n)
    assert abs(x.var() - var) < 4 * math.sqrt((kurt - var ** 2) / n)
    lo, hi = dist.bounds
    assert x.min() >= lo and x.max() <= hi
    if dist.kind == "integers":
        assert x.dtype.kind == "i" and set(np.unique(x)) == set(range(3, 13))


@pytest.mark.parametrize("sample, field, reason", [
    ('size = 8\n"gear1.errors.eccentricity" = {uniform = [6.0, 1.0]}', ECC, "needs lo <= hi"),
    ('size = 8\n"gear1.errors.eccentricity" = {uniform = [-1.0, 3.0]}', ECC, "outside the field's range"),
    ('size = 8\n"gear1.errors.eccentricity" = {normal = [2.0, -0.5]}', ECC, "sd >= 0"),
    ('size = 8\n"gear1.errors.eccentricity" = {normal = [2.0, 0.5], bounds = [3.0, 1.0]}', ECC, "lo < hi"),
    ('size = 8\n"gear1.errors.eccentricity" = {normal = [-2.0, 0.5]}', ECC, "outside the range"),
    ('size = 8\n"gear1.errors.eccentricity" = {uniform = [0.0, 1.0], bounds = [0.0, 1.0]}', ECC, "bounds go with"),
    ('size = 8\n"gear1.errors.eccentricity" = {poisson = [2.0]}', ECC, "one of uniform"),
    ('size = 8\n"gear1.errors.eccentricity" = [0.0, 1.0]', ECC, "distribution table"),
    ('size = 8\n"gear1.errors.seed" = {uniform = [0.0, 10.0]}', "gear1.errors.seed", "integer field takes"),
    ('size = 8\n"gear1.errors.grade" = {integers = [0, 12]}', "gear1.errors.grade", "must be <= 11"),
    ('size = 8\n"gear2.spring.stiffness" = {uniform = [0.0, 1.0]}', "gear2.spring.stiffness", "draws numbers"),
    ('size = 8\n"dynamic.enabled" = {uniform = [0.0, 1.0]}', "dynamic.enabled", "draws numbers"),
    ('size = 8\n"gear1.errors.pitch" = {uniform = [0.0, 1.0]}', "gear1.errors.pitch", "draws numbers"),
    ('size = 8\n"gear1.errors.eccentricty" = {uniform = [0.0, 1.0]}', "gear1.errors.eccentricty", "no such scene field"),
    ('size = 1\n"gear1.errors.eccentricity" = {uniform = [0.0, 1.0]}', "sample.size", "at least 2"),
    ('size = 8\nmethod = "halton"\n"gear1.errors.eccentricity" = {uniform = [0.0, 1.0]}', "sample.method", "one of"),
    ('size = 8\ndesign = "morris"\n"gear1.errors.eccentricity" = {uniform = [0.0, 1.0]}', "sample.design", "one of"),
    ('size = 8', "sample", "draws no field"),
])
def test_bad_distributions_are_refused_before_any_work_naming_the_field(sample, field, reason, monkeypatch):
    assert_refused_before_any_work(monkeypatch, sampled, sample, field, reason)


def test_a_field_is_either_swept_or_drawn_and_a_sample_takes_no_points():
    with pytest.raises(SceneError, match="drawn by") as e:
        sampled('size = 4\n"gear1.errors.eccentricity" = {uniform = [0.0, 1.0]}',
                grid="[grid]\n\"gear1.errors.eccentricity\" = [1.0, 2.0]\n")
    assert e.value.field == ECC
    with pytest.raises(SceneError, match="not \\[\\[points\\]\\]"):
        sampled('size = 4\n"gear1.errors.eccentricity" = {uniform = [0.0, 1.0]}',
                grid="[[points]]\n\"dynamic.speed\" = 60.0\n")


def test_cli_refuses_a_bad_sample_with_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('[grid]\n"dynamic.speed" = [50.0]\n[sample]\nsize = 4\n"gear1.errors.eccentricity" = {uniform = [3.0, 1.0]}\n')
    assert main(["sweep", str(bad), "-o", str(tmp_path / "bad.nc"), "--workers", "0"]) == 2
    assert "gear1.errors.eccentricity" in capsys.readouterr().err


# ---------------------------------------------------------------- Sobol indices

def test_sobol_indices_of_the_ishigami_function_within_their_intervals():
    """Ishigami: f = sin x1 + a sin^2 x2 + b x3^4 sin x1, x_i uniform on [-pi, pi]: closed-form
    first-order and total indices (Sobol' & Levitan 1999)."""
    a, b, pi = 7.0, 0.1, math.pi
    fields = tuple(Distribution(f"x{i}", "uniform", (-pi, pi), (-pi, pi), False) for i in range(3))
    s = Sample(1024, "sobol", 5, "saltelli", fields)
    assert s.builds == 1024 * 5
    x = np.column_stack([s.values[f"x{i}"] for i in range(3)])
    y = np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])
    v1, v2, v13 = 0.5 * (1 + b * pi ** 4 / 5) ** 2, a ** 2 / 8, b ** 2 * pi ** 8 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    exact_first, exact_total = np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v
    res = sobol_indices(y, s.block, s.row)
    for got, exact in ((res["first"], exact_first), (res["total"], exact_total)):
        assert np.all(got[:, 1] <= exact) and np.all(exact <= got[:, 2]), (got, exact)
        assert np.all(got[:, 2] - got[:, 1] < 0.25)          # intervals that say something
    # the same estimator as scipy's
    from scipy.stats import sobol_indices as scipy_sobol
    blocks = [y[s.block == k] for k in range(5)]
    ref = scipy_sobol(func={"f_A": blocks[0][None], "f_B": blocks[1][None], "f_AB": np.stack(blocks[2:])[:, None]}, n=1024)
    np.testing.assert_allclose(res["first"][:, 0], ref.first_order, atol=1e-12)
    np.testing.assert_allclose(res["total"][:, 0], ref.total_order, atol=1e-12)
    # a row with a failed build is left out of every index, not counted as zero
    y[s.block == 3] = np.where(np.arange(1024) == 10, np.nan, y[s.block == 3])
    assert sobol_indices(y, s.block, s.row)["rows"] == 1023


@pytest.mark.parametrize("spec, value", [({"uniform": [2.0, 2.0]}, 2.0), ({"normal": [2.0, 0.0]}, 2.0),
                                         ({"normal": [2.0, 0.0], "bounds": [1.0, 3.0]}, 2.0)])
def test_a_zero_width_distribution_holds_the_field_at_its_value(spec, value):
    """One tolerance switched off inside a sample: the field is the same in every build, the
    other drawn fields still vary."""
    st = make_study(small_scene(), grid=None, outputs=["ste_p2p"],
                    sample={"size": 8, "method": "lhs", "seed": 2, ECC: spec,
                            "gear1.errors.eccentricity_phase": {"uniform": [0.0, 360.0]}})
    v = st.sample.values
    assert np.all(v[ECC] == value) and np.ptp(v["gear1.errors.eccentricity_phase"]) > 0
    assert "fixed at 2" in st.sample.fields[0].describe()
    seeds = make_study(small_scene(), outputs=["ste_p2p"],
                       sample={"size": 4, "gear1.errors.seed": {"integers": [5, 5]}}).sample.values["gear1.errors.seed"]
    assert seeds.dtype.kind == "i" and set(seeds) == {5}


def small_scene():
    """The base scene of the sampled studies here."""
    return sampled('size = 2\n"gear1.errors.eccentricity" = {uniform = [0.0, 1.0]}').base_scene()


def test_a_percentile_interval_is_distribution_free_and_none_where_the_sample_cannot_bound_it():
    """Order statistics with binomial coverage: the P95 interval of 8 builds does not exist (all
    8 lie below the P95 with probability 0.95^8 = 0.66); the smallest sample that bounds it at
    95 % has 72 builds, [X_(65)...] covering at least 95 % whatever the distribution."""
    rng = np.random.default_rng(3)
    assert np.isnan(quantile_interval(rng.normal(size=8), 0.95)).all()
    assert "8 independent builds cannot bound the P95 at 95 % (it takes 72)" == interval_note(8, 0.95)
    assert min_builds(0.95) == 72 and min_builds(0.05) == 72 and min_builds(0.5) == 6
    assert 0.95 ** 72 <= 0.025 < 0.95 ** 71
    # coverage, checked by simulation on a skewed distribution: at least 95 % of 4000 samples of 100
    exact = stats.lognorm(1.0).ppf(0.95)
    hits = [lo <= exact <= hi for lo, hi in (quantile_interval(stats.lognorm(1.0).rvs(100, random_state=rng), 0.95)
                                             for _ in range(4000))]
    assert np.mean(hits) >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / 4000)
    # the interval never lies beyond the sample (a bootstrap's could not exceed its maximum either,
    # but it claimed a bound it could not give)
    x = rng.normal(size=100)
    lo, hi = quantile_interval(x, 0.95)
    assert x.min() <= lo <= np.quantile(x, 0.95) <= hi <= x.max()
    s = summary_statistics(x[:8])
    assert np.isnan(s[0.95][1:]).all() and np.isfinite(s[0.5][1:]).all() and s["n_independent"] == 8


def test_statistics_of_a_known_sample():
    rng = np.random.default_rng(1)
    x = rng.normal(3.0, 2.0, 2000)
    s = summary_statistics(x)
    for q in (0.05, 0.5, 0.95):
        est, lo, hi = s[q]
        exact = stats.norm(3.0, 2.0).ppf(q)
        assert lo <= exact <= hi and lo < est < hi
    assert s["mean"][1] <= 3.0 <= s["mean"][2]
    p, lo, hi = exceedance(x, 6.0)
    assert lo <= stats.norm(3.0, 2.0).sf(6.0) <= hi and p == np.mean(x > 6.0)
    # none of 100 exceeds: the probability is 0 but may be up to 3.6 % (Clopper-Pearson, 95 %)
    assert exceedance(np.zeros(100), 1.0) == pytest.approx((0.0, 0.0, 1 - 0.025 ** (1 / 100)))


# ---------------------------------------------------------------- sampled studies on the engine

RESUME = 'size = 6\nmethod = "lhs"\nseed = 2\n"gear1.errors.seed" = {integers = [0, 999]}\n' \
         '"gear1.errors.eccentricity" = {uniform = [0.0, 4.0]}\n'
RESUME_GRID = '[grid]\n"gear1.errors.grade" = [0, 6]\n'


@pytest.fixture(scope="module")
def sampled_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("sample") / "sampled.nc"
    return run_sweep(sampled(RESUME, RESUME_GRID), out, workers=0, progress=False), out


def test_a_sampled_archive_holds_the_draws_and_every_output_over_grid_and_sample(sampled_run):
    res, _ = sampled_run
    ds = res.dataset
    st = sampled(RESUME, RESUME_GRID)
    assert ds["ste_p2p"].dims == ("gear1_errors_grade", "sample") and ds.sizes["sample"] == 6
    np.testing.assert_array_equal(ds["gear1_errors_eccentricity"].values, st.sample.values[ECC])
    assert ds["gear1_errors_eccentricity"].attrs["scene_field"] == ECC
    assert ds["gear1_errors_eccentricity"].attrs["units"] == "um"
    assert ds.attrs["sample_method"] == "lhs" and (ds["status"] == 1).all()
    # the same draws at every grid point: grade 6 adds pitch errors to the same runouts
    p2p = ds["ste_p2p"].values
    assert np.all(p2p[1] != p2p[0])


def test_a_sampled_study_resumes_after_an_interruption(sampled_run, tmp_path, monkeypatch):
    res, _ = sampled_run
    out = tmp_path / "resumed.nc"
    count_points(monkeypatch, stop_after=4)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(sampled(RESUME, RESUME_GRID), out, workers=0, progress=False)
    assert not out.exists() and len(list(parts_folder(out).glob("*.pkl"))) == 4
    monkeypatch.undo()
    calls = count_points(monkeypatch)
    again = run_sweep(sampled(RESUME, RESUME_GRID), out, workers=0, progress=False)
    assert len(calls) == 8 and again.reused == 4
    drop = ["wall_time"]
    xr.testing.assert_identical(again.dataset.drop_vars(drop).assign_attrs(created="", history=""),
                                res.dataset.drop_vars(drop).assign_attrs(created="", history=""))


def test_render_of_a_sampled_study_with_a_limit(sampled_run, tmp_path, capsys):
    res, path = sampled_run
    assert main(["render", str(path), "-o", str(tmp_path), "--limit", "ste_p2p=6.0"]) == 0
    for stem in ("distribution_ste_p2p", "convergence_ste_p2p"):      # named after the archive
        assert (tmp_path / f"{path.stem}_{stem}.png").stat().st_size > 10_000
    said = capsys.readouterr().out
    assert "Sobol indices: a plain sample" in said
    # the statistics printed as a table: each grid point's mean, P5, P50, P95 and exceedance
    assert "  ste_p2p [µm]:" in said or "  ste_p2p [um]:" in said
    for g in ("gear1.errors.grade = 0", "gear1.errors.grade = 6"):
        row = next(line for line in said.splitlines() if line.strip().startswith(g + ":"))
        assert all(w in row for w in ("builds", "mean ", "P5 ", "P50 ", "P95 ", "P(> 6)")), row
    with xr.open_dataset(tmp_path / f"{path.stem}_study_tables.nc", engine="netcdf4") as f:
        tab = f.load()
    ds = res.dataset
    for g in range(2):
        y = ds["ste_p2p"].isel(gear1_errors_grade=g).values
        p = tab["exceedance_probability"].isel(gear1_errors_grade=g).sel(limit="ste_p2p")
        assert float(p.sel(bound="estimate")) == np.mean(y > 6.0)
        pct = tab["sample_percentile"].isel(gear1_errors_grade=g).sel(output="ste_p2p", bound="estimate")
        np.testing.assert_allclose(pct.values, np.quantile(y, [0.05, 0.5, 0.95]))
        row = next(line for line in said.splitlines() if line.strip().startswith(f"gear1.errors.grade = {[0, 6][g]}:"))
        assert f"P95 {np.quantile(y, 0.95):.4g}" in row and f"mean {np.mean(y):.4g}" in row
    # a limit on an output the archive does not have, or a malformed one: exit 2 before any work
    assert main(["render", str(path), "-o", str(tmp_path / "x"), "--limit", "dte_rms=0.5"]) == 2
    assert main(["render", str(path), "-o", str(tmp_path / "x"), "--limit", "ste_p2p=abc"]) == 2
    assert not (tmp_path / "x").exists()


def test_sampled_ste_statistics_against_the_closed_form(tmp_path):
    """A driver with runout e: its teeth's centre is off the bearing axis, so the STE over a
    driver revolution is the perfect pair's mesh-periodic STE (peak-to-peak r) less e cos(theta
    + phase): p2p = 2 e + r, less at most 2 e (1 - cos(pi / Z)) where the mesh's extremes fall
    off the once-per-revolution extremes. With e uniform on [2, 12] um, p2p is uniform on
    [4 + r, 24 + r]: mean 14 + r, percentile q at 4 + 20 q + r."""
    sample = ('size = 24\nmethod = "lhs"\nseed = 4\n"gear1.errors.eccentricity" = {uniform = [2.0, 12.0]}\n'
              '"gear1.errors.eccentricity_phase" = {uniform = [0.0, 360.0]}\n')
    st = sampled(sample)
    perfect = make_study(st.base_scene().replace(**{ECC: 1e-9}), grid={"dynamic.speed": [100.0]},
                         outputs={"scalars": ["ste_p2p"]})           # r over a whole driver revolution
    ref = run_sweep(perfect, tmp_path / "r.nc", workers=0, progress=False)
    r = float(ref.dataset["ste_p2p"].squeeze())
    ds = run_sweep(st, tmp_path / "ecc.nc", workers=0, progress=False).dataset
    g = st.base_scene().gear1
    # the first-order closed form leaves out: the mesh's extremes off the once-per-revolution
    # ones (below), and the moment arms, which stay about the bearing axis while the flanks move
    # by e: the TE (about 60 um here, mostly the rigid backlash offset) changes by e / r_b of itself
    r_b = g.module * g.teeth * math.cos(math.radians(g.pressure_angle)) / 2 * 1e3      # um
    below = 2 * 12.0 * (1 - math.cos(math.pi / g.teeth))                                 # um
    arm = 2 * 12.0 / r_b * 60.0                                                           # um
    e = ds["gear1_errors_eccentricity"].values
    p2p = ds["ste_p2p"].values
    assert np.all(p2p <= 2 * e + r + arm) and np.all(p2p >= 2 * e + r - below - arm)
    assert np.std(p2p - 2 * e) < 0.05                  # p2p follows 2 e, whatever the phase
    tab = sample_tables(ds)
    pct = tab["sample_percentile"].sel(output="ste_p2p")
    for q in (0.05, 0.5, 0.95):
        _, lo, hi = pct.sel(quantile=q).values
        if q == 0.5:
            assert lo - below - arm <= 4 + 20 * q + r <= hi + arm, (q, lo, hi, r)
        else:       # 24 builds cannot bound a P5 or P95 at 95 % (it takes 72): no interval
            assert np.isnan(lo) and np.isnan(hi) and 24 < min_builds(q)
    _, lo, hi = tab["sample_mean"].sel(output="ste_p2p").values
    assert lo - below - arm <= 14 + r <= hi + arm


def test_a_sampled_study_on_dask_interrupted_and_resumed_in_process_gives_the_same_archive(sampled_run, tmp_path,
                                                                                          monkeypatch):
    """Builds are ordinary tasks: two stored by a 2-worker LocalCluster, Ctrl-C, the rest here."""
    res, _ = sampled_run
    out = tmp_path / "dask.nc"
    with ctrl_c_after_stored(monkeypatch, 2), pytest.raises(KeyboardInterrupt):
        run_sweep(sampled(RESUME, RESUME_GRID), out, workers=2, progress=False)
    again = run_sweep(sampled(RESUME, RESUME_GRID), out, workers=0, progress=False)
    assert again.reused == 2 and again.computed == 10
    xr.testing.assert_identical(again.dataset.drop_vars("wall_time").assign_attrs(created="", history=""),
                                res.dataset.drop_vars("wall_time").assign_attrs(created="", history=""))


def test_the_convergence_figure_stays_readable_when_the_p95_ties(tmp_path, monkeypatch):
    """Builds whose top values tie: the P95 of the first rows equals the whole sample's, an
    error of 0 that a log axis would put 16 decades down. The axis keeps at most six decades,
    and says why the P95 of a small sample has no band."""
    from study.report import sample_views
    n = 32
    # the top quarter tied at 3 um but for the last bits (sums in another order: 0.1 + 0.2 != 0.3)
    top = 3.0 + np.arange(8) * np.spacing(3.0)
    y = np.r_[np.linspace(1.0, 2.0, n - 8), top]
    y = y[np.random.default_rng(0).permutation(n)]
    ds = xr.Dataset({"ste_p2p": ("sample", y, {"units": "um"}), "status": ("sample", np.ones(n, np.int8)),
                     "wall_time": ("sample", np.full(n, 0.1), {"units": "s"})}, coords={"sample": np.arange(n)})
    tables = sample_tables(ds)
    p95 = tables["convergence_p95"].sel(output="ste_p2p")
    est = p95.sel(bound="estimate").values
    assert np.allclose(est[1:], 3.0, rtol=1e-15, atol=0) and (est[1:] != est[-1]).any()     # ties but for the last bit
    assert np.isnan(p95.sel(bound="low").values).all()                          # 32 builds cannot bound a P95
    figures = []
    monkeypatch.setattr(sample_views, "save_figure", lambda fig, path: figures.append(fig) or path)
    sample_views.convergence_figure(ds, tables, "ste_p2p", tmp_path / "c.png")
    fig = figures[0]
    for ax in fig.axes:
        if ax.get_yscale() == "log":
            lo, hi = ax.get_ylim()
            assert hi / lo <= 1.01e6, (lo, hi)
    assert any("too few independent builds to bound the P95" in t.get_text() for t in fig.axes[1].texts)

"""Plots and renders: every file written, not blank, and showing the colours the data say.

A tiny lightened pair (24 teeth, 4 holes, coarse FE mesh) runs the whole path: run archive ->
make_figures -> PNGs; the renders run off-screen here (EGL), without skipping.
"""
import matplotlib
import numpy as np
import pytest
import xarray as xr
from matplotlib.image import imread

from study.inputs.springs import archive_body_fields
from study.report import render_inputs, stiffness_render, stress_render
from study.report.figures import make_figures
from study.report.render_geometry import extrude
from study.report.sweep_view import sweep_view
from study.report.te_plots import hole_mesh_angles
from study.run import run_scene
from study.scene import default_scene, load_scene

# the small lightened pair with 4 holes, short runs
TINY_LIGHTENED = {
    "gear2.body.holes": 4,
    "quasi_static.rotation": 45.0, "quasi_static.angle_step": 0.25,
    "dynamic.duration": 0.03, "dynamic.ramp_time": 0.005,
    # the paper's per-tooth springs: the solid driver's tooth (body wind-up included) is stiffer
    # than every lightened tooth, which the stiffness map's colour range is checked against
    "coupling.model": "paper",
}


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    scene = load_scene("small_lightened").replace(**TINY_LIGHTENED)
    ds = run_scene(scene)
    out = tmp_path_factory.mktemp("figs")
    paths = make_figures(ds, out, fields=archive_body_fields(ds))
    return ds, out, paths


@pytest.fixture(scope="module")
def fields(tiny):
    """The lightened driven gear's FE body fields the renders draw (from the FE cache now)."""
    return archive_body_fields(tiny[0], solve=False)


def _png(path):
    img = imread(path)
    assert img.ndim == 3 and img.shape[0] > 300 and img.shape[1] > 300
    return img[..., :3]


def test_every_supported_figure_is_written_and_not_blank(tiny):
    ds, out, paths = tiny
    names = sorted(p.name for p in paths)
    assert names == sorted(["ste.png", "dte.png", "spectrum.png", "tooth_stiffness.png", "campbell.png", "gear_pair.png",
                            "fe_stress_gear2.png", "strength.png"])
    for p in paths:
        img = _png(p)
        white = np.all(img > 0.97, axis=-1).mean()
        assert 0.05 < white < 0.98, f"{p.name}: {white:.1%} white"       # something drawn, not all ink
        assert img.std() > 0.05, f"{p.name} looks blank"


def test_archive_without_dynamics_skips_what_it_cannot_draw(tiny, tmp_path, capsys):
    ds, _, _ = tiny
    static_only = ds.drop_vars([v for v in ds.variables if "time" in ds[v].dims or "frequency" in ds[v].dims
                                or v.startswith("dte_peak")])
    paths = make_figures(static_only, tmp_path, renders=False)
    assert sorted(p.name for p in paths) == ["campbell.png", "spectrum.png", "ste.png", "strength.png", "tooth_stiffness.png"]
    said = capsys.readouterr().out
    assert "skip DTE plot" in said and "skip renders" in said


def test_renders_read_the_fe_cache_and_skip_without_fields(tiny, fields, tmp_path, capsys, monkeypatch):
    """The pictures start no FE solve: the fields come from the FE cache (bit for bit what the
    solve gave), and without them the renders are skipped with the reason."""
    ds, _, _ = tiny
    k2 = ds["tooth_stiffness"].sel(gear=2).values[:24]
    assert list(fields) == [2] and [f.tooth for f in fields[2]] == [int(np.argmax(k2)), int(np.argmin(k2))]
    from study.inputs.gearsetup import gear_setup
    from study.inputs.springs import body_fields
    fresh = body_fields(gear_setup(render_inputs.required_scene(ds), 2), [f.tooth for f in fields[2]], solve=True)
    for a, b in zip(fields[2], fresh):
        assert np.array_equal(a.points, b.points) and np.array_equal(a.triangles, b.triangles)
        assert np.array_equal(a.displacement, b.displacement) and np.array_equal(a.von_mises, b.von_mises)
    paths = make_figures(ds, tmp_path)
    said = capsys.readouterr().out
    assert "skip gear pair and FE stress renders: no FE body fields of lightened gear 2" in said
    assert not {"gear_pair.png", "fe_stress_gear2.png"} & {p.name for p in paths}
    with pytest.raises(ValueError, match="lightened gear 2"):
        render_inputs.pair_bodies(ds)
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "empty"))
    assert archive_body_fields(ds, solve=False) == {}              # nothing cached there, nothing solved


def test_stiffness_map_colour_range_and_pixels_match_the_tooth_stiffness(tiny, fields, tmp_path):
    ds, _, _ = tiny
    k2 = ds["tooth_stiffness"].sel(gear=2).values[:24]
    k1 = ds["tooth_stiffness"].sel(gear=1).values[:24]
    assert np.ptp(k2) > 0.005 * k2.mean()            # the holes make the driven teeth differ
    res = stiffness_render.gear_pair_render(ds, tmp_path / "pair.png", fields)
    # the colour bar spans exactly the lightened gear's stiffness; the solid driver (stiffer,
    # one value) lies outside and is drawn grey
    assert res.clim == pytest.approx((k2.min(), k2.max()), rel=1e-12)
    assert k1.min() > res.clim[1]
    assert len(res.probes) == 24
    img = _png(res.path)
    cmap = matplotlib.colormaps[stiffness_render.STIFFNESS_CMAP]
    err = []
    for row, col, k in res.probes:
        want = np.array(cmap((k - res.clim[0]) / (res.clim[1] - res.clim[0]))[:3])
        err.append(np.abs(img[row - 1:row + 2, col - 1:col + 2].reshape(-1, 3) - want).max(axis=1).min())
    err = np.array(err)
    assert np.median(err) < 0.03 and np.mean(err < 0.06) >= 0.9, err
    # the stiffest and the softest tooth show the two ends of the colour map
    far = cmap(1.0)[:3], cmap(0.0)[:3]
    assert np.abs(np.array(far[0]) - np.array(far[1])).max() > 0.5
    # every tooth of both bodies got its own index (FE mesh and outline alike)
    bodies = render_inputs.pair_bodies(ds, fields)
    for g in (1, 2):
        assert set(np.unique(bodies[g].tooth)) == set(range(-1, 24))


def test_extruded_body_keeps_web_thinner_and_scalars_per_tooth(tiny, fields):
    ds, _, _ = tiny
    b = render_inputs.pair_bodies(ds, fields)[2]
    k2 = ds["tooth_stiffness"].sel(gear=2).values[:24]
    val = np.where(b.tooth >= 0, k2[np.clip(b.tooth, 0, None)], np.nan)
    mesh = extrude(b, 0.0, (0.0, 0.0), val, "k_phi")
    z = mesh.points[:, 2]
    assert z.max() == pytest.approx(17.0 / 2) and z.min() == pytest.approx(-17.0 / 2)
    assert np.any(np.isclose(np.abs(z), 8.0 / 2))           # the web's faces
    kk = mesh.cell_data["k_phi"]
    assert np.nanmin(kk) == pytest.approx(k2.min()) and np.nanmax(kk) == pytest.approx(k2.max())


def test_stress_render_scale_spans_zero_to_the_fillet_peak(tiny, fields, tmp_path):
    ds, _, _ = tiny
    sc = render_inputs.required_scene(ds)
    fields = fields[2]
    geo = sc.geometry(2)
    peaks = [stress_render.fillet_peak(f, geo, f.tooth) / 1e6 for f in fields]
    # the loaded tooth's fillet carries far more than the body on average
    assert all(p > 5 * np.median(f.von_mises) / 1e6 for p, f in zip(peaks, fields))
    res = stress_render.fe_stress_render(ds, tmp_path / "stress.png", 2, fields)
    assert res.clim == pytest.approx((0.0, max(peaks)))
    img = _png(res.path)[:, : _png(res.path).shape[1] // 2]          # left column: stress
    cmap = matplotlib.colormaps[stress_render.STRESS_CMAP]
    hot = np.array(cmap(1.0)[:3])
    cold = np.array(cmap(0.0)[:3])
    # the hot end of the scale appears (fillet) and the cold end covers much of the body
    # (teeth away from the load carry nothing)
    assert np.any(np.abs(img - hot).max(axis=-1) < 0.08)
    assert np.mean(np.abs(img - cold).max(axis=-1) < 0.15) > 0.05


def test_sweep_view_facets_the_other_dimensions():
    rng = np.random.default_rng(1)
    ds = xr.Dataset(
        {"dte_rms": (("n_holes", "speed", "web_thickness"), rng.random((3, 4, 2)), {"units": "um", "long_name": "DTE RMS"})},
        coords={"n_holes": ("n_holes", [0, 4, 6], {"units": "1", "long_name": "holes"}),
                "speed": ("speed", [50.0, 100.0, 150.0, 200.0], {"units": "rad s-1", "long_name": "driver speed"}),
                "web_thickness": ("web_thickness", [8.0, 12.0], {"units": "mm", "long_name": "web thickness"})})
    fig = sweep_view(ds, "dte_rms", "speed", hue="n_holes")
    axes = fig.axes
    assert len(axes) == 2                                    # one panel per web thickness
    lines = axes[1].get_lines()
    assert len(lines) == 3                                   # one line per hole count
    np.testing.assert_allclose(lines[2].get_ydata(), ds["dte_rms"].isel(web_thickness=1, n_holes=2).values)
    assert "[rad/s]" in axes[0].get_xlabel() or "[rad/s]" in axes[1].get_xlabel()
    assert "[µm]" in axes[0].get_ylabel()
    with pytest.raises(ValueError, match="not a dimension"):
        sweep_view(ds, "dte_rms", "angle")
    with pytest.raises(KeyError, match="no variable"):
        sweep_view(ds, "ste", "speed")


def test_render_cli_writes_plots_beside_the_archive(tiny, tmp_path):
    from study.archive.netcdf import write_netcdf
    from study.cli import main
    ds, _, _ = tiny
    path = tmp_path / "run.nc"
    write_netcdf(ds, path)
    assert main(["render", str(path), "--no-renders"]) == 0
    # named after the archive: two archives rendered into one folder keep their own figures
    assert {p.name for p in tmp_path.glob("*.png")} == {f"run_{n}.png" for n in ("ste", "dte", "spectrum", "tooth_stiffness",
                                                                              "campbell", "strength")}
    write_netcdf(ds, tmp_path / "other.nc")
    assert main(["render", str(tmp_path / "other.nc"), "--no-renders"]) == 0
    assert len(list(tmp_path.glob("run_*.png"))) == len(list(tmp_path.glob("other_*.png"))) == 6


def test_hole_passes_on_the_ste_axis_follow_the_gear_ratio():
    # a hole centre of the driven gear reaches the mesh every 360/N deg of driven rotation,
    # i.e. every 360/N * z2/z1 deg of driver rotation
    base = default_scene()
    for z1, z2, expect in ((67, 67, [0.0, 60.0, 120.0]), (40, 80, [0.0, 120.0])):
        sc = base.replace(**{"gear1.teeth": z1, "gear2.teeth": z2, "gear1.body.web_height": 23.25 * z1 / 67 - 4,
                             "gear2.body.hole_circle_radius": 32.36 + 0.75 * (z2 - 67)})
        ds = xr.Dataset(attrs={"scene": sc.to_toml()})
        np.testing.assert_allclose(hole_mesh_angles(ds, 120.0), expect, atol=1e-9)
    shifted = base.replace(**{"gear2.body.hole_phase": 15.0})
    ds = xr.Dataset(attrs={"scene": shifted.to_toml()})
    np.testing.assert_allclose(hole_mesh_angles(ds, 120.0), [15.0, 75.0])


def test_axis_labels_leave_a_long_names_remark_to_the_archive():
    """A long name's remark in parentheses would crowd a legend title and squeeze the panels."""
    from study.report.plot_style import axis_label
    speed = xr.DataArray([50.0], dims="speed", attrs={
        "units": "rad s-1", "long_name": "final driver speed (the driver turns forward; a reversed load is a negative torque)"})
    assert axis_label(speed) == "final driver speed [rad/s]"
    short = xr.DataArray([1.0], dims="x", attrs={"units": "mm", "long_name": "rim (l1)"})
    assert axis_label(short) == "rim (l1) [mm]"


def test_contact_shading_counts_the_contacts_that_carry_a_share_of_the_load(tmp_path, monkeypatch):
    """Where one tooth carries 918 of 1060 N and two others 71 N each, one contact is loaded,
    not three; a real double contact (560 / 500 N) stays two, and three real shares stay three."""
    from study.report import te_plots
    ang = np.arange(0.0, 6.0, 0.1)
    force = np.zeros((ang.size, 4))
    force[:, 0] = 1060.0
    force[10:20] = [918.0, 71.0, 71.0, 0.0]
    force[20:30] = [560.0, 500.0, 0.0, 0.0]
    force[30:40] = [400.0, 350.0, 310.0, 0.0]
    touching = (force > 0).sum(axis=1)
    ds = xr.Dataset({"ste": ("angle", np.full(ang.size, 40.0), {"units": "um"}),
                     "ste_contacts": ("angle", touching),
                     "ste_tooth_force": (("angle", "driver_tooth"), force, {"units": "N"})},
                    coords={"angle": ang}, attrs={"backlash_offset_um": 33.0, "contact_ratio": 1.8})
    n = te_plots.loaded_contacts(ds)
    assert list(n[[5, 15, 25, 35]]) == [1, 1, 2, 3] and touching[15] == 3
    figures = []
    monkeypatch.setattr(te_plots, "save_figure", lambda fig, path: figures.append(fig) or path)
    te_plots.ste_plot(ds, tmp_path / "ste.png")
    ax = figures[0].axes[0]
    spans = [(p.get_label(), p.get_x(), p.get_x() + p.get_width()) for p in ax.patches]
    three = [(a, b) for label, a, b in spans if label == "3 or more loaded contacts"]
    assert three and all(a > 2.9 and b < 4.0 for a, b in three)      # only 3.0-3.9 deg: the real triple share
    assert "at least 10 % of the load" in figures[0]._suptitle.get_text()

"""Study views of a 5-dimension archive shaped like study/scenes/sensitivity.toml's grid, with
synthetic outputs (no solver): every view is written, for any number of swept dimensions."""
import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr
from cf_check import cf_errors
from matplotlib.image import imread

from study.report.figures import make_figures

GRID = {"n_holes": ([0, 3, 6, 9, 12], "1", "number of lightening holes"),
        "hole_radius": ([5.0, 7.0], "mm", "radius of the lightening holes"),
        "rim_thickness": ([5.0, 7.0], "mm", "rim thickness under the root circle"),
        "web_thickness": ([6.0, 10.0], "mm", "web thickness"),
        "speed": ([100.0, 200.0], "rad s-1", "driver speed")}
OUTPUTS = {"ste_p2p": "um", "dte_rms": "um", "mass_saving_gear2": "%", "root_stress_max_gear2": "MPa",
           "root_stress_ratio_gear2": "1"}


def synthetic_study() -> xr.Dataset:
    """Plausible-looking outputs over the grid: holes and thin webs save mass and cost STE and
    stress; speed matters for the DTE only; one point failed."""
    coords = {d: xr.DataArray(np.array(v), dims=d, coords={d: (d, np.array(v), {"units": u, "long_name": ln})})
              for d, (v, u, ln) in GRID.items()}
    n, r, rim, web, w = (coords[d] for d in GRID)
    hole_area = n * r ** 2 / (12 * 7.0 ** 2)                          # 0..1
    saving = 100 * (0.45 * (1 - web / 17.0) + 0.25 * hole_area * web / 17.0 + 0.01 * (7.0 - rim))
    ste = 1.6 + 0.9 * hole_area * (10.0 / web) + 0.15 * (7.0 - rim)
    dte = 0.5 * ste * (1 + 0.004 * (w - 100.0)) + 0.1 * hole_area * w / 100.0
    ratio = 1.0 + 0.35 * hole_area * (7.0 - rim + 1.0) / 3.0 + 0.02 * (10.0 - web) / 4.0
    data = {"ste_p2p": ste, "dte_rms": dte, "mass_saving_gear2": saving,
            "root_stress_max_gear2": 310.0 * ratio, "root_stress_ratio_gear2": ratio}
    dims = tuple(GRID)
    ds = xr.Dataset({k: v.broadcast_like(n * r * rim * web * w).transpose(*dims).astype(float)
                     .assign_attrs(units=OUTPUTS[k], long_name=k.replace("_", " ")) for k, v in data.items()},
                    attrs={"title": "Synthetic 5-parameter study", "outputs": ", ".join(OUTPUTS)})
    status = np.ones(ds["ste_p2p"].shape, np.int8)
    status[2, 1, 0, 0, 1] = 4                                       # a failed point
    ds["status"] = (dims, status, {"units": "1", "long_name": "status of the study point",
                                   "flag_values": np.arange(5, dtype=np.int8),
                                   "flag_meanings": "pending ok diverged invalid failed"})
    for k in OUTPUTS:
        ds[k] = ds[k].where(ds["status"] == 1)
    return ds


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    ds = synthetic_study()
    out = tmp_path_factory.mktemp("study_views")
    return ds, out, make_figures(ds, out)


def test_a_five_dimension_study_renders_main_effects_ranking_and_tradeoff(rendered, capsys):
    ds, _, paths = rendered
    names = sorted(p.name for p in paths)
    assert names == sorted([f"main_effects_{v}.png" for v in OUTPUTS] + ["sensitivity.png", "tradeoff.png"])
    for p in paths:
        img = imread(p)[..., :3]
        assert img.shape[0] > 300 and img.shape[1] > 300 and img.std() > 0.05, p.name


def test_the_tables_pass_cf_and_the_ranking_finds_what_the_synthetic_study_built_in(rendered):
    ds, out, _ = rendered
    path = out / "study_tables.nc"
    assert cf_errors(path) == []
    with xr.open_dataset(path) as tables:
        tables = tables.load()
    share = tables["sensitivity_share"]
    # speed enters only the DTE: no share of the STE (but for the failed point's imbalance), a share of the DTE
    assert float(share.sel(output="ste_p2p", term="speed")) == pytest.approx(0.0, abs=1e-3)
    assert float(share.sel(output="dte_rms", term="speed")) > 0.05
    assert float(share.sel(output="mass_saving_gear2", term="web_thickness")) > 0.5
    assert int(tables["sensitivity_points"].sel(output="ste_p2p")) == ds["status"].size - 1
    flags = tables["pareto_ste_p2p"]
    assert set(flags.dims) == set(GRID) and flags.dtype == np.int8 and 2 <= int(flags.sum()) < 40
    assert float(ds["root_stress_ratio_gear2"].where(flags == 1).max()) <= 1.15
    assert flags.attrs["flag_meanings"] == "not_pareto pareto"


def test_main_effects_count_points_of_an_output_stored_over_fewer_dimensions(tmp_path, monkeypatch):
    """An STE stored over the body fields only (not over speed) is counted over every point of
    the study, as the status that selects it is: one failed point of six is "5 of 6"."""
    from study.report import study_views
    titles = []

    def keep_title(fig, path):
        titles.append(fig._suptitle.get_text())
        plt.close(fig)
        return path
    monkeypatch.setattr(study_views, "save_figure", keep_title)
    ds = xr.Dataset({"ste_p2p": ("n_holes", np.array([1.0, 1.2, 1.5]), {"units": "um"})},
                    coords={"n_holes": [0, 3, 6], "speed": [100.0, 200.0]})
    status = np.ones((3, 2), np.int8)
    status[1, 0] = 4
    ds["status"] = (("n_holes", "speed"), status)
    study_views.main_effects_figure(ds, "ste_p2p", ["n_holes", "speed"], tmp_path / "me.png")
    assert "(5 of 6 points ok)" in titles[0]
    ds["status"][:] = 1
    study_views.main_effects_figure(ds, "ste_p2p", ["n_holes", "speed"], tmp_path / "me.png")
    assert "points ok" not in titles[1]


def test_strength_over_the_hole_pattern_is_drawn_from_the_studys_strength_outputs(tmp_path):
    """The root, rim and web stress of gear 2 and its smallest S_F over two swept parameters:
    strength_gear2.png among the study's figures, something drawn; without the outputs, no view."""
    from study.report.study_views import strength_figure
    ds = synthetic_study().isel(rim_thickness=0, web_thickness=0, speed=0, drop=True)
    n, r = ds["n_holes"], ds["hole_radius"]
    web = (20.0 + 0.5 * n * r).where(n > 0).broadcast_like(ds["ste_p2p"])
    for name, v in (("bending_stress_root_gear2", 310.0 + 0 * web), ("rim_stress_max_gear2", 40.0 + 0 * web),
                    ("web_stress_max_gear2", web), ("bending_safety_gear2", 1000.0 / np.fmax(310.0, web))):
        ds[name] = v.assign_attrs(units="MPa" if "stress" in name else "1", long_name=name)
    paths = make_figures(ds, tmp_path, renders=False)
    assert "strength_gear2.png" in [p.name for p in paths]
    img = imread(tmp_path / "strength_gear2.png")[..., :3]
    assert img.std() > 0.05
    with pytest.raises(KeyError):
        strength_figure(synthetic_study(), ["n_holes"], tmp_path / "none.png")
    plt.close("all")

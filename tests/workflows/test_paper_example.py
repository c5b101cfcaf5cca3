"""The paper example leads with the default model: it runs the paper's model to reproduce the
paper and the default beside it, its summary opens with both models' numbers, and its STE and
DTE figures draw both curves, each labelled with its model."""
import math

import numpy as np
import pytest
import xarray as xr

import study
from study.report import te_plots
from workflows import paper_example

# a small lightened pair (FE in seconds), short runs, no transient
SMALL = ["--set", "quasi_static.rotation=15", "--set", "quasi_static.angle_step=0.5", "--set", "dynamic.duration=0.03",
         "--set", "dynamic.ramp_time=0.005", "--transient-rotation", "0"]


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper_example") / "example.nc"
    assert paper_example.main(["small_lightened", "-o", str(out), "--no-figures", *SMALL]) == 0
    with xr.open_dataset(out, engine="netcdf4") as ds:
        return ds.load()


def test_the_example_runs_the_papers_model_and_keeps_the_default_beside_it(example):
    ds = example
    assert ds.attrs["coupling_model"] == "paper" and ds.attrs["default_coupling_model"] == "compliance"
    assert ds["ste_default"].dims == ("angle",) and ds["dte_default"].dims == ("time",)
    assert ds["ste_default"].attrs["units"] == ds["dte_default"].attrs["units"] == "um"
    # the default's curves are those of a run of the same scene by the default model
    scene = study.load_scene("small_lightened", [s for s in SMALL[1::2] if "=" in s])
    default = study.run_scene(scene)
    assert default.attrs["coupling_model"] == "compliance"
    np.testing.assert_allclose(ds["ste_default"].values, default["ste"].values, rtol=1e-12)
    np.testing.assert_allclose(ds["dte_default"].values, default["dte"].values, rtol=1e-12)
    assert math.isclose(ds.attrs["default_mesh_mode_frequency_hz"], default.attrs["mesh_mode_frequency_hz"])
    # the two models differ (else the comparison would say nothing)
    assert not np.allclose(ds["ste_default"].values, ds["ste"].values, atol=1e-3)


def test_the_summary_leads_with_both_models_numbers(example, capsys):
    ds = example
    study.print_summary(ds, "x.nc", 1.0)
    out = capsys.readouterr().out.splitlines()
    head = "\n".join(out[:12])
    assert out[2].startswith("  two models of this scene") and "default: compliance (agrees with the FE reference)" in out[2]
    assert "paper (the paper's MUBOCO-PR: reproduces the paper)" in out[2]
    row = next(line for line in out if line.strip().startswith("STE peak-to-peak [um]")).split()
    assert float(row[-2]) == pytest.approx(float(np.ptp(ds["ste_default"].values)), abs=6e-4)
    assert float(row[-1]) == pytest.approx(float(np.ptp(ds["ste"].values)), abs=6e-4)
    s = study.summarize(ds)
    rms = next(line for line in out if line.strip().startswith("DTE RMS after the ramp [um]")).split()
    assert float(rms[-1]) == pytest.approx(s["dte_rms"], abs=6e-4)
    assert "mesh mode [Hz]" in head and "1Z critical driver speed [rad/s]" in head
    assert out.index(next(line for line in out if line.startswith("  model: paper"))) > 9   # the run's details after


@pytest.mark.parametrize("plot, curve", [(te_plots.ste_plot, "ste"), (te_plots.dte_plot, "dte")])
def test_the_ste_and_dte_figures_draw_both_models_each_named(example, plot, curve, tmp_path, monkeypatch):
    figures = []
    monkeypatch.setattr(te_plots, "save_figure", lambda fig, path: figures.append(fig) or path)
    plot(example, tmp_path / f"{curve}.png")
    fig = figures[0]
    for ax in fig.axes[:2]:
        labels = {line.get_label(): line for line in ax.get_lines()}
        assert {"default model: compliance", "paper model"} <= set(labels), labels
        y = labels["default model: compliance"].get_ydata()
        want = example[f"{curve}_default"].values - (example.attrs["backlash_offset_um"] if curve == "ste" else 0.0)
        assert np.allclose(y, want[: y.size]) or np.allclose(y, want[-y.size:])
    assert "default: compliance (agrees with the FE reference)" in fig._suptitle.get_text()

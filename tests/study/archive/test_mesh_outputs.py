"""Run-archive outputs of the loaded mesh: dynamic tooth forces and K_v, titles that follow
the scene as run, and the CSV export."""
import numpy as np
import pandas as pd
import pytest
from helpers import scene_overrides, solid_scene
from PIL import Image

from study.cli import main


def test_dynamic_factor_is_one_near_zero_speed_and_tooth_forces_carry_the_load():
    """At 5 rad/s (the mesh frequency 60 times below the mesh mode) the largest dynamic tooth
    force over 2.5 mesh periods is the static one (K_v = 1 within 1 %), and at every instant
    the loaded contacts' forces times rb2 add up to the transmitted torque."""
    from study.run import run_scene
    from study.scene_model import build_scene_model
    sc = solid_scene(**{"dynamic.speed": 5.0, "dynamic.ramp_time": 0.002, "dynamic.duration": 0.05,
                        "dynamic.output_step": 5e-5})
    ds = run_scene(sc, static=False, dynamic=True)
    assert float(ds["dynamic_factor"]) == pytest.approx(1.0, abs=0.01)
    rb2 = build_scene_model(sc).base_radii[1]
    steady = ds["time"] >= ds.attrs["spectrum_start_s"]
    load = ds["dte_contact_force"].where(steady, drop=True).sum("contact_slot") * rb2
    np.testing.assert_allclose(load, 50.0, rtol=0.01)
    # each tooth's largest force is the largest force of the contacts naming it, on both gears
    f = ds["dte_tooth_force_max"]
    assert float(f.sel(gear=1).max()) == pytest.approx(float(f.sel(gear=2).max()), rel=1e-12)
    assert np.all(ds["dte_contact_tooth2"].values[ds["dte_contact_force"].values > 0] >= 0)


# the small lightened pair set over the paper example, with short runs
SMALL_RUN = {**scene_overrides("small_lightened"), "quasi_static.rotation": 30.0, "quasi_static.angle_step": 0.25,
             "dynamic.ramp_time": 0.002, "dynamic.duration": 0.01}


@pytest.fixture(scope="module")
def eight_holes(tmp_path_factory):
    """`lightgear run` of the embedded paper scene (its free-text title says 6 holes) with
    ``--set gear2.body.holes=8`` on a small pair, and every figure `lightgear render` draws."""
    out = tmp_path_factory.mktemp("h8")
    args = ["run", "-o", str(out / "h8.nc")] + [a for k, v in SMALL_RUN.items() for a in ("--set", f"{k}={v}")]
    assert main(args) == 0
    assert main(["render", str(out / "h8.nc")]) == 0
    return out


def test_set_holes_puts_the_count_run_in_the_archive_and_figure_titles(eight_holes):
    import xarray as xr
    with xr.open_dataset(eight_holes / "h8.nc") as ds:
        title = ds.attrs["title"]
    assert "8 holes" in title and "6 holes" not in title
    pngs = sorted(eight_holes.glob("*.png"))
    assert {p.stem for p in pngs} >= {"ste", "dte", "spectrum", "tooth_stiffness", "campbell", "gear_pair",
                                      "fe_stress_gear2"}
    for p in pngs:
        t = Image.open(p).info.get("Title", "")
        assert "8 holes" in t and "6 holes" not in t, (p.name, t)


def test_export_round_trips_and_prints_clean_numbers(eight_holes):
    import xarray as xr
    assert main(["export", str(eight_holes / "h8.nc"), "-o", str(eight_holes / "csv")]) == 0
    with xr.open_dataset(eight_holes / "h8.nc") as ds:
        angle = pd.read_csv(eight_holes / "csv" / "angle.csv")
        np.testing.assert_allclose(angle["ste [um]"], ds["ste"].values, rtol=1e-14)
        np.testing.assert_array_equal(angle["ste_contacts [-]"], ds["ste_contacts"].values)
        np.testing.assert_allclose(angle["angle [degree]"], ds["angle"].values, rtol=1e-14)
        force = pd.read_csv(eight_holes / "csv" / "angle__driver_tooth.csv")
        back = force.pivot(index="angle [degree]", columns="driver_tooth [-]", values="ste_tooth_force [N]")
        np.testing.assert_allclose(back.values, ds["ste_tooth_force"].values, rtol=1e-14)
        scalars = pd.read_csv(eight_holes / "csv" / "scalars.csv").set_index("name")
        assert scalars.loc["mesh_stiffness_mean", "value"] == pytest.approx(float(ds["mesh_stiffness_mean"]), rel=1e-14)
        assert scalars.loc["mesh_stiffness_mean", "unit"] == "N um-1"
    text = (eight_holes / "csv" / "angle.csv").read_text()
    assert "0000000000" not in text and "9999999999" not in text

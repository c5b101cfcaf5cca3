"""The shipped run-up scene (study/scenes/runup.toml, 0 -> 400 rad/s in 1 s) as a user runs
it: a converged run is not flagged, however long it runs, and its order map is kept.

Its energy-balance error accumulates over the run (the trapezoidal quadrature of the powers,
O(dt²) of the energy the dampers take out) to more than half the mesh's potential energy,
which the guard once took for a step that misses the contact events (exit 3); halving the
step moves its DTE by less than 1 %."""
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from solver.mbs.dynamics import simulate
from study.cli import main
from study.scene import load_scene
from study.scene_model import build_scene_model

pytestmark = pytest.mark.slow      # two 1 s run-ups of the paper pair

SCENE = Path(__file__).resolve().parents[2] / "study" / "scenes" / "runup.toml"


@pytest.fixture(scope="module")
def archive(tmp_path_factory):
    out = tmp_path_factory.mktemp("runup") / "runup.nc"
    assert main(["run", str(SCENE), "-o", str(out), "--no-static"]) == 0
    with xr.open_dataset(out) as ds:
        return ds.load()


def test_the_shipped_runup_passes_with_its_order_map(archive):
    ds = archive
    assert ds.attrs["dynamic_status"] == "ok" and "order_amplitude" in ds
    assert ds.attrs["energy_error_margin"] < 1.0
    assert ds.attrs["coupling_model"] == "compliance"      # the default for its lightened gear


def test_the_paper_models_runup_passes_the_guard_an_absolute_limit_would_fail(tmp_path):
    """The paper's model on the shipped run-up: its error grows with the energy dissipated over
    the 1 s run beyond half the mesh's largest potential energy (the absolute limit that once
    flagged it) and stays within the guard's dissipation term."""
    out = tmp_path / "runup_paper.nc"
    assert main(["run", str(SCENE), "-o", str(out), "--no-static", "--set", "coupling.model=paper"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.attrs["dynamic_status"] == "ok" and ds.attrs["energy_error_margin"] < 1.0
        assert ds.attrs["energy_error_max_J"] > 0.5 * ds.attrs["potential_energy_max_J"]


def test_the_shipped_runup_is_converged_at_its_step(archive):
    """DTE RMS after the torque ramp at half the archive's step within 1 % of the archive's."""
    ds = archive
    sc = load_scene(str(SCENE), [])
    d = sc.dynamic
    half = simulate(build_scene_model(sc), d.speed_end, d.duration, d.torque, d.ramp_time, d.duration,
                    dt=0.5 * ds.attrs["dt_s"], output_step=d.output_step)
    assert half.status == 0

    def rms(t, te):
        sel = t >= 2 * d.ramp_time
        return float(np.sqrt(np.mean((te[sel] - te[sel].mean()) ** 2)))
    assert rms(half.time, half.te * 1e6) == pytest.approx(rms(ds["time"].values, ds["dte"].values), rel=0.01)


def test_render_says_why_a_run_has_no_order_map():
    from study.report.figures import order_map_missing
    dte = {"dte": ("time", np.zeros(3))}
    stopped = xr.Dataset(dte, attrs={"runup_speed_end_rad_s": 400.0,
                                     "order_tracking_skipped": "the run-up stopped before its end: energy growth at t = 0.5 s"})
    assert order_map_missing(stopped).startswith("the run-up stopped before its end: energy growth")
    assert order_map_missing(xr.Dataset(dte)) == "not a run-up (dynamic.speed_end = 0)"
    assert "no dynamic analysis" in order_map_missing(xr.Dataset())


def test_a_flagged_runup_keeps_its_order_map_with_the_flag(monkeypatch):
    """A run-up that completes but is flagged inaccurate keeps its order tracking, the flag
    beside it (the guard made to flag every run here)."""
    from helpers import solid_scene

    import solver.mbs.dynamics as dyn
    from study.run import run_scene

    def flag(res, alpha=0.0):
        res.status, res.message = dyn.INACCURATE, "inaccurate: energy balance error (made to flag)"
        return res
    monkeypatch.setattr(dyn, "accuracy_check", flag)
    sc = solid_scene(**{"dynamic.speed_end": 400.0, "dynamic.duration": 0.06, "dynamic.ramp_time": 0.005,
                        "quasi_static.enabled": False})
    ds = run_scene(sc)
    assert ds.attrs["dynamic_status"].startswith("inaccurate")
    assert "order_amplitude" in ds and ds["order_amplitude"].attrs["status"].startswith("inaccurate")

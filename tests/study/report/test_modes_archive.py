"""The modes in a run archive: mesh mode, critical speeds, the free decay's ratio beside the
modal one, the Campbell figure, and the sweep scalars of the modal analysis alone."""
import math

import numpy as np
import pytest
from helpers import solid_scene

from study.archive.summary import summarize
from study.report.campbell import campbell_plot
from study.run import run_scene
from study.sweep import engine
from study.sweep.outputs import outputs_from_table

SHORT = {"dynamic.ramp_time": 0.002, "dynamic.duration": 0.006, "quasi_static.enabled": False}


@pytest.fixture(scope="module")
def archive():
    return run_scene(solid_scene(**SHORT, **{"contact.damping_ratio": 0.08}))


def test_archive_has_the_modes_and_the_ratio_the_run_has(archive):
    ds = archive
    assert ds["mode_frequency"].dims == ("mode", "mesh_position") and ds["mode_damping"].attrs["units"] == "1"
    assert str(ds["mode_kind"].values[0]) == "mesh"
    assert all(str(k).startswith("tooth") for k in ds["mode_kind"].values[1:])
    assert ds.attrs["mesh_damping_ratio_requested"] == 0.08
    assert ds.attrs["mesh_mode_damping"] == pytest.approx(0.08, rel=1e-4)
    # the free decay where the modal ratio is nearest its mean, against the modal ratio there (see tests/solver/mbs/test_modes.py)
    assert ds.attrs["mesh_mode_damping_decay"] == pytest.approx(ds.attrs["mesh_mode_damping_at_decay"], rel=0.03)
    assert ds.attrs["c_con_used"] == 0.0 and np.all(ds.attrs["c_phi_used_N_mm_s_rad"] > 0)


def test_critical_speed_puts_the_order_on_the_mode(archive):
    """At the critical speed the excitation's frequency, order x driven rotation frequency,
    is the mode's mean frequency."""
    ds = archive
    z1 = z2 = 67
    for e, o in zip(ds["excitation"].values, ds["excitation_order"].values):
        w1 = float(ds["critical_speed"].sel(excitation=e, mode=0))
        assert o * w1 * z1 / z2 / (2 * math.pi) == pytest.approx(float(ds["mode_frequency"].sel(mode=0).mean()), rel=1e-9)
    s = summarize(ds)
    assert s["critical_speed_3z"] == pytest.approx(s["critical_speed_z"] / 3)
    assert 2500 < s["mesh_mode_frequency"] < 4000


def test_campbell_figure(archive, tmp_path):
    path = campbell_plot(archive, tmp_path / "campbell.png")
    assert path.stat().st_size > 20000


def test_modal_scalars_need_no_time_integration():
    r = engine.run_point(solid_scene(**SHORT), outputs_from_table({"scalars": ["mesh_mode_damping", "critical_speed_z"]}))
    assert r["status"] == "ok", r["message"]
    assert r["scalars"]["mesh_mode_damping"] == pytest.approx(0.05, rel=1e-4)
    assert r["wall_time"] < 20

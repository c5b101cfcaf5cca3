"""Computed order tracking of a run-up: a synthetic signal with known orders, and the paper
pair's run-up against steady runs and the modal critical speed."""
import math

import numpy as np
import pytest
from helpers import solid_scene

from solver.mbs.dynamics import simulate
from solver.mbs.modes import modal_analysis
from study.archive.modes import critical_speeds
from study.archive.order_tracking import OrderBlocks, driver_angle, order_cut, order_map
from study.archive.spectra import amplitude_spectrum
from study.scene_model import build_scene_model


def test_order_map_recovers_the_orders_of_a_synthetic_run_up():
    """DTE = 0.3 um at order 67 + 0.1 um at order 6 of the driven gear (z1 = 60, z2 = 67),
    the driver sped up 0 -> 300 rad/s in 1 s: every block reads both amplitudes (whole
    revolutions per block: the orders sit on bins; within 2 %, the linear resampling of 17
    samples a period at the end) and its mean speed."""
    t = np.arange(0.0, 1.0, 2e-5)
    rev = driver_angle(t, 300.0, 1.0) * 60 / 67 / (2 * math.pi)
    x = 0.3 * np.cos(2 * math.pi * 67 * rev) + 0.1 * np.sin(2 * math.pi * 6 * rev + 0.4)
    speed, order, amp = order_map(t, x, 300.0, 1.0, 60, 67, OrderBlocks(speed_min=20.0))
    assert speed.min() >= 20 and np.all(np.diff(speed) > 0) and speed.max() < 300
    np.testing.assert_allclose(order_cut(speed, order, amp, 67), 0.3, rtol=0.02)
    np.testing.assert_allclose(order_cut(speed, order, amp, 6), 0.1, rtol=0.01)
    # blocks are whole driven revolutions, one every 1/8 revolution: at 150 rad/s a revolution
    # takes 2 pi 67/60 / 150 = 47 ms, in which the driver gains 14 rad/s; blocks follow by 1/8 of it
    assert np.interp(150.0, speed[:-1], np.diff(speed)) == pytest.approx(300.0 * 2 * math.pi * 67 / 60 / 150.0 / 8, rel=0.05)


def test_run_up_tracks_the_steady_mesh_order_and_peaks_at_the_critical_speed():
    """The solid paper pair (5 % mesh damping) sped up 0 -> 400 rad/s in 0.5 s: the mesh
    order's amplitude matches steady runs within 10 % away from its resonance, and peaks
    within 3 % of the modal critical speed of the mesh order (1Z on the mesh mode)."""
    from study.archive.modes import modal_variables
    m = build_scene_model(solid_scene())
    run = simulate(m, 400.0, 0.5, 50.0, 0.01, 0.5)
    assert run.status == 0
    speed, order, amp = order_map(run.time, run.te * 1e6, 400.0, 0.5, 67, 67, OrderBlocks(speed_min=20.0))
    z = order_cut(speed, order, amp, 67)
    for w in (100.0, 150.0, 200.0):
        st = simulate(m, w, 0.01, 50.0, 0.01, 0.05)
        sel = st.time >= 0.02
        f, a = amplitude_spectrum(st.te[sel] * 1e6, 1e-5)
        steady = a[np.abs(f - 67 * w / (2 * math.pi)) < 2 * f[1]].max()
        assert np.interp(w, speed, z) == pytest.approx(steady, rel=0.10)
    _c, data, attrs = modal_variables(modal_analysis(m, 50.0), None, m, 50.0, 0)
    crit = critical_speeds(np.array([attrs["mesh_mode_frequency_hz"]]), np.array([67.0]), 67, 67)[0, 0]
    assert speed[np.argmax(z)] == pytest.approx(crit, rel=0.03)


def test_run_up_scene_archives_the_order_map_instead_of_a_spectrum():
    from study.run import run_scene
    ds = run_scene(solid_scene(**{"dynamic.speed_end": 400.0, "dynamic.duration": 0.1, "dynamic.ramp_time": 0.002,
                                  "quasi_static.enabled": False}))
    assert "dte_amplitude" not in ds and ds.attrs["runup_speed_end_rad_s"] == 400.0
    a = ds["order_amplitude"]
    assert a.dims == ("runup_speed", "tracked_order") and a.attrs["units"] == "um"
    assert ds["runup_speed"].attrs["units"] == "rad/s" and float(ds["runup_speed"].max()) < 400.0
    assert float(ds["tracked_order"].max()) <= 5 * 67 + 10
    # the mesh order stands out of the map at every speed
    z = a.sel(tracked_order=67.0).values
    assert np.all(z > 10 * np.median(a.values, axis=1))

"""Spectra: known tones come back with the Hann window's known error; order axes; named peaks."""
from types import SimpleNamespace

import numpy as np
import pytest

from study.archive import run_variables
from study.archive.spectra import (
    HANN_MAIN_LOBE_BINS,
    amplitude_spectrum,
    named_orders,
    named_peaks,
    sideband_orders,
    ste_order_spectrum,
)

HANN_SCALLOP = 1 - (np.sinc(0.5) / (1 - 0.5**2))   # 15.1 %: Hann loss half-way between bins


def tone(n, dt, f, a, phase=0.3):
    t = np.arange(n) * dt
    return a * np.sin(2 * np.pi * f * t + phase)


@pytest.mark.parametrize("offset", [0.0, 0.25, 0.5])
def test_single_tone_amplitude_and_frequency_within_hann_error(offset):
    n, dt = 4000, 1e-4
    df = 1 / (n * dt)
    f0 = (137 + offset) * df
    f, a = amplitude_spectrum(tone(n, dt, f0, 2.0) + 5.0, dt)
    i = np.argmax(a)
    assert abs(f[i] - f0) <= 0.5 * df + 1e-9
    ratio = a[i] / 2.0
    assert 1 - HANN_SCALLOP - 1e-3 <= ratio <= 1 + 1e-6
    if offset == 0.0:
        assert ratio == pytest.approx(1.0, abs=1e-6)        # exact at a bin centre
    # zero padding samples between bins: the loss shrinks below 1 %
    fp, ap = amplitude_spectrum(tone(n, dt, f0, 2.0), dt, pad=4)
    assert ap.max() / 2.0 == pytest.approx(1.0, abs=0.01)
    assert abs(fp[np.argmax(ap)] - f0) <= 0.125 * df + 1e-9
    # resolution = 1 / record length, whatever the padding
    assert f[1] - f[0] == pytest.approx(df) and fp[1] - fp[0] == pytest.approx(df / 4)


def test_two_tones_and_dc_are_separated():
    n, dt = 8192, 5e-5
    df = 1 / (n * dt)
    x = 3.0 + tone(n, dt, 400 * df, 1.5) + tone(n, dt, 1234 * df, 0.02, 1.1)
    f, a = amplitude_spectrum(x, dt, detrend=False)
    assert a[0] == pytest.approx(3.0, rel=1e-3)             # the mean reads as itself
    assert a[400] == pytest.approx(1.5, rel=1e-6)
    assert a[1234] == pytest.approx(0.02, rel=1e-3)        # a small tone beside a large one
    assert a[800] < 1e-6                                    # Hann sidelobes fall off fast


def test_bad_input_is_rejected():
    with pytest.raises(ValueError, match="at least 8"):
        amplitude_spectrum(np.ones(4), 1.0)
    with pytest.raises(ValueError, match="pad"):
        amplitude_spectrum(np.ones(64), 1.0, pad=0)
    with pytest.raises(ValueError, match="sample step"):
        amplitude_spectrum(np.ones(64), 0.0)


def test_ste_order_axis_counts_driven_gear_revolutions():
    # driver 20 teeth, driven 40: the driven gear turns half as fast; one driver revolution
    # sampled every 0.1 deg = half a driven revolution -> resolution 2 orders
    z1, z2, n_holes = 20, 40, 4
    th1 = np.radians(np.arange(0, 360, 0.1))
    th2 = th1 * z1 / z2
    ste = 10 + 0.5 * np.cos(z2 * th2) + 0.1 * np.cos(n_holes * th2 + 0.7) + np.where(np.arange(th1.size) == 50, np.nan, 0)
    order, amp, res = ste_order_spectrum(ste, 0.1, z1, z2, pad=1)
    assert res == pytest.approx(2.0)
    assert amp[np.argmin(abs(order - z2))] == pytest.approx(0.5, rel=2e-3)     # mesh order Z (gap interpolated)
    assert amp[np.argmin(abs(order - n_holes))] == pytest.approx(0.1, rel=1e-2)  # hole order N
    assert order[np.argmax(amp)] == pytest.approx(z2)


def test_named_peaks_find_mesh_hole_sidebands_and_the_unexplained():
    z, n = 30, 5
    o = np.arange(0, 200, 0.125)
    amp = np.full(o.size, 1e-4)
    # 6Z and 6Z+N lie beyond the named table (5 mesh harmonics): still mesh orders, not "other"
    for order, a in ((n, 0.2), (z, 1.0), (2 * z, 0.3), (z + n, 0.05), (47.0, 0.4), (103.5, 0.1), (6 * z, 0.5),
                     (6 * z + n, 0.45)):
        amp[np.argmin(abs(o - order))] = a
    peaks = {p.name: p for p in named_peaks(o, amp, n, z, resolution=0.5)}
    assert peaks["Z"].amplitude == 1.0 and peaks["Z"].order == z
    assert peaks["N"].amplitude == 0.2 and peaks["2Z"].amplitude == 0.3
    assert peaks["Z+N"].amplitude == 0.05 and peaks["Z-N"].amplitude == pytest.approx(1e-4)
    assert peaks["other 1"].order == 47.0 and peaks["other 2"].order == 103.5
    assert np.isnan(peaks["other 1"].nominal)
    # a solid gear (N = 0) keeps the table of one sideband a side, NaN hole entries
    solid = named_peaks(o, amp, 0, z, resolution=0.5)
    assert [p.name for p in solid] == [nm for nm, _ in named_orders(0, z)] + [f"other {k}" for k in range(1, 5)]
    assert np.isnan({p.name: p for p in solid}["N"].amplitude)
    assert [nm for nm, _ in named_orders(6, 67)][:5] == ["N", "2N", "Z-N", "Z", "Z+N"]


def test_dte_spectrum_in_the_archive_has_orders_and_named_peaks():
    z, n_holes, speed = 67, 6, 100.0          # driven speed [rad/s]
    f_rot = speed / (2 * np.pi)
    dt, T = 1e-5, 0.2
    t = np.arange(int(round(T / dt)) + 1) * dt
    te = 40e-6 + 0.3e-6 * np.sin(2 * np.pi * z * f_rot * t) + 0.05e-6 * np.sin(2 * np.pi * n_holes * f_rot * t)
    res = SimpleNamespace(time=t, te=te, force_max=np.zeros_like(t), n_contacts=np.zeros(t.size, int),
                          driver_torque=np.zeros_like(t), energy_error=np.zeros_like(t), potential=np.zeros_like(t),
                          dissipated=np.zeros_like(t), status=0, dt=dt,
                          steps=t.size, omega_max=1.0, message="ok", max_active_teeth=4)
    coords, data, _ = run_variables.dynamic_variables(res, 0.02, speed, n_holes, z)
    order = coords["order"].values
    np.testing.assert_allclose(order, coords["frequency"].values / f_rot)
    names = list(coords["dte_peak"].values)
    amp = dict(zip(names, data["dte_peak_amplitude"].values))
    found = dict(zip(names, data["dte_peak_order"].values))
    res_orders = data["dte_amplitude"].attrs["resolution_Hz"] / f_rot
    assert 0.3 * (1 - HANN_SCALLOP) <= amp["Z"] <= 0.3 * 1.0001
    assert 0.05 * (1 - HANN_SCALLOP) <= amp["N"] <= 0.05 * 1.0001
    assert abs(found["Z"] - z) <= res_orders and abs(found["N"] - n_holes) <= res_orders
    freq = dict(zip(names, data["dte_peak_frequency"].values))
    assert freq["Z"] == pytest.approx(found["Z"] * f_rot)
    assert data["dte_amplitude"].attrs["window"] == "hann"


def test_once_per_revolution_orders_of_gears_with_errors_are_named():
    """An STE over twelve driver revolutions of a 20/30 pair with a once-per-driver-revolution
    tone (1.0 um: order Z2/Z1 = 1.5 of the driven gear) and a once-per-driven-revolution tone
    (0.4 um: order 1) reads them as R1 and R2; without revolution orders the table is the
    perfect pair's, and the tones are unexplained peaks."""
    step = 0.25
    theta = np.radians(np.arange(0.0, 12 * 360.0, step))
    ste = 1.0 * np.cos(theta + 0.2) + 0.4 * np.cos(theta * 20 / 30 - 0.5) + 0.1 * np.cos(20 * theta)
    c, d = run_variables.ste_spectrum_variables(np.degrees(theta), ste, 20, 30, 0.0, revolutions=True)
    names = list(c["ste_peak"].values)
    assert names[:2] == ["R1", "R2"]
    np.testing.assert_allclose(d["ste_peak_nominal_order"].values[:2], [1.5, 1.0])
    np.testing.assert_allclose(d["ste_peak_amplitude"].values[:2], [1.0, 0.4], rtol=0.02)
    c0, d0 = run_variables.ste_spectrum_variables(np.degrees(theta), ste, 20, 30, 0.0)
    assert "R1" not in list(c0["ste_peak"].values)
    assert list(c0["ste_peak"].values) == names[2:]
    others = d0["ste_peak_order"].values[[n.startswith("other") for n in c0["ste_peak"].values]]
    assert np.any(np.abs(others - 1.5) < 0.1) and np.any(np.abs(others - 1.0) < 0.1)


def test_spectrum_panel_draws_one_revolution_line_for_a_one_to_one_pair():
    """Gears with errors: the once-per-revolution orders R1 (driver) and R2 (driven) get their
    own colour; on a 1:1 pair they are one order and the panel draws one line, named R1=R2, and
    one table row (two lines and rows otherwise)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from study.report.te_plots import spectrum_panel
    order = np.linspace(0.0, 100.0, 2001)
    amp = np.full_like(order, 1e-3)
    for r2 in (1.0, 1.5):
        peaks = [("R1", 1.0, 1.0, 2.0), ("R2", r2, r2, 2.0), ("Z", 67.0, 67.0, 0.1)]
        fig, ax = plt.subplots()
        spectrum_panel(ax, order, amp, peaks, 100.0, "STE", "")
        labels = [t.get_text().strip() for t in ax.texts]
        plt.close(fig)
        if r2 == 1.0:
            assert "R1=R2" in labels and "R1" not in labels and "R2" not in labels
            assert sum("R1=R2:" in t for t in labels) == 1           # the peak table's row
        else:
            assert "R1" in labels and "R2" in labels and "R1=R2" not in labels


def test_every_resolved_hole_sideband_is_named_and_dc_leakage_is_no_peak():
    """kZ +- jN for every j up to half way to the next mesh harmonic (the 8-hole gear's
    kZ +- 2N at 51, 118, 185 and 217 included), and nothing of them when the record cannot
    resolve the hole order; the window's lobe of DC never reads as an unexplained peak."""
    z, n, res = 67, 8, 0.35
    o = np.arange(0, 360, res / 4)
    amp = np.full(o.size, 1e-5)
    for order, a in ((z, 1.0), (51, 0.2), (118, 0.1), (185, 0.15), (217, 0.05), (2 * z + 4 * n, 0.07)):
        amp[np.argmin(abs(o - order))] = a
    amp[:4] = [0.5, 0.3, 0.1, 0.05]                 # leakage of the mean into the first bins
    amp[5] = 0.06                                   # a maximum inside DC's main lobe
    peaks = {p.name: p for p in named_peaks(o, amp, n, z, resolution=res)}
    assert sideband_orders(n, z) == 4
    for name, order in (("Z-2N", 51), ("2Z-2N", 118), ("3Z-2N", 185), ("3Z+2N", 217), ("2Z+4N", 2 * z + 4 * n)):
        assert peaks[name].order == pytest.approx(order, abs=res) and peaks[name].amplitude > 0.01
    others = [p for k, p in peaks.items() if k.startswith("other") and np.isfinite(p.order)]
    assert all(p.order > HANN_MAIN_LOBE_BINS * res for p in others)
    # 3-order resolution (120 deg of STE): tones 8 orders apart overlap, no sideband is named
    assert sideband_orders(n, z, 3.0) == 0
    coarse = [p.name for p in named_peaks(o, amp, n, z, resolution=3.0)]
    assert "Z" in coarse and not any("Z-" in nm or "Z+" in nm for nm in coarse)


def _dte_record(speed, duration, n_holes=4, z=20, start=0.0):
    """A DTE of a 20-tooth pair with 4 holes over ``duration`` s at driven ``speed`` [rad/s]."""
    f_rot = speed / (2 * np.pi)
    dt = 1e-5
    t = np.arange(int(round(duration / dt)) + 1) * dt
    te = 40e-6 + 0.3e-6 * np.sin(2 * np.pi * z * f_rot * t) + 0.08e-6 * np.sin(2 * np.pi * n_holes * f_rot * t + 0.4)
    res = SimpleNamespace(time=t, te=te, force_max=np.zeros_like(t), n_contacts=np.zeros(t.size, int),
                          driver_torque=np.zeros_like(t), energy_error=np.zeros_like(t), potential=np.zeros_like(t),
                          dissipated=np.zeros_like(t), status=0, dt=dt,
                          steps=t.size, omega_max=1.0, message="ok", max_active_teeth=4)
    coords, data, _ = run_variables.dynamic_variables(res, start, speed, n_holes, z)
    return dict(zip(list(coords["dte_peak"].values), data["dte_peak_amplitude"].values)), data


def test_a_record_shorter_than_one_hole_period_names_no_hole_order_and_says_why():
    """52 deg of the driven gear's rotation (5 rad/s for 0.18 s) against a hole period of
    90 deg: no N, no 2N (the record cannot tell the hole pattern from its own mean), NaN with
    the reason; the mesh order, with 2.9 periods a tooth pitch, is still named. A record of two
    hole periods names N again."""
    amp, data = _dte_record(5.0, np.radians(52.0) / 5.0)
    assert np.isnan(amp["N"]) and np.isnan(amp["2N"]) and np.isfinite(amp["Z"])
    note = data["dte_peak_amplitude"].attrs["not_resolved"]
    assert "0.58 of a hole period" in note and "90 deg" in note
    amp, data = _dte_record(5.0, np.radians(180.0) / 5.0)
    assert amp["N"] == pytest.approx(0.08, rel=0.2) and "not_resolved" not in data["dte_peak_amplitude"].attrs


def test_the_once_per_revolution_order_of_a_whole_revolution_ste_is_measured():
    """An STE over exactly one driver revolution (3601 angles at 0.1 deg) of a 67/67 pair with a
    runout wave of 7 um and a twice-per-revolution one of 4 um: R1 is one period in the record,
    inside the window's lobe of DC (the windowed spectrum reads NaN or 8-9 um there, by phase),
    and is measured by its own fit: 7 um within 0.5 % at every phase."""
    angle = np.arange(3601) * 0.1
    theta = np.radians(angle)
    for phase in (0.3, 1.2, 2.0):
        ste = 40.0 + 7.0 * np.cos(theta + phase) + 4.0 * np.cos(2 * theta - 0.7) + 0.2 * np.cos(67 * theta)
        c, d = run_variables.ste_spectrum_variables(angle, ste, 67, 67, 6.0, revolutions=True)
        amp = dict(zip(list(c["ste_peak"].values), d["ste_peak_amplitude"].values))
        assert amp["R1"] == pytest.approx(7.0, rel=0.005) and amp["R2"] == pytest.approx(7.0, rel=0.005), phase
        assert d["ste_peak_order"].values[0] == 1.0 and amp["Z"] == pytest.approx(0.2, rel=0.16)

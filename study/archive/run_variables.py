"""Solver results -> the run archive's variables (`study.archive.schema` declares each: dims,
unit, long name): the STE and its spectrum, the DTE and its spectrum, named spectral peaks,
mesh efficiency, the tooth springs, and the scene's title.

  ste(angle)               static transmission error [um] over driver rotation [deg]
  ste_contacts(angle)      loaded tooth contacts [1]
  ste_tooth_force(angle, tooth)  normal force on each driver tooth [N]
  dte(time)                dynamic transmission error [um]
  contact_force_max(time)  largest contact force over each output interval [N]
  dte_contacts(time), driver_torque(time), energy_balance_error(time)
  mesh_efficiency                  work out over work in after the ramp (with flank friction) [1]
  dte_amplitude(frequency) amplitude spectrum of DTE after the ramp [um], coordinate order
  dte_peak_*(dte_peak)     named peaks of that spectrum (hole order N, mesh order Z, harmonics,
                           sidebands kZ+-N, the largest unexplained ones): order, frequency, amplitude
  ste_amplitude(ste_order) amplitude spectrum of STE over orders of the driven gear's rotation [um]
  ste_peak_*(ste_peak)     named peaks of the STE spectrum
  tooth_stiffness(gear, tooth), stiffness_ratio(gear, tooth)
Global attributes: the scene as TOML, backlash offset, mesh and hole orders, versions.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.energy_guard import energy_error_limit
from solver.mbs.kernels.status import COMPLETED
from study.archive.schema import variable
from study.archive.spectra import (
    HANN_MAIN_LOBE_BINS,
    Peak,
    amplitude_spectrum,
    fill_gaps,
    hole_period_note,
    named_peaks,
    ste_order_spectrum,
    tone_amplitude,
)
from study.scene import opening_text


def scene_title(scene) -> str:
    """A title that says what the scene as run is (never its free-text title, which an
    override leaves behind): teeth and module, each body, load and speed, coupling model."""
    g1, g2 = scene.gear1, scene.gear2

    def body(name, g, n):
        b = g.body
        if not scene.is_lightened(n):
            return f"{name} solid"
        return f"{name} {opening_text(b)}, web {b.web_thickness:g} mm, rim {b.rim_height:g} mm"
    parts = [f"z {g1.teeth}/{g2.teeth}, m {g1.module:g} mm", body("driver", g1, 1), body("driven", g2, 2)]
    d, qs = scene.dynamic, scene.quasi_static
    load = f"{(d.torque if d.enabled else qs.torque):g} N·m"
    if d.enabled:
        load += f", {d.speed:g} rad/s" if d.speed_end <= 0 else f", run-up 0-{d.speed_end:g} rad/s"
    parts.append(load)
    parts.append(f"{scene.coupling_model_name} model")     # the model run, 'auto' resolved
    return "; ".join(parts)


def opening_attrs(scene) -> dict:
    """Global attributes naming each gear's openings: ``opening_gearN`` ('round', 'slot',
    'window', or 'none' without holes) and ``openings_gearN`` (in words, `study.scene.opening_text`)."""
    out = {}
    for g in (1, 2):
        b = scene.gear(g).body
        out[f"opening_gear{g}"] = b.opening if b.holes else "none"
        out[f"openings_gear{g}"] = opening_text(b)
    return out


def static_variables(res, offset_m: float) -> dict:
    angle_deg = np.degrees(res.angle)
    coords = {"angle": variable("angle", angle_deg)}
    data = {
        "ste": variable("ste", res.te * units.UM_PER_M,
                    comment=f"zero at the zero-backlash conjugate position; rigid teeth in drive contact read +{offset_m * 1e6:.4f} um"),
        "ste_contacts": variable("ste_contacts", res.n_contacts.astype("int16")),
        "ste_tooth_force": variable("ste_tooth_force", res.tooth_force),
        "ste_converged": variable("ste_converged", res.converged.astype("int8")),
    }
    coords["driver_tooth"] = variable("driver_tooth", np.arange(res.tooth_force.shape[1]))
    return coords, data


def peak_variables(prefix: str, peaks, frequency_per_order: float | None = None, note: str = "") -> tuple[dict, dict]:
    """A small table of named spectral peaks along dimension ``{prefix}_peak`` (names as coordinate);
    ``note``: why some named orders are NaN (the amplitudes' attribute ``not_resolved``)."""
    dim = f"{prefix}_peak"
    coords = {dim: variable(dim, np.array([p.name for p in peaks], dtype=object))}
    data = {
        f"{dim}_nominal_order": variable(f"{dim}_nominal_order", np.array([p.nominal for p in peaks])),
        f"{dim}_order": variable(f"{dim}_order", np.array([p.order for p in peaks])),
        f"{dim}_amplitude": variable(f"{dim}_amplitude", np.array([p.amplitude for p in peaks])),
    }
    if note:
        data[f"{dim}_amplitude"].attrs["not_resolved"] = note
    if frequency_per_order is not None:
        data[f"{dim}_frequency"] = variable(f"{dim}_frequency", np.array([p.order for p in peaks]) * frequency_per_order)
    return coords, data


def ste_spectrum_variables(angle_deg, ste_um, z1: int, z2: int, hole_order: float, pad: int = 4,
                           revolutions: bool = False) -> tuple[dict, dict]:
    """STE amplitude spectrum over orders per revolution of the driven gear, and its named peaks
    (``revolutions``: also each gear's once-per-revolution order, R1 = Z2/Z1 and R2 = 1)."""
    angle_deg = np.asarray(angle_deg, float)
    if angle_deg.size < 16:
        return {}, {}
    step = float(angle_deg[1] - angle_deg[0])
    order, amp, res = ste_order_spectrum(ste_um, step, z1, z2, pad=pad)
    coords = {"ste_order": variable("ste_order", order)}
    data = {"ste_amplitude": variable("ste_amplitude", amp, resolution_orders=res, zero_padding=pad,
                                  record_driven_revolutions=1.0 / res,
                                  comment="driven rotation = driver rotation * z1/z2; NaN samples interpolated")}
    peaks = named_peaks(order, amp, hole_order, z2, res, revolution_orders=(z2 / z1, 1.0) if revolutions else None)
    x, _ = fill_gaps(ste_um)
    for i, p in enumerate(peaks):
        # a once-per-revolution order with whole periods in the record but inside the window's
        # lobe of DC (R1 on an STE over one driver revolution): the window's leakage of the mean
        # and of the next orders makes its peak; measured by its own fit instead
        if p.name in ("R1", "R2") and p.nominal <= HANN_MAIN_LOBE_BINS * res and p.nominal / res >= 1.0 - 1e-3:
            peaks[i] = Peak(p.name, p.nominal, p.nominal, tone_amplitude(x, p.nominal / res))
    c, d = peak_variables("ste", peaks, note=hole_period_note(hole_order, res))
    coords.update(c); data.update(d)
    return coords, data


def dynamic_variables(res, spectrum_start: float, driven_speed: float, hole_order: float = 0.0,
                      mesh_order: float | None = None, revolution_orders: tuple | None = None) -> tuple[dict, dict, dict]:
    """DTE and its spectrum after ``spectrum_start`` [s] with the named peaks (``revolution_orders``:
    see `study.archive.spectra.named_orders`)."""
    coords = {"time": variable("time", res.time)}
    data = {
        "dte": variable("dte", res.te * units.UM_PER_M),
        "contact_force_max": variable("contact_force_max", res.force_max),
        "dte_contacts": variable("dte_contacts", res.n_contacts.astype("int16")),
        "driver_torque": variable("driver_torque", res.driver_torque),
        "energy_balance_error": variable("energy_balance_error", res.energy_error),
    }
    attrs = {}
    sel = res.time >= spectrum_start
    if sel.sum() >= 16 and res.status in COMPLETED:     # an inaccurate run keeps its numbers, flagged
        dt = float(res.time[1] - res.time[0])
        f, a = amplitude_spectrum(res.te[sel] * units.UM_PER_M, dt)
        f_rot = driven_speed / (2 * np.pi)
        coords["frequency"] = variable("frequency", f)
        coords["order"] = variable("order", f / f_rot if f_rot > 0 else np.full_like(f, np.nan))
        data["dte_amplitude"] = variable("dte_amplitude", a, resolution_Hz=1.0 / (sel.sum() * dt), start_s=float(res.time[sel][0]))
        if f_rot > 0 and mesh_order:
            peaks = named_peaks(f / f_rot, a, hole_order, mesh_order, 1.0 / (sel.sum() * dt) / f_rot,
                                revolution_orders=revolution_orders)
            c, v = peak_variables("dte", peaks, f_rot, note=hole_period_note(hole_order, 1.0 / (sel.sum() * dt) / f_rot))
            coords.update(c); data.update(v)
    attrs.update(dt_s=res.dt, steps=res.steps, omega_max_rad_s=res.omega_max, dynamic_status=res.message,
                 max_active_teeth=res.max_active_teeth)
    if res.time.size > 1:
        # the energy guard's margin: largest |error| / limit over the run (flagged above 1)
        err = np.abs(res.energy_error)
        attrs.update(energy_error_max_J=float(err.max()), potential_energy_max_J=float(np.max(res.potential)),
                     energy_error_margin=float(np.max(err / np.maximum(energy_error_limit(res), 1e-300))))
    return coords, data, attrs


def efficiency_variable(res, torque: float, speed: float, start: float) -> dict:
    """``mesh_efficiency``: output over input work of the dynamic run ``res`` after ``start``
    [s], at the constant driver speed ``speed`` [rad/s] and resisting torque ``torque`` [N·m]:
    torque*|theta2 change| / (speed * integral of the driver torque). NaN without a window."""
    sel = res.time >= start
    eta = float("nan")
    if sel.sum() >= 2 and res.status in COMPLETED:
        t, tq = res.time[sel], res.driver_torque[sel]
        w_in = speed * float(np.sum(0.5 * (tq[1:] + tq[:-1]) * np.diff(t)))
        eta = abs(torque) * abs(float(res.theta2[sel][-1] - res.theta2[sel][0])) / w_in if w_in > 0 else eta
    return {"mesh_efficiency": variable("mesh_efficiency", eta, start_s=float(start))}


def stiffness_variables(k_nmm: tuple, ratio: tuple) -> tuple[dict, dict]:
    zmax = max(len(k) for k in k_nmm)
    K = np.full((2, zmax), np.nan)
    R = np.full((2, zmax), np.nan)
    for g in range(2):
        K[g, : len(k_nmm[g])] = k_nmm[g]
        R[g, : len(ratio[g])] = ratio[g]
    coords = {"gear": variable("gear", np.array([1, 2])), "tooth": variable("tooth", np.arange(zmax))}
    data = {"tooth_stiffness": variable("tooth_stiffness", K), "stiffness_ratio": variable("stiffness_ratio", R)}
    return coords, data


def largest_peaks(ds: xr.Dataset, n: int = 5, min_order: float = 0.5):
    """The n largest local maxima of dte_amplitude: list of (frequency Hz, order, amplitude um),
    from ``min_order`` and beyond the window's main lobe of DC (leakage of the mean)."""
    if "dte_amplitude" not in ds:
        return []
    from study.archive.spectra import HANN_MAIN_LOBE_BINS
    a = ds["dte_amplitude"].values
    f = ds["frequency"].values
    o = ds["order"].values
    lobe = HANN_MAIN_LOBE_BINS * float(ds["dte_amplitude"].attrs.get("resolution_Hz", 0.0))
    in_lobe = (f <= lobe) & np.isfinite(o)      # (no orders at standstill)
    min_order = max(min_order, float(np.max(o[in_lobe])) if in_lobe.any() else 0.0)
    idx = [i for i in range(1, a.size - 1) if a[i] >= a[i - 1] and a[i] >= a[i + 1] and o[i] > min_order]
    idx.sort(key=lambda i: -a[i])
    return [(float(f[i]), float(o[i]), float(a[i])) for i in idx[:n]]

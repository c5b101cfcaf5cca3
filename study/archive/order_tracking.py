"""Computed order tracking of a run-up: DTE resampled to the driven gear's angle, amplitude
spectra over blocks of whole revolutions, giving amplitudes over (speed, order).

In a run-up (`dynamic.speed_end`) the driver's speed rises linearly from 0 to ``speed_end``
[rad/s] over the whole run (`solver.mbs.kernels.mechanics.driver_motion` with the ramp as
long as the run), so its angle is known in closed form; the driven gear turns at z1/z2 of it
(its TE deviation, microradians, does not matter to the resampling). Each block of ``revs``
driven revolutions, one every 1/8 revolution, gives one spectrum (Hann window, amplitudes of
tones, order resolution 1/revs) at the block's mean driver speed. A block smears the speed
by what the driver gains during it: at speed w over a run-up of rate a, a 2 pi z2/z1 / w,
so the low speeds, where a revolution takes long, are coarse.
"""
from __future__ import annotations

import numpy as np

from study.archive.schema import variable
from study.archive.spectra import amplitude_spectrum


def driver_angle(t, speed_end: float, ramp: float):
    """Driver angle [rad] of the linear speed ramp 0 -> speed_end [rad/s] over ramp [s]."""
    t = np.asarray(t, dtype=float)
    return np.where(t < ramp, 0.5 * speed_end / ramp * t * t, speed_end * (t - 0.5 * ramp))


def order_map(time, dte, runup: tuple, teeth: tuple, revs: float = 1.0, samples_per_rev: int = 1024,
              speed_min: float = 0.0, hop: float = 0.125):
    """(driver speed [rad/s] of each block, orders [1], amplitude (speed, order) [dte units]) of
    a run-up ``runup`` = (speed_end [rad/s], ramp [s]) of a pair of ``teeth`` = (z1, z2): blocks
    of ``revs`` driven revolutions, one every ``hop`` revolutions (overlapping)."""
    (speed_end, ramp), (z1, z2) = runup, teeth
    time = np.asarray(time, dtype=float)
    rev = driver_angle(time, speed_end, ramp) * z1 / z2 / (2 * np.pi)      # driven revolutions
    grid = np.arange(int(np.floor(rev[-1] * samples_per_rev))) / samples_per_rev
    x = np.interp(grid, rev, dte)
    t_grid = np.interp(grid, rev, time)
    m = int(round(revs * samples_per_rev))
    step = max(1, int(round(hop * samples_per_rev)))
    speeds, rows, order = [], [], np.zeros(0)
    for start in range(0, grid.size - m + 1, step):
        sl = slice(start, start + m)
        w = float(np.mean(np.minimum(t_grid[sl], ramp))) * speed_end / ramp
        if w < speed_min:
            continue
        order, amp = amplitude_spectrum(x[sl], 1.0 / samples_per_rev)
        speeds.append(w)
        rows.append(amp)
    return np.array(speeds), order, np.array(rows).reshape(len(rows), order.size)


def order_cut(speed, order, amplitude, target: float, half_width: float = 0.5) -> np.ndarray:
    """Largest amplitude within +-half_width orders of ``target``, for each speed."""
    sel = np.abs(order - target) <= half_width
    return amplitude[:, sel].max(axis=1) if sel.any() else np.full(len(speed), np.nan)


def order_tracking_variables(time, dte_um, speed_end: float, ramp: float, z1: int, z2: int,
                             revs: float = 1.0, max_order: float | None = None) -> tuple[dict, dict]:
    """``order_amplitude(runup_speed, tracked_order)`` [um] of a run-up, orders up to ``max_order``
    (default 5 Z2 + 10)."""
    speed, order, amp = order_map(time, dte_um, (speed_end, ramp), (z1, z2), revs, speed_min=0.05 * speed_end)
    keep = order <= (max_order or 5 * z2 + 10)
    coords = {"runup_speed": variable("runup_speed", speed), "tracked_order": variable("tracked_order", order[keep])}
    data = {"order_amplitude": variable("order_amplitude", amp[:, keep], revolutions_per_block=revs)}
    return coords, data

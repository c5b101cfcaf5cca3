"""Amplitude spectra of transmission-error signals and the gear orders that explain their peaks.

One-sided amplitude spectrum with a Hann window, scaled by the window's coherent gain so a
sinusoid of amplitude A (um) inside the record reads A at its bin (within the window's
scalloping loss, at most 15 % for Hann between bins; exact at bin centres). Resolution =
1 / record length; zero padding (``pad``) samples the same window-smoothed spectrum more
finely (it lowers the scalloping loss, not the resolution).

Orders are counted per revolution of the driven gear: the hole order is the number of holes
N of the driven gear, the mesh order its tooth count Z; with pitch errors or eccentricity the
once-per-revolution orders of the driver (Z2/Z1, named R1) and of the driven gear (1, R2). STE is sampled over driver angle; its
spectrum over driven-gear orders uses the driven rotation theta2 = theta1 * z1 / z2.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WINDOW = "hann"
HANN_MAIN_LOBE_BINS = 2.0   # half-width of the Hann main lobe in resolution bins


def amplitude_spectrum(signal, dt: float, detrend: bool = True, pad: int = 1):
    """Frequencies [1/dt units, e.g. Hz] and one-sided amplitudes (signal units) of a uniformly
    sampled signal; ``pad`` >= 1 zero-pads the windowed record to pad times its length."""
    x = np.asarray(signal, dtype=float)
    if x.ndim != 1 or x.size < 8:
        raise ValueError("amplitude_spectrum needs a 1-D signal of at least 8 samples")
    if not (dt > 0):
        raise ValueError(f"amplitude_spectrum: sample step must be positive, got {dt}")
    if int(pad) != pad or pad < 1:
        raise ValueError(f"amplitude_spectrum: pad must be an integer >= 1, got {pad}")
    if detrend:
        x = x - x.mean()
    w = np.hanning(x.size)
    n = int(pad) * x.size
    spec = np.fft.rfft(x * w, n=n)
    amp = 2.0 * np.abs(spec) / w.sum()
    amp[0] *= 0.5
    freq = np.fft.rfftfreq(n, dt)
    return freq, amp


def fill_gaps(x) -> tuple[np.ndarray, int]:
    """Signal with non-finite samples linearly interpolated from their neighbours, and their count."""
    x = np.asarray(x, dtype=float).copy()
    bad = ~np.isfinite(x)
    nb = int(bad.sum())
    if nb and nb < x.size:
        i = np.arange(x.size)
        x[bad] = np.interp(i[bad], i[~bad], x[~bad])
    return x, nb


def ste_order_spectrum(ste_um, angle_step_deg: float, z1: int, z2: int, pad: int = 4):
    """Orders per driven-gear revolution [1] and amplitudes [um] of an STE sampled every
    ``angle_step_deg`` degrees of driver rotation; also the resolution [orders]."""
    step_rev = angle_step_deg / 360.0 * z1 / z2      # driven revolutions per sample
    x, _ = fill_gaps(ste_um)
    order, amp = amplitude_spectrum(x, step_rev, pad=pad)
    return order, amp, 1.0 / (x.size * step_rev)


@dataclass(frozen=True)
class Peak:
    name: str          # "N", "2N", "Z", "2Z", "Z-N", "Z+N", ..., "other 1", ...
    nominal: float     # nominal order [1] (NaN for unexplained peaks)
    order: float       # order of the largest amplitude found near it [1]
    amplitude: float   # amplitude there [signal units]


def sideband_orders(hole_order: float, mesh_order: float, resolution: float | None = None) -> int:
    """How many hole sidebands kZ +- jN (j = 1..J) a record resolves on each side of a mesh
    order: those up to half way to the next mesh harmonic (J = Z / (2N), at least 1), when
    the record's ``resolution`` [orders] keeps the main lobes of tones N apart from
    overlapping (N >= 2 x HANN_MAIN_LOBE_BINS x resolution); 0 when it does not (``None``:
    resolved). A gear without holes keeps J = 1 (NaN entries)."""
    n = float(hole_order) if hole_order and hole_order > 0 else 0.0
    if n <= 0:
        return 1
    if resolution is not None and n < 2 * HANN_MAIN_LOBE_BINS * resolution:
        return 0
    return max(1, int(0.5 * float(mesh_order) / n + 1e-9))


def hole_period_note(hole_order: float, resolution: float) -> str:
    """Why a record names no hole order: '' when it spans at least one hole period (1/N of a
    driven revolution), else the reason (a record shorter than one hole period cannot tell the
    hole pattern from the window's leakage of its mean). ``resolution`` [orders] = 1 / the
    record's length in driven revolutions."""
    n = float(hole_order) if hole_order and hole_order > 0 else 0.0
    if n <= 0 or not resolution > 0 or n / resolution >= 1.0 - 1e-9:
        return ""
    return (f"hole orders not resolved: the record spans {n / resolution:.2f} of a hole period ({360.0 / resolution:.3g} "
            f"deg of the driven gear's rotation, a hole period {360.0 / n:.3g} deg); a hole order needs at least one "
            "hole period in the record")


def tone_amplitude(x, cycles: float) -> float:
    """Amplitude of the sinusoid of ``cycles`` periods over the record ``x`` (uniform samples),
    by least squares with a constant: exact for a periodic signal over whole periods, where a
    windowed spectrum puts a one-period tone inside the window's lobe of DC."""
    x = np.asarray(x, float)
    phase = 2 * np.pi * cycles * np.arange(x.size) / x.size
    basis = np.column_stack([np.ones(x.size), np.cos(phase), np.sin(phase)])
    coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
    return float(np.hypot(coef[1], coef[2]))


def sideband_name(kz: str, j: int, sign: str) -> str:
    return f"{kz}{sign}N" if j == 1 else f"{kz}{sign}{j}N"


def named_orders(hole_order: float, mesh_order: float, mesh_harmonics: int = 5, hole_harmonics: int = 2,
                 revolution_orders: tuple | None = None, sidebands: int = 1) -> list[tuple[str, float]]:
    """(name, order) of the orders a lightened gear pair excites: hole order N and its harmonics
    (up to the larger of ``hole_harmonics`` and ``sidebands``), mesh order Z and its
    harmonics, and the sidebands kZ +- jN, j = 1..``sidebands`` (`sideband_orders`). NaN
    orders when N = 0 (kept so every scene has the same table). ``revolution_orders`` =
    (driver, driven) once-per-revolution orders (Z2/Z1 and 1 in driven-gear orders), given
    for gears with pitch errors or eccentricity: named R1 and R2 first (none otherwise, so a
    perfect pair's table is unchanged)."""
    n = float(hole_order) if hole_order and hole_order > 0 else float("nan")
    z = float(mesh_order)
    out = [] if revolution_orders is None else [("R1", float(revolution_orders[0])), ("R2", float(revolution_orders[1]))]
    out += [("N" if h == 1 else f"{h}N", h * n) for h in range(1, max(hole_harmonics, sidebands) + 1)]
    for k in range(1, mesh_harmonics + 1):
        kz = "Z" if k == 1 else f"{k}Z"
        out += [(sideband_name(kz, j, "-"), k * z - j * n) for j in range(sidebands, 0, -1)]
        out.append((kz, k * z))
        out += [(sideband_name(kz, j, "+"), k * z + j * n) for j in range(1, sidebands + 1)]
    return out


def _lobe_window(order: np.ndarray):
    """``window(o, w)`` -> (lo, hi): a slice of ``order`` that holds every bin within ``w`` of
    ``o`` (a few bins more on each side, the exact test is the caller's), found by bisection on
    an increasing axis; the whole axis when it is not increasing (NaN orders)."""
    if order.size < 2 or not np.all(np.diff(order) > 0):
        return lambda o, w: (0, order.size)

    def window(o, w):
        lo = int(np.searchsorted(order, o - w, "left")) - 2
        hi = int(np.searchsorted(order, o + w, "right")) + 2
        return max(lo, 0), min(hi, order.size)
    return window


@dataclass(frozen=True)
class PeakTable:
    """What `named_peaks` names and looks for: the mesh harmonics kZ (k = 1..mesh_harmonics)
    and hole harmonics, the unexplained peaks besides them, from ``min_order`` [1] on."""
    mesh_harmonics: int = 5
    hole_harmonics: int = 2
    unexplained: int = 4
    min_order: float = 0.5


def named_peaks(order, amplitude, hole_order: float, mesh_order: float, resolution: float,
                revolution_orders: tuple | None = None, settings: PeakTable = PeakTable()) -> list[Peak]:
    """The amplitude found at each named order and the ``unexplained`` largest local maxima that
    lie outside every named order's main lobe and off the higher mesh harmonics kZ (and kZ+-N)
    the table does not name (names "other 1", ...; NaN when fewer).

    A named order's amplitude is the largest value within the Hann main lobe (+-2 resolution
    bins) of the nominal order, but no nearer to another named order (or to order 0) than half
    way; it is NaN when that largest value is not a local maximum (no peak, or only the skirt
    of a neighbouring peak the record is too short to resolve). The sidebands kZ +- jN named
    are those the record resolves (`sideband_orders`); none when the hole order is closer
    than a main lobe's width; no hole order (jN, kZ +- jN) when the record is shorter than one
    hole period (`hole_period_note`). Maxima on DC's main lobe (window leakage of the mean) are
    never unexplained peaks."""
    mesh_harmonics, hole_harmonics = settings.mesh_harmonics, settings.hole_harmonics
    unexplained, min_order = settings.unexplained, settings.min_order
    order = np.asarray(order, float)
    amp = np.asarray(amplitude, float)
    tol = max(HANN_MAIN_LOBE_BINS * resolution, 1e-9)
    no_holes = bool(hole_period_note(hole_order, resolution))     # shorter than a hole period: no jN, no kZ+-jN
    sidebands = sideband_orders(hole_order, mesh_order, resolution)
    table = named_orders(hole_order, mesh_order, mesh_harmonics, hole_harmonics, revolution_orders, sidebands)
    finite = np.array([0.0] + [o for _, o in table if np.isfinite(o)])
    is_peak = np.zeros(amp.size, bool)
    is_peak[1:-1] = (amp[1:-1] >= amp[:-2]) & (amp[1:-1] >= amp[2:])
    peaks = []
    nominal = []
    window = _lobe_window(order)
    for name, o in table:
        i = None
        if np.isfinite(o):
            # search the main lobe, but no closer to another named order (or to 0) than half way
            d = np.abs(finite - o)
            w = min(tol, 0.5 * d[d > 1e-9].min()) if np.any(d > 1e-9) else tol
            lo, hi = window(o, w)
            sel = np.abs(order[lo:hi] - o) <= w
            if sel.any():
                i = lo + np.flatnonzero(sel)[np.argmax(amp[lo:hi][sel])]
            nominal.append(o)
        if no_holes and name.endswith("N"):
            i = None
        if i is not None and is_peak[i]:
            peaks.append(Peak(name, o, float(order[i]), float(amp[i])))
        else:     # nothing there, or only the skirt of a neighbour's lobe (not resolved)
            peaks.append(Peak(name, o, float("nan"), float("nan")))
    nominal = np.asarray(nominal)
    if sidebands == 0 and np.isfinite(mesh_order) and mesh_order > 0:
        # sidebands the record cannot resolve still explain what stands on the mesh lobes' skirts
        j = np.arange(1, sideband_orders(hole_order, mesh_order) + 1) * float(hole_order)
        k = np.arange(1, mesh_harmonics + 1)[:, None] * float(mesh_order)
        nominal = np.concatenate([nominal, (k - j).ravel(), (k + j).ravel()])
    is_max = np.zeros(amp.size, bool)
    is_max[1:-1] = (amp[1:-1] >= amp[:-2]) & (amp[1:-1] > amp[2:])
    is_max &= (order >= min_order) & (order > tol)      # not on the window's lobe of DC (leakage of the mean)
    # mesh harmonics beyond the named ones (and their hole sidebands) are explained too
    if np.isfinite(mesh_order) and mesh_order > 0 and order.size:
        k = np.arange(mesh_harmonics + 1, int(order.max() / mesh_order) + 2)
        side = hole_order if np.isfinite(hole_order) and hole_order > 0 else 0.0
        j = np.arange(-sidebands, sidebands + 1) * side
        nominal = np.concatenate([nominal, (k[:, None] * mesh_order + j[None, :]).ravel()])
    idx = np.flatnonzero(is_max)
    if nominal.size and idx.size:    # the distances at the candidate maxima only (not every bin)
        idx = idx[np.min(np.abs(order[idx, None] - nominal[None, :]), axis=1) > tol]
    idx = idx[np.argsort(-amp[idx])]
    chosen: list[int] = []
    for i in idx:   # one maximum per main lobe (zero padding makes side-by-side maxima)
        if all(abs(order[i] - order[j]) > tol for j in chosen):
            chosen.append(i)
        if len(chosen) == unexplained:
            break
    for k in range(unexplained):
        if k < len(chosen):
            i = chosen[k]
            peaks.append(Peak(f"other {k + 1}", float("nan"), float(order[i]), float(amp[i])))
        else:
            peaks.append(Peak(f"other {k + 1}", float("nan"), float("nan"), float("nan")))
    return peaks

"""Amplitude spectra of transmission-error signals.

One-sided amplitude spectrum with a Hann window, scaled by the window's coherent gain so a
sinusoid of amplitude A (um) inside the record reads A at its bin (within the window's
scalloping loss, at most 15 % for Hann between bins). Resolution = 1 / record length.
"""
from __future__ import annotations

import numpy as np

WINDOW = "hann"


def amplitude_spectrum(signal, dt: float, detrend: bool = True):
    """Frequencies [Hz] and one-sided amplitudes (signal units) of a uniformly sampled signal."""
    x = np.asarray(signal, dtype=float)
    if x.ndim != 1 or x.size < 8:
        raise ValueError("amplitude_spectrum needs a 1-D signal of at least 8 samples")
    if detrend:
        x = x - x.mean()
    w = np.hanning(x.size)
    spec = np.fft.rfft(x * w)
    amp = 2.0 * np.abs(spec) / w.sum()
    amp[0] *= 0.5
    freq = np.fft.rfftfreq(x.size, dt)
    return freq, amp

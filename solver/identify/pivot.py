"""Identification of the pseudo-rigid tooth spring (pivot radius, k_phi, n) from FE compliance.

A rigid tooth turning by phi about a pivot Q on its axis at radius r_Q moves the tooth's
centreline point on the load line by phi * lever along the load, lever = |r_b - r_Q cos t| for
the line of action touching the base circle at polar angle t (t = psi_b - u, u the roll parameter
of the load point). With the spring M = k phi the compliance along the load is

    c(u) = lever(u, r_Q)^2 / k.

Fitting c(u) measured by FE at several load points along the profile gives r_Q and k; fitting
M = k_phi phi^n over several load levels gives n. The body FE is linear, so its n is 1: an
exponent above 1 (the paper's 1.1) must come from a nonlinear source (contact in the FE model,
measurements); `fit_power_law` takes such data as they are. SI units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SpringFit:
    pivot_radius: float     # m
    k_phi: float            # N·m/rad^n
    n: float                # 1
    rms_rel_error: float    # RMS relative residual of the compliance fit


def lever(base_radius: float, t, pivot_radius: float):
    """Distance [m] from the pivot (r_Q, 0) to the line of action touching the base circle at t."""
    return np.abs(base_radius - pivot_radius * np.cos(t))


def fit_pivot(base_radius: float, t, compliance) -> tuple[float, float, float]:
    """Least-squares (r_Q [m], k [N·m/rad], RMS relative residual) of c = lever^2 / k.

    sqrt(c) = |r_b - r_Q cos t| / sqrt(k) is linear in (1/sqrt(k), r_Q/sqrt(k)) where the
    lever keeps its sign (the pivot below all load lines), so the fit is a linear solve.
    """
    t = np.asarray(t, float)
    c = np.asarray(compliance, float)
    if t.size < 2 or np.any(c <= 0):
        raise ValueError("compliance: need at least two positive values")
    A = np.column_stack([base_radius * np.ones_like(t), -np.cos(t)])
    (a, b), *_ = np.linalg.lstsq(A, np.sqrt(c), rcond=None)
    k = 1.0 / a**2
    r_q = b / a
    res = lever(base_radius, t, r_q) ** 2 / k / c - 1
    return float(r_q), float(k), float(np.sqrt(np.mean(res**2)))


def fit_power_law(moment, rotation) -> tuple[float, float]:
    """(k_phi [N·m/rad^n], n) of M = k_phi * phi^n by least squares in log-log."""
    m, p = np.asarray(moment, float), np.asarray(rotation, float)
    if m.size < 2 or np.any(m <= 0) or np.any(p <= 0):
        raise ValueError("moment, rotation: need at least two positive pairs")
    n, logk = np.polyfit(np.log(p), np.log(m), 1)
    return float(math.exp(logk)), float(n)

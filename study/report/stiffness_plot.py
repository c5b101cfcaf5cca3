"""Per-tooth spring stiffness plot of a run archive (matplotlib, Agg, PNG); reads only the
dataset (``tooth_stiffness``, ``stiffness_ratio``) and the scene TOML in its attributes.
"""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from solver.geometry import hole_angles, opening_half_angle
from study.report.plot_style import C_HOLE, C_LIGHT, C_SOLID, archive_scene, figure_title, need, save_figure, unit_text
from study.scene import OPENING_WORDS


def stiffness_plot(ds: xr.Dataset, path) -> Path:
    """Per-tooth spring stiffness against tooth index; a gear whose teeth all have the same
    spring is stated in the legend instead of drawn (it would flatten the other's variation).
    Hole positions shaded (angular width of the hole seen from the gear centre), and the
    stiffness ratio to the solid gear on the right axis."""
    need(ds, "tooth_stiffness")
    sc = archive_scene(ds)
    k = ds["tooth_stiffness"]
    r = ds["stiffness_ratio"] if "stiffness_ratio" in ds else None
    fig, ax = plt.subplots(figsize=(11, 5.2), constrained_layout=True)
    figure_title(fig, ds, "Tooth spring stiffness k_φ, tooth by tooth (teeth over holes vs between holes)")
    styles = {1: ("s", C_SOLID, "gear 1 (driver)"), 2: ("o", C_LIGHT, "gear 2 (driven)")}
    drawn = []
    for g in ds["gear"].values:
        kg = k.sel(gear=g).values
        ok = np.isfinite(kg)
        m, c, lab = styles.get(int(g), ("o", None, f"gear {g}"))
        if np.ptp(kg[ok]) <= 1e-9 * abs(kg[ok]).max():
            ax.plot([], [], " ", label=f"{lab}: every tooth {kg[ok][0]:.4g} {unit_text(k)}")
            continue
        ax.plot(np.flatnonzero(ok), kg[ok], marker=m, ms=5, lw=1.2, color=c, label=lab)
        drawn.append(int(g))
    first = True
    if sc is not None:
        for g in drawn or (1, 2):
            b = sc.gear(g).body
            if b.holes == 0:
                continue
            pitch = 360.0 / sc.gear(g).teeth
            half = math.degrees(opening_half_angle(sc.body_spec(g))) / pitch
            what = OPENING_WORDS[b.opening][:-1]
            for centre in hole_angles(b.holes, b.hole_phase, 360.0):
                c = (centre % 360.0) / pitch
                ax.axvspan(c - half, c + half, color=C_HOLE, alpha=0.15, lw=0,
                           label=f"{what} of gear {g} (angular extent)" if first else None)
                ax.axvline(c, color=C_HOLE, ls="--", lw=0.8, label=f"{what} centre" if first else None)
                first = False
    ax.set_xlabel("tooth index [–] (tooth k's axis at k·360°/Z from tooth 0)")
    ax.set_ylabel(f"spring stiffness k_φ [{unit_text(k)}]")
    zmax = int(np.isfinite(k.values).sum(axis=1).max())
    ax.set_xlim(-0.5, zmax - 0.5)
    ax.grid(alpha=0.3)
    if r is not None and drawn:
        g = drawn[-1]
        sec = ax.secondary_yaxis("right", functions=_ratio_axis(k.sel(gear=g).values, r.sel(gear=g).values))
        sec.set_ylabel(f"stiffness ratio to the solid gear [–] (gear {g})")
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=4, fontsize=9, frameon=False)
    return save_figure(fig, path)


def _ratio_axis(kk, rr):
    """Forward/inverse maps k -> ratio (k = k_solid * ratio for 'fe-ratio' springs)."""
    ok = np.isfinite(kk) & np.isfinite(rr) & (rr > 0)
    scale = float(np.median(kk[ok] / rr[ok])) if ok.any() else 1.0
    return (lambda x: x / scale, lambda y: y * scale)



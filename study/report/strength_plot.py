"""Strength map of a run archive (matplotlib, Agg, PNG): the largest tensile stress at every
strength site of each gear under the run's loads (``site_stress``, ``site_position``: root
fillets, inner rim, web opening edges and ligaments), the hot spot of each location marked with
its stress and safety factor. Reads only the dataset.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from study.report.plot_style import figure_title, need, save_figure

MARKERS = {"root": ("v", "#d62728"), "rim": ("s", "#9467bd"), "web": ("D", "#111111")}


def strength_plot(ds: xr.Dataset, path) -> Path:
    """Per gear: the whole body's sites coloured by their largest tensile stress [MPa] (one
    scale per gear), and a close view around the web's hot spot (the root's without openings),
    each location's hot spot marked and labelled with its stress and S_F."""
    need(ds, "site_stress", "site_position", "bending_stress")
    gears = [g for g in ds["gear"].values if np.isfinite(ds["site_stress"].sel(gear=g).values).any()]
    if not gears:
        raise ValueError("no strength sites in the archive")
    fig, axes = plt.subplots(len(gears), 2, figsize=(13, 6.2 * len(gears)), constrained_layout=True, squeeze=False)
    figure_title(fig, ds, "Largest tensile stress under the run's loads, at the roots, the rim and the web "
                          "(hot spots marked)")
    for row, g in zip(axes, gears):
        s = ds["site_stress"].sel(gear=g).values
        xy = ds["site_position"].sel(gear=g).values
        loc = ds["site_location"].sel(gear=g).values
        ok = np.isfinite(s)
        hot = ds["stress_position"].sel(gear=g).values
        peak = ds["bending_stress"].sel(gear=g).values
        sf = ds["bending_safety"].sel(gear=g).values
        has_web = np.isfinite(peak[2])
        centre = hot[2] if has_web else hot[0]
        span = 0.35 * float(np.hypot(*xy[ok].T).max())
        for ax, zoom in zip(row, (False, True)):
            sel = ok.copy()
            top = float(np.nanmax(s))
            if zoom:
                sel &= (np.abs(xy[:, 0] - centre[0]) < span) & (np.abs(xy[:, 1] - centre[1]) < span)
                if has_web:         # the web and rim on their own scale (the roots' stress is far higher)
                    sel &= loc != 0
                    top = float(np.nanmax(s[sel]))
            order = np.argsort(s[sel])          # the hottest drawn last, on top
            sc = ax.scatter(xy[sel, 0][order], xy[sel, 1][order], c=s[sel][order], s=9 if zoom else 3, cmap="turbo",
                            vmin=0.0, vmax=top, linewidths=0)
            fig.colorbar(sc, ax=ax, shrink=0.8, label=("web and rim sites: " if zoom and has_web else "")
                         + "largest tensile (max principal) stress [MPa]")
            for k, name in enumerate(("root", "rim", "web")):
                if not np.isfinite(peak[k]):
                    continue
                m, c = MARKERS[name]
                inside = not zoom or (abs(hot[k, 0] - centre[0]) < span and abs(hot[k, 1] - centre[1]) < span)
                if inside:
                    ax.plot(*hot[k], m, ms=11, mfc="none", mec=c, mew=2.0,
                            label=f"{name}: {peak[k]:.1f} MPa, S_F {sf[k]:.2f}")
            ax.set_aspect("equal")
            ax.set_xlabel("x [mm] (gear frame: tooth 0 on +x)")
            ax.set_ylabel("y [mm]")
            ax.grid(alpha=0.25)
            if zoom:
                ax.set_xlim(centre[0] - span, centre[0] + span)
                ax.set_ylim(centre[1] - span, centre[1] + span)
                where = f"{ds['web_stress_site'].sel(gear=g).values} hot spot" if has_web else "root hot spot (no web openings)"
                ax.set_title(f"gear {g}: around the {where}" + (" (roots left out)" if has_web else ""), fontsize=10)
            else:
                mode = str(ds["failure_mode"].sel(gear=g).values)
                ax.set_title(f"gear {g}: m_B {float(ds['backup_ratio'].sel(gear=g)):.2f}, "
                             f"Y_B {float(ds['rim_thickness_factor_iso6336'].sel(gear=g)):.2f}, failure mode {mode}",
                             fontsize=10)
            ax.legend(loc="upper right", fontsize=8, framealpha=0.85)
    return save_figure(fig, path)

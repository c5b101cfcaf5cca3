"""Campbell diagram of a run archive: the pair's mode frequencies [Hz] against driver speed
[rad/s], the excitation order lines (kZ, N, 2N, kZ +- N of the driven gear's rotation) and
the critical speeds where a line meets the mesh mode (`study.archive.modes`)."""
from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from study.report.plot_style import figure_title, need, save_figure


def campbell_plot(ds: xr.Dataset, path):
    need(ds, "mode_frequency", "critical_speed")
    f = ds["mode_frequency"]
    fmesh = f.sel(mode=0)
    speed = ds.attrs.get("driven_speed_rad_s", 0.0)
    mesh_order = ds.attrs["mesh_order"]
    cs = ds["critical_speed"].sel(mode=0)
    # driven speed / driver speed = z1 / z2: from the 1Z critical speed and the mesh frequency
    ratio = 2 * math.pi * float(fmesh.mean()) / (mesh_order * float(cs.sel(excitation="1Z")))
    driver_speed = speed / ratio if ratio > 0 else 0.0
    runup = float(ds.attrs.get("runup_speed_end_rad_s", 0.0))     # a run-up sweeps 0 -> runup
    x_max = max(1.3 * float(cs.sel(excitation="1Z")), 2.0 * driver_speed if not runup else 1.05 * runup)
    x = np.linspace(0.0, x_max, 200)
    fig, ax = plt.subplots(figsize=(8.5, 6.5))
    y_max = 1.6 * float(fmesh.max())
    for m in ds["mode"].values:
        fm = f.sel(mode=m)
        if not np.isfinite(fm).any() or float(fm.min()) > y_max:
            continue
        lo, hi = float(fm.min()), float(fm.max())
        kind = str(ds["mode_kind"].values[m])
        ax.axhspan(lo, hi, color="C3" if m == 0 else "C2", alpha=0.35, lw=0,
                   label=f"{kind} mode: {lo:.0f}-{hi:.0f} Hz over the mesh period, zeta "
                         f"{float(ds['mode_damping'].sel(mode=m).mean()):.3f}")
    for e, o in zip(ds["excitation"].values, ds["excitation_order"].values):
        style = dict(color="0.2", lw=1.0) if str(e).endswith("Z") else dict(color="0.55", lw=0.7, ls="--")
        y = o * x * ratio / (2 * math.pi)
        ax.plot(x, y, **style)
        k = np.searchsorted(y, 0.97 * y_max)
        if 0 < k < x.size and str(e).endswith("Z"):
            ax.text(x[k], y[k], str(e), fontsize=7, ha="left", va="top")
        elif y[-1] < y_max:
            ax.text(x[-1], y[-1], str(e), fontsize=7, ha="left", va="center")
    crit = [(str(e), float(v)) for e, v in zip(ds["excitation"].values, cs.values) if v <= x_max]
    for _e, v in crit:
        ax.plot(v, float(fmesh.mean()), "o", color="C3", ms=5)
    if crit:
        ax.plot([], [], "o", color="C3", label="critical speeds of the mesh mode (dots; kZ lines solid, N and "
                "sidebands kZ+-N dashed): " + ", ".join(f"{e} {v:.0f}" for e, v in crit if e.endswith("Z")) + " rad/s")
    if runup > 0:
        ax.axvspan(0.0, runup, color="C0", alpha=0.07, lw=0, label=f"run-up 0-{runup:.0f} rad/s")
    elif driver_speed > 0:
        ax.axvline(driver_speed, color="C0", lw=1.2, label=f"run speed {driver_speed:.0f} rad/s")
    higher = {}
    for m in ds["mode"].values:
        fm = float(np.nanmean(f.sel(mode=m)))
        if fm > y_max:
            kind = str(ds["mode_kind"].values[m])
            higher.setdefault("body" if kind == "body" else "tooth", []).append(fm)
    if higher:
        ax.text(0.99, 0.01, "; ".join(f"{len(v)} {k} mode{'s' if len(v) > 1 else ''} above, "
                                      f"{min(v) / 1e3:.0f}-{max(v) / 1e3:.0f} kHz" for k, v in higher.items()),
                transform=ax.transAxes, ha="right", va="bottom", fontsize=8, color="0.3")
    ax.set_xlim(0, x_max)
    ax.set_ylim(0, y_max)
    ax.set_xlabel("driver speed [rad/s]")
    ax.set_ylabel("frequency [Hz]")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.11), fontsize=7.5, frameon=False)
    figure_title(fig, ds, "Campbell diagram: modes of the loaded pair and excitation orders", width=95)
    fig.subplots_adjust(bottom=0.24)
    return save_figure(fig, path)


def order_map_plot(ds: xr.Dataset, path):
    """Order map of a run-up (log amplitude over driver speed and order) with the Campbell
    overlay: the mesh mode as the curve order = f 2 pi / (driver speed z1/z2) and the critical
    speeds of the kZ lines; below, the order cuts N, Z, 2Z, 3Z against speed."""
    need(ds, "order_amplitude")
    sp = ds["runup_speed"].values
    order = ds["tracked_order"].values
    amp = ds["order_amplitude"].values
    z = float(ds.attrs["mesh_order"])
    n = float(ds.attrs.get("hole_order", 0.0))
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(9, 8.5), height_ratios=(3, 2), sharex=True)
    floor = max(float(np.nanmax(amp)) * 1e-4, 1e-6)
    mesh = ax.pcolormesh(sp, order, np.log10(np.maximum(amp.T, floor)), shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=(ax, ax2), label="log10 DTE amplitude [um] (order map)", shrink=0.6, anchor=(0.0, 1.0))
    if "mode_frequency" in ds and "critical_speed" in ds:
        cs1 = float(ds["critical_speed"].sel(excitation="1Z", mode=0))
        f = ds["mode_frequency"].sel(mode=0)
        for fm, ls in ((float(f.mean()), "-"), (float(f.min()), ":"), (float(f.max()), ":")):
            # order at which the mode sits for driver speed w: f / (w z1/z2 / 2pi) = z * cs1 / w * fm / fmean
            ax.plot(sp, z * cs1 / sp * fm / float(f.mean()), color="w", lw=1.0, ls=ls)
        ax.plot([], [], color="k", lw=1.0, label=f"mesh mode {float(f.mean()):.0f} Hz (dotted: range over the mesh period)")
        for k in range(1, 6):
            c = float(ds["critical_speed"].sel(excitation=f"{k}Z", mode=0))
            if sp.min() <= c <= sp.max():
                ax.plot(c, k * z, "o", mfc="none", mec="r", ms=8)
                ax2.axvline(c, color="0.6", lw=0.8, ls="--")
                ax2.text(c, 1.0, f"{k}Z", transform=ax2.get_xaxis_transform(), fontsize=7, ha="center", va="bottom")
        ax.plot([], [], "o", mfc="none", mec="r", label="critical speeds kZ (modal)")
        ax.legend(loc="upper right", fontsize=8)
    ax.set_ylim(0, min(order.max(), 5.5 * z))
    ax.set_ylabel("order of the driven gear's rotation [1]")
    cuts = [("Z", z), ("2Z", 2 * z), ("3Z", 3 * z)] + ([("N", n)] if n > 0 else [])
    for name, o in cuts:
        sel = np.abs(order - o) <= 0.5
        ax2.semilogy(sp, amp[:, sel].max(axis=1), lw=1.2, label=f"order {name} = {o:g}")
    ax2.set_xlabel("driver speed [rad/s]")
    ax2.set_ylabel("DTE amplitude [um]")
    ax2.legend(fontsize=8)
    status = ds["order_amplitude"].attrs.get("status", "")
    if status:      # a completed run-up whose energy balance does not close: kept, flagged
        fig.text(0.5, 0.005, "flagged: " + status[:160] + ("..." if len(status) > 160 else ""), ha="center",
                 va="bottom", fontsize=7, color="C3", wrap=True)
    figure_title(fig, ds, "Run-up: computed order tracking of DTE, Campbell overlay and order cuts", width=100)
    return save_figure(fig, path)

"""Transmission-error plots of a run archive (matplotlib, Agg, PNG). They read only the dataset
(and the scene TOML in its attributes).

Each ``*_plot(ds, path)`` writes one PNG and returns its path; it raises ``KeyError`` naming
the variable when the dataset lacks what the plot needs (`study.report.figures` decides what to draw).

  ste_plot        STE [um] against driver angle [deg], single/double contact shaded, solid-gear
                  STE, the angles where a hole centre of the driven gear passes the mesh
  dte_plot        DTE [um] against time [s], speed/torque ramp and spectrum window marked, zoom
  spectrum_plot   DTE (and STE) amplitude spectra [um], log amplitude against driven-gear order,
                  hole/mesh orders and sidebands labelled, unexplained peaks annotated
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from study.archive.spectra import HANN_MAIN_LOBE_BINS, sideband_orders
from study.report.plot_style import (
    C_DEFAULT,
    C_HOLE,
    C_LIGHT,
    C_OTHER,
    C_REV,
    C_SIDE,
    C_SOLID,
    archive_scene,
    figure_title,
    need,
    save_figure,
)


def _runs(mask: np.ndarray):
    """(start, stop) index pairs of the True runs of a boolean array."""
    m = np.concatenate([[False], mask.astype(bool), [False]])
    d = np.diff(m.astype(int))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


LOADED_SHARE = 0.10      # a contact carrying less of the pair's load than this does not count as loaded
_ZONES = {2: ("2 loaded contacts", "#f5cba7"), 3: ("3 or more loaded contacts", "#e59866")}


def loaded_contacts(ds: xr.Dataset) -> np.ndarray | None:
    """Number of contacts carrying at least `LOADED_SHARE` of the pair's normal load at each STE
    angle (from ``ste_tooth_force``; ``ste_contacts``, every touching contact, without it): a
    tooth entering or leaving the mesh with a few newtons is no load share."""
    if "ste_tooth_force" in ds:
        f = np.abs(ds["ste_tooth_force"].transpose("angle", ...).values)
        total = f.sum(axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            share = np.where(total > 0, f / total, 0.0)
        return (share >= LOADED_SHARE).sum(axis=1)
    return ds["ste_contacts"].values if "ste_contacts" in ds else None
_ZONE_WORD = {1: "1", 2: "2", 3: "3"}


def _shade_contacts(ax, angle, contacts, words: bool = False) -> None:
    """Shade the angle ranges by the number of loaded tooth contacts (white = single)."""
    step = float(angle[1] - angle[0]) if angle.size > 1 else 0.0
    for n, (label, color) in _ZONES.items():
        first = True
        for a, b in _runs(contacts == n if n < 3 else contacts >= n):
            ax.axvspan(angle[a] - step / 2, angle[b - 1] + step / 2, color=color, alpha=0.55, lw=0,
                       label=label if first else None)
            first = False
    if words:
        for n, word in _ZONE_WORD.items():
            for a, b in _runs(contacts == n if n < 3 else contacts >= n):
                ax.text(0.5 * (angle[a] + angle[b - 1]), 1.0, word, transform=ax.get_xaxis_transform(),
                        ha="center", va="bottom", fontsize=8, color="0.25")


def hole_mesh_angles(ds: xr.Dataset, angle_max: float) -> np.ndarray:
    """Driver angles [deg] at which a hole centre of the driven gear is on the line of centres
    (its teeth over the hole are in mesh). Gear 2 turns clockwise by theta1*z1/z2 and brings its
    teeth into mesh in increasing index order, so body angle beta meets the mesh at theta1 = beta*z2/z1."""
    sc = archive_scene(ds)
    if sc is None or sc.gear2.body.holes == 0:
        return np.array([])
    b = sc.gear2.body
    ratio = sc.gear2.teeth / sc.gear1.teeth
    spacing = 360.0 / b.holes
    beta = b.hole_phase % spacing + spacing * np.arange(int(angle_max / ratio / spacing) + 2)
    theta = beta * ratio
    return theta[theta <= angle_max]


def model_curves(ds: xr.Dataset, what: str) -> tuple[str, str | None, str]:
    """Labels of the archive model's curve and of the default model's beside it (None when the
    archive holds one model) for a ``what`` ('STE', 'DTE') plot, and a line for the title saying
    which is which."""
    if f"{what.lower()}_default" not in ds:
        return what if what == "DTE" else "lightened pair", None, ""
    from study.report.summary import model_label
    ran, dflt = str(ds.attrs.get("coupling_model", "?")), str(ds.attrs["default_coupling_model"])
    return (f"{ran} model", f"default model: {dflt}",
            f"\ntwo models: {model_label(dflt, True)}; {model_label(ran)}")


# ------------------------------------------------------------------ STE

def ste_plot(ds: xr.Dataset, path) -> Path:
    """STE against driver angle: whole range, a zoom over three mesh periods with the contact
    zones, and (with a solid-gear STE) the difference lightened - solid, the hole effect."""
    need(ds, "ste", "angle")
    ang = ds["angle"].values
    off = float(ds.attrs.get("backlash_offset_um", 0.0))
    ste = ds["ste"].values - off            # the elastic part: the rigid half-backlash offset taken out
    contacts = loaded_contacts(ds)
    by_share = "ste_tooth_force" in ds
    solid = ds["ste_solid"].values - off if "ste_solid" in ds else None
    holes = hole_mesh_angles(ds, ang[-1])
    nrow = 3 if solid is not None else 2
    fig, axes = plt.subplots(nrow, 1, figsize=(11, 3.0 * nrow + 1.2), constrained_layout=True)
    eps = ds.attrs.get("contact_ratio", float("nan"))
    loaded = f"loaded contact ratio {float(ds['loaded_contact_ratio']):.3f}, " if "loaded_contact_ratio" in ds else ""
    main, other, which = model_curves(ds, "STE")
    dflt = ds["ste_default"].values - off if other else None
    figure_title(fig, ds, f"Static transmission error (STE), elastic part: STE less the {off:.3f} µm half-backlash offset; "
                          f"shading: loaded contacts ({loaded}geometric {eps:.3f}; tip corners count"
                          + (f"; a contact counts when it carries at least {100 * LOADED_SHARE:g} % of the load)" if by_share
                             else ")") + which, width=130)
    ax = axes[0]
    if contacts is not None:
        _shade_contacts(ax, ang, contacts)
    if other:
        ax.plot(ang, dflt, color=C_DEFAULT, lw=1.0, label=other)
    ax.plot(ang, ste, color=C_LIGHT, lw=1.0, label=main)
    if solid is not None:
        ax.plot(ang, solid, color=C_SOLID, lw=0.9, alpha=0.8,
                label="solid driven gear" + (f" ({main})" if other else ""))
    _mark_holes(ax, holes, ang[0], ang[-1])
    ax.set_xlabel("driver rotation [°]")
    ax.set_ylabel(f"STE − {off:.3f} µm [µm]")
    ax.set_xlim(ang[0], ang[-1])
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + 0.5 * (hi - lo))        # room for the legend above the curves
    ax.legend(loc="upper right", fontsize=9, ncol=4, framealpha=0.9)
    ax.grid(alpha=0.3)
    # zoom: three mesh periods
    sc = archive_scene(ds)
    z1 = sc.gear1.teeth if sc else int(ds.attrs.get("mesh_order", 67))
    period = 360.0 / z1
    ax = axes[1]
    sel = ang <= ang[0] + 3 * period
    if contacts is not None:
        _shade_contacts(ax, ang[sel], contacts[sel], words=True)
    if other:
        ax.plot(ang[sel], dflt[sel], color=C_DEFAULT, lw=1.5, marker=".", ms=3, label=other)
    ax.plot(ang[sel], ste[sel], color=C_LIGHT, lw=1.5, marker=".", ms=3, label=main)
    if solid is not None:
        ax.plot(ang[sel], solid[sel], color=C_SOLID, lw=1.2, alpha=0.8, label="solid driven gear")
    if other or solid is not None:
        ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_xlabel(f"driver rotation [°] (zoom: three mesh periods of {period:.3f}°; numbers: loaded contacts)")
    ax.set_ylabel(f"STE − {off:.3f} µm [µm]")
    ax.set_xlim(ang[sel][0], ang[sel][-1])
    ax.grid(alpha=0.3)
    if solid is not None:
        ax = axes[2]
        d = ste - solid
        ax.plot(ang, d, color="0.6", lw=0.7, label="lightened − solid")
        # mean over one mesh period: the slow modulation by the holes (order N)
        step = float(ang[1] - ang[0])
        n = max(1, int(round(period / step)))
        if d.size > 2 * n:
            ma = np.convolve(d, np.ones(n) / n, mode="same")
            ma[: n // 2] = np.nan; ma[-(n // 2):] = np.nan
            ax.plot(ang, ma, color=C_HOLE, lw=2.0, label="mean over one mesh period")
        _mark_holes(ax, holes, ang[0], ang[-1])
        ax.set_xlabel("driver rotation [°]")
        ax.set_ylabel("STE difference [µm]")
        ax.set_xlim(ang[0], ang[-1])
        ax.set_title("effect of the lightening: STE(lightened) − STE(solid)" + (f", {main}" if other else ""), fontsize=10)
        ax.legend(loc="upper right", fontsize=9, ncol=3, framealpha=0.9)
        ax.grid(alpha=0.3)
    return save_figure(fig, path)


def _mark_holes(ax, angles, lo: float, hi: float) -> None:
    inside = [a for a in angles if lo < a < hi]     # a line on the frame would leave only its legend entry
    for i, a in enumerate(inside):
        ax.axvline(a, color=C_HOLE, ls="--", lw=1.2, label="hole centre of the driven gear in mesh" if i == 0 else None)


# ------------------------------------------------------------------ DTE

def dte_plot(ds: xr.Dataset, path) -> Path:
    """DTE against time with the ramp and the spectrum window, and a zoom on the steady end."""
    need(ds, "dte", "time")
    t = ds["time"].values
    dte = ds["dte"].values
    ramp = float(ds.attrs.get("ramp_time_s", 0.0))
    start = float(ds.attrs.get("spectrum_start_s", ramp))
    fig, axes = plt.subplots(2, 1, figsize=(11, 7.5), constrained_layout=True)
    main, other, which = model_curves(ds, "DTE")
    dflt = ds["dte_default"].values if other else None
    figure_title(fig, ds, "Dynamic transmission error (DTE)" + which)
    ax = axes[0]
    speed_end = float(ds.attrs.get("runup_speed_end_rad_s", 0.0))
    if speed_end > 0:      # a run-up: one speed ramp over the whole run, no steady spectrum
        ax.axvspan(t[0], ramp, color="#f9e79f", alpha=0.7, lw=0, label=f"torque ramp (0–{ramp * 1e3:.3g} ms)")
        ax.plot([], [], " ", label=f"driver speed 0 → {speed_end:.0f} rad/s linearly over the run (top axis)")
        rate = speed_end / t[-1]
        sec = ax.secondary_xaxis("top", functions=(lambda x: x * rate, lambda w: w / rate))
        sec.set_xlabel("driver speed [rad/s]")
    else:
        ax.axvspan(t[0], ramp, color="#f9e79f", alpha=0.7, lw=0, label=f"speed and torque ramp (0–{ramp * 1e3:.3g} ms)")
        ax.axvline(start, color="0.3", ls=":", lw=1.2, label=f"spectrum from {start * 1e3:.3g} ms")
    if other:
        ax.plot(t, dflt, color=C_DEFAULT, lw=0.6, label=other)
    ax.plot(t, dte, color=C_LIGHT, lw=0.6, label=main)
    if "ste" in ds:
        ax.axhline(float(np.nanmean(ds["ste"].values)), color=C_SOLID, ls="--", lw=1.0, label="mean STE" + (f" ({main})" if other else ""))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("DTE [µm]")
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="lower right", fontsize=9, framealpha=0.9)
    ax.grid(alpha=0.3)
    # zoom on the last two hole periods (or 20 mesh periods without holes)
    ax = axes[1]
    f_rot = float(ds.attrs.get("driven_speed_rad_s", 0.0)) / (2 * np.pi)
    n_h = float(ds.attrs.get("hole_order", 0.0))
    z = float(ds.attrs.get("mesh_order", 0.0))
    if speed_end > 0:
        span, what = 0.05 * (t[-1] - t[0]), f"last 5 %, {0.95 * speed_end:.0f}–{speed_end:.0f} rad/s"
    elif f_rot > 0 and n_h > 0:
        span, what = 2.0 / (n_h * f_rot), "two hole passes"
    elif f_rot > 0 and z > 0:
        span, what = 20.0 / (z * f_rot), "20 mesh periods"
    else:
        span, what = 0.1 * (t[-1] - t[0]), "last 10 %"
    sel = t >= max(t[-1] - span, start)
    if other:
        ax.plot(t[sel] * 1e3, dflt[sel], color=C_DEFAULT, lw=1.0, label=other)
    ax.plot(t[sel] * 1e3, dte[sel], color=C_LIGHT, lw=1.0, label=main)
    if "ste" in ds:
        ax.axhline(float(np.nanmean(ds["ste"].values)), color=C_SOLID, ls="--", lw=1.0,
                   label="mean STE" + (f" ({main})" if other else ""))
    if other or "ste" in ds:
        ax.legend(loc="lower right", fontsize=9)
    ax.set_xlabel(f"time [ms] (zoom on the end: {what})")
    ax.set_ylabel("DTE [µm]")
    ax.grid(alpha=0.3)
    return save_figure(fig, path)


# ------------------------------------------------------------------ spectra

def _peak_table(ds, prefix):
    dim = f"{prefix}_peak"
    if dim not in ds.coords or f"{dim}_amplitude" not in ds:
        return []
    names = [str(n) for n in ds[dim].values]
    return list(zip(names, ds[f"{dim}_nominal_order"].values, ds[f"{dim}_order"].values, ds[f"{dim}_amplitude"].values))


TABLE_ROWS = 14      # named peaks listed beside a spectrum, largest first


def spectrum_panel(ax, order, amp, peaks, xmax, what, res_text):
    """One spectrum on ``ax``: amplitude [um] against order [-] up to xmax, with the named
    orders of ``peaks`` (name, nominal order, found order, amplitude [um]) drawn as lines and
    listed in a table beside the axes; ``what`` names the signal (DTE, STE) on the y axis."""
    from matplotlib.lines import Line2D
    sel = (order > 0) & (order <= xmax)
    ax.semilogy(order[sel], np.maximum(amp[sel], 1e-12), color=C_SOLID, lw=0.8)
    pos = amp[sel][amp[sel] > 0]
    lo = max(float(np.percentile(pos, 5)) if pos.size else 1e-6, 1e-9)
    hi = float(pos.max()) if pos.size else 1.0
    ax.set_ylim(lo / 2, hi * 12)
    others = [(o, a) for name, _, o, a in peaks if name.startswith("other") and np.isfinite(o) and o <= xmax]
    for i, (o, a) in enumerate(sorted(others)):
        ax.plot(o, a, "v", color=C_OTHER, ms=7)
        ax.annotate(f"{o:.1f}", (o, a), xytext=(0, 8 + 11 * (i % 3)), textcoords="offset points", ha="center",
                    fontsize=8, color=C_OTHER)
    table = []
    rev = {name: nominal for name, nominal, _o, _a in peaks if name in ("R1", "R2")}
    same_rev = len(rev) == 2 and abs(rev["R1"] - rev["R2"]) < 1e-9     # a 1:1 pair: one order, one line
    for name, nominal, o, a in peaks:
        if name.startswith("other") or not np.isfinite(nominal) or nominal > xmax:
            continue
        if same_rev and name == "R2":
            continue
        if same_rev and name == "R1":
            name = "R1=R2"
        hole = name.endswith("N") and "Z" not in name
        once = name.startswith("R")
        mesh = "N" not in name and not once
        color = C_REV if once else (C_HOLE if hole else (C_LIGHT if mesh else C_SIDE))
        main_line = hole or mesh or once
        ax.axvline(nominal, color=color, lw=1.0 if main_line else 0.7, ls="-" if main_line else ":", alpha=0.8)
        ax.text(nominal, 0.99, f" {name}", transform=ax.get_xaxis_transform(), rotation=90, va="top",
                ha="right", fontsize=8, color=color)
        if np.isfinite(a):
            table.append((a, f"{name:>6s}: {a:.3g}"))
            if main_line:
                ax.plot(o, a, "o", mfc="none", color=color, ms=7)
    ax.set_xlim(0, xmax)
    ax.set_ylabel(f"{what} amplitude [µm]")
    ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], color=C_HOLE, label="hole orders jN"), Line2D([], [], color=C_LIGHT, label="mesh order kZ"),
               Line2D([], [], color=C_SIDE, ls=":", label="hole sidebands kZ ± jN"),
               Line2D([], [], color=C_OTHER, marker="v", ls="", label="largest unexplained peaks (order)")]
    if rev:
        handles.insert(0, Line2D([], [], color=C_REV, label="once per revolution: R1 driver, R2 driven"))
    leg = ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=8, frameon=False)
    leg.set_in_layout(True)
    shown = sorted(table, key=lambda r: -r[0])[:TABLE_ROWS]
    more = f"\n(+{len(table) - len(shown)} smaller)" if len(table) > len(shown) else ""
    ax.text(1.01, 0.55, "largest named peaks [µm]\n" + ("\n".join(r[1] for r in shown) + more if table else "(none resolved)"),
            transform=ax.transAxes, ha="left", va="top", fontsize=8, family="monospace",
            bbox=dict(fc="white", ec="0.7"))
    ax.text(0.995, 0.02, res_text, transform=ax.transAxes, ha="right", va="bottom", fontsize=8, color="0.3",
            bbox=dict(fc="white", ec="none", alpha=0.8))


def spectrum_plot(ds: xr.Dataset, path) -> Path:
    """Amplitude spectra (log) against the driven gear's order: DTE (after the ramp) and STE.

    Blue lines: hole order N and harmonics; red: mesh order Z and harmonics; green dotted:
    sidebands kZ +- jN (those the record resolves); purple triangles: the largest peaks no named order explains."""
    # (a run at dynamic.speed = 0 has no orders: its DTE spectrum has no order axis to draw on)
    has_dte = "dte_amplitude" in ds and "order" in ds.coords and bool(np.isfinite(ds["order"].values).any())
    has_ste = "ste_amplitude" in ds
    if not (has_dte or has_ste):
        raise KeyError("no STE spectrum, and no DTE spectrum over orders (driver speed 0)")
    z = float(ds.attrs.get("mesh_order", 0.0)) or 100.0
    nrow = int(has_dte) + int(has_ste)
    fig, axes = plt.subplots(nrow, 1, figsize=(13, 3.8 * nrow + 1.0), constrained_layout=True, squeeze=False)
    figure_title(fig, ds, "Amplitude spectra against the driven gear's order (N holes, Z teeth)")
    i = 0
    if has_dte:
        order = ds["order"].values
        amp = ds["dte_amplitude"].values
        peaks = _peak_table(ds, "dte")
        others = [o for n, _, o, _ in peaks if n.startswith("other") and np.isfinite(o)]
        xmax = min(float(np.nanmax(order)), max(3.3 * z, 1.1 * max(others, default=0)))
        a = ds["dte_amplitude"].attrs
        res = a.get("resolution_Hz", float("nan"))
        f_rot = float(ds.attrs.get("driven_speed_rad_s", 0.0)) / (2 * np.pi)
        unresolved = ds["dte_peak_amplitude"].attrs.get("not_resolved", "") if "dte_peak_amplitude" in ds else ""
        spectrum_panel(axes[i, 0], order, amp, peaks, xmax, "DTE",
                        (f"{a.get('window', '?')} window, resolution {res:.3g} Hz = {res / f_rot:.3g} orders, "
                         f"from {a.get('start_s', float('nan')) * 1e3:.3g} ms" if f_rot > 0 else "")
                        + (f"\n{unresolved}" if unresolved else ""))
        ax = axes[i, 0]
        ax.set_xlabel("order of the driven gear's rotation [–]")
        if f_rot > 0:
            sec = ax.secondary_xaxis("top", functions=(lambda o: o * f_rot, lambda f: f / f_rot))
            sec.set_xlabel("frequency [Hz]")
        ax.set_title("DTE after the ramp", fontsize=10, loc="left")
        i += 1
    if has_ste:
        order = ds["ste_order"].values
        amp = ds["ste_amplitude"].values
        a = ds["ste_amplitude"].attrs
        xmax = min(float(np.nanmax(order)), 3.3 * z)
        res = float(a.get("resolution_orders", float("nan")))
        n_h = float(ds.attrs.get("hole_order", 0.0))
        note = ""
        if n_h > 0 and sideband_orders(n_h, z, res) == 0:
            sc = archive_scene(ds)
            ratio = sc.gear2.teeth / sc.gear1.teeth if sc else 1.0
            need_deg = 360.0 * 2 * HANN_MAIN_LOBE_BINS / n_h * ratio
            note = (f"\nhole sidebands kZ ± jN not resolved: their main lobes (± {HANN_MAIN_LOBE_BINS * res:.3g} orders) "
                    f"overlap at N = {n_h:g}; an STE over {need_deg:.0f}° of driver rotation or more resolves them")
        if "ste_peak_amplitude" in ds and ds["ste_peak_amplitude"].attrs.get("not_resolved"):
            note += "\n" + ds["ste_peak_amplitude"].attrs["not_resolved"]
        spectrum_panel(axes[i, 0], order, amp, _peak_table(ds, "ste"), xmax, "STE",
                        f"{a.get('window', '?')} window, resolution {res:.3g} orders "
                        f"({a.get('record_driven_revolutions', float('nan')):.3g} driven revolutions), "
                        f"zero padding x{a.get('zero_padding', 1)}" + note)
        axes[i, 0].set_xlabel("order of the driven gear's rotation [–]")
        axes[i, 0].set_title("STE (quasi-static)", fontsize=10, loc="left")
    return save_figure(fig, path)



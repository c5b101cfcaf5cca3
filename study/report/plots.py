"""Plots of run and sweep archives (matplotlib, Agg backend, PNG). They read only datasets.

Each ``*_plot(ds, path)`` writes one PNG and returns its path; it raises ``KeyError`` naming
the variable when the dataset lacks what the plot needs (`study.report.figures` decides what to draw).

  ste_plot        STE against driver angle, single/double contact shaded, solid-gear STE,
                  the angles where a hole centre of the driven gear passes the mesh
  dte_plot        DTE against time, speed/torque ramp and spectrum window marked, zoom
  spectrum_plot   DTE (and STE) amplitude spectra, log amplitude against driven-gear order,
                  hole/mesh orders and sidebands labelled, unexplained peaks annotated
  stiffness_plot  per-tooth spring stiffness against tooth index, hole positions marked
  sweep_view      any output against one or two swept dimensions, faceted by the others
"""
from __future__ import annotations

import math
import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

DPI = 110
_PRETTY_UNITS = {"um": "µm", "degree": "°", "N mm rad-1": "N·mm/rad", "N m rad-1": "N·m/rad",
                 "N m": "N·m", "1": "–", "Hz": "Hz", "s": "s", "N": "N", "J": "J", "mm": "mm",
                 "rad s-1": "rad/s", "MPa": "MPa"}
C_LIGHT, C_SOLID, C_HOLE, C_SIDE, C_OTHER = "#c0392b", "#2c3e50", "#2980b9", "#27ae60", "#7d3c98"


def pretty_unit(unit: str | None) -> str:
    if unit is None:
        return "–"
    return _PRETTY_UNITS.get(unit, unit)


def axis_label(v: xr.DataArray, name: str | None = None) -> str:
    """'long name [unit]' of a variable or coordinate."""
    ln = v.attrs.get("long_name", name or v.name or "")
    return f"{ln} [{pretty_unit(v.attrs.get('units'))}]"


def _need(ds: xr.Dataset, *names: str) -> None:
    missing = [n for n in names if n not in ds.variables]
    if missing:
        raise KeyError(f"dataset lacks {', '.join(missing)}")


def _scene(ds: xr.Dataset):
    if "scene" not in ds.attrs:
        return None
    from study.scene import loads_scene
    return loads_scene(ds.attrs["scene"], "archive attribute 'scene'")


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def _title(fig, ds, what: str, width: int | None = None) -> None:
    """Figure title: what is shown, then the archive's title; wrapped to ``width`` characters."""
    t = ds.attrs.get("title", "")
    text = f"{what}\n{t}" if t else what
    if width:
        text = "\n".join(textwrap.fill(line, width) for line in text.split("\n"))
    fig.suptitle(text, fontsize=12 if not width else 10)


def _runs(mask: np.ndarray):
    """(start, stop) index pairs of the True runs of a boolean array."""
    m = np.concatenate([[False], mask.astype(bool), [False]])
    d = np.diff(m.astype(int))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


_ZONES = {2: ("double contact", "#f5cba7"), 3: ("triple contact", "#e59866")}
_ZONE_WORD = {1: "single", 2: "double", 3: "triple"}


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
    sc = _scene(ds)
    if sc is None or sc.gear2.body.holes == 0:
        return np.array([])
    b = sc.gear2.body
    ratio = sc.gear2.teeth / sc.gear1.teeth
    spacing = 360.0 / b.holes
    beta = b.hole_phase % spacing + spacing * np.arange(int(angle_max / ratio / spacing) + 2)
    theta = beta * ratio
    return theta[theta <= angle_max]


# ------------------------------------------------------------------ STE

def ste_plot(ds: xr.Dataset, path) -> Path:
    """STE against driver angle: whole range, a zoom over three mesh periods with the contact
    zones, and (with a solid-gear STE) the difference lightened - solid, the hole effect."""
    _need(ds, "ste", "angle")
    ang = ds["angle"].values
    ste = ds["ste"].values
    contacts = ds["ste_contacts"].values if "ste_contacts" in ds else None
    solid = ds["ste_solid"].values if "ste_solid" in ds else None
    holes = hole_mesh_angles(ds, ang[-1])
    nrow = 3 if solid is not None else 2
    fig, axes = plt.subplots(nrow, 1, figsize=(11, 3.0 * nrow + 1.2), constrained_layout=True)
    _title(fig, ds, "Static transmission error (STE)")
    ax = axes[0]
    if contacts is not None:
        _shade_contacts(ax, ang, contacts)
    ax.plot(ang, ste, color=C_LIGHT, lw=1.0, label="lightened pair")
    if solid is not None:
        ax.plot(ang, solid, color=C_SOLID, lw=0.9, alpha=0.8, label="solid driven gear")
    _mark_holes(ax, holes)
    ax.set_xlabel("driver rotation [°]")
    ax.set_ylabel("STE [µm]")
    ax.set_xlim(ang[0], ang[-1])
    ax.legend(loc="upper right", fontsize=9, ncol=4, framealpha=0.9)
    ax.grid(alpha=0.3)
    # zoom: three mesh periods
    sc = _scene(ds)
    z1 = sc.gear1.teeth if sc else int(ds.attrs.get("mesh_order", 67))
    period = 360.0 / z1
    ax = axes[1]
    sel = ang <= ang[0] + 3 * period
    if contacts is not None:
        _shade_contacts(ax, ang[sel], contacts[sel], words=True)
    ax.plot(ang[sel], ste[sel], color=C_LIGHT, lw=1.5, marker=".", ms=3, label="lightened pair")
    if solid is not None:
        ax.plot(ang[sel], solid[sel], color=C_SOLID, lw=1.2, alpha=0.8, label="solid driven gear")
    ax.set_xlabel(f"driver rotation [°] (zoom: three mesh periods of {period:.3f}°)")
    ax.set_ylabel("STE [µm]")
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
        _mark_holes(ax, holes)
        ax.set_xlabel("driver rotation [°]")
        ax.set_ylabel("STE difference [µm]")
        ax.set_xlim(ang[0], ang[-1])
        ax.set_title("effect of the lightening: STE(lightened) − STE(solid)", fontsize=10)
        ax.legend(loc="upper right", fontsize=9, ncol=3, framealpha=0.9)
        ax.grid(alpha=0.3)
    return _save(fig, path)


def _mark_holes(ax, angles) -> None:
    for i, a in enumerate(angles):
        ax.axvline(a, color=C_HOLE, ls="--", lw=1.2, label="hole centre in mesh" if i == 0 else None)
        ax.text(a, 0.98, " hole", transform=ax.get_xaxis_transform(), color=C_HOLE, fontsize=8, va="top")


# ------------------------------------------------------------------ DTE

def dte_plot(ds: xr.Dataset, path) -> Path:
    """DTE against time with the ramp and the spectrum window, and a zoom on the steady end."""
    _need(ds, "dte", "time")
    t = ds["time"].values
    dte = ds["dte"].values
    ramp = float(ds.attrs.get("ramp_time_s", 0.0))
    start = float(ds.attrs.get("spectrum_start_s", ramp))
    fig, axes = plt.subplots(2, 1, figsize=(11, 7.5), constrained_layout=True)
    _title(fig, ds, "Dynamic transmission error (DTE)")
    ax = axes[0]
    ax.axvspan(t[0], ramp, color="#f9e79f", alpha=0.7, lw=0, label=f"speed and torque ramp (0–{ramp * 1e3:.3g} ms)")
    ax.axvline(start, color="0.3", ls=":", lw=1.2, label=f"spectrum from {start * 1e3:.3g} ms")
    ax.plot(t, dte, color=C_LIGHT, lw=0.6, label="DTE")
    if "ste" in ds:
        ax.axhline(float(np.nanmean(ds["ste"].values)), color=C_SOLID, ls="--", lw=1.0, label="mean STE")
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
    if f_rot > 0 and n_h > 0:
        span, what = 2.0 / (n_h * f_rot), "two hole passes"
    elif f_rot > 0 and z > 0:
        span, what = 20.0 / (z * f_rot), "20 mesh periods"
    else:
        span, what = 0.1 * (t[-1] - t[0]), "last 10 %"
    sel = t >= max(t[-1] - span, start)
    ax.plot(t[sel] * 1e3, dte[sel], color=C_LIGHT, lw=1.0)
    if "ste" in ds:
        ax.axhline(float(np.nanmean(ds["ste"].values)), color=C_SOLID, ls="--", lw=1.0, label="mean STE")
        ax.legend(loc="lower right", fontsize=9)
    ax.set_xlabel(f"time [ms] (zoom on the end: {what})")
    ax.set_ylabel("DTE [µm]")
    ax.grid(alpha=0.3)
    return _save(fig, path)


# ------------------------------------------------------------------ spectra

def _peak_table(ds, prefix):
    dim = f"{prefix}_peak"
    if dim not in ds.coords or f"{dim}_amplitude" not in ds:
        return []
    names = [str(n) for n in ds[dim].values]
    return list(zip(names, ds[f"{dim}_nominal_order"].values, ds[f"{dim}_order"].values, ds[f"{dim}_amplitude"].values))


def _spectrum_panel(ax, order, amp, peaks, xmax, what, res_text):
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
    for name, nominal, o, a in peaks:
        if name.startswith("other") or not np.isfinite(nominal) or nominal > xmax:
            continue
        hole = name.endswith("N") and "Z" not in name
        mesh = "N" not in name
        color = C_HOLE if hole else (C_LIGHT if mesh else C_SIDE)
        ax.axvline(nominal, color=color, lw=1.0 if (hole or mesh) else 0.7, ls="-" if (hole or mesh) else ":", alpha=0.8)
        ax.text(nominal, 0.99, f" {name}", transform=ax.get_xaxis_transform(), rotation=90, va="top",
                ha="right", fontsize=8, color=color)
        if np.isfinite(a):
            table.append(f"{name:>5s}: {a:.3g}")
            if hole or mesh:
                ax.plot(o, a, "o", mfc="none", color=color, ms=7)
    ax.set_xlim(0, xmax)
    ax.set_ylabel(f"{what} amplitude [µm]")
    ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], color=C_HOLE, label="hole order N, 2N"), Line2D([], [], color=C_LIGHT, label="mesh order kZ"),
               Line2D([], [], color=C_SIDE, ls=":", label="sidebands kZ ± N"),
               Line2D([], [], color=C_OTHER, marker="v", ls="", label="largest unexplained peaks (order)")]
    leg = ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=8, frameon=False)
    leg.set_in_layout(True)
    ax.text(1.01, 0.55, "peak amplitude [µm]\n" + ("\n".join(table) if table else "(none resolved)"),
            transform=ax.transAxes, ha="left", va="top", fontsize=8, family="monospace",
            bbox=dict(fc="white", ec="0.7"))
    ax.text(0.995, 0.02, res_text, transform=ax.transAxes, ha="right", va="bottom", fontsize=8, color="0.3",
            bbox=dict(fc="white", ec="none", alpha=0.8))


def spectrum_plot(ds: xr.Dataset, path) -> Path:
    """Amplitude spectra (log) against the driven gear's order: DTE (after the ramp) and STE.

    Blue lines: hole order N and harmonics; red: mesh order Z and harmonics; green dotted:
    sidebands kZ +- N; purple triangles: the largest peaks no named order explains."""
    has_dte = "dte_amplitude" in ds and "order" in ds.coords
    has_ste = "ste_amplitude" in ds
    if not (has_dte or has_ste):
        raise KeyError("dataset lacks dte_amplitude and ste_amplitude")
    z = float(ds.attrs.get("mesh_order", 0.0)) or 100.0
    nrow = int(has_dte) + int(has_ste)
    fig, axes = plt.subplots(nrow, 1, figsize=(13, 3.8 * nrow + 1.0), constrained_layout=True, squeeze=False)
    _title(fig, ds, "Amplitude spectra against the driven gear's order (N holes, Z teeth)")
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
        _spectrum_panel(axes[i, 0], order, amp, peaks, xmax, "DTE",
                        f"{a.get('window', '?')} window, resolution {res:.3g} Hz = {res / f_rot:.3g} orders, "
                        f"from {a.get('start_s', float('nan')) * 1e3:.3g} ms" if f_rot > 0 else "")
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
        _spectrum_panel(axes[i, 0], order, amp, _peak_table(ds, "ste"), xmax, "STE",
                        f"{a.get('window', '?')} window, resolution {a.get('resolution_orders', float('nan')):.3g} orders "
                        f"({a.get('record_driven_revolutions', float('nan')):.3g} driven revolutions), "
                        f"zero padding x{a.get('zero_padding', 1)}")
        axes[i, 0].set_xlabel("order of the driven gear's rotation [–]")
        axes[i, 0].set_title("STE (quasi-static)", fontsize=10, loc="left")
    return _save(fig, path)


# ------------------------------------------------------------------ tooth stiffness

def stiffness_plot(ds: xr.Dataset, path) -> Path:
    """Per-tooth spring stiffness against tooth index; a gear whose teeth all have the same
    spring is stated in the legend instead of drawn (it would flatten the other's variation).
    Hole positions shaded (angular width of the hole seen from the gear centre), and the
    stiffness ratio to the solid gear on the right axis."""
    _need(ds, "tooth_stiffness")
    sc = _scene(ds)
    k = ds["tooth_stiffness"]
    r = ds["stiffness_ratio"] if "stiffness_ratio" in ds else None
    fig, ax = plt.subplots(figsize=(11, 5.2), constrained_layout=True)
    _title(fig, ds, "Tooth spring stiffness k_φ, tooth by tooth (teeth over holes vs between holes)")
    styles = {1: ("s", C_SOLID, "gear 1 (driver)"), 2: ("o", C_LIGHT, "gear 2 (driven)")}
    drawn = []
    for g in ds["gear"].values:
        kg = k.sel(gear=g).values
        ok = np.isfinite(kg)
        m, c, lab = styles.get(int(g), ("o", None, f"gear {g}"))
        if np.ptp(kg[ok]) <= 1e-9 * abs(kg[ok]).max():
            ax.plot([], [], " ", label=f"{lab}: every tooth {kg[ok][0]:.4g} N·mm/rad")
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
            half = math.degrees(math.asin(min(1.0, b.hole_radius / b.hole_circle_radius))) / pitch
            for h in range(b.holes):
                c = ((b.hole_phase + h * 360.0 / b.holes) % 360.0) / pitch
                ax.axvspan(c - half, c + half, color=C_HOLE, alpha=0.15, lw=0,
                           label=f"hole of gear {g} (angular extent)" if first else None)
                ax.axvline(c, color=C_HOLE, ls="--", lw=0.8, label="hole centre" if first else None)
                first = False
    ax.set_xlabel("tooth index [–] (tooth k's axis at k·360°/Z from tooth 0)")
    ax.set_ylabel(f"spring stiffness k_φ [{pretty_unit(k.attrs.get('units'))}]")
    zmax = int(np.isfinite(k.values).sum(axis=1).max())
    ax.set_xlim(-0.5, zmax - 0.5)
    ax.grid(alpha=0.3)
    if r is not None and drawn:
        g = drawn[-1]
        sec = ax.secondary_yaxis("right", functions=_ratio_axis(k.sel(gear=g).values, r.sel(gear=g).values))
        sec.set_ylabel(f"stiffness ratio to the solid gear [–] (gear {g})")
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=4, fontsize=9, frameon=False)
    return _save(fig, path)


def _ratio_axis(kk, rr):
    """Forward/inverse maps k -> ratio (k = k_solid * ratio for 'fe-ratio' springs)."""
    ok = np.isfinite(kk) & np.isfinite(rr) & (rr > 0)
    scale = float(np.median(kk[ok] / rr[ok])) if ok.any() else 1.0
    return (lambda x: x / scale, lambda y: y * scale)


# ------------------------------------------------------------------ sweeps

def sweep_view(ds: xr.Dataset, var: str, x: str, hue: str | None = None, col: str | None = None,
               row: str | None = None, path=None, reduce: str | None = None):
    """A chosen output against one swept dimension ``x`` (lines coloured by ``hue``), one
    panel per value of ``col`` (and ``row``). Dimensions of ``var`` not named are faceted: the
    first into ``col``, the next into ``row``; more than that is an error (reduce them first,
    or pass ``reduce='mean'|'max'|'min'`` to collapse them). Writes ``path`` when given and
    returns it, else returns the figure."""
    if var not in ds:
        raise KeyError(f"sweep_view: no variable {var!r} in the dataset (have: {', '.join(map(str, ds.data_vars))})")
    da = ds[var]
    named = [d for d in (x, hue, col, row) if d is not None]
    for d in named:
        if d not in da.dims:
            raise ValueError(f"sweep_view: {d!r} is not a dimension of {var!r} (dims: {', '.join(da.dims)})")
    rest = [d for d in da.dims if d not in named]
    if reduce is not None and rest:
        da = getattr(da, reduce)(dim=rest, keep_attrs=True)
        rest = []
    for d in list(rest):
        if col is None:
            col = d
        elif row is None:
            row = d
        else:
            continue
        rest.remove(d)
    if rest:
        raise ValueError(f"sweep_view: {var!r} has more dimensions than x, hue, col and row ({', '.join(rest)}); "
                         "select or reduce them first")
    ncol = da.sizes[col] if col else 1
    nrow = da.sizes[row] if row else 1
    # wide enough for the hue legend beside the panels and a wrapped title above them
    width = max(min(4.2 * ncol, 20) + (3.0 if hue else 1.5), 7.0)
    fig, axes = plt.subplots(nrow, ncol, figsize=(width, min(3.3 * nrow, 16) + 1.3),
                             sharex=True, sharey=True, squeeze=False, constrained_layout=True)
    xv = ds[x]
    cmap = plt.get_cmap("viridis")
    nh = da.sizes[hue] if hue else 1
    for i in range(nrow):
        for j in range(ncol):
            ax = axes[i, j]
            sub = da
            parts = []
            if row:
                sub = sub.isel({row: i}); parts.append(_coord_text(ds, row, i))
            if col:
                sub = sub.isel({col: j}); parts.append(_coord_text(ds, col, j))
            for h in range(nh):
                line = sub.isel({hue: h}) if hue else sub
                c = cmap(h / max(nh - 1, 1)) if hue else C_LIGHT
                ax.plot(xv.values, line.transpose(x).values, marker="o", ms=4, color=c,
                        label=_coord_text(ds, hue, h) if hue else None)
            if parts:
                ax.set_title(", ".join(parts), fontsize=9)
            ax.grid(alpha=0.3)
            if i == nrow - 1:
                ax.set_xlabel(axis_label(xv, x))
            if j == 0:   # the long name is in the title; the axis keeps the variable and its unit
                ax.set_ylabel(f"{var} [{pretty_unit(da.attrs.get('units'))}]")
    if hue:
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside right center", fontsize=8, title=axis_label(ds[hue], hue))
    _title(fig, ds, f"{var}: {da.attrs.get('long_name', var)}, against {ds[x].attrs.get('long_name', x)}",
           width=int(8 * width))
    if path is None:
        return fig
    return _save(fig, path)


def _coord_text(ds, dim, i) -> str:
    v = ds[dim].values[i] if dim in ds.coords else i
    unit = pretty_unit(ds[dim].attrs.get("units")) if dim in ds.coords else ""
    unit = "" if unit == "–" else f" {unit}"
    try:
        return f"{dim} = {float(v):.4g}{unit}"
    except (TypeError, ValueError):
        return f"{dim} = {v}"

"""Sweep view of a sweep archive (matplotlib, Agg, PNG): any output against one or two swept
dimensions, faceted by the others. Reads only the dataset.
"""
from __future__ import annotations

import matplotlib.pyplot as plt
import xarray as xr

from study.report.plot_style import C_LIGHT, figure_title, integer_ticks, param_label, pretty_unit, save_figure


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
            integer_ticks(ax, xv.values)
            if i == nrow - 1:
                ax.set_xlabel(param_label(ds, x))
            if j == 0:   # the long name is in the title; the axis keeps the variable and its unit
                ax.set_ylabel(f"{var} [{pretty_unit(da.attrs.get('units'))}]")
    if hue:
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside right center", fontsize=8, title=param_label(ds, hue))
    figure_title(fig, ds, f"{var}: {da.attrs.get('long_name', var)}, against {ds[x].attrs.get('long_name', x)}",
           width=int(8 * width))
    if path is None:
        return fig
    return save_figure(fig, path)


def _coord_text(ds, dim, i) -> str:
    v = ds[dim].values[i] if dim in ds.coords else i
    unit = pretty_unit(ds[dim].attrs.get("units")) if dim in ds.coords else ""
    unit = "" if unit == "–" else f" {unit}"
    try:
        return f"{dim} = {float(v):.4g}{unit}"
    except (TypeError, ValueError):
        return f"{dim} = {v}"

"""Views of a sampled study (`study.sweep.sample`), from the archive and the tables of
`study.report.distributions` (matplotlib, Agg, PNG):

  distribution_figure  per output: the empirical CDF and the histogram at each grid point,
                       P5 / P50 / P95 with their confidence intervals, a limit and the
                       probability of exceeding it
  convergence_figure   per output: mean and P95 with their intervals against the number of
                       builds, and their error (interval half-width, distance to the whole
                       sample's value) against the compute time spent
  sobol_figure         per output: first-order and total Sobol indices of each drawn field with
                       their intervals, ranked, one panel a grid point (Saltelli design)

`sample_figures` draws them all and writes the tables to ``study_tables.nc``.
"""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from study.report.distributions import (
    QUANTILES,
    drawn_fields,
    grid_points,
    min_builds,
    output_at,
    point_label,
    sample_outputs,
    sample_tables,
)
from study.report.plot_style import C_HOLE, C_LIGHT, C_SOLID, axis_label, figure_title, pretty_unit, save_figure

ERROR_FLOOR = 1e-6      # errors below this fraction of the output's scale are ties, not points on a log axis
COLOURS = (C_HOLE, C_LIGHT, C_SOLID, "#27ae60", "#7d3c98", "#d68910", "#16a085", "#7f8c8d")


def _colour(k: int) -> str:
    return COLOURS[k % len(COLOURS)]


def _est(tab: xr.DataArray) -> tuple[float, float, float]:
    return tuple(float(tab.sel(bound=b)) for b in ("estimate", "low", "high"))


def distribution_figure(ds: xr.Dataset, tables: xr.Dataset, var: str, path, limit: float | None = None):
    """ECDF (left) and histogram (right) of ``var`` at every grid point; writes ``path``."""
    fig, (ax_c, ax_h) = plt.subplots(1, 2, figsize=(12.5, 4.8), constrained_layout=True)
    unit = pretty_unit(ds[var].attrs.get("units"))
    points = grid_points(ds)
    all_y = [output_at(ds, var, at) for at in points]
    finite = np.concatenate([y[np.isfinite(y)] for y in all_y]) if all_y else np.array([])
    bins = np.histogram_bin_edges(finite, bins=min(40, max(8, int(np.sqrt(finite.size))))) if finite.size else 10
    for k, (at, y) in enumerate(zip(points, all_y)):
        y = np.sort(y[np.isfinite(y)])
        if y.size == 0:
            continue
        c = _colour(k)
        sel = {d: i for d, i in at.items()}
        pct = tables["sample_percentile"].isel(sel).sel(output=var)
        p5, p50, p95 = (_est(pct.sel(quantile=q)) for q in QUANTILES)
        bound = (f"[{p95[1]:.3g}, {p95[2]:.3g}]" if np.isfinite(p95[1:]).all() else
                 f"(no 95 % interval: it takes {min_builds(0.95)} independent builds)")
        label = f"{point_label(ds, at)} ({y.size} builds): P95 {p95[0]:.3g} {unit} {bound}"
        if limit is not None and "exceedance_probability" in tables:
            e = _est(tables["exceedance_probability"].isel(sel).sel(limit=var))
            label += f"\nP(> {limit:g}) = {e[0]:.3f} [{e[1]:.3f}, {e[2]:.3f}]"
        ax_c.step(y, np.arange(1, y.size + 1) / y.size, where="post", color=c, lw=1.4, label=label)
        for q, (est, lo, hi) in zip(QUANTILES, (p5, p50, p95)):
            if np.isfinite([lo, hi]).all():
                ax_c.errorbar([est], [q], xerr=[[est - lo], [hi - est]], fmt="o", ms=4, color=c, capsize=3, lw=1.2)
            else:           # the sample cannot bound this percentile: the estimate alone, open
                ax_c.plot([est], [q], "o", ms=5, mfc="white", color=c)
        ax_h.hist(y, bins=bins, density=True, histtype="stepfilled", alpha=0.25, color=c)
        ax_h.hist(y, bins=bins, density=True, histtype="step", color=c, lw=1.2, label=point_label(ds, at))
        for est in (p5[0], p50[0], p95[0]):
            ax_h.axvline(est, color=c, lw=0.8, ls=":")
    for q in QUANTILES:
        ax_c.axhline(q, color="0.6", lw=0.6, ls=":")
    if limit is not None:
        for ax in (ax_c, ax_h):
            ax.axvline(limit, color="k", lw=1.2, ls="--", label=f"limit {limit:g} {unit}" if ax is ax_h else None)
    ax_c.set_xlabel(axis_label(ds[var], var))
    ax_c.set_ylabel("fraction of builds at or below [–]")
    ax_c.set_ylim(-0.02, 1.02)
    ax_c.set_title("empirical CDF; dots: P5, P50, P95 with their 95 % intervals (open: too few builds for one)",
                   fontsize=9)
    ax_c.legend(fontsize=7.5, loc="lower right")
    ax_h.set_xlabel(axis_label(ds[var], var))
    ax_h.set_ylabel(f"probability density [1/{unit}]")
    ax_h.set_title("histogram; dotted: P5, P50, P95", fontsize=9)
    ax_h.legend(fontsize=8)
    for ax in (ax_c, ax_h):
        ax.grid(alpha=0.3)
    figure_title(fig, ds, f"Distribution of {var} over the builds: {ds[var].attrs.get('long_name', var)}", width=130)
    return save_figure(fig, path)


def convergence_figure(ds: xr.Dataset, tables: xr.Dataset, var: str, path):
    """Mean and P95 of ``var`` against the builds (top) and their error against the compute
    time (bottom), one line a grid point; writes ``path``."""
    fig, axes = plt.subplots(2, 2, figsize=(12.5, 8.0), constrained_layout=True)
    unit = pretty_unit(ds[var].attrs.get("units"))
    builds = tables["convergence_builds"].values
    for col, (name, what) in enumerate((("convergence_mean", "mean"), ("convergence_p95", "P95"))):
        top, bottom = axes[0, col], axes[1, col]
        lows = []
        for k, at in enumerate(grid_points(ds)):
            c = _colour(k)
            t = tables[name].isel(at).sel(output=var)
            est, lo, hi = (t.sel(bound=b).values for b in ("estimate", "low", "high"))
            time = tables["convergence_time"].isel(at).values
            top.fill_between(builds, lo, hi, color=c, alpha=0.18, lw=0)
            top.plot(builds, est, marker="o", ms=3, color=c, label=point_label(ds, at))
            half = (hi - lo) / 2.0
            dist = np.abs(est - est[-1])
            # a tie with the whole sample's value (or an interval of tied builds) is an error of 0,
            # not 1e-16 on a log axis: below a millionth of the output's scale it is left out
            floor = ERROR_FLOOR * max(float(np.nanmax(np.abs(est), initial=0.0)), float(np.nanmax(half, initial=0.0)))
            shown = half > floor
            bottom.loglog(time[shown], half[shown], marker="o", ms=3, color=c,
                          label=f"{point_label(ds, at)}: half-width of the 95 % interval")
            ok = dist > floor
            bottom.loglog(time[ok], dist[ok], marker="x", ms=4, ls="--", color=c,
                          label=f"{point_label(ds, at)}: distance to the whole sample's {what}")
            lows.append(floor)
        top.set_xscale("log", base=2)
        top.set_xlabel("builds [–]")
        top.set_ylabel(f"{what} of {var} [{unit}]")
        top.set_title(f"{what} with its 95 % interval ({'bootstrap' if what == 'mean' else 'order statistics'}) "
                      "over the first builds", fontsize=9)
        if name == "convergence_p95" and np.isnan(tables[name].sel(output=var, bound="low").values).any():
            top.text(0.02, 0.02, "no band: too few independent builds to bound the P95 at 95 % "
                                 f"(it takes {min_builds(0.95)})", transform=top.transAxes, fontsize=8, color="0.3")
        ymin, ymax = bottom.get_ylim()
        if bottom.has_data() and ymax / ymin > 1e6:      # readable: at most six decades down from the largest error
            bottom.set_ylim(max(ymin, ymax * 1e-6, max(lows, default=0.0)), ymax)
        bottom.set_xlabel("compute time of those builds [s] (sum of their wall_time)")
        bottom.set_ylabel(f"error of the {what} [{unit}]")
        bottom.set_title(f"error of the {what} against run time (slope -1/2: Monte Carlo)", fontsize=9)
        for ax in (top, bottom):
            ax.grid(alpha=0.3, which="both")
        top.legend(fontsize=8)
        bottom.legend(fontsize=7)
    figure_title(fig, ds, f"Convergence of the statistics of {var} with the number of builds and the run time", width=130)
    return save_figure(fig, path)


def sobol_figure(ds: xr.Dataset, tables: xr.Dataset, var: str, path):
    """First-order and total Sobol indices of ``var``, ranked by the total, one panel a grid
    point; writes ``path``."""
    points = grid_points(ds)
    fields = [str(f) for f in tables["field"].values]
    ncol = min(len(points), 3)
    nrow = -(-len(points) // ncol)
    height = 0.42 * len(fields) + 1.4
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.6 * ncol + 1.0, height * nrow + 1.3), squeeze=False,
                             constrained_layout=True, sharex=True)
    lows = np.concatenate([tables[v].sel(output=var, bound="low").values.ravel() for v in ("sobol_first", "sobol_total")])
    highs = np.concatenate([tables[v].sel(output=var, bound="high").values.ravel() for v in ("sobol_first", "sobol_total")])
    xlim = (max(-1.0, min(-0.1, np.nanmin(lows, initial=0.0) - 0.05)), min(2.0, max(1.1, np.nanmax(highs, initial=0.0) + 0.05)))
    for k, at in enumerate(points):
        ax = axes[k // ncol, k % ncol]
        s1 = tables["sobol_first"].isel(at).sel(output=var)
        st = tables["sobol_total"].isel(at).sel(output=var)
        tot = np.nan_to_num(st.sel(bound="estimate").values, nan=-1.0)
        order = np.argsort(-tot, kind="stable")
        y = np.arange(len(fields))[::-1]
        for yi, i in zip(y, order):
            for shift, tab, colour, lab in ((0.18, st, C_LIGHT, "total S_T"), (-0.18, s1, C_HOLE, "first order S_1")):
                est, lo, hi = (float(tab.isel(field=i).sel(bound=b)) for b in ("estimate", "low", "high"))
                if not np.isfinite(est):
                    continue
                ax.barh(yi + shift, est, height=0.34, color=colour, label=lab if yi == y[0] else None)
                ax.errorbar([est], [yi + shift], xerr=[[max(est - lo, 0)], [max(hi - est, 0)]], fmt="none",
                            ecolor="k", capsize=2.5, lw=0.9)
        ax.set_yticks(y, [fields[i] for i in order], fontsize=8)
        ax.axvline(0.0, color="0.3", lw=0.6)
        ax.set_xlim(*xlim)
        ax.axvline(1.0, color="0.3", lw=0.6, ls=":")
        ax.grid(axis="x", alpha=0.3)
        n_ok = int(ds["sample_row"].max()) + 1
        ax.set_title(f"{point_label(ds, at)} ({n_ok} rows of the design)", fontsize=9)
        ax.set_xlabel("share of the variance [–]", fontsize=8)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8, loc="lower right")
        else:
            ax.text(0.5, 0.5, "fewer than 4 complete rows: no indices", transform=ax.transAxes, ha="center", fontsize=9)
    for k in range(len(points), nrow * ncol):
        axes[k // ncol, k % ncol].set_visible(False)
    figure_title(fig, ds, f"Which drawn field drives {var}: Sobol indices with 95 % intervals (bootstrap), "
                          "ranked by the total index", width=int(11 * (5.6 * ncol + 1.0)))
    return save_figure(fig, path)


def _with_interval(v: tuple[float, float, float]) -> str:
    return f"{v[0]:.4g} [{v[1]:.4g}, {v[2]:.4g}]" if np.isfinite(v[1:]).all() else f"{v[0]:.4g} (no interval)"


def sample_table_text(ds: xr.Dataset, tables: xr.Dataset, outputs: list[str]) -> str:
    """The statistics of a sampled study as a printed table: per output and grid point the
    builds kept, the mean and P5 / P50 / P95 with their 95 % intervals (none where the sample
    cannot support one) and each limit's probability of exceedance."""
    lines = []
    for var in outputs:
        unit = pretty_unit(ds[var].attrs.get("units"))
        lines.append(f"  {var} [{unit}]: {ds[var].attrs.get('long_name', var)}")
        for at in grid_points(ds):
            t = tables.isel(at)
            cells = [f"{int(t['sample_count'].sel(output=var))} builds",
                     f"mean {_with_interval(_est(t['sample_mean'].sel(output=var)))}"]
            cells += [f"P{100 * q:g} {_with_interval(_est(t['sample_percentile'].sel(output=var, quantile=q)))}"
                      for q in QUANTILES]
            if "exceedance_probability" in t and var in t["limit"].values:
                e = _est(t["exceedance_probability"].sel(limit=var))
                lim = float(t["limit_value"].sel(limit=var))
                cells.append(f"P(> {lim:g}) {e[0]:.3f} [{e[1]:.3f}, {e[2]:.3f}]")
            lines.append(f"    {point_label(ds, at)}: " + "; ".join(cells))
    if any("(no interval)" in line for line in lines):
        lines.append(f"  (no interval: {tables.attrs['independent_builds']} independent builds a grid point cannot bound "
                     f"that percentile at 95 %; a P95 takes {min_builds(0.95)}, a median {min_builds(0.5)})")
    return "\n".join(lines)


def sample_figures(ds: xr.Dataset, name, skip, limits: dict | None = None) -> list:
    """Every view of a sampled study (``name(stem)`` -> PNG path, ``skip(what, why)`` prints
    what is left out); the tables go to ``study_tables.nc`` beside them."""
    from study.archive.netcdf import provenance, write_netcdf
    limits = dict(limits or {})
    outputs = sample_outputs(ds)
    tables = sample_tables(ds, outputs, limits)
    out = []
    varying = []
    for var in outputs:
        y = np.concatenate([output_at(ds, var, at) for at in grid_points(ds)])
        y = y[np.isfinite(y)]
        if y.size < 2:
            skip(f"views of {var}", "fewer than two builds ok")
        elif np.ptp(y) == 0.0:
            skip(f"views of {var}", f"the same value in every build ({y[0]:.6g}): the drawn fields do not change it")
        else:
            varying.append(var)
    for var in varying:
        out.append(distribution_figure(ds, tables, var, name(f"distribution_{var}"), limits.get(var)))
        out.append(convergence_figure(ds, tables, var, name(f"convergence_{var}")))
        if "sobol_first" in tables:
            out.append(sobol_figure(ds, tables, var, name(f"sobol_{var}")))
    if "sobol_first" not in tables:
        skip("Sobol indices", f"a plain sample of {', '.join(drawn_fields(ds))}: the indices need the Saltelli "
                              "design ([sample] design = \"saltelli\")")
    path = name("study_tables").with_suffix(".nc")
    # (with the provenance of an archive: `lightgear export` and `render` take it as one)
    attrs = {**provenance(), **{k: ds.attrs[k] for k in ("title", "study_key") if k in ds.attrs}}
    write_netcdf(tables.assign_attrs(attrs, comment="computed by `lightgear render` from the sampled study's builds "
                                                    "(study.report.distributions)"), path)
    print(f"  study tables: {path}")
    if varying:
        print(sample_table_text(ds, tables, varying))
    return out

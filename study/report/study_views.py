"""Views of a whole study, for any number of swept dimensions (matplotlib, Agg, PNG), from the
archive alone (`study.report.effects` computes what they show):

  main_effects_figure   one output against each swept parameter: mean over the other parameters,
                        min-max band, one panel a parameter
  sensitivity_figure    each output's variance split into parameters, largest interaction and
                        rest, a horizontal bar chart a panel
  tradeoff_figure       mass saving [%] against a TE measure, coloured by root stress [MPa], the
                        points over the stress limit hollow, the Pareto set joined and ringed
"""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from study.report.effects import MASS_SAVING, STRESS_RATIO, kept, main_effect
from study.report.plot_style import (
    C_HOLE,
    C_LIGHT,
    C_SOLID,
    axis_label,
    figure_title,
    integer_ticks,
    param_label,
    pretty_unit,
    save_figure,
)

STRESS = "root_stress_max_gear2"


def _positions(ds, dim):
    """x positions and tick labels of a swept parameter (numbers as they are, text as 0, 1, ...)."""
    v = ds[dim].values if dim in ds.coords else np.arange(ds.sizes[dim])
    if v.dtype.kind in "fiub":
        return v.astype(float), None
    return np.arange(v.size, dtype=float), [str(s) for s in v]


def _param_label(ds, dim: str) -> str:
    return param_label(ds, dim)


def main_effects_figure(ds: xr.Dataset, var: str, swept: list[str], path):
    """``var`` against each swept parameter (mean over the others, min-max band); writes ``path``."""
    n = len(swept)
    ncol = min(n, 3)
    nrow = -(-n // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.6 * ncol + 0.6, 2.9 * nrow + 1.3), sharey=True,
                             squeeze=False, constrained_layout=True)
    unit = pretty_unit(ds[var].attrs.get("units"))
    for k, dim in enumerate(swept):
        ax = axes[k // ncol, k % ncol]
        me = main_effect(ds, var, dim)
        x, labels = _positions(ds, dim)
        ax.fill_between(x, me["min"].values, me["max"].values, color=C_LIGHT, alpha=0.18, lw=0,
                        label="min–max over the others")
        ax.plot(x, me["mean"].values, marker="o", ms=4, color=C_LIGHT, label="mean over the others")
        if labels:
            ax.set_xticks(x, labels)
        elif x.size <= 6:
            ax.set_xticks(x)
        else:
            integer_ticks(ax, ds[dim].values if dim in ds.coords else x)
        ax.set_xlabel(_param_label(ds, dim), fontsize=9)
        ax.grid(alpha=0.3)
        if k % ncol == 0:
            ax.set_ylabel(f"{var} [{unit}]")
    for k in range(n, nrow * ncol):
        axes[k // ncol, k % ncol].set_visible(False)
    axes[0, 0].legend(fontsize=8, loc="best")
    ok = kept(ds, var)         # over every point: an output over fewer dims is broadcast by the status
    kept_n, total = int(ok.notnull().sum()), int(ok.size)
    note = "" if kept_n == total else f" ({kept_n} of {total} points ok)"
    figure_title(fig, ds, f"Main effects on {var}: {ds[var].attrs.get('long_name', var)}{note}",
                 width=int(9 * (3.6 * ncol + 0.6)))
    return save_figure(fig, path)


def _term_colour(term: str, swept: list[str]) -> str:
    if term == "rest":
        return "0.6"
    if " x " in term:
        return C_HOLE
    return C_LIGHT


def sensitivity_figure(ds: xr.Dataset, table: xr.Dataset, path):
    """One horizontal bar chart a study output: its variance shares (main effects, its largest
    two-way interaction, rest); outputs constant over the study are left out. Writes ``path``."""
    share = table["sensitivity_share"]
    outputs = [str(o) for o in share["output"].values if np.isfinite(share.sel(output=o).values).any()]
    terms = [str(t) for t in share["term"].values]
    swept = [t for t in terms if t != "rest" and " x " not in t]
    ncol = min(len(outputs), 4)
    nrow = -(-len(outputs) // ncol)
    height = 0.22 * (len(swept) + 2) + 0.9
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.9 * ncol + 1.2, height * nrow + 1.4), sharex=True,
                             squeeze=False, constrained_layout=True)
    for k, out in enumerate(outputs):
        ax = axes[k // ncol, k % ncol]
        s = share.sel(output=out)
        names = [t for t in terms if np.isfinite(float(s.sel(term=t)))]
        vals = np.array([float(s.sel(term=t)) for t in names])
        y = np.arange(len(names))[::-1]
        ax.barh(y, vals, color=[_term_colour(t, swept) for t in names], height=0.7)
        ax.set_yticks(y, names, fontsize=7.5)
        for yi, v in zip(y, vals):
            ax.text(max(v, 0.0) + 0.02, yi, f"{100 * v + 0.0:.0f} %" if abs(v) >= 0.005 else "0 %", va="center",
                    fontsize=7)
        ax.set_xlim(min(0.0, vals.min() - 0.05), 1.18)
        ax.axvline(0.0, color="0.3", lw=0.6)
        npts = int(table["sensitivity_points"].sel(output=out)) if "sensitivity_points" in table else None
        ax.set_title(out + (f" ({npts} pts)" if npts is not None else ""), fontsize=9)
        ax.grid(axis="x", alpha=0.3)
        if k // ncol == nrow - 1 or k + ncol >= len(outputs):
            ax.set_xlabel("share of the variance [–]", fontsize=8)
            ax.xaxis.set_tick_params(labelbottom=True)
    for k in range(len(outputs), nrow * ncol):
        axes[k // ncol, k % ncol].set_visible(False)
    figure_title(fig, ds, "Sensitivity: share of each output's variance over the study grid "
                          "(red: a parameter's main effect, blue: the largest two-way interaction, grey: rest)",
                 width=int(10 * (3.9 * ncol + 1.2)))
    return save_figure(fig, path)


STRESS_SPAN = 0.1      # the stress colour scale spans at least this fraction of its mid value


def stress_norm(values):
    """Colour scale of the root stress [MPa]: the points' range, widened to STRESS_SPAN of its
    middle when narrower (a spread of a few % reads as one colour, not as the whole bar)."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    mid, half = 0.5 * (lo + hi), 0.5 * max(hi - lo, STRESS_SPAN * abs(0.5 * (lo + hi)))
    return plt.Normalize(mid - half, mid + half)


def _label_dims(ds, *names) -> list[str]:
    """The swept dimensions the archived variables ``names`` lie over (not those of the status)."""
    dims = set().union(*(ds[n].dims for n in names))
    return [str(d) for d in xr.broadcast(*(kept(ds, n) for n in names))[0].dims if d in dims]


def point_labels(arrays, dims) -> np.ndarray:
    """A short label of each point of ``arrays`` broadcast together (flattened in that order):
    its values of the swept parameters ``dims`` ('/'-joined, in the order of the broadcast)."""
    a = xr.broadcast(*arrays)[0]
    if not a.dims:
        return np.array([""], dtype=object)
    st = a.stack(_p=a.dims)
    cols = [st[d].values for d in a.dims if d in dims]
    return np.array(["/".join(f"{v:g}" if isinstance(v, (int, float, np.number)) else str(v) for v in vals)
                     for vals in zip(*cols)] if cols else [""] * st.size, dtype=object)


def tradeoff_figure(ds: xr.Dataset, pareto_flags: xr.Dataset, path, te_limits: dict | None = None, chosen: int | None = None):
    """Mass saving against each TE measure with a ``pareto_<te>`` flag in ``pareto_flags``; colour:
    root stress [MPa] when archived; hollow: over the stress limit; the Pareto set joined.
    ``te_limits``: {TE measure: limit [its units]} drawn as dashed lines; ``chosen``: the index of
    a point (in the points flattened in the order of the dims) marked by a star."""
    te = [str(v)[len("pareto_"):] for v in pareto_flags.data_vars]
    fig, axes = plt.subplots(1, len(te), figsize=(5.6 * len(te) + 1.4, 5.0), squeeze=False, constrained_layout=True)
    gain = kept(ds, MASS_SAVING)
    stress = kept(ds, STRESS) if STRESS in ds else None
    ratio = kept(ds, STRESS_RATIO)
    sc = None
    for ax, t in zip(axes[0], te):
        flag = pareto_flags[f"pareto_{t}"]
        limit = float(flag.attrs.get("stress_limit", np.nan))
        g, c, r, f = (a.values.ravel() for a in xr.broadcast(gain, kept(ds, t), ratio, flag.astype(bool)))
        s = xr.broadcast(stress, gain)[0].values.ravel() if stress is not None else np.full(g.shape, np.nan)
        shown = np.isfinite(g) & np.isfinite(c)
        solid = shown & (np.abs(g) < 1e-9)          # the solid driven gear: the reference of the trade
        shown &= ~solid
        within = shown & (r <= limit)
        over = shown & ~(r <= limit)
        if stress is not None and np.isfinite(s[shown]).any():
            norm = stress_norm(s[shown])
            coloured = within & np.isfinite(s)
            if coloured.any():
                sc = ax.scatter(c[coloured], g[coloured], c=s[coloured], cmap="viridis", norm=norm, s=28, zorder=3,
                                label=f"stress ratio ≤ {limit:g}")
            if over.any():
                ax.scatter(c[over], g[over], facecolors="none", edgecolors=plt.get_cmap("viridis")(norm(s[over])),
                           s=28, zorder=3, label=f"stress ratio > {limit:g} (or unknown)")
            nostress = within & ~np.isfinite(s)
            if nostress.any():
                ax.scatter(c[nostress], g[nostress], color="0.5", s=28, zorder=3, label="no root stress archived")
        else:
            if within.any():
                ax.scatter(c[within], g[within], color=C_LIGHT, s=28, zorder=3, label=f"stress ratio ≤ {limit:g}")
            if over.any():
                ax.scatter(c[over], g[over], facecolors="none", edgecolors=C_LIGHT, s=28, zorder=3,
                           label=f"stress ratio > {limit:g} (or unknown)")
        if solid.any():
            ax.scatter(c[solid], g[solid], marker="s", s=45, color="k", zorder=4, label="solid driven gear (reference)")
            ax.axvline(float(np.min(c[solid])), color="k", ls=":", lw=0.9, zorder=1)
        labels = point_labels((gain, kept(ds, t), ratio, flag.astype(bool)), _label_dims(ds, MASS_SAVING, t))
        done = set()
        for i in np.flatnonzero((f | solid) if (shown | solid).sum() > 12 else (shown | solid)):
            if (c[i], g[i]) not in done:     # points that differ only where neither quantity does: one label
                done.add((c[i], g[i]))
                ax.annotate(labels[i], (c[i], g[i]), xytext=(4, 3), textcoords="offset points", fontsize=6.5,
                            color="0.25")
        order = np.argsort(c[f])
        ax.plot(c[f][order], g[f][order], color=C_SOLID, lw=1.2, zorder=2, drawstyle="steps-post")
        ax.scatter(c[f], g[f], s=110, facecolors="none", edgecolors=C_SOLID, lw=1.4, zorder=4,
                   label=f"Pareto set ({int(f.sum())} points)")
        if te_limits and t in te_limits:
            ax.axvline(te_limits[t], color="0.3", ls="--", lw=1.0, zorder=1, label=f"{t} limit {te_limits[t]:.3g}")
        if chosen is not None:
            ax.scatter(c[chosen], g[chosen], marker="*", s=280, color=C_HOLE, edgecolors="k", lw=0.6, zorder=5,
                       label="chosen")
        ax.set_xlabel(axis_label(ds[t], t))
        ax.set_ylabel(axis_label(ds[MASS_SAVING], MASS_SAVING))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")
        ax.set_title(f"{MASS_SAVING} against {t}: up and left is better\npoint labels: "
                     + ", ".join(_label_dims(ds, MASS_SAVING, t)), fontsize=9)
    if sc is not None:
        fig.colorbar(sc, ax=axes[0, -1], label=axis_label(ds[STRESS], STRESS))
    n_ok = int(np.isfinite(gain.values).sum())
    figure_title(fig, ds, f"Trade-off: mass saved against transmission error ({n_ok} points ok)",
                 width=int(9 * (5.6 * len(te) + 1.4)))
    return save_figure(fig, path)


STRENGTH_LINES = (("bending_stress_root_gear{g}", "root", "v", "#d62728"), ("rim_stress_max_gear{g}", "rim", "s", "#9467bd"),
                  ("web_stress_max_gear{g}", "web", "D", "#111111"))


def strength_figure(ds: xr.Dataset, swept: list[str], path, g: int = 2):
    """Gear g's largest tensile stress at the root, in the rim and in the web against each swept
    parameter (mean over the others, min-max band), with its smallest S_F on a second axis where
    the study has it; writes ``path``."""
    lines = [(v.format(g=g), lab, m, c) for v, lab, m, c in STRENGTH_LINES if v.format(g=g) in ds]
    if not lines:
        raise KeyError(f"the study has none of gear {g}'s strength outputs")
    n = len(swept)
    ncol = min(n, 3)
    nrow = -(-n // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol + 0.6, 3.2 * nrow + 1.3), sharey=True,
                             squeeze=False, constrained_layout=True)
    sf = f"bending_safety_gear{g}"
    for k, dim in enumerate(swept):
        ax = axes[k // ncol, k % ncol]
        x, labels = _positions(ds, dim)
        for var, lab, m, c in lines:
            me = main_effect(ds, var, dim)
            if not np.isfinite(me["mean"].values).any():
                continue
            ax.fill_between(x, me["min"].values, me["max"].values, color=c, alpha=0.12, lw=0)
            ax.plot(x, me["mean"].values, marker=m, ms=5, color=c, label=lab)
        if sf in ds:
            tw = ax.twinx()
            tw.plot(x, main_effect(ds, sf, dim)["min"].values, ls=":", color="#2ca02c", marker=".",
                    label="smallest S_F (right)")
            tw.set_ylabel("bending safety S_F [1]", color="#2ca02c")
            if k == 0:
                tw.legend(loc="center right", fontsize=8)
        if labels:
            ax.set_xticks(x, labels)
        elif ds[dim].values.dtype.kind in "iu":
            integer_ticks(ax, x)
        ax.set_xlabel(_param_label(ds, dim))
        ax.grid(alpha=0.3)
        if k % ncol == 0:
            ax.set_ylabel("largest tensile stress [MPa]")
        if k == 0:
            ax.legend(loc="upper left", fontsize=8, title="mean over the others", title_fontsize=8)
    for k in range(n, nrow * ncol):
        axes[k // ncol, k % ncol].set_visible(False)
    figure_title(fig, ds, f"Gear {g}: largest tensile stress at the root, in the rim and in the web over the study "
                          "(static contact forces; band: min-max over the other parameters)", width=int(30 * ncol + 20))
    return save_figure(fig, path)

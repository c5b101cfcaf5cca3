"""All the figures an archive supports: plots (`study.report.te_plots`, `study.report.stiffness_plot`,
`study.report.sweep_view`) and renders (`study.report.stiffness_render`, `study.report.stress_render`).

``make_figures(ds, outdir)`` writes PNGs into ``outdir`` and returns their paths; what the
dataset cannot support (no STE, no DTE, no lightened body to show stress in) is skipped with one
printed line saying why. A spectrum needs no render, and a solid gear needs no FE: renders of
a lightened body reuse one FE solve (cached springs, one factorisation) for both images.

A sweep archive (dimensions beyond a single run's) gets, for any number of swept dimensions,
the study views (`study.report.study_views`): main effects of each output, the sensitivity
ranking (grid layout) and the mass / TE trade-off with its Pareto set, with their tables
(``sensitivity_share``, ``pareto_*``) written to ``study_tables.nc`` beside the figures; and,
with up to four swept dimensions, one sweep view per output that varies only over them.
A sampled study (a ``sample`` dimension) gets the views of `study.report.sample_views` instead.

CLI: ``lightgear render ARCHIVE.nc [-o DIR]`` (default: beside the archive).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import xarray as xr

# dimensions of a single run archive; any other dimension is a swept parameter
RUN_DIMS = {"angle", "time", "frequency", "gear", "tooth", "driver_tooth", "driven_tooth", "contact_slot", "ste_order", "ste_peak", "dte_peak",
            "mode", "mesh_position", "excitation", "runup_speed", "tracked_order",
            "location", "ligament", "axis", "site"}      # the strength's (study.archive.strength)
TABLE_DIMS = {"output", "term"}          # the study's sensitivity table (`study.report.effects`)


def swept_dims(ds: xr.Dataset) -> list[str]:
    return [d for d in ds.dims if d not in RUN_DIMS and d not in TABLE_DIMS]


def run_plots() -> tuple:
    """The plots of a run archive: (variables, any of which the plot draws; file stem; plot
    function; what is skipped and why when the archive has none of the variables). Imported
    here, not at the top: building the command line loads no matplotlib."""
    from study.report.campbell import campbell_plot, order_map_plot
    from study.report.stiffness_plot import stiffness_plot
    from study.report.strength_plot import strength_plot
    from study.report.te_plots import dte_plot, spectrum_plot, ste_plot
    return (
        (("ste",), "ste", ste_plot, "STE plot", "the archive has no quasi-static analysis (ste)"),
        (("dte",), "dte", dte_plot, "DTE plot", "the archive has no dynamic analysis (dte)"),
        (("dte_amplitude", "ste_amplitude"), "spectrum", spectrum_plot, "spectrum plot",
         "no spectrum in the archive (DTE record too short or not computed)"),
        (("tooth_stiffness",), "tooth_stiffness", stiffness_plot, "stiffness plot", "no tooth_stiffness in the archive"),
        (("mode_frequency",), "campbell", campbell_plot, "Campbell diagram", "no modes in the archive"),
        (("order_amplitude",), "order_map", order_map_plot, "order map", order_map_missing),
        (("site_stress",), "strength", strength_plot, "strength map", "no strength in the archive (no static analysis)"),
    )


def order_map_missing(ds: xr.Dataset) -> str:
    """Why a run archive has no order map: no dynamic run, not a run-up, or a run-up that
    stopped before its end (the reason `study.run` recorded)."""
    if "order_tracking_skipped" in ds.attrs:
        return str(ds.attrs["order_tracking_skipped"])
    if "dte" not in ds:
        return "the archive has no dynamic analysis (dte)"
    if "runup_speed_end_rad_s" in ds.attrs:
        return "the run-up's archive has no order tracking"
    return "not a run-up (dynamic.speed_end = 0)"


def fresh(path: Path, after: float | None) -> bool:
    """True when the figure ``path`` was written at or after ``after`` (a file time [s], that of
    the archive it shows; None: never)."""
    return after is not None and path.is_file() and path.stat().st_mtime >= after


def render_paths(ds: xr.Dataset, outdir, prefix: str = "") -> list[Path]:
    """The files of a run archive's pyvista renders: the gear pair, each lightened gear's FE stress."""
    from study.report.render_inputs import required_scene
    sc = required_scene(ds)
    return [Path(outdir) / f"{prefix}{stem}.png"
            for stem in ["gear_pair", *(f"fe_stress_gear{g}" for g in (1, 2) if sc.is_lightened(g))]]


def renders_fresh(ds: xr.Dataset, outdir, prefix: str, after: float | None) -> bool:
    """True when every render of the run archive ``ds`` (`render_paths`) was written at or
    after ``after`` (`fresh`): they are taken as they are, and need no FE fields."""
    return all(fresh(p, after) for p in render_paths(ds, outdir, prefix))


def make_figures(ds: xr.Dataset, outdir, prefix: str = "", renders: bool = True, limits: dict | None = None,
                 fields: dict | None = None, reuse_after: float | None = None) -> list[Path]:
    """Write every plot and render ``ds`` supports into ``outdir``; return the PNG paths.
    ``limits`` ({output: value}): the probability of exceeding each, for a sampled study.
    ``fields`` ({gear: [BodyField under the stiffest tooth's load, under the softest's]},
    `study.inputs.springs.archive_body_fields`): what the renders of a lightened gear draw;
    without them those renders are skipped (the pictures start no FE solve).
    ``reuse_after`` (a run archive's file time [s]): a run's figure already in ``outdir`` and
    written since is taken as it is, not drawn again (`lightgear report` after `render`)."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    out: list[Path] = []

    def name(stem):
        return outdir / f"{prefix}{stem}.png"

    def skip(what, why):
        print(f"  skip {what}: {why}")

    swept = swept_dims(ds)
    if "sample" in swept:       # a sampled study: distributions, convergence, Sobol indices
        from study.report.sample_views import sample_figures
        return sample_figures(ds, name, skip, limits)
    if limits:
        raise ValueError(f"limits ({', '.join(limits)}) apply to a sampled study; this archive has no sample dimension")
    if swept:
        return _sweep_figures(ds, swept, name, skip)
    for variables, stem, plot, what, why in run_plots():
        if not any(v in ds for v in variables):
            skip(what, why(ds) if callable(why) else why)
            continue
        if fresh(name(stem), reuse_after):
            out.append(name(stem))
            continue
        try:
            out.append(plot(ds, name(stem)))
        except (ValueError, KeyError, IndexError) as e:
            # an archive run accepted whose data this plot cannot show (no orders at speed 0,
            # too short a record): said, and the other figures still drawn
            import matplotlib.pyplot as plt
            plt.close("all")
            skip(what, f"nothing to draw in this archive ({str(e).splitlines()[0] if str(e) else type(e).__name__})")
    if "dte_amplitude" in ds and "order" in ds.coords and not np.isfinite(ds["order"].values).any():
        skip("DTE spectrum panel", "no orders of the driven gear's rotation at driver speed 0")
    if not renders:
        skip("renders", "not asked for")
        return out
    if "scene" not in ds.attrs or "tooth_stiffness" not in ds:
        skip("renders", "the archive has no scene attribute or no tooth_stiffness")
        return out
    if renders_fresh(ds, outdir, prefix, reuse_after):
        done = render_paths(ds, outdir, prefix)
        print(f"  renders: the {len(done)} already beside the archive")
        return out + done
    out += _renders(ds, name, skip, fields or {})
    return out


def _renders(ds, name, skip, fields: dict) -> list[Path]:
    from study.report.render_inputs import missing_fields, required_scene
    from study.report.stiffness_render import gear_pair_render
    from study.report.stress_render import fe_stress_render
    sc = required_scene(ds)
    lightened = [g for g in (1, 2) if sc.is_lightened(g)]
    missing = missing_fields(ds, fields)
    if missing:
        skip("gear pair and FE stress renders", f"no FE body fields of lightened gear {', '.join(map(str, missing))} "
             "given (the pictures start no FE solve; study.render reads them from the FE cache or solves them)")
        return []
    t0 = time.perf_counter()
    out = [gear_pair_render(ds, name("gear_pair"), {g: fields[g][0] for g in lightened}).path]
    for g in lightened:
        out.append(fe_stress_render(ds, name(f"fe_stress_gear{g}"), g, fields=fields[g]).path)
    if not lightened:
        skip("FE stress render", "both gears are solid (no FE body needed)")
    print(f"  renders: {time.perf_counter() - t0:.1f} s")
    return out


def _sweep_figures(ds, swept, name, skip) -> list[Path]:
    out = _study_views(ds, swept, name, skip)
    if len(swept) > 4:
        skip("sweep views", f"{len(swept)} swept dimensions ({', '.join(swept)}): "
                            "the main effects, sensitivity and trade-off views cover them")
        return out
    return out + _sweep_views(ds, swept, name, skip)


def _study_views(ds, swept, name, skip) -> list[Path]:
    """Main effects, sensitivity ranking and trade-off; their tables go to ``study_tables.nc``
    beside the figures. They are computed here, from the points of the archive rendered, and
    not stored by ``lightgear sweep``: the archives of the parts of a split study open together
    as one (open_mfdataset), and a variance split or Pareto set of one part is wrong for the whole."""
    from study.archive.netcdf import provenance, write_netcdf
    from study.report.effects import pareto_table, sensitivity_table, study_outputs, varies
    from study.report.study_views import main_effects_figure, sensitivity_figure, tradeoff_figure
    out, tables = [], []
    outputs = study_outputs(ds, swept)
    constant = [v for v in outputs if not varies(ds, v)]
    if constant:
        skip("figures of outputs that take one value", ", ".join(f"{v} = {_value(ds, v)}" for v in constant))
    outputs = [v for v in outputs if v not in constant]
    _status_table(ds)
    if swept == ["point"]:
        skip("main effects and sensitivity", "explicit study points (no factorial grid to average over)")
    elif not outputs:
        skip("main effects and sensitivity", f"no numeric output over the swept dimensions ({', '.join(swept)})")
    else:
        for var in outputs:
            out.append(main_effects_figure(ds, var, swept, name(f"main_effects_{var}")))
        table = sensitivity_table(ds, swept, outputs)
        tables.append(table)
        if np.isfinite(table["sensitivity_share"].values).any():
            out.append(sensitivity_figure(ds, table, name("sensitivity")))
        else:
            skip("sensitivity ranking", "every output is constant over the points that are ok")
    if any(f"{v}_gear2" in ds for v in ("web_stress_max", "rim_stress_max", "bending_stress_root")):
        from study.report.study_views import strength_figure
        if swept == ["point"]:
            skip("strength view", "explicit study points (no factorial grid to average over)")
        else:
            out.append(strength_figure(ds, swept, name("strength_gear2")))
    pareto = pareto_table(ds, skip=skip)
    if pareto.data_vars:
        tables.append(pareto)
        out.append(tradeoff_figure(ds, pareto, name("tradeoff")))
    if tables:
        path = name("study_tables").with_suffix(".nc")
        # (with the provenance of an archive: `lightgear export` and `render` take it as one)
        attrs = {**provenance(), **{k: ds.attrs[k] for k in ("title", "study_key") if k in ds.attrs}}
        write_netcdf(xr.merge(tables).assign_attrs(attrs, comment="computed by `lightgear render` from the "
                              "study archive's points (study.report.effects)"), path)
        print(f"  study tables: {path}")
    return out


def _value(ds, var) -> str:
    from study.report.effects import kept
    v = kept(ds, var).values
    v = v[np.isfinite(v)]
    unit = str(ds[var].attrs.get("units", ""))
    return f"{v[0]:.4g} {unit if unit not in ('1', '-') else ''}".strip() if v.size else "NaN at every point"


def _status_table(ds) -> None:
    """Print how many points end in each status flag (a flag is no quantity to draw)."""
    if "status" not in ds:
        return
    names = str(ds["status"].attrs.get("flag_meanings", "")).split()
    values = list(ds["status"].attrs.get("flag_values", range(len(names))))
    st = ds["status"].values.ravel()
    counts = [f"{n} {int(np.sum(st == v))}" for n, v in zip(names, values) if np.sum(st == v)]
    print("  status of the points: " + ", ".join(counts))


def _sweep_views(ds, swept, name, skip) -> list[Path]:
    from study.report.effects import NOT_OUTPUTS, varies
    from study.report.sweep_view import sweep_view
    out = []
    for var in ds.data_vars:
        da = ds[var]
        if str(var).startswith("pareto_") or var in NOT_OUTPUTS or (da.dtype.kind in "fiu" and not varies(ds, var)):
            continue   # a flag (trade-off view, status table), bookkeeping, or a value that does not vary
        dims = [d for d in swept if d in da.dims]
        if da.dtype.kind not in "fiu" or not dims or not set(da.dims) <= set(swept):
            continue   # (a static output lies only over the fields its analysis reads)
        hue = dims[1] if len(dims) > 1 else None
        out.append(sweep_view(ds, var, dims[0], hue=hue, path=name(f"sweep_{var}")))
    if not out:
        skip("sweep views", f"no numeric output varies only over the swept dimensions ({', '.join(swept)})")
    return out

"""Work-precision of the FE mesh size: what a coarser FE body costs in accuracy, and what it saves.

The scene runs at a few FE element sizes (``fe.mesh_size``, by default 2, 1 and 1/2 times the
default outline size, a quarter of the smaller module: coarse, default, fine) with its own
coupling model (the default compliance model takes the tooth coupling and the tooth springs
from the FE bodies). At each size:

* the FE time of each gear's inputs (its tooth springs and its compliance fit, every FE
  result a run of the scene asks for), CPU [s], from an empty FE cache (a temporary folder,
  nothing kept in memory: what the first run of that size pays; with ``fresh_fe=False``
  the cache in use, so a cached body counts near 0);
* the STE [um] over the quasi-static case's driver angles (`precision_cases.static_case`,
  static Newton at its default tolerance) and its CPU time [s];
* the dynamic run of the scene's own dynamic section (its window, ramps and output step)
  with the production integrator's defaults (`solver.mbs.dynamics.simulate`), its DTE [um]
  over the steady part (from twice the ramp time) and its CPU time [s], best of
  ``repeats`` after a warm-up run (compile excluded).

Errors against the finest size [um]: STE mean, STE peak-to-peak and the largest STE
difference over the angles; DTE RMS (about its mean) and the largest DTE difference over the
steady part. The DTE differences also hold each size's time-integration error at its own
default step (a few nm, `docs/numbers.md`), far below the mesh's share where that is
larger than 0.01 um.
"""
from __future__ import annotations

import contextlib
import math
import os
import tempfile
import time

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.dynamics import simulate
from solver.mbs.statics import solve_static
from study.scene import Scene, SceneError
from study.verify.precision_cases import static_case

LEVELS = (("coarse", 2.0), ("default", 1.0), ("fine", 0.5))   # x the default outline size
DTE_NORMS = ("rms", "linf")


def default_size_mm(scene: Scene) -> float:
    """The FE outline size [mm] the scene runs with: fe.mesh_size, else a quarter of the
    smaller module (`solver.fe.mesh.default_mesh_size`)."""
    return scene.fe.mesh_size or min(scene.gear1.module, scene.gear2.module) / 4.0


@contextlib.contextmanager
def empty_fe_cache():
    """An empty FE cache for the block: a temporary folder as ``$LIGHTGEAR_CACHE`` and nothing
    held in memory (`solver.store.STORE`); the folder and the memory the block filled are
    dropped after it, the former cache folder in use again."""
    from solver.store import STORE
    before = os.environ.get("LIGHTGEAR_CACHE")
    with tempfile.TemporaryDirectory(prefix="lightgear-fe-") as tmp:
        os.environ["LIGHTGEAR_CACHE"] = tmp
        STORE.clear()
        try:
            yield tmp
        finally:
            STORE.clear()
            if before is None:
                os.environ.pop("LIGHTGEAR_CACHE", None)
            else:
                os.environ["LIGHTGEAR_CACHE"] = before


def fe_cpu_times(scene: Scene) -> np.ndarray:
    """CPU seconds of each gear's FE inputs (tooth springs, coupling fit) of ``scene``, gear 1
    first, as a run of the scene computes them (gear 1 makes the condensed rim that gear 2 of
    the same rim height reuses)."""
    from study.inputs.springs import tooth_springs
    from study.scene_model import coupled_springs, gear_setups, geometry_model
    setups = gear_setups(scene)
    pair = []

    def kinematics():
        if not pair:
            pair.append(geometry_model(scene, setups))
        return pair[0]
    out = np.zeros(2)
    for i, s in enumerate(setups):
        c0 = time.process_time()
        if scene.coupling_model == "none":
            tooth_springs(s)
        else:
            coupled_springs(scene, s, setups, kinematics)
        out[i] = time.process_time() - c0
    return out


def _best_cpu(fn, repeats: int):
    """(result, best CPU time [s]) of ``repeats`` calls of fn after one warm-up call."""
    out = fn()
    best = math.inf
    for _ in range(max(1, repeats)):
        c0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - c0)
    return out, best


def level_runs(scene: Scene, rotation_deg: float, repeats: int, fresh_fe: bool) -> dict:
    """FE, model, STE and DTE of ``scene`` (its fe.mesh_size set): the quantities of one mesh
    level, SI times [s], TE [um] (see the module docstring)."""
    from study.scene_model import build_scene_model
    with empty_fe_cache() if fresh_fe else contextlib.nullcontext():
        fe = fe_cpu_times(scene)
        c0 = time.process_time()
        model = build_scene_model(scene)
        build = time.process_time() - c0
    case = static_case(scene, rotation_deg)
    st, static_cpu = _best_cpu(lambda: solve_static(model, case.angles, case.torque), repeats)
    d = scene.dynamic
    kw = {"dt": d.time_step} if d.time_step > 0 else {}
    dyn, dynamic_cpu = _best_cpu(lambda: simulate(model, d.speed, d.ramp_time, d.torque, d.ramp_time, d.duration,
                                                  output_step=d.output_step, **kw), repeats)
    if dyn.status:
        raise RuntimeError(f"fe.mesh_size = {scene.fe.mesh_size:g} mm: the dynamic run stopped: {dyn.message}")
    start = d.spectrum_start if d.spectrum_start > 0 else 2.0 * d.ramp_time
    steady = dyn.time >= start - 1e-12
    if steady.sum() < 2:
        raise SceneError("dynamic.duration", f"the mesh study needs a steady part after twice the ramp time "
                                             f"({start:g} s): got {d.duration:g} s")
    return {"fe": fe, "build": build, "ste": st.te * units.UM_PER_M, "static_cpu": static_cpu,
            "dte": dyn.te[steady] * units.UM_PER_M, "dynamic_cpu": dynamic_cpu, "dt": dyn.dt,
            "steady_start": start}


def mesh_study(scene: Scene, factors=tuple(f for _, f in LEVELS), names=None, rotation_deg: float = 6.0,
               repeats: int = 2, fresh_fe: bool = True, progress=None) -> xr.Dataset:
    """The scene's STE and DTE and their errors against the finest FE mesh, with the FE and run
    CPU times, at fe.mesh_size = each of ``factors`` x `default_size_mm` (``names``: one label
    each, default coarse / default / fine for the default factors) -> Dataset over ``mesh``.
    ``rotation_deg`` [deg]: the STE's range (at quasi_static.angle_step); ``repeats``: timed
    runs of the statics and the dynamics (best kept, after a warm-up); ``fresh_fe``: each size's
    FE from an empty cache (`empty_fe_cache`); ``progress(i, size_mm, row)``: after each size."""
    factors = tuple(float(f) for f in factors)
    if len(factors) < 2 or any(not (f > 0 and math.isfinite(f)) for f in factors):
        raise ValueError(f"factors: at least two positive mesh-size factors, got {factors}")
    if names is None:
        names = [n for n, f in LEVELS if f in factors] if set(factors) <= {f for _, f in LEVELS} else \
            [f"x{f:g}" for f in factors]
    if len(names) != len(factors):
        raise ValueError(f"names: one per factor ({len(factors)}), got {len(names)}")
    order = np.argsort(factors)[::-1]          # coarse first, the finest last
    factors = [factors[i] for i in order]
    names = [names[i] for i in order]
    h0 = default_size_mm(scene)
    rows = []
    for i, f in enumerate(factors):
        sc = scene.replace(**{"fe.mesh_size": h0 * f})
        rows.append(level_runs(sc, rotation_deg, repeats, fresh_fe))
        if progress:
            progress(i, h0 * f, rows[-1])
    return _mesh_dataset(scene, rows, names, [h0 * f for f in factors], h0, (rotation_deg, repeats, fresh_fe))


def _mesh_dataset(scene: Scene, rows: list, names: list, sizes_mm: list, h0: float, how: tuple) -> xr.Dataset:
    """`mesh_study`'s Dataset from its rows (`level_runs`, coarse first) at ``sizes_mm`` [mm]
    (``h0`` [mm] the default size; ``how``: (rotation_deg, repeats, fresh_fe) as given to it)."""
    from study.archive.netcdf import provenance
    from study.verify.precision_study import machine, model_label
    rotation_deg, repeats, fresh_fe = how
    fine = rows[-1]
    n = len(rows)

    def per(key, fn):
        return np.array([fn(r[key]) for r in rows])

    ste_mean, ste_p2p = per("ste", np.mean), per("ste", np.ptp)
    dte_mean = per("dte", np.mean)
    dte_rms = per("dte", lambda x: float(np.sqrt(np.mean((x - x.mean()) ** 2))))
    dte_p2p = per("dte", np.ptp)
    ste_linf = np.array([np.max(np.abs(r["ste"] - fine["ste"])) for r in rows])
    dte_linf = np.array([np.max(np.abs(r["dte"] - fine["dte"])) if r["dte"].shape == fine["dte"].shape else np.nan
                         for r in rows])
    um, s = "um", "s"

    def var(dims, values, units_, name):
        return dims, values, {"units": units_, "long_name": name}
    m = ("mesh",)
    ds = xr.Dataset(
        {
            "fe_cpu_time": var(("mesh", "gear"), np.array([r["fe"] for r in rows]), s,
                               "CPU time of the gear's FE inputs (tooth springs, coupling fit)"
                               + (", from an empty FE cache" if fresh_fe else ", FE cache as found")),
            "model_cpu_time": var(m, per("build", float), s, "CPU time of the rest of the model build "
                                                               "(damping conversion) after the FE"),
            "static_cpu_time": var(m, per("static_cpu", float), s, "CPU time of the statics over the STE's angles"),
            "dynamic_cpu_time": var(m, per("dynamic_cpu", float), s, "CPU time of the dynamic run (compile excluded)"),
            "time_step": var(m, per("dt", float), s, "time step of the dynamic run (the production default)"),
            "ste_mean": var(m, ste_mean, um, "mean static transmission error"),
            "ste_p2p": var(m, ste_p2p, um, "peak-to-peak static transmission error"),
            "dte_mean": var(m, dte_mean, um, "mean dynamic transmission error over the steady part"),
            "dte_rms": var(m, dte_rms, um, "RMS of the dynamic transmission error about its mean, steady part"),
            "dte_p2p": var(m, dte_p2p, um, "peak-to-peak dynamic transmission error, steady part"),
            "ste_mean_error": var(m, np.abs(ste_mean - ste_mean[-1]), um, "STE mean minus the finest mesh's, magnitude"),
            "ste_p2p_error": var(m, np.abs(ste_p2p - ste_p2p[-1]), um, "STE peak-to-peak minus the finest mesh's, "
                                                                       "magnitude"),
            "ste_error_linf": var(m, ste_linf, um, "largest STE difference to the finest mesh over the angles"),
            "dte_rms_error": var(m, np.abs(dte_rms - dte_rms[-1]), um, "DTE RMS minus the finest mesh's, magnitude"),
            "dte_error_linf": var(m, dte_linf, um, "largest DTE difference to the finest mesh over the steady part"),
        },
        coords={
            "mesh": ("mesh", np.arange(n), {"long_name": "mesh level, coarse first"}),
            "gear": ("gear", [1, 2], {"long_name": "gear (1: driver)"}),
            "level": ("mesh", np.array(names, dtype=object), {"long_name": "mesh level name"}),
            "mesh_size": ("mesh", np.array(sizes_mm), {"units": "mm",
                                                                        "long_name": "FE element size at the outline (fe.mesh_size)"}),
        },
        attrs={
            "title": f"work-precision of the FE mesh size, {model_label(scene)}",
            "case": (f"STE under {scene.quasi_static.torque:g} N·m over {rotation_deg:g} deg every "
                     f"{scene.quasi_static.angle_step:g} deg; DTE of the scene's {scene.dynamic.duration:g} s run "
                     f"(0 -> {scene.dynamic.speed:g} rad/s and 0 -> {scene.dynamic.torque:g} N·m in "
                     f"{scene.dynamic.ramp_time * 1e3:g} ms) from {rows[0]['steady_start']:g} s on, production step"),
            "reference": f"the finest mesh, fe.mesh_size = {sizes_mm[-1]:.4g} mm",
            "default_mesh_size_mm": h0, "fresh_fe_cache": int(fresh_fe), "repeats": int(repeats),
            **provenance(), "machine": machine(), "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "scene": scene.to_toml(),
        },
    )
    return ds


def mesh_table(ds: xr.Dataset) -> str:
    """The mesh study as a text table: size, STE and DTE with their errors [um], CPU [s]."""
    lines = [f"{ds.attrs['title']}: {ds.attrs['case']}", f"  reference: {ds.attrs['reference']}",
             f"  {'level':8s} {'size mm':>8s} {'STE mean':>9s} {'err':>8s} {'STE p2p':>8s} {'err':>8s} "
             f"{'STE linf':>9s} {'DTE rms':>8s} {'err':>8s} {'DTE linf':>9s} {'FE s g1':>8s} {'FE s g2':>8s} "
             f"{'static s':>9s} {'dyn s':>7s}"]
    for i in range(ds.sizes["mesh"]):
        v = {k: float(ds[k].values[i]) for k in ("mesh_size", "ste_mean", "ste_mean_error", "ste_p2p", "ste_p2p_error",
                                                 "ste_error_linf", "dte_rms", "dte_rms_error", "dte_error_linf",
                                                 "static_cpu_time", "dynamic_cpu_time")}
        fe = ds["fe_cpu_time"].values[i]
        lines.append(f"  {ds['level'].values[i]:8s} {v['mesh_size']:8.4g} {v['ste_mean']:9.4g} {v['ste_mean_error']:8.2g} "
                     f"{v['ste_p2p']:8.4g} {v['ste_p2p_error']:8.2g} {v['ste_error_linf']:9.2g} {v['dte_rms']:8.4g} "
                     f"{v['dte_rms_error']:8.2g} {v['dte_error_linf']:9.2g} {fe[0]:8.3g} {fe[1]:8.3g} "
                     f"{v['static_cpu_time']:9.3g} {v['dynamic_cpu_time']:7.3g}")
    lines.append("  (errors [um] against the finest mesh; CPU times [s])")
    return "\n".join(lines)


def mesh_plot(ds: xr.Dataset, path) -> None:
    """Two log-log panels: each error [um] against the FE CPU time of both gears [s], and
    against the mesh size [mm] (the finest, the reference, as a dotted line)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from study.verify.precision_report import save_with_footer
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 5))
    fe = ds["fe_cpu_time"].sum("gear").values
    h = ds["mesh_size"].values
    keep = np.arange(ds.sizes["mesh"] - 1)
    for k, label in (("ste_mean_error", "STE mean"), ("ste_p2p_error", "STE peak-to-peak"),
                     ("ste_error_linf", "STE, largest difference"), ("dte_rms_error", "DTE RMS"),
                     ("dte_error_linf", "DTE, largest difference")):
        e = ds[k].values[keep]
        ok = np.isfinite(e) & (e > 0)
        if ok.any():
            a.loglog(fe[keep][ok], e[ok], "o-", label=label)
            b.loglog(h[keep][ok], e[ok], "o-", label=label)
    a.axvline(fe[-1], color="k", ls=":", lw=1, label=f"the finest mesh (the reference): {fe[-1]:.3g} s")
    b.axvline(h[-1], color="k", ls=":", lw=1, label=f"the finest mesh (the reference): {h[-1]:.3g} mm")
    for i in keep:
        a.annotate(f"{ds['level'].values[i]} ({h[i]:.3g} mm)", (fe[i], 0.02), xycoords=("data", "axes fraction"),
                   fontsize=7, rotation=90, va="bottom", ha="right")
    a.set_xlabel("FE CPU time of both gears, empty cache [s]" if ds.attrs.get("fresh_fe_cache") else
                 "FE CPU time of both gears [s]")
    b.set_xlabel("FE element size at the outline, fe.mesh_size [mm]")
    for ax in (a, b):
        ax.set_ylabel("error against the finest mesh [um]")
        ax.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=8, loc="upper right")           # the lines fall to the right: room above them
    b.legend(handles=b.get_lines()[-1:], fontsize=8, loc="upper left")   # the colours are the left panel's
    fig.suptitle(ds.attrs["title"])
    save_with_footer(fig, ds, f"reference: {ds.attrs['reference']}", path, top=0.95)

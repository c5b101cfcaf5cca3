"""The work-precision study's runs and dataset: every `Spec` of a case timed and its TE error
measured against the reference, into one xarray Dataset with dims (run, norm).

Errors: TE minus reference TE [um] on the common output grid, as norms ``final`` (last
sample), ``l2`` (root mean square over the samples) and ``linf`` (largest magnitude).
Wall and CPU time [s]: best of ``repeats`` runs after a warm-up run of each numba method
(compile time and the first call are timed apart, in ``first_call_time``); a run over 10 s is
timed once. The CPU time (user + system of the process) is the figure to compare on a shared
machine. A failed run keeps NaN errors and its message.
"""
from __future__ import annotations

import math
import os
import platform
import time

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.kernels.status import COMPLETED, NONFINITE, OK
from solver.mbs.model import Model
from study.archive.netcdf import provenance
from study.scene import Scene
from study.verify.precision_cases import (
    Spec,
    dynamic_case,
    dynamic_reference,
    dynamic_specs,
    static_case,
    static_reference,
    static_specs,
)

NORMS = ("final", "l2", "linf")

def machine() -> str:
    """CPU, cores, memory and Python of this machine, for plot footers and attrs."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = ""
    try:
        with open("/proc/meminfo") as f:
            kb = int(f.readline().split()[1])
            mem = f", {kb / 2**20:.0f} GB"
    except (OSError, ValueError, IndexError):
        pass
    return f"{cpu}, {os.cpu_count()} CPUs{mem}, {platform.system()} {platform.machine()}, Python {platform.python_version()}"


def te_error_norms(te: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """(final, l2, linf) of te - ref [um]; NaN when te is shorter than ref or not finite."""
    if te.shape != ref.shape or not np.all(np.isfinite(te)):
        return np.full(3, np.nan)
    e = (te - ref) * units.UM_PER_M
    return np.array([abs(e[-1]), math.sqrt(float(np.mean(e * e))), float(np.max(np.abs(e)))])


def _timed(fn, repeats: int):
    """(result, best wall time [s], best CPU time [s]) of repeats calls; one call when it takes
    over 10 s."""
    best = best_cpu = math.inf
    out = None
    for _ in range(max(1, repeats)):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        best_cpu = min(best_cpu, time.process_time() - c0)
        best = min(best, time.perf_counter() - t0)
        if best > 10.0:
            break
    return out, best, best_cpu


def run_study(specs: list[Spec], ref_te: np.ndarray, chk_te: np.ndarray, names: tuple, repeats: int = 3,
              mask: np.ndarray | None = None, progress=None, attrs: dict | None = None) -> xr.Dataset:
    """Run every spec (warm-up, then best of repeats), measure its TE error against ref_te
    (over ``mask`` of the samples, default all) -> dataset with dims (run, norm)."""
    mask = np.ones(ref_te.shape, bool) if mask is None else mask
    n = len(specs)
    err = np.full((n, 3), np.nan)
    wall = np.full(n, np.nan)
    cpu = np.full(n, np.nan)
    first = np.full(n, np.nan)
    steps = np.zeros(n, dtype=np.int64)
    status = []
    message = []
    warmed = set()
    for i, s in enumerate(specs):
        try:
            if s.warmup and s.method not in warmed:
                t0 = time.perf_counter()
                s.run()
                first[i] = time.perf_counter() - t0
                warmed.add(s.method)
            (te, nst, st, msg), best, best_cpu = _timed(s.run, repeats)
            steps[i] = nst
            if st in COMPLETED:       # inaccurate: completed, its error is what the study measures
                st = OK
                wall[i] = best
                cpu[i] = best_cpu
                err[i] = te_error_norms(te[mask], ref_te[mask])
                if not np.all(np.isfinite(err[i])):
                    st, msg = NONFINITE, "output not finite or incomplete"
            status.append("ok" if st == OK else "failed")
            message.append(msg)
        except Exception as e:            # a failed run stays in the dataset with its message
            status.append("failed")
            message.append(f"{type(e).__name__}: {e}")
        if progress:
            progress(i, s, err[i], wall[i], message[-1])
    e_chk = te_error_norms(chk_te[mask], ref_te[mask])
    run = np.arange(n)
    ds = xr.Dataset(
        {
            "te_error": (("run", "norm"), err, {"units": "um", "long_name": "TE error against the reference"}),
            "wall_time": ("run", wall, {"units": "s", "long_name": f"wall time, best of {repeats} after a warm-up run"}),
            "cpu_time": ("run", cpu, {"units": "s", "long_name": f"CPU time (user + system) of the process, best of "
                                                                  f"{repeats} after a warm-up run"}),
            "first_call_time": ("run", first, {"units": "s", "long_name": "wall time of the method's first call (numba compile included), NaN after the first run of a method"}),
            "steps": ("run", steps, {"units": "1", "long_name": "steps (static: Newton iterations over all angles)"}),
            "status": ("run", np.array(status, dtype=object), {"long_name": "ok or failed"}),
            "message": ("run", np.array(message, dtype=object), {"long_name": "solver or guard message"}),
        },
        coords={
            "run": ("run", run, {"long_name": "run index"}),
            "norm": ("norm", list(NORMS), {"long_name": "error norm: final sample, root mean square, largest magnitude"}),
            "method": ("run", np.array([s.method for s in specs], dtype=object), {"long_name": "solver"}),
            "step": ("run", np.array([s.step for s in specs]), {"units": "s", "long_name": "fixed time step (NaN: adaptive)"}),
            "rtol": ("run", np.array([s.rtol for s in specs]), {"units": "1", "long_name": "relative tolerance (NaN: fixed step)"}),
        },
        attrs={
            "reference": names[0],
            "cross_check": names[1],
            **{f"reference_difference_{k}_um": float(v) for k, v in zip(NORMS, e_chk)},
            **provenance(),
            "machine": machine(),
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            **(attrs or {}),
        },
    )
    return ds


def model_label(scene: Scene) -> str:
    """The model a study's scene runs, for titles: 'paper model' or '<coupling.model> model'."""
    m = scene.coupling_model
    return "paper model" if m == "none" else f"{m} model"


def dynamic_study(scene: Scene, model: Model, duration: float = 0.002, ramp_fraction: float = 0.5,
                  repeats: int = 3, progress=None, **spec_kw) -> xr.Dataset:
    case = dynamic_case(scene, duration, ramp_fraction)
    specs, dt_b = dynamic_specs(model, case, **spec_kw)
    ref, chk, names = dynamic_reference(model, case, dt_b)
    return run_study(specs, ref, chk, names, repeats, progress=progress, attrs={
        "title": f"work-precision, dynamic scene (DTE), {model_label(scene)}", "model": model_label(scene),
        "case": (f"driver 0 -> {case.speed:g} rad/s and load 0 -> {case.torque:g} N·m in {case.ramp * 1e3:g} ms, "
                 f"{case.duration * 1e3:g} ms in all (shortened window; the scene runs {scene.dynamic.duration:g} s "
                 f"with a {scene.dynamic.ramp_time * 1e3:g} ms ramp), TE every {case.output_step * 1e6:g} us"),
        "explicit_stability_step_s": dt_b, "duration_s": case.duration, "ramp_time_s": case.ramp,
        "scene": scene.to_toml()})


def static_study(scene: Scene, model: Model, rotation_deg: float = 6.0, repeats: int = 3, progress=None,
                 **spec_kw) -> xr.Dataset:
    case = static_case(scene, rotation_deg)
    specs, dt_b = static_specs(model, case, **spec_kw)
    ref, chk, names = static_reference(model, case)
    # the transient starts from rest: compare after its ramp and one ramp time of settling
    settle = case.speed * 1.5 * case.ramp
    mask = case.angles >= settle
    return run_study(specs, ref, chk, names, repeats, mask=mask, progress=progress, attrs={
        "title": f"work-precision, quasi-static scene (STE), {model_label(scene)}", "model": model_label(scene),
        "case": (f"STE under {case.torque:g} N·m over {math.degrees(case.rotation):g} deg of driver rotation "
                 f"every {math.degrees(case.angle_step):g} deg; transient: 0 -> {case.speed:g} rad/s and 0 -> "
                 f"{case.torque:g} N·m in {case.ramp * 1e3:g} ms, errors from {math.degrees(settle):.3g} deg on"),
        # a coupled model's transient runs at the production (implicit-damper) step bound
        "transient_step_bound_s" if model.coupled else "explicit_stability_step_s": dt_b, "scene": scene.to_toml()})

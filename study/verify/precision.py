"""Work-precision study: TE error against wall time for every solver of a scene.

Dynamic scene (DTE): every method integrates the same equations, those of the scipy peer
(`solver.peers.scipy_dynamics`: every tooth free, none frozen), over a shortened window (the paper's
0.2 s is out of reach of the scipy solvers) with the speed and torque ramps scaled to it:
  explicit   velocity Verlet at fractions of its stability step,
  implicit   HHT-alpha at multiples of that step, alpha = 0 and alpha < 0,
  Radau, LSODA  scipy stiff solvers at several relative tolerances,
plus ``explicit, active set``: the production path (idle teeth frozen rigid to their hub),
whose error also holds that model reduction.
Reference: DOP853 at rtol 1e-10; cross-check: Verlet at 1/32 of its stability step. Their
mutual difference is in the dataset attrs and on the plot; it must lie far below the errors.

Quasi-static scene (STE over a rotation of the driver): the static Newton solver at several
tolerances, and the paper's slow-ramp transient with the explicit and the implicit
integrators. Reference: static Newton at tol 1e-13; cross-check: `scipy.optimize.root` on the
plain-Python forces. The transient's error also holds its physical ringing (not a solver
error): it is measured on the angles after the ramp.

Errors: TE minus reference TE [um] on the common output grid, as norms ``final`` (last
sample), ``l2`` (root mean square over the samples) and ``linf`` (largest magnitude).
Wall time [s]: best of ``repeats`` runs after a warm-up run of each numba method (compile
time and the first call are timed apart, in ``first_call_time``); a run over 10 s is timed
once. A failed run keeps NaN errors and its message.

`lightgear precision [SCENE] [-o OUT.nc]` runs both for a scene (default: the paper example).
"""
from __future__ import annotations

import math
import os
import platform
import time
from dataclasses import dataclass

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.dynamics import at_driver_angles, simulate, slow_ramp_window
from solver.mbs.implicit import simulate_implicit
from solver.mbs.model import Model
from solver.mbs.stability import stable_time_step
from solver.mbs.statics import solve_static
from solver.peers.scipy_dynamics import simulate_explicit_all_teeth, simulate_scipy
from solver.peers.scipy_statics import solve_static_scipy
from study.report import results
from study.scene import Scene, load_scene

NORMS = ("final", "l2", "linf")


@dataclass(frozen=True)
class Spec:
    """One run of the study: method name, step [s] (fixed-step) or rtol [-] (adaptive), and
    the callable returning (TE [m] on the output grid, steps, status, message)."""
    method: str
    step: float
    rtol: float
    run: object
    warmup: bool = True      # False: nothing to compile (the scipy peer), no warm-up run


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
    """(result, best wall time [s]) of repeats calls; one call when it takes over 10 s."""
    best = math.inf
    out = None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
        if best > 10.0:
            break
    return out, best


def _dyn(res) -> tuple:
    return res.te, res.steps, res.status, res.message


# ------------------------------------------------------------------ dynamic scene

@dataclass(frozen=True)
class DynamicCase:
    """Loads of the shortened dynamic window (SI): the paper's 0 -> speed and 0 -> torque
    ramps, scaled to end at ``ramp`` [s], over ``duration`` [s], TE sampled every
    ``output_step`` [s]."""
    speed: float
    torque: float
    ramp: float
    duration: float
    output_step: float

    @property
    def loads(self) -> tuple:
        return self.speed, self.ramp, self.torque, self.ramp, self.duration


def dynamic_case(scene: Scene, duration: float = 0.002, ramp_fraction: float = 0.5,
                 output_step: float = 1e-5) -> DynamicCase:
    """The scene's dynamic loads over a window of ``duration`` [s], the ramps ending at
    ``ramp_fraction`` of it (the paper's 10 ms ramp of a 0.2 s run, scaled down)."""
    if not duration > 0:
        raise ValueError(f"duration: must be positive, got {duration}")
    if not 0 < ramp_fraction <= 1:
        raise ValueError(f"ramp_fraction: must lie in (0, 1], got {ramp_fraction}")
    d = scene.dynamic
    ramp = round(duration * ramp_fraction / output_step) * output_step
    return DynamicCase(d.speed, d.torque, ramp, duration, output_step)


def dynamic_specs(model: Model, case: DynamicCase, explicit_fractions=(1, 2, 4, 8),
                  implicit_multiples=(8, 4, 2, 1, 0.5), alphas=(0.0, -0.1),
                  rtols=(1e-3, 1e-5), scipy_methods=("Radau", "LSODA"), active_set: bool = True,
                  scipy_max_wall_time: float = 120.0) -> tuple[list[Spec], float]:
    """The runs of the dynamic study and the explicit stability step [s] they are scaled by.

    A scipy run taking longer than ``scipy_max_wall_time`` [s] stops and stays in the study
    as a failed run with its message."""
    dt_b, _w = stable_time_step(model, case.torque)
    L, o = case.loads, case.output_step
    specs = []
    for f in explicit_fractions:
        dt = dt_b / f
        specs.append(Spec("explicit", dt, math.nan,
                          lambda dt=dt: _dyn(simulate_explicit_all_teeth(model, *L, dt=dt, output_step=o))))
    if active_set:
        for f in explicit_fractions:
            dt = dt_b / f
            specs.append(Spec("explicit, active set", dt, math.nan,
                              lambda dt=dt: _dyn(simulate(model, *L, dt=dt, output_step=o))))
    for a in alphas:
        for k in implicit_multiples:
            dt = min(dt_b * k, o)
            specs.append(Spec(f"implicit alpha={a:g}", dt, math.nan,
                              lambda dt=dt, a=a: _dyn(simulate_implicit(model, *L, dt=dt, output_step=o,
                                                                        alpha=a, all_teeth=True))))
    for m in scipy_methods:
        for tol in rtols:
            specs.append(Spec(m, math.nan, tol,
                              lambda m=m, tol=tol: _dyn(simulate_scipy(model, *L, method=m, rtol=tol, output_step=o,
                                                                       max_wall_time=scipy_max_wall_time)),
                              warmup=False))
    return specs, dt_b


def dynamic_reference(model: Model, case: DynamicCase, dt_bound: float):
    """(reference TE [m], cross-check TE [m], names): DOP853 at rtol 1e-10 and Verlet at
    dt_bound/32 [s], both with every tooth free."""
    ref = simulate_scipy(model, *case.loads, method="DOP853", rtol=1e-10, output_step=case.output_step)
    chk = simulate_explicit_all_teeth(model, *case.loads, dt=dt_bound / 32, output_step=case.output_step)
    for r, name in ((ref, "DOP853 reference"), (chk, "explicit cross-check")):
        if r.status:
            raise RuntimeError(f"{name} failed: {r.message}")
    return ref.te, chk.te, ("scipy DOP853, rtol 1e-10, every tooth free",
                            f"explicit Verlet at dt = {dt_bound / 32 * 1e9:.4g} ns (1/32 of the stability step), every tooth free")


# ------------------------------------------------------------------ quasi-static scene

@dataclass(frozen=True)
class StaticCase:
    """The quasi-static analysis over ``rotation`` [rad] of the driver at ``angle_step`` [rad]:
    torque [N·m], and the slow-ramp transient's speed [rad/s] and ramp time [s]."""
    torque: float
    rotation: float
    angle_step: float
    speed: float
    ramp: float

    @property
    def angles(self) -> np.ndarray:
        n = int(math.floor(self.rotation / self.angle_step + 1e-9)) + 1
        return np.arange(n) * self.angle_step


def static_case(scene: Scene, rotation_deg: float = 6.0) -> StaticCase:
    """The scene's quasi-static analysis over ``rotation_deg`` [deg] (one mesh cycle is
    360/Z1 deg) instead of the scene's rotation."""
    qs = scene.quasi_static
    if not rotation_deg > 0:
        raise ValueError(f"rotation_deg: must be positive, got {rotation_deg}")
    return StaticCase(qs.torque, rotation_deg * units.DEG, qs.angle_step * units.DEG, qs.speed, qs.ramp_time)


def _transient_te(res, case: StaticCase) -> np.ndarray:
    """Transient TE [m] interpolated at the case's driver angles (NaN past the run's end)."""
    return at_driver_angles(res, case.speed, case.ramp, case.angles)[0]


def static_specs(model: Model, case: StaticCase, tols=(1e-2, 1e-4, 1e-6, 1e-8),
                 explicit_fractions=(1, 2, 4), implicit_multiples=(256, 64, 16, 4),
                 alphas=(0.0, -0.1)) -> tuple[list[Spec], float]:
    angles = case.angles
    specs = []
    for tol in tols:
        def run(tol=tol):
            r = solve_static(model, angles, case.torque, tol=tol, raise_on_failure=False)
            bad = int(np.sum(r.iterations < 0))
            return r.te, int(np.sum(np.abs(r.iterations))), int(bad > 0), f"not converged at {bad} angles" if bad else "ok"
        specs.append(Spec("static Newton", math.nan, tol, run))
    dt_b, _w = stable_time_step(model, case.torque)
    dt_out, t_end = slow_ramp_window(angles, case.angle_step, case.speed, case.ramp)
    L = (case.speed, case.ramp, case.torque, case.ramp, t_end)

    def transient(res):
        return _transient_te(res, case), res.steps, res.status, res.message
    for f in explicit_fractions:
        dt = dt_b / f
        specs.append(Spec("slow-ramp transient, explicit", dt, math.nan,
                          lambda dt=dt: transient(simulate(model, *L, dt=dt, output_step=dt_out))))
    for a in alphas:
        for k in implicit_multiples:
            dt = min(dt_b * k, dt_out)
            specs.append(Spec(f"slow-ramp transient, implicit alpha={a:g}", dt, math.nan,
                              lambda dt=dt, a=a: transient(simulate_implicit(model, *L, dt=dt, output_step=dt_out, alpha=a))))
    return specs, dt_b


def static_reference(model: Model, case: StaticCase):
    ref = solve_static(model, case.angles, case.torque, tol=1e-13)
    chk = solve_static_scipy(model, case.angles, case.torque)
    return ref.te, chk, ("static Newton (numba), tol 1e-13",
                         "scipy.optimize.root (MINPACK hybrd) on the plain-Python forces, xtol 1e-13")


# ------------------------------------------------------------------ the study

def run_study(specs: list[Spec], ref_te: np.ndarray, chk_te: np.ndarray, names: tuple, repeats: int = 3,
              mask: np.ndarray | None = None, progress=None, attrs: dict | None = None) -> xr.Dataset:
    """Run every spec (warm-up, then best of repeats), measure its TE error against ref_te
    (over ``mask`` of the samples, default all) -> dataset with dims (run, norm)."""
    mask = np.ones(ref_te.shape, bool) if mask is None else mask
    n = len(specs)
    err = np.full((n, 3), np.nan)
    wall = np.full(n, np.nan)
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
            (te, nst, st, msg), best = _timed(s.run, repeats)
            steps[i] = nst
            if st == 0:
                wall[i] = best
                err[i] = te_error_norms(te[mask], ref_te[mask])
                if not np.all(np.isfinite(err[i])):
                    st, msg = 1, "output not finite or incomplete"
            status.append("ok" if st == 0 else "failed")
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
            **results.provenance(),
            "machine": machine(),
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            **(attrs or {}),
        },
    )
    return ds


def dynamic_study(scene: Scene, model: Model, duration: float = 0.002, ramp_fraction: float = 0.5,
                  repeats: int = 3, progress=None, **spec_kw) -> xr.Dataset:
    case = dynamic_case(scene, duration, ramp_fraction)
    specs, dt_b = dynamic_specs(model, case, **spec_kw)
    ref, chk, names = dynamic_reference(model, case, dt_b)
    return run_study(specs, ref, chk, names, repeats, progress=progress, attrs={
        "title": "work-precision, dynamic scene (DTE)",
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
        "title": "work-precision, quasi-static scene (STE)",
        "case": (f"STE under {case.torque:g} N·m over {math.degrees(case.rotation):g} deg of driver rotation "
                 f"every {math.degrees(case.angle_step):g} deg; transient: 0 -> {case.speed:g} rad/s and 0 -> "
                 f"{case.torque:g} N·m in {case.ramp * 1e3:g} ms, errors from {math.degrees(settle):.3g} deg on"),
        "explicit_stability_step_s": dt_b, "scene": scene.to_toml()})


def cheapest(ds: xr.Dataset, target_um: float, norm: str = "linf"):
    """(method, step [s] or rtol, wall time [s]) of the fastest ok run with error <= target_um
    [um] in ``norm``; None when no run reaches it."""
    e = ds["te_error"].sel(norm=norm).values
    w = ds["wall_time"].values
    ok = np.isfinite(e) & (e <= target_um) & np.isfinite(w)
    if not ok.any():
        return None
    i = int(np.flatnonzero(ok)[np.argmin(w[ok])])
    setting = ds["step"].values[i] if np.isfinite(ds["step"].values[i]) else ds["rtol"].values[i]
    return str(ds["method"].values[i]), float(setting), float(w[i])


def table(ds: xr.Dataset) -> str:
    """The study as a text table: method, step/tolerance, errors [um], wall time [s], status."""
    lines = [f"{ds.attrs['title']}: {ds.attrs['case']}",
             f"  reference: {ds.attrs['reference']}; cross-check: {ds.attrs['cross_check']}; "
             f"their difference (linf) {ds.attrs['reference_difference_linf_um']:.2g} um",
             f"  {'method':42s} {'step/rtol':>10s} {'final um':>10s} {'l2 um':>10s} {'linf um':>10s} {'time s':>9s}  status"]
    for i in range(ds.sizes["run"]):
        step = ds["step"].values[i]
        setting = f"{step * 1e6:.4g} us" if np.isfinite(step) else f"{ds['rtol'].values[i]:.0e}"
        e = ds["te_error"].values[i]
        st = ds["status"].values[i]
        msg = "" if st == "ok" else f"  {ds['message'].values[i]}"
        lines.append(f"  {ds['method'].values[i]:42s} {setting:>10s} {e[0]:10.3g} {e[1]:10.3g} {e[2]:10.3g} "
                     f"{ds['wall_time'].values[i]:9.3g}  {st}{msg}")
    for target in (0.1, 0.01):
        c = cheapest(ds, target)
        lines.append(f"  cheapest for {target:g} um (linf): " + (f"{c[0]} at {setting_label(c[0], c[1])}, {c[2]:.3g} s"
                                                                 if c else "none of the runs"))
    return "\n".join(lines)


def setting_label(method: str, setting: float) -> str:
    """'dt 0.312 us' for a fixed-step method, 'rtol 1e-06' for an adaptive one or the static solver."""
    fixed = method.startswith(("explicit", "implicit", "slow-ramp"))
    return f"dt {setting * 1e6:.4g} us" if fixed else f"rtol {setting:g}"


def plot(ds: xr.Dataset, path, norm: str = "linf") -> None:
    """Log-log work-precision diagram: TE error [um] against wall time [s], one line per method,
    with a footer naming the machine, the versions and the reference."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 6))
    methods = list(dict.fromkeys(ds["method"].values))
    for m in methods:
        sel = (ds["method"].values == m)
        e = ds["te_error"].sel(norm=norm).values[sel]
        w = ds["wall_time"].values[sel]
        ok = np.isfinite(e) & np.isfinite(w) & (e > 0)
        if ok.any():
            order = np.argsort(w[ok])
            ax.loglog(w[ok][order], e[ok][order], "o-", label=m)
    d = ds.attrs.get(f"reference_difference_{norm}_um", float("nan"))
    if np.isfinite(d) and d > 0:
        ax.axhline(d, color="k", ls=":", lw=1, label="reference vs cross-check")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel(f"TE error, {norm} norm [um]")
    ax.set_title(ds.attrs.get("title", "work-precision"))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    footer = (f"{ds.attrs.get('case', '')}\nreference: {ds.attrs['reference']}; cross-check: {ds.attrs['cross_check']}\n"
              f"{ds.attrs['machine']}; {ds.attrs.get('software', '')}; {ds.attrs['date']}")
    fig.text(0.01, 0.005, footer, fontsize=6, va="bottom", wrap=True)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ------------------------------------------------------------------ CLI

def add_arguments(p):
    p.add_argument("scene", nargs="?", help="scene TOML (default: the embedded paper example)")
    p.add_argument("-o", "--output", default="results/work_precision.nc",
                   help="archive base name: writes BASE_dynamic.nc and BASE_static.nc with their plots (.png)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene field by its dotted path")
    p.add_argument("--duration", type=float, default=0.002, help="dynamic window [s] (default 0.002)")
    p.add_argument("--ramp-fraction", type=float, default=0.5, help="ramps end at this fraction of the window")
    p.add_argument("--rotation", type=float, default=6.0, help="quasi-static driver rotation [deg] (default 6)")
    p.add_argument("--repeats", type=int, default=3, help="timed repeats per run (best is kept)")
    p.add_argument("--only", choices=("dynamic", "static"), help="run only one of the two studies")


def main(args) -> int:
    from pathlib import Path

    from study.setup import build_scene_model
    scene = load_scene(args.scene, args.overrides)
    model = build_scene_model(scene)
    base = Path(args.output)
    base.parent.mkdir(parents=True, exist_ok=True)

    def progress(i, s, e, w, msg):
        setting = setting_label(s.method, s.step if math.isfinite(s.step) else s.rtol)
        print(f"  [{i + 1}] {s.method}, {setting}: linf {e[2]:.3g} um, {w:.3g} s  {'' if msg == 'ok' else msg}",
              flush=True)
    for kind in ("static", "dynamic"):
        if args.only and args.only != kind:
            continue
        print(f"{kind} study ...", flush=True)
        if kind == "dynamic":
            ds = dynamic_study(scene, model, args.duration, args.ramp_fraction, args.repeats, progress)
        else:
            ds = static_study(scene, model, args.rotation, args.repeats, progress)
        path = base.with_name(f"{base.stem}_{kind}.nc")
        results.write_netcdf(ds, path)
        plot(ds, path.with_suffix(".png"))
        print(table(ds))
        print(f"  archive: {path}\n  plot: {path.with_suffix('.png')}", flush=True)
    return 0


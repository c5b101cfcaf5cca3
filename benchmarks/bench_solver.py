"""Solver speed on the Table 1 pair: warm STE, the paper's dynamic case, compile and cache
start, and the plain numpy + scipy (LSODA) implementation of the same equations.

Targets (2-core x86_64): STE over 120 deg at 0.1 deg (1201 angles) < 0.1 s warm; the paper's
dynamic case (0.2 s at 100 rad/s, solid and lightened) < 1 s on one core, with its TE error
against a tight reference; first-call compile < 15 s (fresh numba cache, new process; the default
and the paper model, each its own row); next process start with the cache < 2 s; and the ratio
to scipy's LSODA per simulated second.
Run: python benchmarks/bench_solver.py [--quick]   (writes results/benchmarks/solver.csv)
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import common  # noqa: I001  (first: pins BLAS to one thread before numpy loads)
import numpy as np
from common import PAPER_DYNAMIC, ROOT, SHORT_DYNAMIC, best_of

# one process: first STE and first dynamic run with whatever numba cache NUMBA_CACHE_DIR holds, of
# the coupling model named by the first argument ('auto', the default: the compliance model, whose
# kernels couple the teeth through the body; 'paper': the plain kernels)
FIRST_CALL = r'''
import json, sys, time
c0, t0 = time.process_time(), time.perf_counter()
import numpy as np
from study.scene import default_scene
from study.scene_model import build_scene_model
from solver.mbs.statics import solve_static
from solver.mbs.dynamics import simulate
m = build_scene_model(default_scene().solid(gears=(2,)).replace(**{"coupling.model": sys.argv[1]}))
c1, t1 = time.process_time(), time.perf_counter()
solve_static(m, np.radians(np.arange(0.0, 1.0, 0.1)), 50.0)
c2, t2 = time.process_time(), time.perf_counter()
simulate(m, 100.0, 1e-4, 50.0, 1e-4, 2e-4)
c3, t3 = time.process_time(), time.perf_counter()
print(json.dumps(dict(imports=t1 - t0, static=t2 - t1, dynamic=t3 - t2, total=t3 - t0,
                      cpu_imports=c1 - c0, cpu_static=c2 - c1, cpu_dynamic=c3 - c2, cpu_total=c3 - c0)))
'''


FIRST_CALL_MODELS = (("auto", "default model (compliance)"), ("paper", "paper model"))


def run_first_call(cache_dir: str, model: str = "auto") -> tuple[dict, float]:
    """Figures of one fresh process [s] and its wall time seen from outside (with start-up);
    model: the scene's coupling.model ('auto': the default)."""
    import json
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir, PYTHONPATH=str(ROOT))
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", FIRST_CALL, model], cwd=ROOT, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if out.returncode:
        raise RuntimeError(out.stderr)
    return json.loads(out.stdout.strip().splitlines()[-1]), wall


def main(argv=None) -> int:
    args, rep = common.quick_options(__doc__.splitlines()[0], "fewer repeats, no lightened scene", argv)
    rows = _first_call_rows()
    kinds = ["solid"] if args.quick else ["solid", "lightened"]
    full_cpu = {}
    for kind in kinds:
        rows += _paper_rows(kind, rep, full_cpu)
    window, tls, tim = _window_rows(rep)
    rows += window
    common.add_ratios(rows)
    common.write_table("solver", "Solver speed, Table 1 pair (s; best of N; ratio on CPU time to the fastest in the case)", rows)
    print(f"LSODA / lightgear on the same window: {tls['cpu_min_s'] / tim['cpu_min_s']:.0f}x; LSODA per simulated second / "
          f"lightgear's on the full 0.2 s run: {tls['cpu_min_s'] / SHORT_DYNAMIC[-1] / (full_cpu['solid'] / PAPER_DYNAMIC[-1]):.0f}x")
    return 0


def _first_call_rows() -> list:
    """The first call in a process with a fresh numba cache (compile), and the next ones."""
    rows = []
    # --- compile and cache start (subprocesses, so nothing is warm here)
    for model, label in FIRST_CALL_MODELS:
        with tempfile.TemporaryDirectory() as cache:
            cold, cold_wall = run_first_call(cache, model)
            if model == "auto":
                warm = [run_first_call(cache) for _ in range(3)]
        rows.append(dict(case=f"first call, fresh numba cache, {label}", method="lightgear (compile)",
                         wall_min_s=cold["total"], cpu_min_s=cold["cpu_total"], repeats=1,
                         note=f"target < 15 s; whole process CPU: imports and model build (with the statics kernels) "
                              f"{cold['cpu_imports']:.1f} s, STE {cold['cpu_static']:.1f} s, dynamic {cold['cpu_dynamic']:.1f} s; "
                              f"{cold_wall:.1f} s wall from outside"))
    walls = [w for _d, w in warm]
    rows.append(dict(case="next process, numba cache", method="lightgear (cached)", wall_min_s=min(walls),
                     wall_median_s=float(np.median(walls)), cpu_min_s=min(d["cpu_total"] for d, _w in warm), repeats=3,
                     note="target < 2 s; whole process from outside: start-up, imports, cache load, 10-angle STE, "
                          "0.2 ms dynamic (cpu: inside the process)"))
    return rows


def _paper_rows(kind: str, rep: int, full_cpu: dict) -> list:
    """The warm STE and the paper's dynamic case of the ``kind`` pair (solid, lightened); the
    default run's CPU time [s] into ``full_cpu``."""
    from solver.mbs.dynamics import simulate
    from solver.mbs.stability import stable_time_step
    from solver.mbs.statics import solve_static
    from study.scene_model import static_angles
    rows = []
    m = common.model(kind, "paper")      # the solver's speed on the paper's model (the peers' equations)
    sc = common.scene(kind, "paper")
    # --- warm STE, 120 deg at 0.1 deg
    ang = static_angles(sc)
    torque = sc.quasi_static.torque
    solve_static(m, ang[:5], torque)
    tim, st = best_of(lambda: solve_static(m, ang, torque), rep + 2)
    tight = solve_static(m, ang, torque, tol=1e-13)
    rows.append(dict(case=f"STE {ang.size} angles, {kind}", method="lightgear solve_static", **tim,
                     error_um=float(np.max(np.abs(st.te - tight.te))) * 1e6,
                     note="target < 0.1 s; error vs Newton at tol 1e-13"))
    # --- paper dynamic case
    speed, sramp, tq, tramp, dur = PAPER_DYNAMIC
    dt, _w = stable_time_step(m, tq)
    simulate(m, speed, sramp, tq, tramp, 1e-3, dt=dt)
    ref = simulate(m, speed, sramp, tq, tramp, dur, dt=dt / 8, phi_quiet=1e-9, implicit_dampers=False)
    case = f"dynamic 0.2 s at 100 rad/s, {kind}"
    simulate(m, speed, sramp, tq, tramp, 1e-3)
    runs = ((dict(), "default"), (dict(dt=dt, phi_quiet=1e-9, implicit_dampers=False), "all explicit, phi_quiet 1e-9 rad"))
    for kw, label in runs:
        tim, dy = best_of(lambda: simulate(m, speed, sramp, tq, tramp, dur, **kw), 3)
        err = float(np.max(np.abs(dy.te - ref.te))) * 1e6
        if label == "default":
            full_cpu[kind] = tim["cpu_min_s"]
        rows.append(dict(case=case, method=f"lightgear explicit ({label})", **tim, error_um=err,
                         note=f"target < 1 s; dt {dy.dt * 1e6:.3g} us, {dy.steps} steps, up to {dy.max_active_teeth} "
                              f"active teeth; {tim['cpu_min_s'] / dur:.2f} x real time; error vs the all-explicit run at dt/8"))
    from solver.peers.scipy_dynamics import simulate_explicit_all_teeth
    tim, da = best_of(lambda: simulate_explicit_all_teeth(m, speed, sramp, tq, tramp, dur, dt=dt), 1)
    act = simulate(m, speed, sramp, tq, tramp, dur, dt=dt, phi_quiet=1e-9, implicit_dampers=False)
    rows.append(dict(case=case, method="lightgear explicit, all teeth active", **tim,
                     error_um=float(np.max(np.abs(act.te - da.te))) * 1e6,
                     note="the full model (no tooth frozen); error column = what freezing idle teeth changes "
                          "(default set vs this, same step)"))
    tim, _d = best_of(lambda: simulate(m, speed, sramp, tq, tramp, dur), 1)
    rows.append(dict(case=case, method="lightgear simulate() incl. step estimate", **tim,
                     note="as `lightgear run` calls it (dt from the eigenvalues at 12 positions)"))
    return rows


def _window_rows(rep: int) -> tuple:
    """(rows, scipy LSODA timing, lightgear timing) of the short dynamic window, lightgear
    against plain numpy + scipy LSODA."""
    from solver.mbs.dynamics import simulate
    from solver.mbs.stability import stable_time_step
    from solver.peers.scipy_dynamics import simulate_explicit_all_teeth, simulate_scipy
    rows = []
    # --- plain numpy + scipy LSODA on a short window, against lightgear on the same window
    m = common.model("solid", "paper")     # scipy integrates the paper's per-tooth springs
    dt, _w = stable_time_step(m, 50.0)
    win = SHORT_DYNAMIC
    ref = simulate(m, *win, dt=dt / 8)
    ref_all = simulate_explicit_all_teeth(m, *win, dt=dt / 8)
    tim, dy = best_of(lambda: simulate(m, *win, dt=dt), rep, warmup=True)
    tls, ls = best_of(lambda: simulate_scipy(m, *win, method="LSODA", rtol=1e-4), 1)
    case = f"dynamic {win[-1] * 1e3:.1f} ms window, solid"
    model_err = float(np.max(np.abs(dy.te - ref_all.te))) * 1e6
    rows.append(dict(case=case, method="lightgear explicit", **tim, error_um=float(np.max(np.abs(dy.te - ref.te))) * 1e6,
                     note=f"{tim['cpu_min_s'] / win[-1]:.3g} s per simulated s; error vs dt/8; {model_err:.3g} um vs "
                          f"the all-teeth model at dt/8 (freezing idle teeth in this violent ramp)"))
    rows.append(dict(case=case, method="numpy+scipy LSODA rtol 1e-4", **tls,
                     error_um=float(np.max(np.abs(ls.te - ref_all.te))) * 1e6,
                     note=f"{tls['cpu_min_s'] / win[-1]:.4g} s per simulated s; {ls.steps} steps, {ls.nfev} f-evals, "
                          f"{ls.njev} Jacobians; every tooth free: error vs the all-teeth explicit solver at dt/8"))
    return rows, tls, tim


if __name__ == "__main__":
    sys.exit(main())

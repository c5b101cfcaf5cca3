"""The targets of the speed work, measured in one run, each with met / not met.

* the paper's dynamic case (0.2 s at 100 rad/s, 50 N m, study/scenes/paper.toml loads), solid
  and lightened, on the paper's model (the peers' equations; bench_coupling.py gives the default's): <= 0.3 s CPU on one core, warm (`simulate` as `lightgear run` calls it, with
  its default step and active set);
* its max TE error <= 0.01 um against a tight reference: the all-teeth explicit model (every
  tooth free, every force explicit) at 1/8 of the all-explicit stability step;
* first-call compile <= 10 s CPU (fresh numba cache, new process: imports, the model build, a
  10-angle STE and a 0.2 ms dynamic run, as bench_solver; all of the process's CPU time), one row
  for the default model (compliance: the kernels that couple the teeth through the body) and one
  for the paper model (the plain kernels);
* the standard sensitivity study (study/scenes/sensitivity.toml) from empty FE and numba caches
  <= 60 s wall on 2 local workers (left out with --quick: it takes minutes);
* a cheap study (the bench_large_study scene, 2,000 points; 200 with --quick) on 2 local
  workers: <= 0.05 s CPU per point, all the process tree's CPU over the points;
* the rows of the 16-core machine (the standard study's cold cluster and parallel efficiency,
  the cheap study on 16 workers) are printed as not measured on a smaller machine.
The paper-case rows carry the ratio of the peers' CPU time per simulated second to
lightgear's: numpy + scipy LSODA (rtol 1e-4, solver/peers/scipy_dynamics.py) and Exudyn's
velocity Verlet at the all-explicit stability step (benchmarks/peers/exudyn_pair.py), both
measured in this run on the short window of bench_peers (1.5 ms) and scaled to 0.2 s.
Run: python benchmarks/bench_targets.py [--quick]   (writes results/benchmarks/targets.csv)
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

COLUMNS = ("target", "measured", "unit", "limit", "met", "x_scipy", "x_exudyn", "note")


def peers_per_second(m) -> dict:
    """CPU seconds per simulated second of the scipy (LSODA rtol 1e-4) and Exudyn (velocity
    Verlet at the all-explicit stability step) peers on the short window, every tooth free."""
    from peers.exudyn_pair import simulate_exudyn

    from solver.mbs.dynamics import Drive
    from solver.mbs.stability import stable_time_step
    from solver.peers.scipy_dynamics import simulate_scipy
    win = SHORT_DYNAMIC
    dt, _w = stable_time_step(m, win[2])
    ts, _r = best_of(lambda: simulate_scipy(m, *win, method="LSODA", rtol=1e-4), 1)
    te, _r = best_of(lambda: simulate_exudyn(m, Drive(*win), dt=dt, solver="VelocityVerlet"), 1)
    return dict(scipy=ts["cpu_min_s"] / win[-1], exudyn=te["cpu_min_s"] / win[-1])


def paper_rows(kind: str, rep: int) -> list[dict]:
    from solver.mbs.dynamics import simulate
    from solver.mbs.stability import stable_time_step
    from solver.peers.scipy_dynamics import simulate_explicit_all_teeth
    m = common.model(kind, "paper")     # the peers integrate the paper's per-tooth springs
    speed, sramp, tq, tramp, dur = PAPER_DYNAMIC
    simulate(m, speed, sramp, tq, tramp, 1e-3)
    tim, res = best_of(lambda: simulate(m, speed, sramp, tq, tramp, dur), rep)
    dt_ex, _w = stable_time_step(m, tq)
    ref = simulate_explicit_all_teeth(m, speed, sramp, tq, tramp, dur, dt=dt_ex / 8)
    err = float(np.max(np.abs(res.te - ref.te))) * 1e6
    peer = peers_per_second(m)
    per_s = tim["cpu_min_s"] / dur
    note = (f"dt {res.dt * 1e6:.4g} us, {res.steps} steps, up to {res.max_active_teeth} active teeth; best of {rep}, "
            f"median wall {tim['wall_median_s']:.3g} s")
    ratios = dict(x_scipy=peer["scipy"] / per_s, x_exudyn=peer["exudyn"] / per_s)
    return [dict(target=f"paper dynamic case 0.2 s, {kind}, paper model: CPU", measured=tim["cpu_min_s"], unit="s", limit=0.3,
                 met=tim["cpu_min_s"] <= 0.3, note=note, **ratios),
            dict(target=f"paper dynamic case 0.2 s, {kind}, paper model: max TE error", measured=err, unit="um", limit=0.01,
                 met=err <= 0.01, note=f"vs the all-teeth, all-explicit model at dt {ref.dt * 1e6:.3g} us "
                                       f"(1/8 of its stability step)")]


def compile_rows() -> list[dict]:
    """The first-call compile of the default model (compliance: its kernels couple the teeth
    through the body) and of the paper model (the plain kernels), each in a fresh process."""
    from bench_solver import FIRST_CALL_MODELS, run_first_call
    rows = []
    for model, label in FIRST_CALL_MODELS:
        common.model("solid", model)        # its FE (maps, compliance) in the disk cache: the row is the compile
        with tempfile.TemporaryDirectory() as cache:
            cold, wall = run_first_call(cache, model)
        # the whole process: the model build compiles the statics kernels (the damping ratio's modal
        # analysis solves a static equilibrium), so the STE call alone no longer shows them
        cpu = cold["cpu_total"]
        rows.append(dict(target=f"first-call compile, fresh numba cache, {label}", measured=cpu, unit="s CPU",
                         limit=10.0, met=cpu <= 10.0,
                         note=f"whole first process: imports and model build {cold['cpu_imports']:.1f} s, 10-angle STE "
                              f"{cold['cpu_static']:.1f} s, 0.2 ms dynamic {cold['cpu_dynamic']:.1f} s; {wall:.1f} s wall "
                              f"from outside; load {load()}"))
    return rows


def sensitivity_row() -> dict:
    """The standard sensitivity study in a fresh process, empty FE and numba caches, 2 workers."""
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, LIGHTGEAR_CACHE=os.path.join(tmp, "cache"),
                   NUMBA_CACHE_DIR=os.path.join(tmp, "numba"), PYTHONPATH=str(ROOT))
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "workflows.sensitivity_sweep", "-o", os.path.join(tmp, "s.nc"),
                              "--workers", "2", "--no-progress"], cwd=ROOT, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
    ok = out.returncode == 0
    return dict(target="standard sensitivity study, empty caches, 2 workers", measured=wall, unit="s wall", limit=60.0,
                met=ok and wall <= 60.0, note=("" if ok else f"FAILED (exit {out.returncode}); ") + f"load {load()}")


CHEAP_STUDY = """
import sys, time
sys.path.insert(0, "benchmarks")
from bench_large_study import large_study
from study.sweep.engine import run_sweep
res = run_sweep(large_study({num}, 50.0, 150.0), {out!r}, workers=2, progress=False)
print(res.points)
"""


def cheap_study_row(speeds: int) -> dict:
    """CPU per point of the bench_large_study scene (2 x ``speeds`` points) on 2 local workers,
    warm numba cache: all the CPU of the process tree (client, scheduler, workers: their start
    and imports included) over the points."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    with tempfile.TemporaryDirectory() as tmp:
        # a 4-point study first, not measured: every kernel the study runs in the numba cache
        # (a cache filled by other scenes may lack some, which each worker would then compile)
        subprocess.run([sys.executable, "-c", CHEAP_STUDY.format(num=2, out=os.path.join(tmp, "w.nc"))],
                       cwd=ROOT, env=env, capture_output=True, text=True)
        before = os.times()
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", CHEAP_STUDY.format(num=speeds, out=os.path.join(tmp, "c.nc"))],
                             cwd=ROOT, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = os.times()
    ok = out.returncode == 0
    n = int(out.stdout.split()[-1]) if ok else 2 * speeds
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    per = cpu / n
    return dict(target=f"cheap study ({n} points, bench_large_study scene): CPU per point, 2 workers", measured=per,
                unit="s CPU", limit=0.05, met=ok and per <= 0.05,
                note=("" if ok else f"FAILED (exit {out.returncode}); ") +
                     f"{cpu:.1f} s CPU in all (worker start and imports included), {wall:.1f} s wall, "
                     f"{n / wall:.1f} points/s; load {load()}")


NO_16 = "not measured (no 16-core machine was at hand for it)"
SIXTEEN_CORE_ROWS = [
    dict(target="standard study, FE cache warm, empty numba cache, 16 workers", unit="s wall",
         note="target: <= the warm-cache study + one compile"),
    dict(target="standard study, numba cache warm, 16 / 8 / 2 workers", unit="parallel efficiency",
         limit=0.7, note="target: >= 70 % parallel efficiency at 16 workers"),
    dict(target="cheap study (2000 points), 16 workers", unit="s CPU", limit=0.05,
         note="CPU per point: measured above on 2 workers"),
]


def load() -> str:
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def main(argv=None) -> int:
    args, rep = common.quick_options(__doc__.splitlines()[0], "no sensitivity study (minutes)", argv)
    load0 = load()
    rows = []
    for kind in ("solid", "lightened"):
        rows += paper_rows(kind, rep)
    rows += compile_rows()
    if not args.quick:
        rows.append(sensitivity_row())
    rows.append(cheap_study_row(100 if args.quick else 1000))
    for r in rows:
        r["met"] = "met" if r["met"] else "not met"
    rows += [dict(r, measured=None, met=NO_16) for r in SIXTEEN_CORE_ROWS]
    common.write_table("targets", f"Speed targets (load average {load0} at the start, {load()} at the end; CPU time "
                                  "by process_time)", rows, columns=COLUMNS)
    return 0


if __name__ == "__main__":
    sys.exit(main())

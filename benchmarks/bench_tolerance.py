"""Tolerance studies (`study/scenes/tolerance.toml`): what a sampled build costs.

  statics     1000 builds of the lightened paper pair with tip reliefs (classes 5 and 7, 500
              draws each of pitch set, runout and reliefs, a plain Sobol sample), STE peak-to-peak
              only, on a 2-worker LocalCluster from warm caches: wall time, the builds' own
              compute (sum of `wall_time`), and the study's overhead per build. target < 300 s
  revolution  one build's statics over the paper's 120 deg (no errors) and over the driver
              revolution that a gear with errors needs, and how that time splits (model and
              modes, statics, the rest of `run_point`)
  dynamic     one build's dynamic run (0.2 s at 100 rad/s, DTE outputs), in process
The machine may be shared with other jobs: the load average (1 min) is sampled every 5 s
during each part and its mean and range printed beside each figure.
Run: python benchmarks/bench_tolerance.py [--only statics|revolution|dynamic] [--builds 1000]
(report on stdout and in results/benchmarks/tolerance.txt)
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout, not another installed copy

import numpy as np  # noqa: E402

STUDY = ROOT / "study" / "scenes" / "tolerance.toml"


class LoadMonitor:
    """The 1-minute load average every ``every`` s while the block runs."""

    def __init__(self, every: float = 5.0):
        self.every, self.values, self._stop = every, [], threading.Event()

    def __enter__(self):
        self.values.append(os.getloadavg()[0])
        self._t = threading.Thread(target=self._run, daemon=True)
        self._t.start()
        return self

    def _run(self):
        while not self._stop.wait(self.every):
            self.values.append(os.getloadavg()[0])

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()
        self.values.append(os.getloadavg()[0])

    def __str__(self):
        v = np.array(self.values)
        return f"load {v.mean():.1f} (min {v.min():.1f}, max {v.max():.1f}) on {os.cpu_count()} cores"


def tolerance_study(builds: int, outputs: list[str], design: str = "plain"):
    """tolerance.toml with ``builds`` // 2 draws a class (plain design) and only ``outputs``."""
    import tomllib

    from study.sweep.grid import dumps_study, loads_study
    raw = tomllib.loads(STUDY.read_text())
    raw["sample"]["size"] = builds // len(raw["grid"]["gear1.errors.grade"])
    raw["sample"]["design"] = design
    raw["outputs"] = {"scalars": outputs}
    raw["title"] = "tolerance benchmark"
    return loads_study(dumps_study(raw), STUDY.parent)


def statics(builds: int, report) -> None:
    from study.sweep.engine import run_point, run_sweep
    st = tolerance_study(builds, ["ste_p2p"])
    t0 = time.perf_counter()
    points = st.points()
    t_points = time.perf_counter() - t0
    run_point(points[0].scene, st.outputs)            # this process: imports, kernels, FE map from disk
    with tempfile.TemporaryDirectory() as tmp, LoadMonitor() as load:
        t0 = time.perf_counter()
        res = run_sweep(st, Path(tmp) / "statics.nc", workers=2, progress=False)
        wall = time.perf_counter() - t0
    ds = res.dataset
    compute = float(ds["wall_time"].sum())
    n = int(ds["status"].size)
    ok = int((ds["status"] == 1).sum())
    per = compute / n
    over = (2 * wall - compute) / n
    report(f"statics: {n} builds ({ok} ok) on 2 workers in {wall:.0f} s wall ({load}); "
           f"scenes built and checked on the client in {t_points:.1f} s")
    report(f"  a build's own compute (run_point) {per:.3f} s mean, {compute:.0f} s in all; "
           f"study overhead {over:.3f} s a build (2 x wall - compute, includes worker start and the "
           f"first build's kernel load on each worker) = {over / per:.2f} x the build")
    report(f"  ste_p2p class 5: median {float(ds['ste_p2p'].isel(gear1_errors_grade=0).median()):.2f} um, "
           f"class 7: {float(ds['ste_p2p'].isel(gear1_errors_grade=1).median()):.2f} um")


def revolution(report) -> None:
    import study
    from study.sweep.engine import run_point
    st = tolerance_study(16, ["ste_p2p"])
    scene = st.points()[3].scene
    base = st.base_scene()
    run_point(scene, st.outputs)
    for what, sc in (("paper's 120 deg, no errors", base), ("one driver revolution, with errors", scene)):
        with LoadMonitor() as load:
            best = {}
            for _ in range(5):
                t0 = time.perf_counter()
                ds = study.run_scene(sc, static=True, dynamic=False)
                total = time.perf_counter() - t0
                r = run_point(sc, st.outputs)
                parts = {"statics": ds.attrs["wall_time_static_s"], "modes": ds.attrs["wall_time_modes_s"],
                         "run_scene": total, "run_point": r["wall_time"]}
                best = {k: min(v, best.get(k, np.inf)) for k, v in parts.items()}
        report(f"revolution: {what}: {ds.sizes['angle']} angles; best of 5: statics {best['statics']:.3f} s, "
               f"modes {best['modes']:.3f} s, run_scene {best['run_scene']:.3f} s, run_point {best['run_point']:.3f} s "
               f"({load})")


def dynamic(report) -> None:
    from study.sweep.engine import run_point
    st = tolerance_study(16, ["dte_rms", "dte_p2p", "amp_mesh_order", "ste_p2p"])
    points = st.points()
    run_point(points[0].scene, st.outputs)
    times = []
    with LoadMonitor() as load:
        for p in points[1:4]:
            r = run_point(p.scene, st.outputs)
            times.append(r["wall_time"])
    report(f"dynamic: a build with statics and 0.2 s of DTE at 100 rad/s: {np.mean(times):.2f} s mean of 3 "
           f"({', '.join(f'{t:.2f}' for t in times)} s), in process ({load})")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", choices=("statics", "revolution", "dynamic"))
    p.add_argument("--builds", type=int, default=1000)
    args = p.parse_args(argv)
    out = ROOT / "results" / "benchmarks" / "tolerance.txt"
    out.parent.mkdir(parents=True, exist_ok=True)

    def report(line):
        print(line, flush=True)
        with open(out, "a") as f:
            f.write(line + "\n")
    report(f"# {time.strftime('%Y-%m-%d %H:%M:%S')} bench_tolerance")
    for name, fn in (("revolution", lambda: revolution(report)), ("dynamic", lambda: dynamic(report)),
                     ("statics", lambda: statics(args.builds, report))):
        if args.only in (None, name):
            fn()
    return 0


if __name__ == "__main__":
    sys.exit(main())

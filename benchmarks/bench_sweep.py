"""Parametric sweeps: cost of the study machinery, dask scaling, memory, and the standard study.

  overhead    per-point overhead of run_sweep (in process, and on a warm 1-worker dask cluster)
              against the point's own compute, paper scene (Table 1, FE springs cached),
              dynamic outputs only.                                          target < 5 %
  scaling     throughput of 8 points (paper solid pair, 50 ms of DTE) on 1 and 2 workers of a
              warm LocalCluster.                                             target >= 1.8x
  memory      peak resident memory (driver + scheduler + 2 workers) of a 256-point sweep of a
              cheap scene (20-tooth pair) with its STE, DTE and spectrum curves. target < 4 GB
  sensitivity projected wall time of study/scenes/sensitivity.toml on 2 workers from measured
              parts: a cold FE spring map of a holed body and of a hole-free webbed body, and a
              point's static + dynamic compute (`--full` runs the whole study instead).
The machine may be shared with other jobs: the load average is printed with each figure.
Run: python benchmarks/bench_sweep.py [--full]  (table on stdout, results/benchmarks/sweep.csv)
"""
from __future__ import annotations

import csv
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout, not another installed copy

import numpy as np  # noqa: E402

from study.sweep.engine import dask_client, run_point, run_sweep  # noqa: E402
from study.sweep.grid import loads_study  # noqa: E402
from study.sweep.outputs import SCALARS  # noqa: E402

DYNAMIC = tuple(k for k in SCALARS if not k.startswith("ste"))
SOLID = '"gear2.body.holes" = 0\n"gear2.body.web_thickness" = 17.0\n'
CHEAP = ('"gear1.teeth" = 20\n"gear2.teeth" = 20\n'
         '"gear1.body" = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0}\n'
         '"gear2.body" = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0, holes = 0, web_thickness = 17.0}\n'
         '"quasi_static" = {rotation = 6.0, angle_step = 0.5}\n"dynamic" = {duration = 0.01, ramp_time = 0.002}\n')


def load() -> str:
    return "load %.1f" % os.getloadavg()[0]


def study(scene: str, grid: str, outputs: str) -> object:
    return loads_study(f'title = "bench"\n[scene]\n{scene}\n[grid]\n{grid}\n[outputs]\n{outputs}\n')


def speeds(n: int, start: float = 100.0) -> str:
    return '"dynamic.speed" = [' + ", ".join(f"{start + i:.1f}" for i in range(n)) + "]"


def overhead(tmp: Path) -> list[dict]:
    dyn = "scalars = [" + ", ".join(f'"{k}"' for k in DYNAMIC) + "]"
    n = 4
    t0 = time.perf_counter()  # imports (xarray backends, netCDF4, tqdm), FE map from disk, numba: once
    run_sweep(study("", speeds(1, 90.0), dyn), tmp / "w0.nc", workers=0, progress=False)
    start = time.perf_counter() - t0
    rows = []
    st = study("", speeds(n), dyn)
    t0 = time.perf_counter()
    res = run_sweep(st, tmp / "o0.nc", workers=0, progress=False)
    wall = time.perf_counter() - t0
    comp = float(res.dataset["wall_time"].sum())
    rows.append(dict(figure="overhead in process", value=100 * (wall - comp) / comp, unit="% of compute", target="< 5",
                     note=f"{(wall - comp) / n:.3f} s per point (archive write included), point compute {comp / n:.2f} s; "
                          f"first sweep in a process {start:.1f} s; {load()}"))
    with dask_client(None, 1) as client:
        addr = client.scheduler.address
        t0 = time.perf_counter()
        run_sweep(study("", speeds(1, 95.0), dyn), tmp / "w.nc", scheduler=addr, progress=False)
        first = time.perf_counter() - t0
        st = study("", speeds(n, 110.0), dyn)
        t0 = time.perf_counter()
        res = run_sweep(st, tmp / "o1.nc", scheduler=addr, progress=False)
        wall = time.perf_counter() - t0
    comp = float(res.dataset["wall_time"].sum())
    rows.append(dict(figure="overhead on dask (1 warm worker)", value=100 * (wall - comp) / comp, unit="% of compute",
                     target="< 5", note=f"{(wall - comp) / n:.3f} s per point; first point on a fresh worker "
                                       f"{first:.1f} s (imports, numba cache, FE cache); {load()}"))
    return rows


def scaling(tmp: Path) -> list[dict]:
    out = {}
    for n in (1, 2):
        with dask_client(None, n) as client:
            addr = client.scheduler.address
            run_sweep(study(SOLID + '"dynamic.duration" = 0.05', speeds(2 * n, 60.0), "scalars = [\"dte_rms\"]"),
                      tmp / f"w{n}.nc", scheduler=addr, progress=False)  # warm every worker
            st = study(SOLID + '"dynamic.duration" = 0.05', speeds(8), "scalars = [\"dte_rms\"]")
            t0 = time.perf_counter()
            run_sweep(st, tmp / f"s{n}.nc", scheduler=addr, progress=False)
            out[n] = 8 / (time.perf_counter() - t0)
    return [dict(figure="throughput 1 worker", value=out[1], unit="points/s", target="", note=load()),
            dict(figure="throughput 2 workers", value=out[2], unit="points/s", target="", note=load()),
            dict(figure="speed-up 2 vs 1 worker", value=out[2] / out[1], unit="x", target=">= 1.8",
                 note=f"{os.cpu_count()} cores; {load()}")]


MEMORY = '''
import sys; sys.path.insert(0, {root!r})
from study.sweep.grid import loads_study
from study.sweep.engine import run_sweep
text = """title = "memory"
[scene]
{cheap}
[grid]
"dynamic.speed" = {{start = 50.0, stop = 200.0, num = 16}}
"gear2.spring.k_phi" = {{start = 0.8e6, stop = 1.3e6, num = 16}}
[outputs]
curves = ["ste", "dte", "dte_amplitude"]
"""
r = run_sweep(loads_study(text), {out!r}, workers=2, progress=False)
print(r.computed, r.wall_time)
'''


def memory(tmp: Path) -> list[dict]:
    import psutil
    code = MEMORY.format(root=str(ROOT), cheap=CHEAP, out=str(tmp / "m.nc"))
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, cwd=ROOT)
    peak = 0
    p = psutil.Process(proc.pid)
    while proc.poll() is None:
        try:
            tree = [p] + p.children(recursive=True)
            peak = max(peak, sum(q.memory_info().rss for q in tree if q.is_running()))
        except psutil.Error:
            pass
        time.sleep(0.1)
    n, wall = proc.stdout.read().split()
    return [dict(figure="peak memory, 256-point sweep", value=peak / 2**30, unit="GiB", target="< 4",
                 note=f"{n} points computed in {float(wall):.0f} s on 2 workers, curves ste/dte/spectrum; {load()}")]


def sensitivity(tmp: Path, full: bool) -> list[dict]:
    from workflows.sensitivity_sweep import STUDY, sensitivity_study
    st = sensitivity_study(STUDY)
    n_points = int(np.prod(st.shape))
    if full:
        t0 = time.perf_counter()
        res = run_sweep(st, tmp / "sensitivity.nc", workers=2, progress=True)
        return [dict(figure="standard sensitivity study (measured)", value=(time.perf_counter() - t0) / 60, unit="min",
                     target="", note=f"{res.computed} points on 2 workers; {load()}")]
    # distinct FE bodies: spring maps are cached by body (hole sizes ignored without holes)
    from study.inputs.gearsetup import gear_setup
    bodies = {}
    for p in st.points():
        if p.scene.is_lightened(2):
            bodies[gear_setup(p.scene, 2).key] = p.scene.gear2.body.holes > 0
    os.environ["LIGHTGEAR_CACHE"] = str(tmp / "cache")  # cold FE cache
    times, cpu = {}, {}
    for holes, label in ((6, "holed"), (0, "webbed")):
        sc = [p.scene for p in st.points() if p.scene.gear2.body.holes == holes][0]
        c0 = time.process_time()
        r = run_point(sc, st.outputs)
        c1 = time.process_time()
        r2 = run_point(sc, st.outputs)  # springs now from memory: the point's own compute
        c2 = time.process_time()
        times[label] = (r["wall_time"] - r2["wall_time"], r2["wall_time"])
        cpu[label] = ((c1 - c0) - (c2 - c1), c2 - c1)
    n_holed_bodies = sum(bodies.values())
    n_webbed = len(bodies) - n_holed_bodies

    def project(t):
        fe = n_holed_bodies * t["holed"][0] + n_webbed * t["webbed"][0]
        compute = n_points * (t["holed"][1] + t["webbed"][1]) / 2
        return fe, compute, (fe + compute) / 1.8  # 2 workers at the 1.8x target scaling

    fe, compute, proj = project(times)
    fe_c, compute_c, proj_c = project(cpu)
    what = f"{n_points} points, {len(bodies)} FE bodies ({n_holed_bodies} holed)"
    return [dict(figure="sensitivity: FE map, one holed body", value=times["holed"][0], unit="s", target="",
                 note=f"CPU {cpu['holed'][0]:.1f} s; {load()}"),
            dict(figure="sensitivity: FE map, one webbed body", value=times["webbed"][0], unit="s", target="",
                 note=f"CPU {cpu['webbed'][0]:.1f} s; {load()}"),
            dict(figure="sensitivity: one point (static + dynamic)", value=times["holed"][1], unit="s", target="",
                 note=f"CPU {cpu['holed'][1]:.1f} s; {load()}"),
            dict(figure="standard sensitivity study (projected)", value=proj / 60, unit="min", target="",
                 note=f"{what}: ({fe:.0f} s FE + {compute:.0f} s points) / 1.8 on 2 workers, wall times as measured"),
            dict(figure="same, from CPU times (idle machine)", value=proj_c / 60, unit="min", target="",
                 note=f"({fe_c:.0f} s FE + {compute_c:.0f} s points) / 1.8")]


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    rows = []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        os.chdir(ROOT)
        for part in (overhead, scaling, memory):
            rows += part(tmp)
            print(f"  {part.__name__} done", file=sys.stderr)
        rows += sensitivity(tmp, "--full" in argv)
    w = max(len(r["figure"]) for r in rows)
    print(f"{'figure':{w}s}  {'value':>9s}  {'unit':14s} {'target':7s} note")
    for r in rows:
        print(f"{r['figure']:{w}s}  {r['value']:9.3g}  {r['unit']:14s} {r['target']:7s} {r['note']}")
    out = ROOT / "results" / "benchmarks" / "sweep.csv"
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=["figure", "value", "unit", "target", "note"])
        wr.writeheader()
        wr.writerows(rows)
    print(textwrap.fill(f"machine: {os.cpu_count()} cores; CSV: {out}", 100))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

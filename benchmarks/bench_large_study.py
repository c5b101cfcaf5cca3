"""A 2,000-point study of a cheap scene on 2 local workers: throughput, client memory, the merge.

  study      the example study's 20-tooth pair (uniform springs, no FE; 6 deg of STE, 10 ms of
             DTE), hole count {0, 4} x 1000 speeds, four scalars and the `dte` and
             `dte_amplitude` curves, on a LocalCluster of 2 single-threaded workers: wall time,
             points/s, peak RSS of the client process (this one: the sweep loop, the dask
             client and the LocalCluster's scheduler), CPU a point of this process and of the
             workers (the whole run_sweep: the plan, the workers' start and imports, the merge).
  merge      the same parts merged into the archive again in a fresh process, as `run_sweep`
             does (curves read from the part files in blocks of `MERGE_BLOCK_BYTES`) and, for
             comparison, with every record held in memory first (as before): wall time, peak
             RSS and its rise over the process after imports.
  mfdataset  the archive opened with xr.open_mfdataset beside a second study of 20 more speeds.
The machine may be shared with other jobs: the load average is printed with each figure.
Run: python benchmarks/bench_large_study.py [--quick]   (--quick: 200 points)
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout, not another installed copy

STUDY = """title = "large study"
[scene]
"gear1.teeth" = 20
"gear2.teeth" = 20
"gear1.body" = {{rim_height = 3.0, web_height = 4.0, hub_height = 3.0}}
"gear2.body" = {{rim_height = 3.0, web_height = 4.0, hub_height = 3.0, hole_radius = 1.5, hole_circle_radius = 8.1, web_thickness = 12.0}}
"gear2.spring.stiffness" = "uniform"
"quasi_static" = {{rotation = 6.0, angle_step = 0.5}}
"dynamic" = {{duration = 0.01, ramp_time = 0.002}}
[grid]
"gear2.body.holes" = [0, 4]
"dynamic.speed" = {{start = {start}, stop = {stop}, num = {num}}}
[outputs]
scalars = ["ste_p2p", "dte_rms", "dte_p2p", "tooth_force_max"]
curves = ["dte", "dte_amplitude"]
"""


def rss_mib() -> tuple[float, float]:
    """(current, peak) resident memory of this process [MiB]."""
    fields = dict(line.split(":", 1) for line in Path("/proc/self/status").read_text().splitlines() if ":" in line)
    return int(fields["VmRSS"].split()[0]) / 1024, int(fields["VmHWM"].split()[0]) / 1024


def peak_rss_mib() -> float:
    try:
        return rss_mib()[1]
    except (OSError, KeyError):    # no /proc: ru_maxrss is KiB on Linux
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def load() -> str:
    return "load %.1f" % os.getloadavg()[0]


def large_study(num: int, start: float, stop: float):
    from study.sweep.grid import loads_study
    return loads_study(STUDY.format(num=num, start=start, stop=stop))


def merge(study_args: str, out: str, how: str) -> dict:
    """Merge the kept part files of ``out`` (this process only): 'blocks' as run_sweep does,
    'memory' with every record read first."""
    import xarray as xr  # noqa: F401  (imports before the baseline)

    import study.sweep.archive  # noqa: F401
    from study.archive.netcdf import write_netcdf
    from study.sweep.archive import study_dataset
    from study.sweep.engine import PartStore, parts_folder, run_sweep
    from study.sweep.grid import check_points
    st = large_study(*json.loads(study_args))
    import dask.array  # noqa: F401
    import netCDF4  # noqa: F401
    base = rss_mib()[0]
    t0 = time.perf_counter()
    if how == "blocks":
        res = run_sweep(st, out, workers=0, progress=False, keep_parts=True)
        if res.computed:    # the code changed since the study ran: its parts are another version's
            raise SystemExit(f"the merge computed {res.computed} analyses: the code changed during the benchmark")
    else:
        from collections import Counter

        from study.sweep.tasks import plan, point_result
        points = check_points(st)
        store = PartStore(parts_folder(out))
        _, of_point = plan(st, points)
        shared = Counter(k for keys in of_point.values() for k in keys)
        records = {k: store.get(k) for k in shared}
        results = {idx: point_result(keys, records, shared) for idx, keys in of_point.items()}
        write_netcdf(study_dataset(st, points, results), out)
    return {"wall_s": time.perf_counter() - t0, "peak_mib": peak_rss_mib(), "base_mib": base}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="200 points instead of 2000")
    p.add_argument("--merge", nargs=3, metavar=("STUDY_ARGS", "OUT", "HOW"), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.merge:
        print(json.dumps(merge(*args.merge)))
        return 0

    import numpy as np
    import xarray as xr

    from study.sweep.archive import MERGE_BLOCK_BYTES
    from study.sweep.engine import parts_folder, run_sweep
    speeds = 100 if args.quick else 1000
    study_args = [speeds, 50.0, 150.0]
    tmp = Path(tempfile.mkdtemp(prefix="lightgear-large-"))
    out = tmp / "large.nc"
    base = rss_mib()[0]
    t0 = time.perf_counter()
    cpu0 = os.times()
    res = run_sweep(large_study(*study_args), out, workers=2, progress=False, keep_parts=True)
    wall = time.perf_counter() - t0
    cpu1 = os.times()      # the workers' CPU reaches children_* once the cluster has closed
    own = cpu1.user - cpu0.user + cpu1.system - cpu0.system
    workers_cpu = cpu1.children_user - cpu0.children_user + cpu1.children_system - cpu0.children_system
    client_peak = peak_rss_mib()
    n = res.points
    ds = res.dataset
    curve_mib = sum(ds[c].size * 8 for c in ("dte", "dte_amplitude")) / 2**20
    compute = float(ds["wall_time"].sum())
    print(f"study: {n} points ({int((ds['status'] == 1).sum())} ok; {res.computed} analyses: a static one per hole "
          f"count, a dynamic run per point) on 2 workers in {wall:.1f} s: {n / wall:.2f} points/s; "
          f"point compute {compute / n:.3f} s on average; curves {curve_mib:.1f} MiB; {load()}")
    print(f"client (sweep loop + dask client + LocalCluster scheduler): peak RSS {client_peak:.0f} MiB "
          f"({base:.0f} MiB after imports)")
    print(f"CPU: {own + workers_cpu:.1f} s = {(own + workers_cpu) / n * 1e3:.1f} ms a point: this process (plan, "
          f"client, scheduler, part files, merge) {own / n * 1e3:.1f} ms, the workers and their nannies (start, "
          f"imports, tasks) {workers_cpu / n * 1e3:.1f} ms; {load()}")
    part_mib = sum(f.stat().st_size for f in parts_folder(out).glob("*.pkl")) / 2**20
    for how in ("blocks", "memory"):
        r = subprocess.run([sys.executable, __file__, "--merge", json.dumps(study_args), str(out), how],
                           capture_output=True, text=True, check=True, cwd=ROOT)
        m = json.loads(r.stdout.strip().splitlines()[-1])
        label = f"in blocks of {MERGE_BLOCK_BYTES / 2**20:.0f} MiB" if how == "blocks" else "all records in memory"
        print(f"merge {label}: {m['wall_s']:.1f} s, peak RSS {m['peak_mib']:.0f} MiB "
              f"(+{m['peak_mib'] - m['base_mib']:.0f} MiB over the process after imports); parts {part_mib:.0f} MiB; {load()}")
    more = tmp / "more.nc"
    run_sweep(large_study(10, 151.0, 160.0), more, workers=0, progress=False)
    with xr.open_mfdataset([out, more], engine="netcdf4", combine="by_coords", data_vars="minimal", compat="no_conflicts") as both:
        sizes = dict(both.sizes)
        same = bool(np.array_equal(both["dte"].sel(speed=ds["speed"].values).values, ds["dte"].values, equal_nan=True))
    print(f"open_mfdataset with a 20-point study: sizes {sizes}, the large study's dte unchanged: {same}")
    ds.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

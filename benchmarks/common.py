"""Shared pieces of the benchmark scripts: scenes, best-of-N timing, tables, machine info.

Timings in seconds: wall clock (time.perf_counter), minimum (best) and median of several
repeats, and the process CPU time (time.process_time) of the best repeat. Everything runs
on one core (BLAS threads pinned to 1 below), so on a quiet machine CPU time = wall time; on
a shared machine the wall time also holds the time other processes took, and the CPU time is
the robust figure: ratios are taken on it. Tables are printed and written as CSV under
results/benchmarks/.
"""
from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")      # one core: before numpy is imported

import argparse
import csv
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:               # import this checkout's packages
    sys.path.insert(0, str(ROOT))
OUT = ROOT / "results" / "benchmarks"

# Table 1 loads, dynamic case: 0 -> 100 rad/s and 0 -> 50 N m in 10 ms, 0.2 s simulated
PAPER_DYNAMIC = (100.0, 0.01, 50.0, 0.01, 0.2)
# the short window the slow peers run: 100 rad/s and 50 N m reached in 0.5 ms, 1.5 ms in all
# (one mesh cycle, 0.94 ms at 100 rad/s, at full speed and load)
SHORT_DYNAMIC = (100.0, 0.0005, 50.0, 0.0005, 0.0015)

COLUMNS = ("case", "method", "wall_min_s", "wall_median_s", "cpu_min_s", "repeats", "error_um", "ratio", "note")


def scene(kind: str, coupling: str | None = None):
    """The paper pair (Table 1) with a solid driven gear ('solid') or as published ('lightened':
    the default scene), with the default model or ``coupling`` (a `coupling.model`)."""
    from study.scene import default_scene
    s = default_scene()
    if coupling is not None:
        s = s.replace(**{"coupling.model": coupling})
    if kind == "solid":
        return s.solid(gears=(2,))
    if kind == "lightened":
        return s
    raise ValueError(f"scene kind: 'solid' or 'lightened', got {kind!r}")


def model(kind: str, coupling: str | None = None):
    """Solver model of the scene (`scene`); the lightened gear's FE springs come from
    study.inputs.springs (computed once, then read from its disk cache)."""
    os.environ.setdefault("LIGHTGEAR_CACHE", str(ROOT / ".lightgear-cache"))
    from study.scene_model import build_scene_model
    return build_scene_model(scene(kind, coupling))


def quick_options(description: str, quick_help: str, argv=None) -> tuple[argparse.Namespace, int]:
    """Command line of a benchmark script taking ``--quick`` (what it leaves out: ``quick_help``):
    the parsed arguments and the repeats per figure, 3 with ``--quick``, 5 without."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--quick", action="store_true", help=quick_help)
    args = ap.parse_args(argv)
    return args, (3 if args.quick else 5)


def best_of(fn, repeat: int = 5, warmup: bool = False):
    """dict(wall_min_s, wall_median_s, cpu_min_s, repeats) of ``repeat`` calls of fn(), and
    the last result."""
    if warmup:
        fn()
    walls, cpus = [], []
    res = None
    for _ in range(repeat):
        c0 = time.process_time()
        t0 = time.perf_counter()
        res = fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return dict(wall_min_s=min(walls), wall_median_s=statistics.median(walls), cpu_min_s=min(cpus),
                repeats=repeat), res


def scaled(timing: dict, factor: float) -> dict:
    """The timing figures times factor (a short run extrapolated)."""
    return {k: (v * factor if k.endswith("_s") and v is not None else v) for k, v in timing.items()}


def add_ratios(rows, key="case"):
    """ratio = cpu_min / the smallest cpu_min among rows of the same case."""
    best = {}
    for r in rows:
        if r.get("cpu_min_s") is not None:
            best[r[key]] = min(best.get(r[key], float("inf")), r["cpu_min_s"])
    for r in rows:
        if r.get("cpu_min_s") is not None and r.get("ratio") is None:
            r["ratio"] = r["cpu_min_s"] / best[r[key]]
    return rows


def _fmt(v):
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def write_table(name: str, title: str, rows, columns=COLUMNS) -> Path:
    """Print the table and write it to results/benchmarks/<name>.csv."""
    print(title)
    print(machine_line())
    widths = [max(len(c), *(len(_fmt(r.get(c))) for r in rows)) for c in columns[:-1]]
    print("  ".join(c.ljust(w) for c, w in zip(columns[:-1], widths)) + "  " + columns[-1])
    for r in rows:
        print("  ".join(_fmt(r.get(c)).ljust(w) for c, w in zip(columns[:-1], widths)) + "  " + _fmt(r.get(columns[-1])))
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f"{name}.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["# " + title + " | " + machine_line()])
        w.writerow(columns)
        for r in rows:
            w.writerow([r.get(c, "") if r.get(c) is not None else "" for c in columns])
    print(f"(written {path.relative_to(ROOT)})\n")
    return path


def cpu_model() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def machine_line() -> str:
    import numba
    import numpy
    import scipy
    vers = f"numpy {numpy.__version__}, scipy {scipy.__version__}, numba {numba.__version__}"
    try:
        import exudyn
        vers += f", exudyn {exudyn.__version__}"
    except ImportError:
        pass
    return (f"{cpu_model()}, {os.cpu_count()} cores, {platform.machine()}, Python {platform.python_version()}; "
            f"{vers}; {time.strftime('%Y-%m-%d', time.gmtime())}")

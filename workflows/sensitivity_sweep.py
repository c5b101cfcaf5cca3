"""The standard sensitivity study: hole count, hole radius, rim and web thickness, and speed.

Runs `study/scenes/sensitivity.toml` (80 points over the paper pair) with dask, writes one
labelled archive and prints how each swept field moves the main outputs (mean over the
other fields, ok points only). Any grid axis can be replaced to shrink or refine the study:

    python -m workflows.sensitivity_sweep [-o results/sensitivity/sensitivity.nc]
        [--study STUDY.toml] [--grid gear2.body.holes=0,6 ...] [--set key=value ...]
        [--workers N | --scheduler ADDRESS]

Cost on a 2-core machine: dominated by the FE spring maps of the 36 distinct driven-gear
bodies (cached on disk: a second run with other speeds reuses them); see docs/studies.md.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import study

STUDY = Path(__file__).resolve().parents[1] / "study" / "scenes" / "sensitivity.toml"
DEFAULT_OUT = "results/sensitivity/sensitivity.nc"
SHOWN = ("ste_p2p", "dte_rms", "dte_p2p", "amp_mesh_order", "amp_hole_order", "tooth_force_max")


def sensitivity_study(path: str | Path = STUDY, grid: list[str] = (), overrides: list[str] = ()):
    """The study of ``path`` with grid axes replaced or added (``field=v1,v2,...``; a replaced
    axis keeps its place) and base-scene fields overridden (``key=value``) -> Study."""
    base = study.load_study(path)
    axes = {a.path: list(a.values) for a in base.axes}
    for item in grid:
        field, _, values = item.partition("=")
        if not values:
            raise study.SceneError(field or "grid", "a grid axis must look like field=v1,v2,...")
        axes[field.strip()] = [study.parse_overrides([f"x={v}"])["x"] for v in values.split(",")]
    scene = base.base_scene().replace(**study.parse_overrides(overrides))
    return study.make_study(scene, axes, base.extra, base.outputs, base.title)


def sensitivity_table(ds) -> list[str]:
    """Per swept field and value: the mean of the main outputs over the other fields (ok points)."""
    ok = ds["status"] == study.STATUS.index("ok")
    units = {name: unit for name, _kind, unit, _analysis, _doc in study.outputs()}
    shown = [k for k in SHOWN if k in ds]
    lines = ["field            value      " + "".join(f"{k:>16s}" for k in shown),
             "                            " + "".join(f"{'[' + units[k] + ']':>16s}" for k in shown)]
    dims = [d for d in ds["status"].dims if d != "point"]
    for d in dims:
        for v in ds[d].values:
            row = f"{d:16s} {v!s:10.8s} "
            for k in shown:
                sel = ds[k].where(ok).sel({d: v})
                m = float(sel.mean()) if np.isfinite(sel).any() else math.nan
                row += f"{m:16.4g}"
            lines.append(row)
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", default=DEFAULT_OUT, help="study archive (NetCDF)")
    p.add_argument("--study", default=str(STUDY), help="study TOML (default: study/scenes/sensitivity.toml)")
    p.add_argument("--grid", action="append", default=[], metavar="FIELD=V1,V2",
                   help="replace (or add) one grid axis, e.g. --grid gear2.body.holes=0,6 --grid dynamic.speed=100")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a base scene field, e.g. --set dynamic.duration=0.1")
    p.add_argument("--workers", type=int, default=None, help="LocalCluster workers (default: one per core; 0: in process)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="existing dask scheduler")
    p.add_argument("--no-progress", action="store_true")
    args = p.parse_args(argv)

    st = sensitivity_study(args.study, args.grid, args.overrides)
    n = int(np.prod(st.shape))
    print(f"{st.title}\n  {n} points: " + " x ".join(f"{a.name} {len(a.values)}" for a in st.axes)
          + f" -> {args.output}")
    res = study.run_sweep(st, args.output, workers=args.workers, scheduler=args.scheduler,
                          progress=not args.no_progress)
    ds = res.dataset
    counts = ", ".join(f"{name} {int((ds['status'] == i).sum())}" for i, name in enumerate(study.STATUS) if (ds["status"] == i).any())
    print(f"  {res.points} points; analyses computed {res.computed}, reused {res.reused}, invalid {res.invalid} ({counts}); "
          f"wall time {res.wall_time:.1f} s, compute {float(ds['wall_time'].sum()):.1f} s")
    for line in sensitivity_table(ds):
        print("  " + line)
    return 1 if res.pending else 0


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.sensitivity_sweep", main))

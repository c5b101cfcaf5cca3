"""Stability suite: stiff and extreme variants of the paper pair, each run with every integrator.

The suite is `study.stability_suite` (`study.verify.stability`, whose docstring lists the
scenes, the methods and the plausibility checks); this script runs it and prints, archives and
draws the result.

    python -m workflows.stability [SCENE] [-o results/stability/stability.nc] [--duration 0.002]
"""
from __future__ import annotations

import argparse
import time

import xarray as xr

import study

DEFAULT_OUT = "results/stability/stability.nc"
METHODS = ("explicit", "implicit alpha=0", "implicit alpha=-0.1", "LSODA")


def summary(ds: xr.Dataset) -> str:
    meth = list(ds["method"].values)
    lines = [f"{'scene':24s} " + " ".join(f"{m:>20s}" for m in meth) + "   TE range um (explicit)"]
    st = ds["status"].values
    msg = ds["message"].values
    for i, s in enumerate(ds["scene"].values):
        lines.append(f"{s:24s} " + " ".join(f"{st[i, j]:>20s}" for j in range(len(meth)))
                     + f"   {ds['te_min'].values[i, 0]:8.2f} .. {ds['te_max'].values[i, 0]:8.2f}")
    bad = [(s, meth[j], msg[i, j]) for i, s in enumerate(ds["scene"].values) for j in range(len(meth))
           if st[i, j] != "ok"]
    if bad:
        lines.append("not ok:")
        lines += [f"  {s} / {m}: {msg}" for s, m, msg in bad]
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", help="scene TOML (default: the paper example)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT)
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--duration", type=float, default=0.002, help="simulated time per run [s] (ramps end at half)")
    p.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    p.add_argument("--scenes", nargs="+", default=None, help="run only these scenes (names as in the table)")
    p.add_argument("--scipy-wall", type=float, default=20.0, help="wall-time limit of a scipy run [s]")
    p.add_argument("--mesh-size", type=float, default=1.0, help="FE element size of lightened bodies [mm]")
    args = p.parse_args(argv)
    scene = study.load_scene(args.scene, args.overrides)
    t0 = time.perf_counter()
    ds = study.stability_suite(scene, args.duration, tuple(args.methods), args.scipy_wall, args.scenes,
                                 args.mesh_size)
    study.write(ds, args.output)
    print(summary(ds))
    print(f"archive: {args.output}; {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.stability", main))

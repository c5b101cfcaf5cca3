"""Work-precision diagrams of the paper's two scenes: TE error against wall time per solver.

For the dynamic scene (shortened window, ramps scaled) and the quasi-static scene (STE over
one mesh cycle) it writes an archive and a log-log plot each, prints the tables and the
cheapest method for 0.1 um and 0.01 um TE accuracy. See `study.verify.precision` for the methods,
the references and the norms.

    python -m workflows.work_precision [SCENE] [-o results/work_precision/work_precision.nc]
        [--duration 0.002] [--rotation 6] [--repeats 3] [--only dynamic|static] [--set k=v ...]
"""
from __future__ import annotations

import argparse
import math

import study

DEFAULT_OUT = "results/work_precision/work_precision.nc"


def main(argv=None) -> int:
    """`lightgear precision` with the workflow's default archive."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", help="scene TOML or embedded scene name (default: the paper example)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT,
                   help="archive base name: writes BASE_dynamic.nc and BASE_static.nc with their plots (.png)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--duration", type=float, default=0.002, help="dynamic window [s] (default 0.002)")
    p.add_argument("--ramp-fraction", type=float, default=0.5, help="ramps end at this fraction of the window")
    p.add_argument("--rotation", type=float, default=6.0, help="quasi-static driver rotation [deg] (default 6)")
    p.add_argument("--repeats", type=int, default=3, help="timed repeats per run (best is kept)")
    p.add_argument("--only", choices=("dynamic", "static"), help="run only one of the two studies")
    args = p.parse_args(argv)
    scene = study.load_scene(args.scene, args.overrides)

    def progress(i, s, e, w, msg):
        setting = f"dt {s.step * 1e6:.4g} us" if math.isfinite(s.step) else f"rtol {s.rtol:g}"
        print(f"  [{i + 1}] {s.method}, {setting}: linf {e[2]:.3g} um, {w:.3g} s  {'' if msg == 'ok' else msg}",
              flush=True)
    out = study.precision(scene, args.output, args.duration, args.ramp_fraction, args.rotation, args.repeats,
                          args.only, progress=progress)
    for ds in out.values():
        print(ds.attrs["title"])
        print(study.precision_table(ds))
        print(f"  archive: {ds.attrs['archive']}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.work_precision", main))

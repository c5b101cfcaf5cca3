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

The study in three modules: `study.verify.precision_cases` (the cases, solver ladders and
references), `study.verify.precision_study` (timed runs, errors -> Dataset) and
`study.verify.precision_report` (cheapest run, text table, plot).
"""
from __future__ import annotations

import math

from study.report import results
from study.scene import load_scene
from study.verify.precision_report import plot, setting_label, table
from study.verify.precision_study import dynamic_study, static_study

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


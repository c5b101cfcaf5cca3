"""Work-precision diagrams of the paper's two scenes: TE error against CPU time per solver, for
the paper's plain model and the default compliance model, and against the FE mesh size.

For the dynamic scene (shortened window, ramps scaled) and the quasi-static scene (STE over
one mesh cycle) it writes an archive and a log-log plot each per model, each model measured
against its own converged answer; then the compliance model at three FE mesh sizes (coarse,
default, fine: 2, 1 and 1/2 x a quarter of the module), its STE and DTE against the finest
with the FE and run CPU times. It prints the tables and the cheapest setting for 0.1 um and
0.01 um TE accuracy. See `study.verify.precision` for the methods, the references and the
norms, `study.verify.precision_mesh` for the mesh study.

    python -m workflows.work_precision [SCENE] [-o results/work_precision/work_precision.nc]
        [--model paper|compliance] [--duration 0.002] [--rotation 6] [--repeats 3]
        [--only dynamic|static|mesh] [--mesh-factors 2,1,0.5] [--set k=v ...]

Archives: BASE_dynamic.nc and BASE_static.nc (paper model), BASE_compliance_dynamic.nc and
BASE_compliance_static.nc (compliance model), BASE_mesh.nc (mesh sizes), each with its plot
(.png).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import study

DEFAULT_OUT = "results/work_precision/work_precision.nc"
MODELS = ("paper", "compliance")


def model_output(base: str, model: str) -> str:
    """The archive base of a model's studies: BASE.nc for the paper model (the names the study
    always had), BASE_compliance.nc for the compliance model."""
    p = Path(base)
    return str(p) if model == "paper" else str(p.with_name(f"{p.stem}_{model}{p.suffix}"))


def mesh_factors(text: str) -> tuple:
    """'2,1,0.5' -> (2.0, 1.0, 0.5): at least two positive factors of the default mesh size."""
    try:
        f = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"comma-separated numbers, got {text!r}") from None
    if len(f) < 2 or any(not (x > 0 and math.isfinite(x)) for x in f):
        raise argparse.ArgumentTypeError(f"at least two positive factors, got {text!r}")
    return f


def main(argv=None) -> int:
    """`lightgear precision` for both models with the workflow's default archive, then the mesh study."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", help="scene TOML or embedded scene name (default: the paper example)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT,
                   help="archive base name: writes BASE_dynamic.nc, BASE_static.nc, BASE_compliance_*.nc and "
                        "BASE_mesh.nc with their plots (.png)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--model", choices=MODELS, help="run one model's studies only (default: both, then the mesh study)")
    p.add_argument("--duration", type=float, default=0.002, help="dynamic window [s] (default 0.002)")
    p.add_argument("--ramp-fraction", type=float, default=0.5, help="ramps end at this fraction of the window")
    p.add_argument("--rotation", type=float, default=6.0, help="quasi-static driver rotation [deg] (default 6)")
    p.add_argument("--repeats", type=int, default=3, help="timed repeats per run (best is kept)")
    p.add_argument("--only", choices=("dynamic", "static", "mesh"), help="run only one of the three studies")
    p.add_argument("--mesh-factors", type=mesh_factors, default=(2.0, 1.0, 0.5), metavar="F,F,...",
                   help="mesh study: fe.mesh_size at these multiples of the default (module/4); default 2,1,0.5")
    args = p.parse_args(argv)
    scene = study.load_scene(args.scene, args.overrides)

    def progress(i, s, e, w, msg):
        setting = f"dt {s.step * 1e6:.4g} us" if math.isfinite(s.step) else f"rtol {s.rtol:g}"
        print(f"  [{i + 1}] {s.method}, {setting}: linf {e[2]:.3g} um, {w:.3g} s wall  {'' if msg == 'ok' else msg}",
              flush=True)
    kinds = [k for k in ("static", "dynamic") if args.only in (None, k)]
    for model in MODELS if args.model is None else (args.model,):
        for kind in kinds:
            print(f"{model} model, {kind} study ...", flush=True)
            out = study.precision(scene.replace(**{"coupling.model": model}), model_output(args.output, model),
                                  args.duration, args.ramp_fraction, args.rotation, args.repeats, kind,
                                  progress=progress)
            ds = out[kind]
            print(study.precision_table(ds))
            print(f"  archive: {ds.attrs['archive']}", flush=True)
    if args.only in (None, "mesh") and args.model in (None, "compliance"):
        mesh_run(scene.replace(**{"coupling.model": "compliance"}), args)
    return 0


def mesh_run(scene, args) -> None:
    """The mesh study of the compliance model: archive BASE_mesh.nc, its plot and table."""
    print("compliance model, mesh study at fe.mesh_size "
          f"{' / '.join(f'{f:g}' for f in sorted(args.mesh_factors, reverse=True))} x the default "
          "(each from an empty FE cache; the finest takes longest) ...", flush=True)

    def progress(i, h, row):
        print(f"  [{i + 1}] fe.mesh_size {h:.4g} mm: FE {row['fe'][0]:.3g} + {row['fe'][1]:.3g} s CPU, "
              f"STE mean {row['ste'].mean():.4g} um, dynamic run {row['dynamic_cpu']:.3g} s CPU", flush=True)
    base = Path(args.output)
    path = base.with_name(f"{base.stem}_mesh.nc")
    ds = study.precision_mesh(scene, path, args.mesh_factors, args.rotation, min(args.repeats, 2), progress)
    print(study.precision_mesh_table(ds))
    print(f"  archive: {path}\n  plot: {path.with_suffix('.png')}", flush=True)


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.work_precision", main))

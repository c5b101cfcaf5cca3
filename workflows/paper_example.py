"""The paper's example (Table 1): STE over 120 deg, DTE over 0.2 s, spectra, stiffness map.

It runs the paper's model (``coupling.model = "paper"``, unless ``--set coupling.model=...``
names another), so that it reproduces the paper, and the default model beside it ('auto': the
compliance model for this lightened pair, the one that agrees with the FE reference): the
summary leads with a table of both models' numbers, and the STE and DTE figures draw both.
Besides the run archive of the lightened pair by the paper's model it stores:
  ste_default(angle)     STE of the default model [um]
  dte_default(time)      DTE of the default model [um]; its modes in the attributes
                         default_mesh_mode_frequency_hz, default_critical_speed_1z_rad_s
  ste_solid(angle)       STE of the same pair with a solid driven gear [um]
  ste_transient(angle)   STE from the paper's slow-ramp transient over the first
                         ``--transient-rotation`` degrees [um] (NaN beyond)
and prints how the static and transient STE differ.

    python -m workflows.paper_example [-o results/paper_example/paper_example.nc] [--set k=v ...]
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import study

DEFAULT_OUT = "results/paper_example/paper_example.nc"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", help="scene TOML (default: the paper example)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT)
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--transient-rotation", type=float, default=40.0,
                   help="degrees of the slow-ramp transient run for the static/transient comparison (0: skip)")
    p.add_argument("--no-figures", action="store_true", help="write only the archive")
    args = p.parse_args(argv)

    t0 = time.perf_counter()
    scene = study.load_scene(args.scene, args.overrides)
    default = scene
    if not any(o.split("=")[0].strip() == "coupling.model" for o in args.overrides) and scene.coupling.model == "auto":
        scene = scene.replace(**{"coupling.model": "paper"})     # the paper's model reproduces the paper
    ds = _run(scene)
    if default.coupling_model != scene.coupling_model:
        study.add_default_model(ds, _run(default))     # the default's STE, DTE and modes beside
    if "ste" in ds:
        solid = _run(study.solid_scene(scene, gears=(2,)), dynamic=False)   # the driven gear solid
        ds["ste_solid"] = ("angle", solid["ste"].values, {"units": "um", "long_name": "static transmission error with a solid driven gear"})
        if args.transient_rotation > 0:
            tr_scene = scene.replace(**{"quasi_static.method": "transient",
                                        "quasi_static.rotation": min(args.transient_rotation, scene.quasi_static.rotation)})
            tr = _run(tr_scene, dynamic=False)        # the same springs, from the FE cache
            n = tr.sizes["angle"]
            full = np.full(ds.sizes["angle"], np.nan)
            full[:n] = tr["ste"].values
            ds["ste_transient"] = ("angle", full, {"units": "um", "long_name": "STE from the slow-ramp transient (paper's method)"})
            ds.attrs["wall_time_transient_s"] = tr.attrs["wall_time_static_s"]
    study.write(ds, args.output)
    study.print_summary(ds, args.output, time.perf_counter() - t0)
    if "ste_transient" in ds:
        d = (ds["ste_transient"] - ds["ste"]).dropna("angle")
        settle = d.where(d["angle"] > 1.0, drop=True)
        print(f"  slow-ramp transient vs static STE over {float(d['angle'][-1]):.4g} deg (after 1 deg): "
              f"mean {float(settle.mean()):+.4f} um, RMS {float(np.sqrt((settle**2).mean())):.4f} um, "
              f"max |diff| {float(abs(settle).max()):.4f} um")
    if "ste_solid" in ds:
        print(f"  solid driven gear: STE mean {float(ds['ste_solid'].mean()):.3f} um, "
              f"peak-to-peak {float(ds['ste_solid'].max() - ds['ste_solid'].min()):.3f} um")
    if not args.no_figures:
        for path in study.render(ds, Path(args.output).parent):
            print(f"  figure: {path}")
    return 0


def _run(scene, dynamic=None):
    """`study.run_scene`, its kernels that numba's disk cache lacks compiled by a second process
    while the run builds its FE (``compile_ahead``, as `lightgear run` does)."""
    return study.run_scene(scene, dynamic=dynamic, compile_ahead=True)


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.paper_example", main))

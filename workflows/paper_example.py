"""The paper's example (Table 1): STE over 120 deg, DTE over 0.2 s, spectra, stiffness map.

It runs the paper's model (``coupling.model = "paper"``, unless ``--set coupling.model=...``
names another), so that it reproduces the paper. Besides the run archive of the lightened pair
it stores, for comparison:
  ste_default(angle)     STE of the default model ('auto': the compliance model for this
                         lightened pair, the one that agrees with the FE reference) [um]
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
    ds = study.run_scene(scene)
    if "ste" in ds and default.coupling_model != scene.coupling_model:
        dflt = study.run_scene(default, dynamic=False)       # the static analysis only
        ds["ste_default"] = ("angle", dflt["ste"].values, {
            "units": "um", "long_name": f"static transmission error of the default model ({default.coupling_model_name})"})
        ds.attrs["default_coupling_model"] = default.coupling_model_name
    if "ste" in ds:
        solid = study.run_scene(study.solid_scene(scene, gears=(2,)), dynamic=False)   # the driven gear solid
        ds["ste_solid"] = ("angle", solid["ste"].values, {"units": "um", "long_name": "static transmission error with a solid driven gear"})
        if args.transient_rotation > 0:
            tr_scene = scene.replace(**{"quasi_static.method": "transient",
                                        "quasi_static.rotation": min(args.transient_rotation, scene.quasi_static.rotation)})
            tr = study.run_scene(tr_scene, dynamic=False)        # the same springs, from the FE cache
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
    if "ste_default" in ds:
        print(f"  STE peak-to-peak: {float(np.ptp(ds['ste'].values)):.3f} um by the paper's model, "
              f"{float(np.ptp(ds['ste_default'].values)):.3f} um by the default ({ds.attrs['default_coupling_model']}, "
              f"the model that agrees with the FE reference: docs/models.md)")
    if "ste_solid" in ds:
        print(f"  solid driven gear: STE mean {float(ds['ste_solid'].mean()):.3f} um, "
              f"peak-to-peak {float(ds['ste_solid'].max() - ds['ste_solid'].min()):.3f} um")
    if not args.no_figures:
        for path in study.render(ds, Path(args.output).parent):
            print(f"  figure: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.paper_example", main))

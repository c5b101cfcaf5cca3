"""`lightgear` command line. Each subcommand lives in the module that does the work.

A command module provides ``add_arguments(parser)`` and ``main(args) -> int``; it is imported
only when its command runs, so ``lightgear run`` never loads gmsh or VTK.
"""
from __future__ import annotations

import argparse
import importlib
import sys

# name -> (module, one-line help)
COMMANDS = {
    "run": ("study.run", "run a scene (default: the paper example) and write its archive"),
    "stiffness": ("study.inputs.springs", "per-tooth FE stiffness map of a scene's gears (no solve)"),
    "sweep": ("study.sweep.engine", "run a parametric study (scene + grid) with dask into one NetCDF archive"),
    "fit-contact": ("study.inputs.contact_fit", "fit the contact law k_con*delta^m1 to Weber's contact deflection"),
    "render": ("study.report.figures", "plots and renders (PNG) of a run or sweep archive"),
    "precision": ("study.verify.precision", "work-precision study: TE error against wall time for every solver of a scene"),
    "reference": ("study.verify.fe_reference", "FE reference STE and load sharing (loaded-tooth-contact analysis)"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lightgear", description="Transmission error of lightened spur gears (MUBOCO-PR).")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (module, help_) in COMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        p.set_defaults(_module=module)
        importlib.import_module(module).add_arguments(p)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from study.scene import SceneError
    try:
        return int(importlib.import_module(args._module).main(args) or 0)
    except SceneError as e:
        print(f"lightgear {args.command}: invalid scene: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

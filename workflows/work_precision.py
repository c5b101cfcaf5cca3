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

from study.cli import precision_arguments, precision_command

DEFAULT_OUT = "results/work_precision/work_precision.nc"


def main(argv=None) -> int:
    """`lightgear precision` with the workflow's default archive."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    precision_arguments(p, output=DEFAULT_OUT)
    return precision_command(p.parse_args(argv))


if __name__ == "__main__":
    from study.cli import script_main
    raise SystemExit(script_main("python -m workflows.work_precision", main))

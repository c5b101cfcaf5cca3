"""Two sweep archives compared variable by variable: the largest relative difference of each
numeric data variable, and whether it is within the tolerance (default 1e-6 relative, of the
variable's largest magnitude). For checking that a speed change left a study's numbers alone:
run the study on the old and the new code, then

  python benchmarks/archive_diff.py OLD.nc NEW.nc [--rtol 1e-6] [--skip wall_time ...]

Exit status 1 when a variable differs beyond the tolerance, is missing, or changes its NaNs.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np
import xarray as xr

SKIP = ("wall_time",)       # the compute time of each point [s]: not a result


def differences(a: xr.Dataset, b: xr.Dataset, skip=SKIP) -> list[tuple[str, float, str]]:
    """(variable, largest difference relative to the variable's largest magnitude [-], problem
    or '') of every numeric data variable of ``a``."""
    out = []
    for name in sorted(a.data_vars):
        if name in skip or not np.issubdtype(a[name].dtype, np.number):
            continue
        if name not in b:
            out.append((name, np.nan, "missing"))
            continue
        x, y = np.asarray(a[name].values, float), np.asarray(b[name].values, float)
        if x.shape != y.shape:
            out.append((name, np.nan, f"shape {x.shape} != {y.shape}"))
            continue
        if not np.array_equal(np.isnan(x), np.isnan(y)):
            out.append((name, np.nan, "NaNs differ"))
            continue
        ok = ~np.isnan(x)
        scale = np.max(np.abs(x[ok])) if ok.any() else 0.0
        rel = float(np.max(np.abs(x[ok] - y[ok])) / scale) if scale > 0 else 0.0
        out.append((name, rel, ""))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rtol", type=float, default=1e-6, help="relative tolerance [-] (default 1e-6)")
    ap.add_argument("--skip", nargs="*", default=list(SKIP), help="variables left out")
    args = ap.parse_args(argv)
    with xr.open_dataset(args.old) as a, xr.open_dataset(args.new) as b:
        rows = differences(a.load(), b.load(), tuple(args.skip))
    bad = 0
    for name, rel, problem in rows:
        fail = bool(problem) or rel > args.rtol
        bad += fail
        print(f"{name:32s} {problem or f'{rel:.3g}':>14s}  {'DIFFERS' if fail else 'ok'}")
    print(f"{len(rows)} variables, {bad} beyond {args.rtol:g} relative")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

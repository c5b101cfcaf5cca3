"""Run every benchmarks/bench_*.py, each in its own process, and print their tables.

    python benchmarks/run_all.py                 # all of them
    python benchmarks/run_all.py solver peers    # only bench_solver.py and bench_peers.py
    python benchmarks/run_all.py --list          # what there is
    python benchmarks/run_all.py --quick         # pass --quick to the scripts that take it

Each script prints its table and writes it under results/benchmarks/. The exit status is
non-zero when a script failed; the others still run.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def discover() -> dict[str, Path]:
    return {p.stem[len("bench_"):]: p for p in sorted(HERE.glob("bench_*.py"))}


def accepts_quick(path: Path) -> bool:
    """Whether a script takes ``--quick``: its own option, or the shared `common.quick_options`
    (read from the source, so nothing is imported here)."""
    text = path.read_text()
    return "--quick" in text or "quick_options(" in text


def main(argv=None) -> int:
    found = discover()
    ap = argparse.ArgumentParser(description="Run the lightgear benchmarks, each in its own process.")
    ap.add_argument("names", nargs="*", help=f"benchmarks to run (default all): {', '.join(found)}")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    ap.add_argument("--quick", action="store_true", help="pass --quick to the benchmarks that accept it")
    args = ap.parse_args(argv)
    if args.list:
        for name, path in found.items():
            print(f"{name:12s} {path.relative_to(ROOT)}")
        return 0
    unknown = [n for n in args.names if n not in found]
    if unknown:
        ap.error(f"unknown benchmark(s) {', '.join(unknown)}; known: {', '.join(found)}")
    names = args.names or list(found)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.setdefault("NUMBA_CACHE_DIR", str(ROOT / ".lightgear-cache" / "numba"))
    env.setdefault("MPLBACKEND", "Agg")
    failed = []
    t_all = time.perf_counter()
    for name in names:
        path = found[name]
        cmd = [sys.executable, str(path)]
        if args.quick and accepts_quick(path):
            cmd.append("--quick")
        print(f"=== {name} ({path.relative_to(ROOT)})", flush=True)
        t0 = time.perf_counter()
        rc = subprocess.call(cmd, cwd=ROOT, env=env)
        print(f"=== {name}: {'ok' if rc == 0 else f'FAILED (exit {rc})'} in {time.perf_counter() - t0:.0f} s\n", flush=True)
        if rc:
            failed.append(name)
    print(f"all benchmarks: {time.perf_counter() - t_all:.0f} s" + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

"""Where a scene goes in one run: one `study.run_scene` of a scene (default: the embedded paper
example) followed with `sys.setprofile`, counting

  stays      calls of a function of this checkout that hold a `Scene` (an argument, or a
             variable of an enclosing function the call reads), and the files they are in;
             also counted with its sections (an object of a class of study/scene.py: a gear,
             the dynamic run's settings, ...) held instead of the whole scene
  climbs     calls from a function in solver/ into one in study/ (a solver function calling
             back into the study layer: a cache's maker, a callback), distinct caller/callee pairs
  counters   calls of gear_setups, gear_geometry, the scene's model (build_scene_model or
             scene_model), geometry_model (the pair's kinematics, plain springs), build_model (the
             solver's model assembly) and loaded_equilibria (the equilibria asked for, kept or not)

The run is made twice in one process: the first fills the disk FE cache and compiles; the
in-memory store (`solver.store.STORE`) is then cleared, so the traced second run is that of a
new process with a warm disk cache.

  python benchmarks/scene_trace.py [SCENE] [--set key=value ...] [--list]

``--list`` also prints the files and the climbs one by one.
"""
from __future__ import annotations

import argparse
import os
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:               # import this checkout's packages
    sys.path.insert(0, str(ROOT))

COUNTED = {       # counter -> (file relative to the checkout, function name)
    "gear_setups": ("study/inputs/gearsetup.py", "gear_setups"),
    "gear_geometry": ("solver/geometry.py", "gear_geometry"),
    "build_scene_model": ("study/scene_model.py", "build_scene_model"),
    "scene_model": ("study/scene_model.py", "scene_model"),
    "geometry_model": ("study/scene_model.py", "geometry_model"),
    "build_model": ("solver/mbs/model.py", "build_model"),
    "loaded_equilibria": ("solver/mbs/equilibria.py", "loaded_equilibria"),
}


def _layer(filename: str) -> tuple[str, str] | None:
    """(top folder, path relative to the checkout) of a file of this checkout's packages, else None."""
    try:
        rel = Path(filename).resolve().relative_to(ROOT).as_posix()
    except ValueError:
        return None
    top = rel.split("/", 1)[0]
    return (top, rel) if top in ("solver", "study") else None


def trace(scene) -> dict:
    """The counts of one `run_scene` of ``scene`` (see the module)."""
    import study
    from study.scene import Scene

    layers: dict = {}
    stays: Counter = Counter()
    parts: Counter = Counter()
    climbs: Counter = Counter()
    counters: Counter = Counter()
    wanted = {v: k for k, v in COUNTED.items()}

    def where(code):
        f = code.co_filename
        if f not in layers:
            layers[f] = _layer(f)
        return layers[f]

    def profile(frame, event, arg):
        if event != "call":
            return
        code = frame.f_code
        here = where(code)
        if here is None:
            return
        name = wanted.get((here[1], code.co_name))
        if name:
            counters[name] += 1
        held = frame.f_locals.values()
        if any(isinstance(v, Scene) for v in held):
            stays[(here[1], code.co_qualname)] += 1
        elif any(type(v).__module__ == "study.scene" for v in held):
            parts[(here[1], code.co_qualname)] += 1
        back = frame.f_back
        if here[0] == "study" and back is not None:
            up = where(back.f_code)
            if up is not None and up[0] == "solver":
                climbs[(f"{up[1]}:{back.f_code.co_qualname}", f"{here[1]}:{code.co_qualname}")] += 1

    sys.setprofile(profile)
    try:
        study.run_scene(scene, warn=False)
    finally:
        sys.setprofile(None)
    return {"stays": stays, "parts": parts, "climbs": climbs, "counters": counters}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=None, help="scene file or embedded name (default: the paper example)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a scene field")
    ap.add_argument("--list", action="store_true", help="print the files and climbs one by one")
    args = ap.parse_args(argv)
    os.environ.setdefault("LIGHTGEAR_CACHE", str(ROOT / ".lightgear-cache"))
    import study
    from solver.store import STORE
    scene = study.load_scene(args.scene, args.set)
    study.run_scene(scene, warn=False)          # disk FE cache and numba warm
    STORE.clear()
    out = trace(scene)
    stays, climbs = out["stays"], out["climbs"]
    files = Counter()
    for (f, _), n in stays.items():
        files[f] += n
    print(f"scene: {args.scene or 'paper'} {' '.join(args.set)}")
    print(f"stays of the scene: {sum(stays.values())} calls of {len(stays)} functions in {len(files)} files")
    both = out["parts"] + stays
    print(f"stays of the scene or a section: {sum(both.values())} calls of {len(both)} functions in "
          f"{len({f for f, _ in both})} files")
    print(f"climbs from solver/ into study/: {len(climbs)} caller/callee pairs, {sum(climbs.values())} calls")
    for name in COUNTED:
        print(f"  {name:20s} {out['counters'][name]:4d} calls")
    if args.list:
        print("\nfiles (calls holding the scene):")
        for f, n in sorted(files.items(), key=lambda kv: -kv[1]):
            print(f"  {n:5d}  {f}")
        print("\nclimbs (calls):")
        for (a, b), n in sorted(climbs.items()):
            print(f"  {n:5d}  {a} -> {b}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

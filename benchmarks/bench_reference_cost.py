"""The FE reference's estimate (`study.verify.fe_reference.reference_cost`, what `lightgear
reference` checks against --max-time and the memory available before its work) against what
the reference takes: CPU seconds and peak memory over the process (its RSS after the imports),
each case in a fresh process from an empty FE cache, the estimate taken at a load factor of 1.

Cases: thin rims at fine meshes, where the FE bodies are the whole cost: the small lightened
pair (study/scenes/small_lightened.toml) with a 1.5 mm rim, and the paper pair with a 2.5 mm
rim (the web taking up the rest, as in bench_calculix.py's thin_rim), graded and fine
(`fe.mesh_grading`). A ratio measured/estimated outside [0.5, 2] fails the run (exit 1).
Run: .venv/bin/python benchmarks/bench_reference_cost.py [--quick]  (results/benchmarks/reference_cost.csv)
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

import common

SMALL = ("small_lightened", ["gear2.body.rim_height=1.5", "gear2.body.web_height=13.5"])
PAPER = ("paper", ["gear2.body.rim_height=2.5", "gear2.body.web_height=26.825"])
# (name, scene, overrides): a few sizes each, the finest still within some 3 GB
CASES = [
    ("small 0.5 graded", *SMALL, ["fe.mesh_size=0.5"]),
    ("small 0.25 graded", *SMALL, ["fe.mesh_size=0.25"]),
    ("small 0.18 graded", *SMALL, ["fe.mesh_size=0.18"]),
    ("small 0.35 fine", *SMALL, ["fe.mesh_size=0.35", "fe.mesh_grading='fine'"]),
    ("small 0.25 fine", *SMALL, ["fe.mesh_size=0.25", "fe.mesh_grading='fine'"]),
    ("paper 0.375 graded", *PAPER, ["fe.mesh_size=0.375"]),
    ("paper 0.25 graded", *PAPER, ["fe.mesh_size=0.25"]),
    ("paper 0.375 fine", *PAPER, ["fe.mesh_size=0.375", "fe.mesh_grading='fine'"]),
]
QUICK = ("small 0.5 graded", "small 0.35 fine")

ONE = r'''
import json, resource, sys, time
from study import estimate
estimate.load_factor = lambda: 1.0          # the estimate of a quiet machine
from study.scene import load_scene
from study.scene_model import static_angles
from study.verify.fe_reference import REFERENCE_MEMORY_FACTOR, reference, reference_cost
scene = load_scene(sys.argv[1], sys.argv[2:])
angles = static_angles(scene, None, REFERENCE_MEMORY_FACTOR)
est = reference_cost(scene, angles)
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
c0 = time.process_time()
reference(scene, angles)
print(json.dumps(dict(est_s=est.total_s, est_bytes=sum(est.memory.values()), cpu_s=time.process_time() - c0,
                      bytes=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - rss0)))
'''


def main() -> int:
    args, _ = common.quick_options(__doc__.splitlines()[0], f"only the cases {', '.join(QUICK)}")
    rows, bad = [], []
    for name, scene, base, over in CASES:
        if args.quick and name not in QUICK:
            continue
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, LIGHTGEAR_CACHE=cache, PYTHONPATH=str(common.ROOT))
            out = subprocess.run([sys.executable, "-c", ONE, scene, *base, *over], cwd=common.ROOT, env=env,
                                 capture_output=True, text=True)
        if out.returncode:
            raise RuntimeError(f"{name}: {out.stderr[-2000:]}")
        r = json.loads(out.stdout.strip().splitlines()[-1])
        row = dict(case=name, est_s=r["est_s"], cpu_s=r["cpu_s"], time_ratio=r["cpu_s"] / r["est_s"],
                   est_MB=r["est_bytes"] / 1e6, peak_MB=r["bytes"] / 1e6, memory_ratio=r["bytes"] / r["est_bytes"])
        rows.append(row)
        bad += [f"{name} {k}" for k in ("time_ratio", "memory_ratio") if not 0.5 <= row[k] <= 2.0]
    common.write_table("reference_cost", "FE reference from an empty FE cache: estimate against CPU and peak memory "
                       "over the process (ratio measured / estimated; target within [0.5, 2])", rows,
                       columns=("case", "est_s", "cpu_s", "time_ratio", "est_MB", "peak_MB", "memory_ratio"))
    if bad:
        print("outside a factor of two: " + ", ".join(bad))
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())

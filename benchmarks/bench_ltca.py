"""FE reference (LTCA) of the Table 1 pair, 120 deg at 0.5 deg: time of each stage, cold cache.

Target: the whole reference under 60 s. Each case runs in a fresh process with an empty FE
cache, so the stages are the real cold cost; the second line of each case reruns with the
cache filled (only the contact problems are solved). The second table splits the cold runs into
their stages per gear body, wall and CPU seconds (CPU: all threads of the process; on a busy
machine wall exceeds CPU by the time the process waited for a core):

  imports     numpy, scipy, scikit-fem, the numba kernels (from the numba cache)
  teeth       which teeth meet the mesh over the rotation (rigid pre-search per angle)
  mesh        gmsh triangulation of the whole body
  assembly    scikit-fem basis, closed-form P2 plane-stress stiffness, clamping the bore
  factor      sparse LU of the free-DOF stiffness (SuperLU, symmetric mode)
  loads       flank load vectors and centreline read operators of every load case
  solve       all load cases through the factors (fe.influence: triangular solves on the reach)
  contact     the contact problem at every angle

Run: .venv/bin/python benchmarks/bench_ltca.py  (prints both tables, writes results/benchmarks/ltca.csv
and ltca_stages.csv)
"""
from __future__ import annotations

import csv
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ONE = r'''
import time
w_start, c_start = time.perf_counter(), time.process_time()
import json, os, resource
import numpy as np
from study.scene import default_scene
from study.scene_model import static_angles
from study.verify.fe_reference import reference
s = default_scene()
if {solid}:
    s = s.solid()
angles = static_angles(s, 0.5)
case = "solid" if {solid} else "lightened"
rows, stages = [], [dict(case=case, gear="-", stage="imports", wall_s=time.perf_counter() - w_start,
                         cpu_s=time.process_time() - c_start)]
for run in ("cold", "cached"):
    c0 = time.process_time(); t0 = time.perf_counter()
    res, model, info = reference(s, angles)
    rows.append(dict(case=case + " " + run, angles=int(angles.size),
                     load_cases=int(info["gear1"]["load_cases"] * (not info["gear1"]["cached"]) + info["gear2"]["load_cases"] * (not info["gear2"]["cached"])),
                     compliance_s=info["wall_time_compliance_s"], contact_s=info["wall_time_contact_s"],
                     total_s=time.perf_counter() - t0, cpu_s=time.process_time() - c0,
                     peak_MB=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                     ste_mean_um=float(res.te.mean() * 1e6), ste_p2p_um=float(np.ptp(res.te) * 1e6)))
    if run == "cold":
        stages.append(dict(case=case, gear="-", stage="teeth", wall_s=info["wall_time_teeth_s"], cpu_s=info["cpu_time_teeth_s"]))
        for g in (1, 2):
            st = info[f"gear{{g}}"].get("stages", {{}})
            for name in ("mesh", "assembly", "factor", "loads", "solve"):
                if f"{{name}}_wall_s" in st:
                    stages.append(dict(case=case, gear=str(g), stage=name, wall_s=st[f"{{name}}_wall_s"], cpu_s=st[f"{{name}}_cpu_s"]))
        stages.append(dict(case=case, gear="-", stage="contact", wall_s=info["wall_time_contact_s"], cpu_s=info["cpu_time_contact_s"]))
        stages.append(dict(case=case, gear="-", stage="total (from start)", wall_s=time.perf_counter() - w_start,
                           cpu_s=time.process_time() - c_start))
print(json.dumps(dict(rows=rows, stages=stages)))
'''


def main() -> int:
    root = Path(__file__).resolve().parents[1]
    rows, stages = [], []
    for solid in (True, False):
        with tempfile.TemporaryDirectory() as cache:
            env = {**__import__("os").environ, "LIGHTGEAR_CACHE": cache}
            out = subprocess.run([sys.executable, "-c", ONE.format(solid=solid)], cwd=root, capture_output=True, text=True, env=env)
        if out.returncode:
            raise RuntimeError(out.stderr)
        got = json.loads(out.stdout.strip().splitlines()[-1])
        rows += got["rows"]
        stages += got["stages"]
    head = ("case", "angles", "load_cases", "compliance_s", "contact_s", "total_s", "cpu_s", "peak_MB", "ste_mean_um", "ste_p2p_um")
    print("FE reference STE (LTCA), Table 1 pair, 120 deg at 0.5 deg, default mesh (target: total < 60 s)")
    print(" ".join(f"{h:>16s}" for h in head))
    for r in rows:
        print(" ".join(f"{r[h]:>16.4g}" if isinstance(r[h], float) else f"{r[h]:>16}" for h in head))
    print()
    print("cold-cache stages (s): wall / CPU per gear body")
    shead = ("case", "gear", "stage", "wall_s", "cpu_s")
    print(f"{'case':>10s} {'gear':>4s} {'stage':>20s} {'wall_s':>9s} {'cpu_s':>9s}")
    for r in stages:
        print(f"{r['case']:>10s} {r['gear']:>4s} {r['stage']:>20s} {r['wall_s']:>9.2f} {r['cpu_s']:>9.2f}")
    out_dir = root / "results" / "benchmarks"
    out_dir.mkdir(parents=True, exist_ok=True)
    for name, fields, data in (("ltca.csv", head, rows), ("ltca_stages.csv", shead, stages)):
        with (out_dir / name).open("w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=fields)
            w.writeheader()
            w.writerows(data)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

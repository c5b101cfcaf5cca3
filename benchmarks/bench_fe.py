"""FE tooth-stiffness map of the Table 1 lightened gear: time and memory of each stage.

Target: the whole map (mesh + assembly + factorisation + 67 load cases) under 20 s and 2 GB.
Each mesh size runs in a fresh process so the peak resident memory is its own.
Run: .venv/bin/python benchmarks/bench_fe.py  (prints a table, writes results/benchmarks/fe.csv)
"""
from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

ONE = r'''
import json, resource, time
from solver.fe import body as fe
from solver.fe.mesh import mesh_body
from study.scene import default_scene
from study.inputs.gearsetup import gear_setup
size_mm = {size}
gs = gear_setup(default_scene().replace(**{{"fe.mesh_size": size_mm}}), 2)
g, body = gs.geometry, gs.body
t0 = time.perf_counter(); mesh = mesh_body(g, body, gs.mesh_size); t1 = time.perf_counter()
model = fe.assemble(mesh, g.spec.face_width, body.web_thickness, gs.material)
t2 = time.perf_counter()
k, _ = fe.tooth_stiffness(model, g, gs.pivot_radius, range(g.teeth), gs.force, gs.patch)
t3 = time.perf_counter()
print(json.dumps(dict(size_mm=size_mm, elements=int(mesh.n_elements), dofs=int(model.n_dofs), mesh_s=t1 - t0,
                      assembly_s=model.assembly_time, factor_s=model.factor_time, solves_s=t3 - t2,
                      total_s=t3 - t0, peak_MB=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      k_min=float(k.min()), k_max=float(k.max()))))
'''


def main() -> int:
    root = Path(__file__).resolve().parents[1]
    rows = []
    for size in (0.5, 0.375, 0.3):
        out = subprocess.run([sys.executable, "-c", ONE.format(size=size)], cwd=root, capture_output=True, text=True)
        if out.returncode:
            raise RuntimeError(out.stderr)
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    head = ("size_mm", "elements", "dofs", "mesh_s", "assembly_s", "factor_s", "solves_s", "total_s", "peak_MB", "k_min", "k_max")
    print("FE tooth-stiffness map, Table 1 lightened gear, 67 load cases (k in N m/rad; default size 0.375 mm)")
    print(" ".join(f"{h:>11s}" for h in head))
    for r in rows:
        print(" ".join(f"{r[h]:>11.4g}" if isinstance(r[h], float) else f"{r[h]:>11d}" for h in head))
    out = root / "results" / "benchmarks"
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "fe.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=head)
        w.writeheader()
        w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())

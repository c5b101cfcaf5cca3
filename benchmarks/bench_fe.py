"""FE tooth-stiffness map of the Table 1 lightened gear: time and memory of each stage, fine and
graded meshes; with ``--convergence`` also the graded mesh against the fine one on every tooth.

Target: the whole map (mesh + assembly + factorisation + 67 load cases) under 20 s and 2 GB.
Each (size, grading) runs in a fresh process so the peak resident memory is its own. Times are
CPU seconds of the process (the machine may be shared: the load average is printed).
``--convergence``: every tooth's stiffness and largest fillet stress of four driven-gear bodies
(Table 1; 12 holes of 7 mm in a 6 mm web on a 5 mm rim; the same without holes; the solid body)
on the graded mesh against the fine one (the reference), and the stiffness ratio to the solid.
Run: .venv/bin/python benchmarks/bench_fe.py [--convergence]  (results/benchmarks/fe.csv)
"""
from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

ONE = r'''
import json, resource, sys, time
sys.path.insert(0, {root!r})
from solver.fe import body as fe
from solver.fe.mesh import mesh_body
from study.scene import default_scene
from study.inputs.gearsetup import gear_setup
size_mm = {size}
gs = gear_setup(default_scene().replace(**{{"fe.mesh_size": size_mm}}), 2)
g, body = gs.geometry, gs.body
c0 = time.process_time(); mesh = mesh_body(g, body, gs.mesh_size, grading={grading!r}); c1 = time.process_time()
model = fe.assemble(mesh, g.spec.face_width, body.web_thickness, gs.material)
c2 = time.process_time()
k, U = fe.tooth_stiffness(model, g, gs.pivot_radius, range(g.teeth), gs.force, gs.patch)
c3 = time.process_time()
s = fe.fillet_stress(model, g, U, range(g.teeth))
c4 = time.process_time()
print(json.dumps(dict(size_mm=size_mm, grading={grading!r}, elements=int(mesh.n_elements), dofs=int(model.n_dofs),
                      mesh_s=c1 - c0, assembly_s=model.assembly_cpu, factor_s=model.factor_cpu, solves_s=c3 - c2,
                      stress_s=c4 - c3, total_s=c4 - c0,
                      peak_MB=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      k_min=float(k.min()), k_max=float(k.max()))))
'''

BODIES = {
    "Table 1 (6 holes, 10 mm web)": {},
    "12 holes R7, 6 mm web, 5 mm rim": {"gear2.body.holes": 12, "gear2.body.hole_radius": 7.0,
                                        "gear2.body.rim_height": 5.0, "gear2.body.web_thickness": 6.0},
    "no holes, 6 mm web, 5 mm rim": {"gear2.body.holes": 0, "gear2.body.rim_height": 5.0,
                                     "gear2.body.web_thickness": 6.0},
}


def stages(root: Path) -> list[dict]:
    rows = []
    for size, grading in ((0.375, "fine"), (0.375, "graded"), (0.5, "fine"), (0.3, "graded")):
        code = ONE.format(root=str(root), size=size, grading=grading)
        out = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True)
        if out.returncode:
            raise RuntimeError(out.stderr)
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    return rows


def convergence() -> list[str]:
    """Graded against fine on every tooth of each body in `BODIES` and the solid body."""
    from solver.fe import body as fe
    from solver.fe.mesh import mesh_body
    from study.inputs.gearsetup import gear_setup
    from study.scene import default_scene

    def run(setup, grading):
        g, b = setup.geometry, setup.body
        model = fe.assemble(mesh_body(g, b, setup.mesh_size, grading=grading), g.spec.face_width, b.web_thickness,
                            setup.material)
        k, U = fe.tooth_stiffness(model, g, setup.pivot_radius, range(g.teeth), setup.force, setup.patch)
        return k, fe.fillet_stress(model, g, U, range(g.teeth))

    setups = {name: gear_setup(default_scene().replace(**kw), 2) for name, kw in BODIES.items()}
    setups["solid"] = setups[next(iter(BODIES))].solid()
    res = {name: {gr: run(s, gr) for gr in ("fine", "graded")} for name, s in setups.items()}
    solid = res["solid"]
    lines = [f"{'body':34s} {'max |dk|':>9s} {'mean dk':>9s} {'max |d ratio|':>14s} {'max |d stress|':>15s}"]
    for name, r in res.items():
        dk = r["graded"][0] / r["fine"][0] - 1
        ds = r["graded"][1] / r["fine"][1] - 1
        dr = (r["graded"][0] / solid["graded"][0][0]) / (r["fine"][0] / solid["fine"][0][0]) - 1
        lines.append(f"{name:34s} {abs(dk).max() * 100:8.3f}% {dk.mean() * 100:+8.3f}% {abs(dr).max() * 100:13.3f}% "
                     f"{abs(ds).max() * 100:14.2f}%")
    return lines


def main() -> int:
    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root))
    load = os.getloadavg()[0]
    rows = stages(root)
    head = ("size_mm", "grading", "elements", "dofs", "mesh_s", "assembly_s", "factor_s", "solves_s", "stress_s",
            "total_s", "peak_MB", "k_min", "k_max")
    print(f"FE tooth-stiffness map, Table 1 lightened gear, 67 load cases, CPU s (k in N m/rad; default 0.375 mm "
          f"graded); load average {load:.1f} -> {os.getloadavg()[0]:.1f}")
    print(" ".join(f"{h:>11s}" for h in head))
    for r in rows:
        print(" ".join(f"{r[h]:>11.4g}" if isinstance(r[h], float) else f"{r[h]:>11}" for h in head))
    out = root / "results" / "benchmarks"
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "fe.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=head)
        w.writeheader()
        w.writerows(rows)
    if "--convergence" in sys.argv[1:]:
        print("graded against fine (0.375 mm), every tooth: stiffness, stiffness ratio to the solid body, fillet stress")
        print("\n".join(convergence()))
    return 0


if __name__ == "__main__":
    sys.exit(main())

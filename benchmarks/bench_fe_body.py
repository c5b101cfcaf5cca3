"""CPU of one lightened body's FE inputs in a study: the spring map, its root stress and the bulk
compliance (every tooth loaded at 8 points of its profile), factorised whole against solved
through the teeth and rim condensed once per rim height (`solver.fe.condense`), with the
accuracy of the condensed inputs against the whole body's.

Bodies: the paper's (Table 1: 6 holes, 10 mm web) and one of the standard sensitivity study
(12 holes of 7 mm in a 6 mm web on a 5 mm rim). Per body and path: the CPU seconds of the mesh,
the assembly and factorisation, the map with its stress, and the compliance, from an empty FE
cache, each path in a fresh process with imports and the rim of its rim height made first (as a
study's worker does after its first body of that rim; the rim's own cost is a row of its own).
Run: .venv/bin/python benchmarks/bench_fe_body.py  (results/benchmarks/fe_body.csv)
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

import common

ONE = r'''
import json, os, sys, time
sys.path.insert(0, {root!r})
import numpy as np
from study.scene import default_scene
from study.inputs import compliance as C, springs as S
from study.inputs.cache import FE_CACHE
from study.inputs.gearsetup import gear_setups
C.CONDENSE = {condense}
over = {over!r}
warm = dict(over, **{{"gear2.body.holes": 3, "gear2.body.hole_radius": 5.0}})   # another web of the same rim
def inputs(o):
    setup = gear_setups(default_scene().replace(**o))[1]
    c0 = time.process_time()
    stages = {{}}
    model = C.factorised_body(setup, stages)
    c1 = time.process_time()
    k = S.fe_stiffness(setup); s = S.root_stress(setup)
    c2 = time.process_time()
    g, info = C.gear_compliance(setup, list(range(setup.teeth)), 0)
    c3 = time.process_time()
    return dict(body_s=c1 - c0, mesh_s=stages.get("mesh_cpu_s"), map_s=c2 - c1, compliance_s=c3 - c2,
                total_s=c3 - c0, condensed=model.condensed is not None), (k, s, g.g)
c0 = time.process_time()
inputs(warm)
warm_s = time.process_time() - c0
FE_CACHE.bodies.clear()
row, (k, s, g) = inputs(over)
np.savez({out!r}, k=k, s=s, g=g)
row.update(warm_s=warm_s, load=os.getloadavg()[0])
print(json.dumps(row))
'''

BODIES = {
    "paper (6 holes R6, 10 mm web, rim 6.075 mm)": {},
    "study (12 holes R7, 6 mm web, rim 5 mm)": {"gear2.body.holes": 12, "gear2.body.hole_radius": 7.0,
                                                "gear2.body.rim_height": 5.0, "gear2.body.web_thickness": 6.0},
}


def run(over: dict, condense: bool, out: str) -> dict:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, LIGHTGEAR_CACHE=cache)
        code = ONE.format(root=str(common.ROOT), condense=condense, over=over, out=out)
        p = subprocess.run([sys.executable, "-c", code], cwd=common.ROOT, capture_output=True, text=True, env=env)
    if p.returncode:
        raise RuntimeError(p.stderr)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> int:
    import numpy as np
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, over in BODIES.items():
            res = {}
            for condense in (False, True):
                out = os.path.join(tmp, f"{len(rows)}-{condense}.npz")
                r = run(over, condense, out)
                res[condense] = (r, dict(np.load(out)))
                note = (f"mesh {r['mesh_s']:.2f}, body {r['body_s']:.2f}, map+stress {r['map_s']:.2f}, "
                        f"compliance {r['compliance_s']:.2f} s CPU; load {r['load']:.1f}")
                if condense:
                    a, b = res[True][1], res[False][1]
                    note += (f"; vs whole: stiffness {np.abs(a['k'] / b['k'] - 1).max():.1e}, root stress "
                             f"{np.abs(a['s'] / b['s'] - 1).max():.1e}, compliance "
                             f"{np.abs(a['g'] - b['g']).max() / np.abs(b['g']).max():.1e} (largest relative)")
                    rows.append(dict(case=name, method="first body of its rim (rim condensed)", cpu_min_s=r["warm_s"],
                                     repeats=1, note="imports, the rim and its compliance products, a first web"))
                rows.append(dict(case=name, method="condensed rim" if condense else "whole body", cpu_min_s=r["total_s"],
                                 repeats=1, note=note))
    common.add_ratios([r for r in rows if r["method"] != "first body of its rim (rim condensed)"])
    common.write_table("fe_body", "FE inputs of one lightened body (map, root stress, compliance): CPU s", rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""FE reference (LTCA) of the Table 1 pair, 120 deg at 0.5 deg: time of each stage, cold cache.

Target: the whole reference under 60 s. Each case runs in a fresh process with an empty FE
cache, so the stages are the real cold cost; the second line of each case reruns with the
cache filled (only the contact problems are solved).
Run: .venv/bin/python benchmarks/bench_ltca.py  (prints a table, writes results/benchmarks/ltca.csv)
"""
from __future__ import annotations

import csv
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ONE = r'''
import json, os, resource, time
import numpy as np
from study.scene import default_scene
from study.reference import reference, static_angles
s = default_scene()
if {solid}:
    s = s.replace(**{{"gear2.body.holes": 0, "gear2.body.web_thickness": 17.0}})
angles = static_angles(s, 0.5)
rows = []
for run in ("cold", "cached"):
    c0 = time.process_time(); t0 = time.perf_counter()
    res, model, info = reference(s, angles)
    rows.append(dict(case=("solid" if {solid} else "lightened") + " " + run, angles=int(angles.size),
                     load_cases=int(info["gear1"]["load_cases"] * (not info["gear1"]["cached"]) + info["gear2"]["load_cases"] * (not info["gear2"]["cached"])),
                     compliance_s=info["wall_time_compliance_s"], contact_s=info["wall_time_contact_s"],
                     total_s=time.perf_counter() - t0, cpu_s=time.process_time() - c0,
                     peak_MB=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                     ste_mean_um=float(res.te.mean() * 1e6), ste_p2p_um=float(np.ptp(res.te) * 1e6)))
print(json.dumps(rows))
'''


def main() -> int:
    root = Path(__file__).resolve().parents[1]
    rows = []
    for solid in (True, False):
        with tempfile.TemporaryDirectory() as cache:
            env = {**__import__("os").environ, "LIGHTGEAR_CACHE": cache}
            out = subprocess.run([sys.executable, "-c", ONE.format(solid=solid)], cwd=root, capture_output=True, text=True, env=env)
        if out.returncode:
            raise RuntimeError(out.stderr)
        rows += json.loads(out.stdout.strip().splitlines()[-1])
    head = ("case", "angles", "load_cases", "compliance_s", "contact_s", "total_s", "cpu_s", "peak_MB", "ste_mean_um", "ste_p2p_um")
    print("FE reference STE (LTCA), Table 1 pair, 120 deg at 0.5 deg, default mesh (target: total < 60 s)")
    print(" ".join(f"{h:>16s}" for h in head))
    for r in rows:
        print(" ".join(f"{r[h]:>16.4g}" if isinstance(r[h], float) else f"{r[h]:>16}" for h in head))
    path = root / "results" / "benchmarks" / "ltca.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=head)
        w.writeheader()
        w.writerows(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

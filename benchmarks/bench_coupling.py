"""The foundation-coupled models against the plain one on the Table 1 pair: identification
from the FE body, STE, and the paper's dynamic case.

Target: the coupled models in the same speed class as the plain model (dynamic 0.2 s case
at the default step of a run, and STE): the compliance model's dynamic case within 2 x the
plain model's CPU. The identification needs the FE influence coefficients: the first run computes
and caches them (about 1.5 min for the lightened body's every-tooth loads), later runs read
them; the table shows the cached figure and says which.
Run: python benchmarks/bench_coupling.py [--quick]   (writes results/benchmarks/coupling.csv)
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import common  # noqa: I001  (first: pins BLAS to one thread before numpy loads)
import numpy as np
from common import PAPER_DYNAMIC, best_of


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="solid pair only, fewer repeats")
    args = ap.parse_args(argv)
    os.environ.setdefault("LIGHTGEAR_CACHE", str(common.ROOT / ".lightgear-cache"))
    from solver.mbs.dynamics import simulate
    from solver.mbs.stability import implicit_dampers_apply, stable_time_step
    from solver.mbs.statics import solve_static
    from study.scene_model import build_scene_model, static_angles

    rows = []
    kinds = ["solid"] if args.quick else ["solid", "lightened"]
    for kind in kinds:
        base = common.scene(kind)
        for coupling in ("none", "body-torsion", "compliance"):
            sc = base.replace(**{"coupling.model": coupling})
            t0, c0 = time.perf_counter(), time.process_time()
            m = build_scene_model(sc)
            ident = dict(wall_min_s=time.perf_counter() - t0, cpu_min_s=time.process_time() - c0, repeats=1)
            label = {"none": "plain (paper springs)", "body-torsion": "body-torsion", "compliance": "compliance"}[coupling]
            if coupling != "none":
                rows.append(dict(case=f"identification from the FE body, {kind}", method=label, **ident,
                                 note="FE influence coefficients from the disk cache when present (first run: FE solves)"))
            ang = static_angles(sc)
            tq = sc.quasi_static.torque
            solve_static(m, ang[:5], tq)
            tim, st = best_of(lambda: solve_static(m, ang, tq), 3 if args.quick else 5)
            rows.append(dict(case=f"STE {ang.size} angles, {kind}", method=label, **tim,
                             note=f"mean {st.te.mean() * 1e6:.3f} um, peak-to-peak {np.ptp(st.te) * 1e6:.3f} um"))
            speed, sramp, tq, tramp, dur = PAPER_DYNAMIC
            # the default step of a run (tooth-root dampers implicit where linear), estimated once
            dt, _w = stable_time_step(m, tq, implicit_dampers=implicit_dampers_apply(m))
            simulate(m, speed, sramp, tq, tramp, 1e-3)
            tim, dy = best_of(lambda: simulate(m, speed, sramp, tq, tramp, dur), 1 if args.quick else 3)
            e = np.abs(dy.energy_error)
            rows.append(dict(case=f"dynamic 0.2 s at 100 rad/s, {kind}", method=label, **tim,
                             note=f"dt {dy.dt * 1e6:.3g} us (bound estimate {dt * 1e6:.3g} us), {dy.steps} steps, up to "
                                  f"{dy.max_active_teeth} active teeth; energy error {e.max() / dy.potential.max():.3g} x "
                                  f"the mesh's potential energy; status {dy.message}"))
    common.add_ratios(rows)
    common.write_table("coupling", "Coupled models against the plain one, Table 1 pair (s; ratio on CPU time to the fastest in the case)", rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())

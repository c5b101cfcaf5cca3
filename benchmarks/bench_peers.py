"""lightgear against the tools an engineer would use instead, on the same scenes and equations.

Scenes: the Table 1 pair with a solid driven gear, and as published (lightened driven gear,
per-tooth FE springs from study.inputs.springs, cached on disk).
* Quasi-static STE, 120 deg at 0.1 deg (1201 angles): lightgear's numba Newton sweep against
  a scipy.optimize.root loop over the same equations (solver.peers.scipy_statics, every tooth
  free), timed on the first ROOT_ANGLES angles and scaled per angle.
* Dynamic: the slow peers run a short window (100 rad/s and 50 N m reached in 0.5 ms, 1.5 ms
  simulated): the plain numpy + scipy solve_ivp implementation (solver.peers.scipy_dynamics, LSODA and
  Radau with analytic Jacobian) over a ladder of tolerances, and the same model in Exudyn
  (benchmarks/peers/exudyn_pair.py, its velocity Verlet and RK44 at lightgear's step, and RK44
  at a quarter of it: the check that both codes agree on TE).
  Errors are max |TE - TE_ref| [um] over the window; the reference is the all-teeth explicit
  solver at 1/32 of the stable step (the equations of the peers; it agrees with DOP853 at
  rtol 1e-10 to about 1e-4 um, see tests/test_reference.py). The 0.2 s rows scale the peers'
  window cost per simulated second (marked "scaled"); lightgear's 0.2 s row is measured.
Targets: dynamic >= 500x faster than the scipy peer and faster than Exudyn at equal TE error;
STE >= 1000x faster than the root loop.
Run: python benchmarks/bench_peers.py [--quick]   (writes results/benchmarks/peers.csv)
"""
from __future__ import annotations

import sys

import common  # noqa: I001  (first: pins BLAS to one thread before numpy loads)
import numpy as np
from common import PAPER_DYNAMIC, SHORT_DYNAMIC, best_of

ROOT_ANGLES = 60          # 6 deg: more than one mesh cycle (5.37 deg)


def static_rows(kind, m, sc, rep):
    from solver.mbs.statics import solve_static
    from solver.peers.scipy_statics import static_te_root
    from study.scene_model import static_angles
    ang = static_angles(sc)
    tq = sc.quasi_static.torque
    solve_static(m, ang[:5], tq)
    tim, st = best_of(lambda: solve_static(m, ang, tq), rep + 2)
    troot, rt = best_of(lambda: static_te_root(m, ang[:ROOT_ANGLES], tq), 1)
    scale = ang.size / ROOT_ANGLES
    case = f"STE {ang.size} angles, {kind}"
    err = float(np.max(np.abs(rt.te - st.te[:ROOT_ANGLES]))) * 1e6
    return [dict(case=case, method="lightgear solve_static (numba Newton)", **tim, error_um=0.0,
                 note=f"{tim['cpu_min_s'] / ang.size * 1e6:.3g} us per angle; the reference"),
            dict(case=case, method="scipy optimize.root loop (lm), scaled", **common.scaled(troot, scale), error_um=err,
                 note=f"timed on {ROOT_ANGLES} angles x {scale:.2f}; {troot['cpu_min_s'] / ROOT_ANGLES * 1e3:.3g} ms per angle; "
                      f"{int(np.sum(rt.iterations < 0))} failed")]


def dynamic_rows(kind, m, rep, quick):
    import exudyn
    from peers.exudyn_pair import simulate_exudyn

    from solver.mbs.dynamics import Drive, simulate
    from solver.mbs.kernels.status import OK
    from solver.mbs.stability import stable_time_step
    from solver.peers.scipy_dynamics import simulate_explicit_all_teeth, simulate_scipy
    win = SHORT_DYNAMIC
    T = win[-1]
    dt, _w = stable_time_step(m, win[2])
    ref = simulate_explicit_all_teeth(m, *win, dt=dt / 32)
    case = f"dynamic {T * 1e3:.1f} ms window, {kind}"

    def err(te):
        return float(np.max(np.abs(te - ref.te))) * 1e6 if te.size == ref.te.size else float("nan")

    rows = []
    tim, dy = best_of(lambda: simulate(m, *win, dt=dt), rep, warmup=True)
    rows.append(dict(case=case, method="lightgear explicit (active set)", **tim, error_um=err(dy.te),
                     note=f"dt {dt * 1e6:.3g} us; error includes freezing the idle teeth"))
    tim, da = best_of(lambda: simulate_explicit_all_teeth(m, *win, dt=dt), rep, warmup=True)
    rows.append(dict(case=case, method="lightgear explicit (all teeth)", **tim, error_um=err(da.te),
                     note="exactly the peers' equations"))
    ladder = {"LSODA": (1e-3, 1e-4) if quick else (1e-3, 1e-4, 1e-5), "Radau": (1e-3,) if quick else (1e-3, 1e-4)}
    for meth, tols in ladder.items():
        for rtol in tols:
            tim, r = best_of(lambda: simulate_scipy(m, *win, method=meth, rtol=rtol), 1)
            rows.append(dict(case=case, method=f"numpy+scipy {meth} rtol {rtol:g}", **tim,
                             error_um=err(r.te) if r.status == OK else float("nan"),
                             note=f"{r.steps} steps, {r.nfev} f-evals, {r.njev} Jacobians; {r.message}"))
    for solver, div in (("VelocityVerlet", 1), ("RK44", 1), ("RK44", 4)):
        tim, (t, te, _wall) = best_of(lambda: simulate_exudyn(m, Drive(*win), dt=dt / div, solver=solver), 1)
        rows.append(dict(case=case, method=f"Exudyn {solver} dt {dt / div * 1e6:.3g} us", **tim, error_um=err(te),
                         note=f"Exudyn {exudyn.__version__}; all teeth; Python user-function forces"))
    common.add_ratios(rows)
    # the paper's 0.2 s case: lightgear measured, the peers scaled per simulated second
    speed, sramp, tq, tramp, dur = PAPER_DYNAMIC
    simulate(m, speed, sramp, tq, tramp, 1e-3, dt=dt)
    tim, full = best_of(lambda: simulate(m, speed, sramp, tq, tramp, dur, dt=dt), 3)
    case_full = f"dynamic 0.2 s at 100 rad/s, {kind}"
    out = [dict(case=case_full, method="lightgear explicit (active set)", **tim,
                note=f"measured; {tim['cpu_min_s'] / dur:.2f} x real time; {full.steps} steps")]
    for r in rows:
        if not r["method"].startswith("lightgear"):
            t = {k: r.get(k) for k in ("wall_min_s", "wall_median_s", "cpu_min_s", "repeats")}
            out.append(dict(case=case_full, method=r["method"] + ", scaled", **common.scaled(t, dur / T),
                            note=f"window cost x {dur / T:.0f}"))
    common.add_ratios(out)
    return rows + out


def summary(rows):
    lines = []
    for case in dict.fromkeys(r["case"] for r in rows):
        rs = [r for r in rows if r["case"] == case]
        lg = rs[0]
        if case.startswith("STE"):
            lines.append(f"{case}: root loop / lightgear = {rs[1]['cpu_min_s'] / lg['cpu_min_s']:.0f}x CPU time (target >= 1000x)")
            continue
        if "window" not in case:
            continue
        for lg in rs[:2]:
            lines += _equal_error(case, rs, lg)
    return lines


def _equal_error(case, rs, lg):
    """For each peer family, the cheapest run at an error no larger than lightgear's (x1.5)."""
    lines = []
    e = lg["error_um"]
    for fam in ("numpy+scipy LSODA", "numpy+scipy Radau", "Exudyn"):
        runs = [r for r in rs if r["method"].startswith(fam)]
        ok = [r for r in runs if np.isfinite(r["error_um"]) and r["error_um"] <= max(e, 1e-12) * 1.5]
        if ok:
            c = min(ok, key=lambda r: r["cpu_min_s"])
            lines.append(f"{case}: {c['method']} (error {c['error_um']:.3g} um vs {lg['method']} {e:.3g} um) "
                         f"takes {c['cpu_min_s'] / lg['cpu_min_s']:.0f}x its CPU time")
        elif runs:
            b = min(runs, key=lambda r: r["error_um"] if np.isfinite(r["error_um"]) else 1e30)
            lines.append(f"{case}: no {fam} run reached the error {e:.3g} um of {lg['method']} (best {b['method']}: "
                         f"{b['error_um']:.3g} um, {b['cpu_min_s'] / lg['cpu_min_s']:.0f}x its CPU time)")
    return lines


def main(argv=None) -> int:
    args, rep = common.quick_options(__doc__.splitlines()[0], "solid scene only, shorter tolerance ladders", argv)
    rows = []
    for kind in (["solid"] if args.quick else ["solid", "lightened"]):
        m = common.model(kind, "paper")      # the peers integrate the paper's per-tooth springs
        rows += static_rows(kind, m, common.scene(kind, "paper"), rep)
        rows += dynamic_rows(kind, m, rep, args.quick)
    common.add_ratios(rows)
    common.write_table("peers", "lightgear vs peers, Table 1 pairs (s; best of N; error = max |TE - TE_ref| um; "
                                "ratio on CPU time to the fastest in the case)", rows)
    for line in summary(rows):
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""How the explicit solver's cost grows: with the number of teeth, with the number of teeth
kept in the integration (active set), and with speed. Solid Table 1 gears (m = 1.5 mm, so the
tooth, its springs and the contact law stay the same), 50 N m.

* teeth: Z = 20 ... 200 on both gears, rim/web/hub heights scaled with the root radius,
  driver at 100*67/Z rad/s: the pitch-line speed (5 m/s) and the mesh frequency (1066 Hz)
  stay those of the paper case;
* active teeth: the pre-search margin (fraction of a pitch added to the flank window) and the
  quiet threshold phi_quiet (when a tooth that left the mesh is frozen) at Z = 67, and every
  tooth active (the all-teeth model) as the far end;
* speed: 25 ... 400 rad/s at Z = 67.
Each point: speed and load ramps of 20 ms (a solid Z = 200 gear has 80 times the inertia of
the Z = 67 one: a faster ramp overloads its teeth), 30 ms simulated, at the scene's stable
step; cost = best-of-3 CPU time / simulated time (one core; wall times in the table too);
exponents from least squares on log-log.
Run: python benchmarks/bench_scaling.py [--quick]   (writes results/benchmarks/scaling.csv)
"""
from __future__ import annotations

import argparse
import sys

import common  # noqa: I001  (first: pins BLAS to one thread before numpy loads)
import numpy as np
from common import best_of

RAMP, DUR, TORQUE = 0.02, 0.03, 50.0
COLUMNS = ("series", "value", "wall_min_s", "wall_median_s", "cpu_min_s", "cost_s_per_s", "us_per_step",
           "max_active_teeth", "steps", "note")


def z_model(z: int):
    from study.scene_model import build_scene_model
    s = common.scene("solid", "paper")
    f = (1.5 * z / 2 - 1.25 * 1.5) / (1.5 * 67 / 2 - 1.25 * 1.5)
    over = {}
    for g in (1, 2):
        over[f"gear{g}.teeth"] = z
        for k in ("rim_height", "web_height", "hub_height"):
            over[f"gear{g}.body.{k}"] = getattr(s.gear(g).body, k) * f
    return build_scene_model(s.replace(**over))


def point(series, value, m, speed=100.0, phi_quiet=1e-9, all_teeth=False, note=""):
    from solver.mbs.dynamics import simulate
    from solver.mbs.stability import stable_time_step
    from solver.peers.scipy_dynamics import simulate_explicit_all_teeth
    dt, _w = stable_time_step(m, TORQUE)
    if all_teeth:
        fn = lambda: simulate_explicit_all_teeth(m, speed, RAMP, TORQUE, RAMP, DUR, dt=dt)  # noqa: E731
    else:
        fn = lambda: simulate(m, speed, RAMP, TORQUE, RAMP, DUR, dt=dt, phi_quiet=phi_quiet)  # noqa: E731
    tim, r = best_of(fn, 3, warmup=True)
    if r.status:
        note = (note + "; " if note else "") + r.message
    c = tim["cpu_min_s"]
    return dict(series=series, value=value, **tim, cost_s_per_s=c / DUR, us_per_step=c / r.steps * 1e6,
                max_active_teeth=r.max_active_teeth, steps=r.steps, note=note)


def exponent(x, y) -> float:
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer points")
    args = ap.parse_args(argv)
    from solver.mbs.kernels import layout as L
    rows = []
    zs = (20, 67, 200) if args.quick else (20, 30, 50, 67, 100, 150, 200)
    for z in zs:
        rows.append(point("teeth Z", z, z_model(z), speed=100.0 * 67 / z, note=f"driver {100.0 * 67 / z:.4g} rad/s"))
    base = common.model("solid", "paper")      # the all-teeth reference integrates the paper's springs
    pitch = base.geometry[0].pitch_angle
    margins = (0.5, 2.0, 4.0) if args.quick else (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
    for frac in margins:
        m = common.model("solid", "paper")
        m.pair_par[L.MARGIN] = frac * pitch
        rows.append(point("presearch margin [pitch]", frac, m, note="default 0.5"))
    for pq in ((1e-9, 1e-6) if args.quick else (1e-10, 1e-9, 1e-8, 1e-7, 1e-6)):
        rows.append(point("phi_quiet [rad]", pq, base, phi_quiet=pq, note="default 1e-9"))
    rows.append(point("all teeth active", 134, base, all_teeth=True, note="simulate_explicit_all_teeth"))
    for sp in ((25.0, 100.0, 400.0) if args.quick else (25.0, 50.0, 100.0, 200.0, 400.0)):
        rows.append(point("speed [rad/s]", sp, base, speed=sp))
    common.write_table("scaling", f"Explicit solver cost vs teeth, active teeth and speed (solid pair, {DUR * 1e3:.0f} ms "
                                  f"simulated, ramps {RAMP * 1e3:.0f} ms; s, best of 3, cost = CPU s per simulated s)", rows, COLUMNS)
    sel = [r for r in rows if r["series"] == "teeth Z"]
    print(f"cost per simulated second ~ Z^{exponent([r['value'] for r in sel], [r['cost_s_per_s'] for r in sel]):.2f}, "
          f"cost per step ~ Z^{exponent([r['value'] for r in sel], [r['us_per_step'] for r in sel]):.2f}")
    sel = [r for r in rows if r["series"] in ("presearch margin [pitch]", "phi_quiet [rad]", "all teeth active")]
    print(f"cost per step ~ (max active teeth)^{exponent([r['max_active_teeth'] for r in sel], [r['us_per_step'] for r in sel]):.2f}")
    sel = [r for r in rows if r["series"] == "speed [rad/s]"]
    print(f"cost per simulated second ~ speed^{exponent([r['value'] for r in sel], [r['cost_s_per_s'] for r in sel]):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Stability suite: stiff and extreme variants of the paper pair, each run with every integrator.

Every scene ends either bounded and physically plausible, or with a named failure (the
guard's cause, time and step; a Newton failure; a solver's wall-time limit): never with a
silent NaN. Checks of plausibility on a run that the guards let through: TE and contact force
finite and bounded (|TE| below the backlash offset plus a tenth of the module, the force below
that of 20 um of penetration or 20 times the static mesh force), and no energy growth (work in >= stored + dissipated energy
within 2 % of the larger of work and stored energy).

Scenes (overrides of the scene given, default the paper example; short runs: ``--duration``,
the ramps ending at half of it):
  paper, contact stiffness x100 and x0.01, no damping at all, teeth 100x lighter (density
  / 100: hub and teeth lighter alike), holes leaving a 0.5 mm ligament to the rim, a 1 mm web,
  1 hole, 24 holes, driver at 1000 rad/s, mesh frequency at the torsional resonance, zero
  torque (rattle in the backlash), reversed torque (-50 N·m: the load drives, coast flanks in
  contact), a torque reversal during the run (+50 -> -50 N·m from 60 to 80 % of the run: the
  mesh crosses the backlash and hits the coast flanks), tenfold overload (deep penetration,
  corner contact).
Lightened bodies take FE springs (cached on disk; ``--mesh-size`` mm, coarse by default).
Methods: explicit (at its stability step), implicit HHT alpha = 0 and alpha = -0.1 (at four
times that step), and the scipy peer LSODA (rtol 1e-4, every tooth free, stopped after
``scipy_wall`` seconds).

`study.stability_suite` runs it; `python -m workflows.stability` prints and archives its table.
"""
from __future__ import annotations

import math
import time

import numpy as np
import scipy.linalg
import xarray as xr

from solver import units
from solver.mbs.dynamics import Drive, ExplicitIntegrator
from solver.mbs.implicit import ImplicitIntegrator
from solver.mbs.kernels.status import INACCURATE
from solver.mbs.method import choose_method
from solver.mbs.stability import linearized_system
from solver.mbs.statics import solve_static
from solver.peers.scipy_dynamics import ScipyIntegrator
from study.archive.netcdf import provenance
from study.scene_model import build_scene_model, load_table

METHODS = ("explicit", "implicit alpha=0", "implicit alpha=-0.1", "LSODA")


def suite(scene) -> list[tuple[str, dict]]:
    """(name, overrides) of the suite's scenes, derived from ``scene``."""
    g2 = scene.gear2
    b = g2.body
    r_rim = g2.module * (g2.teeth / 2 - g2.dedendum) - b.rim_height           # mm, inner rim radius
    lig = r_rim - b.hole_circle_radius - 0.5                                    # hole radius leaving 0.5 mm
    holes = max(b.holes, 6)
    r24 = 0.5 * (2 * b.hole_circle_radius * math.sin(math.pi / 24)) - 0.75      # 1.5 mm between holes
    damping0 = {"gear1.spring.c_phi": 0.0, "gear2.spring.c_phi": 0.0, "contact.c_con": 0.0}
    d = scene.dynamic
    return [
        ("paper", {}),
        ("contact stiffness x100", {"contact.k_con": scene.contact.k_con * 100}),
        ("contact stiffness x0.01", {"contact.k_con": scene.contact.k_con * 0.01}),
        ("no damping", damping0),
        ("teeth 100x lighter", {"material.density": scene.material.density / 100}),
        ("0.5 mm ligament", {"gear2.body.holes": holes, "gear2.body.hole_radius": round(lig, 3)}),
        ("web 1 mm", {"gear2.body.web_thickness": 1.0}),
        ("1 hole", {"gear2.body.holes": 1}),
        ("24 holes", {"gear2.body.holes": 24, "gear2.body.hole_radius": round(min(b.hole_radius, r24), 3)}),
        ("1000 rad/s", {"dynamic.speed": 1000.0}),
        ("torsional resonance", {"dynamic.speed": None}),          # set from the model below
        ("zero torque", {"dynamic.torque": 0.0}),
        ("reversed torque", {"dynamic.torque": -abs(d.torque)}),
        ("torque reversal", {"dynamic.torque_change_time": None}),   # set from the duration below
        ("overload x10", {"dynamic.torque": 10 * d.torque}),
    ]


def torsional_frequency(model, torque: float) -> float:
    """Lowest non-zero natural frequency [rad/s] of the loaded pair at the nominal position:
    the torsional mode (driven hub against the mesh)."""
    st = solve_static(model, np.array([0.0]), torque if abs(torque) > 1e-9 else 1.0)
    M, K, _ = linearized_system(model, 0.0, st.theta2[0], st.phi_last)
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)
    lam = lam[lam > 1e-6 * lam.max()]
    return float(math.sqrt(lam.min()))


def plausibility(res, model, torque: float, method: str) -> str:
    """'' when the run is bounded and plausible, else the reason."""
    if not (np.all(np.isfinite(res.te)) and np.all(np.isfinite(res.force_max))):
        return "non-finite output"
    te_bound = model.backlash_offset + 0.1 * model.geometry[0].spec.module
    if np.max(np.abs(res.te)) > te_bound:
        return f"|TE| {np.max(np.abs(res.te)) * 1e6:.4g} um beyond {te_bound * 1e6:.4g} um"
    # 20 um of penetration (far beyond the elastic contact of the paper's pair) or, for a
    # soft contact that needs more under load, 20 times the static mesh force
    k, m1 = model.law_par[0], model.law_par[1]
    f_bound = max(k * 20e-6 ** m1, 20 * abs(torque) / model.base_radii[1])
    if np.max(res.force_max) > f_bound:
        return f"contact force {np.max(res.force_max):.4g} N beyond {f_bound:.4g} N"
    e = res.kinetic + res.potential
    growth = -res.energy_error
    scale = max(np.max(np.abs(res.work)), np.max(e), 1e-12)
    if np.max(growth) > 0.02 * scale:
        return f"energy grows by {np.max(growth):.3g} J ({np.max(growth) / scale:.1%} of the work)"
    return ""


def run_one(model, scene, method: str, duration: float, scipy_wall: float):
    d = scene.dynamic
    ramp = duration / 2
    # the torque-reversal scene's table; None: the ramp
    drive = Drive(d.speed, ramp, d.torque, ramp, duration, load_table(scene))
    if method == "LSODA":
        scipy = ScipyIntegrator(method="LSODA", rtol=1e-4, output_step=d.output_step, max_wall_time=scipy_wall)
        return scipy.run(model, drive), float("nan")
    choice = choose_method(model, d.torque, duration, "explicit" if method == "explicit" else "implicit")
    if method == "explicit":
        return ExplicitIntegrator(dt=choice.dt, output_step=d.output_step).run(model, drive), choice.dt
    alpha = 0.0 if method.endswith("=0") else -0.1
    return ImplicitIntegrator(dt=choice.dt, output_step=d.output_step, alpha=alpha).run(model, drive), choice.dt


def run_suite(scene, duration: float = 0.002, methods=None, scipy_wall: float = 20.0, names=None,
              mesh_size: float = 1.0, progress=print) -> xr.Dataset:
    """Stiff and extreme variants of a scene (`suite`), each run with every integrator of
    ``methods`` (None: `METHODS`) -> Dataset over (scene, method): status, message, TE range
    [um], largest contact force [N], step [s], wall time [s]."""
    from study.errors import check_scene_argument
    check_scene_argument("stability_suite", scene)
    methods = tuple(methods or METHODS)
    scenes = [(n, o) for n, o in suite(scene) if names is None or n in names]
    shape = (len(scenes), len(methods))
    status = np.full(shape, "", dtype=object)
    message = np.full(shape, "", dtype=object)
    te_min = np.full(shape, np.nan)
    te_max = np.full(shape, np.nan)
    fmax = np.full(shape, np.nan)
    step = np.full(shape, np.nan)
    wall = np.full(shape, np.nan)
    speeds = np.full(len(scenes), np.nan)
    torques = np.full(len(scenes), np.nan)
    for i, (name, over) in enumerate(scenes):
        over = dict(over)
        try:
            sc = scene.replace(**{"fe.mesh_size": mesh_size, "dynamic.duration": max(duration, scene.dynamic.output_step),
                                  **{k: v for k, v in over.items() if v is not None}})
            model = build_scene_model(sc)
            if "dynamic.torque_change_time" in over and over["dynamic.torque_change_time"] is None:
                sc = sc.replace(**{"dynamic.ramp_time": duration / 2, "dynamic.torque_change_time": 0.6 * duration,
                                   "dynamic.torque_change_duration": 0.2 * duration,
                                   "dynamic.torque_after": -sc.dynamic.torque})
            if "dynamic.speed" in over and over["dynamic.speed"] is None:
                w = torsional_frequency(model, sc.dynamic.torque)
                sc = sc.replace(**{"dynamic.speed": w / model.teeth[0]})      # mesh frequency = w
        except Exception as e:                   # a scene that cannot be built is a named failure
            status[i, :] = "invalid"
            message[i, :] = f"{type(e).__name__}: {e}"
            progress(f"{name}: invalid scene: {e}")
            continue
        speeds[i] = sc.dynamic.speed
        torques[i] = sc.dynamic.torque
        for j, m in enumerate(methods):
            t0 = time.perf_counter()
            try:
                res, dt = run_one(model, sc, m, duration, scipy_wall)
                wall[i, j] = time.perf_counter() - t0
                step[i, j] = dt if math.isfinite(dt) else res.dt
                te_min[i, j] = np.min(res.te) * units.UM_PER_M if res.te.size else np.nan
                te_max[i, j] = np.max(res.te) * units.UM_PER_M if res.te.size else np.nan
                fmax[i, j] = np.max(res.force_max) if res.force_max.size else np.nan
                if res.status == INACCURATE:
                    status[i, j] = "implausible"
                    message[i, j] = res.message
                elif res.status:
                    status[i, j] = "failed"
                    message[i, j] = res.message
                else:
                    why = plausibility(res, model, sc.dynamic.torque, m)
                    status[i, j] = "implausible" if why else "ok"
                    message[i, j] = why or "bounded and plausible"
            except Exception as e:
                wall[i, j] = time.perf_counter() - t0
                status[i, j] = "failed"
                message[i, j] = f"{type(e).__name__}: {e}"
            progress(f"{name:24s} {m:20s} {status[i, j]:11s} {wall[i, j]:7.2f} s  {message[i, j]}")
    return xr.Dataset(
        {
            "status": (("scene", "method"), status, {"long_name": "ok, failed (named by the guard or solver), implausible, invalid"}),
            "message": (("scene", "method"), message, {"long_name": "guard, solver or plausibility message"}),
            "te_min": (("scene", "method"), te_min, {"units": "um", "long_name": "smallest TE"}),
            "te_max": (("scene", "method"), te_max, {"units": "um", "long_name": "largest TE"}),
            "contact_force_max": (("scene", "method"), fmax, {"units": "N", "long_name": "largest contact force"}),
            "step": (("scene", "method"), step, {"units": "s", "long_name": "time step (scipy: mean step)"}),
            "wall_time": (("scene", "method"), wall, {"units": "s", "long_name": "wall time of the run"}),
            "speed": ("scene", speeds, {"units": "rad/s", "long_name": "final driver speed"}),
            "torque": ("scene", torques, {"units": "N*m", "long_name": "final resisting torque on gear 2"}),
        },
        coords={"scene": [n for n, _ in scenes], "method": list(methods)},
        attrs={"title": "stability suite", "duration_s": duration, "ramp_time_s": duration / 2,
               "fe_mesh_size_mm": mesh_size, "scipy_wall_time_limit_s": scipy_wall,
               "scene_base": scene.to_toml(), **provenance()},
    )

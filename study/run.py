"""Run one scene: scene -> model -> static and dynamic solves -> run archive (xarray).

`lightgear run [SCENE.toml] [-o OUT.nc] [--set key=value ...]` runs the embedded paper
example when no scene is given, writes the archive and prints a summary.
"""
from __future__ import annotations

import functools
import math
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.dynamics import run_loads, simulate
from solver.mbs.implicit import choose_method, simulate_implicit
from solver.mbs.kernels.layout import R_PV
from solver.mbs.model import ContactLaw, GearInput, Model, build_model
from solver.mbs.statics import solve_static
from study.report import results
from study.scene import Scene, load_scene


def tooth_springs(scene: Scene, g: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-tooth k_phi [N·mm/rad^n_k] and FE stiffness ratio [1] of gear g.

    A solid gear needs no FE: every tooth gets the scene's k_phi. A lightened gear's springs
    come from the FE body model (`study.inputs.springs`), unless its spring.stiffness is 'uniform'.
    """
    gs = scene.gear(g)
    z = gs.teeth
    if not scene.is_lightened(g) or gs.spring.stiffness == "uniform":
        return np.full(z, gs.spring.k_phi), np.ones(z)
    from study.inputs.springs import tooth_springs as fe_springs
    return fe_springs(scene, g)


@functools.lru_cache(maxsize=16)
def coupling_fit(scene: Scene, g: int):
    """Gear g's foundation coupling identified from its FE body: a `BodyTorsionFit`
    ('body-torsion'), a `ToothComplianceFit` ('compliance'), or None (the plain model).
    Kept per scene: a run asks for it for the springs and again for the model."""
    from study.inputs import coupling
    model = scene.coupling.model
    if model == "body-torsion":
        return coupling.body_torsion(scene, g)
    if model == "compliance":
        return coupling.tooth_compliance(scene, g)
    return None


def coupled_springs(scene: Scene, g: int) -> tuple[np.ndarray, np.ndarray]:
    """Gear g's tooth springs without the body wind-up [N·mm/rad] (linear, n_k = 1; with the
    compliance model each tooth's own spring, loaded alone) and the FE stiffness ratio [1] of
    the plain model's springs."""
    fit = coupling_fit(scene, g)
    k = fit.k_tooth if scene.coupling.model == "body-torsion" else fit.k_own
    return k / units.spring_stiffness_to_si(1.0), tooth_springs(scene, g)[1]


def scene_springs(scene: Scene):
    """((k1, r1), (k2, r2)): per-tooth springs [N·mm/rad^n_k] and stiffness ratios of both gears."""
    if scene.coupling.model != "none":
        return coupled_springs(scene, 1), coupled_springs(scene, 2)
    return tooth_springs(scene, 1), tooth_springs(scene, 2)


def build_scene_model(scene: Scene, springs=None) -> Model:
    """The solver model of a scene (SI). ``springs`` = ((k1, r1), (k2, r2)) skips the FE of
    the tooth springs (a coupled model still takes its body springs from the FE)."""
    springs = springs or scene_springs(scene)
    gears = []
    for g in (1, 2):
        gs = scene.gear(g)
        fit = coupling_fit(scene, g)
        cmat = None
        if fit is not None:
            k_body, n_k, pivot = fit.k_body, 1.0, fit.pivot_radius
            if scene.coupling.model == "compliance":
                cmat = fit.compliance
        else:
            k_body, n_k, pivot = math.inf, gs.spring.n_k, scene.pivot_radius(g)
        gears.append(GearInput(tooth=scene.tooth_spec(g), body=scene.body_spec(g),
                               pivot_radius=pivot,
                               k_phi=units.spring_stiffness_to_si(np.asarray(springs[g - 1][0], float)),
                               n_k=n_k, c_phi=units.spring_damping_to_si(gs.spring.c_phi),
                               n_c=gs.spring.n_c, body_stiffness=k_body, tooth_compliance=cmat))
    c = scene.contact
    law = ContactLaw(units.contact_stiffness_to_si(c.k_con, c.m1), c.m1,
                     units.contact_damping_to_si(c.c_con, c.m2, c.m3), c.m2, c.m3)
    return build_model(gears[0], gears[1], law, scene.material_spec())


def geometry_model(scene: Scene) -> Model:
    """The pair's geometry, inertia and contact law without any FE: plain uniform springs of
    the scene's k_phi and no foundation coupling. For what needs the kinematics and the
    contact law only (the mesh positions, the FE reference), not the tooth springs."""
    plain = scene.replace(**{"coupling.model": "none"})
    z1, z2 = scene.gear1.teeth, scene.gear2.teeth
    return build_scene_model(plain, springs=((np.full(z1, scene.gear1.spring.k_phi), np.ones(z1)),
                                             (np.full(z2, scene.gear2.spring.k_phi), np.ones(z2))))


def static_angles(scene: Scene) -> np.ndarray:
    """Driver angles [rad] of the quasi-static analysis."""
    qs = scene.quasi_static
    n = int(math.floor(qs.rotation / qs.angle_step + 1e-9)) + 1
    return np.radians(np.arange(n) * qs.angle_step)


def run_static(scene: Scene, model: Model):
    """STE by equilibrium at each angle, or by the paper's slow-ramp transient."""
    qs = scene.quasi_static
    angles = static_angles(scene)
    if qs.method == "static":
        return solve_static(model, angles, qs.torque, raise_on_failure=False)
    # slow-ramp transient: the driver reaches qs.speed after ramp_time; sample TE at the angles
    from solver.mbs.kernels.explicit import driver_motion
    from solver.mbs.statics import StaticResult
    dt_out = math.radians(qs.angle_step) / qs.speed / 4
    t_end = qs.ramp_time / 2 + angles[-1] / qs.speed + 2 * dt_out
    dyn = simulate(model, qs.speed, qs.ramp_time, qs.torque, qs.ramp_time, t_end, output_step=dt_out)
    th1 = np.array([driver_motion(t, qs.speed, qs.ramp_time)[0] for t in dyn.time])
    te = np.interp(angles, th1, dyn.te, right=np.nan)
    th2 = np.interp(angles, th1, dyn.theta2, right=np.nan)
    nc = np.round(np.interp(angles, th1, dyn.n_contacts)).astype(np.int64)
    it = np.where(np.isfinite(te), 1, -1)
    return StaticResult(angles, te, th2, nc, np.full((angles.size, model.teeth[0]), np.nan), it, qs.torque, np.full(model.n_teeth, np.nan))


def load_table(scene: Scene) -> np.ndarray | None:
    """The resisting-torque profile [time s, torque N·m] of a scene whose load changes during
    the run (dynamic.torque_change_time > 0): ramp to dynamic.torque, hold, then linear to
    dynamic.torque_after; None for the plain ramp."""
    d = scene.dynamic
    if d.torque_change_time <= 0:
        return None
    t1 = d.torque_change_time
    return np.array([[0.0, 0.0], [d.ramp_time, d.torque], [t1, d.torque],
                     [t1 + d.torque_change_duration, d.torque_after]])


def run_dynamic(scene: Scene, model: Model):
    """DTE run with the scene's integrator: dynamic.method 'explicit', 'implicit' or 'auto'
    (chosen from the stability step; see `solver.mbs.implicit.choose_method`). The result carries
    ``choice`` (the MethodChoice) for the archive."""
    d = scene.dynamic
    table = load_table(scene)
    step_torque = run_loads(table, d.torque)[1]
    choice = choose_method(model, step_torque, d.duration, d.method, d.time_step or None, d.alpha)
    args = (model, d.speed, d.ramp_time, d.torque, d.ramp_time, d.duration)
    if choice.method == "implicit":
        res = simulate_implicit(*args, dt=choice.dt, output_step=d.output_step, alpha=d.alpha, load_table=table)
    else:
        res = simulate(*args, dt=choice.dt, output_step=d.output_step, load_table=table)
    if math.isfinite(choice.omega_max):
        res.omega_max = choice.omega_max
    res.choice = choice
    return res


def run_scene(scene: Scene, static: bool | None = None, dynamic: bool | None = None, springs=None) -> xr.Dataset:
    """Run the analyses a scene asks for (or those forced by static/dynamic) -> run archive."""
    static = scene.quasi_static.enabled if static is None else static
    dynamic = scene.dynamic.enabled if dynamic is None else dynamic
    t0 = time.perf_counter()
    springs = springs or scene_springs(scene)
    t_springs = time.perf_counter() - t0
    model = build_scene_model(scene, springs)
    coords, data = results.stiffness_variables((springs[0][0], springs[1][0]), (springs[0][1], springs[1][1]))
    z1, z2 = model.teeth
    d = scene.dynamic
    driven_speed = d.speed * z1 / z2
    attrs = {
        "title": scene.title or "lightgear run",
        "scene": scene.to_toml(),
        "backlash_offset_um": model.backlash_offset * units.UM_PER_M,
        "contact_ratio": model.pair.contact_ratio,
        "mesh_order": float(z2),
        "hole_order": float(scene.gear2.body.holes),
        "driven_speed_rad_s": driven_speed,
        "ramp_time_s": d.ramp_time,
        "wall_time_springs_s": t_springs,
        "coupling": scene.coupling.model,
        "body_stiffness_N_m_rad": np.array([k if math.isfinite(k) else 0.0 for k in model.body_stiffness]),
        "pivot_radius_mm": model.gear_par[:, R_PV] * units.MM_PER_M,
        "teeth_coupled": int(model.teeth_coupled),
        "te_convention": "TE = rb1*theta1 + rb2*theta2, positive when the driven gear lags, zero at the zero-backlash conjugate position",
        **results.provenance(),
    }
    if static:
        t0 = time.perf_counter()
        st = run_static(scene, model)
        attrs["wall_time_static_s"] = time.perf_counter() - t0
        attrs["static_method"] = scene.quasi_static.method
        attrs["static_torque_N_m"] = scene.quasi_static.torque
        c, v = results.static_variables(st, model.backlash_offset)
        coords.update(c); data.update(v)
        c, v = results.ste_spectrum_variables(c["angle"].values, v["ste"].values, z1, z2, scene.gear2.body.holes)
        coords.update(c); data.update(v)
    if dynamic:
        t0 = time.perf_counter()
        dy = run_dynamic(scene, model)
        attrs["wall_time_dynamic_s"] = time.perf_counter() - t0
        start = d.spectrum_start or 2 * d.ramp_time
        attrs["spectrum_start_s"] = start
        c, v, a = results.dynamic_variables(dy, start, driven_speed, scene.gear2.body.holes, z2)
        coords.update(c); data.update(v); attrs.update(a)
        attrs["dynamic_method"] = dy.choice.method
        attrs["dynamic_method_reason"] = dy.choice.reason
        attrs["hht_alpha"] = d.alpha if dy.choice.method == "implicit" else float("nan")
    return xr.Dataset(data, coords=coords, attrs=attrs)


def summarize(ds: xr.Dataset) -> dict:
    """Scalars a sensitivity study needs (NaN where the archive lacks the analysis)."""
    out = {}
    nan = float("nan")
    off = ds.attrs.get("backlash_offset_um", 0.0)
    if "ste" in ds:
        ste = ds["ste"].values
        out["ste_mean"] = float(np.nanmean(ste))
        out["ste_elastic_mean"] = float(np.nanmean(ste) - off)
        out["ste_p2p"] = float(np.nanmax(ste) - np.nanmin(ste))
    if "dte" in ds:
        t = ds["time"].values
        sel = t >= ds.attrs.get("spectrum_start_s", 0.0)
        dte = ds["dte"].values[sel]
        out["dte_mean"] = float(np.mean(dte)) if dte.size else nan
        out["dte_rms"] = float(np.sqrt(np.mean((dte - dte.mean()) ** 2))) if dte.size else nan
        out["dte_p2p"] = float(np.ptp(dte)) if dte.size else nan
        out["tooth_force_max"] = float(np.max(ds["contact_force_max"].values)) if dte.size else nan
    if "dte_amplitude" in ds:
        z = ds.attrs["mesh_order"]
        for name, order in (("mesh", z), ("mesh2", 2 * z), ("mesh3", 3 * z), ("hole", ds.attrs["hole_order"])):
            out[f"amp_{name}_order"] = amplitude_at_order(ds, order) if order > 0 else nan
    for k in ("wall_time_springs_s", "wall_time_static_s", "wall_time_dynamic_s"):
        if k in ds.attrs:
            out[k] = float(ds.attrs[k])
    return out


def amplitude_at_order(ds: xr.Dataset, order: float, half_width: float = 0.5) -> float:
    """Largest DTE amplitude [um] within +-half_width orders of ``order``."""
    o = ds["order"].values
    sel = np.abs(o - order) <= half_width
    return float(ds["dte_amplitude"].values[sel].max()) if sel.any() else float("nan")


# ------------------------------------------------------------------ CLI

def add_arguments(p):
    p.add_argument("scene", nargs="?", help="scene TOML (default: the embedded paper example)")
    p.add_argument("-o", "--output", default="results/run.nc", help="archive to write (NetCDF)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene field by its dotted path, e.g. --set gear2.body.holes=3")
    p.add_argument("--no-static", action="store_true", help="skip the quasi-static STE")
    p.add_argument("--no-dynamic", action="store_true", help="skip the dynamic DTE")
    p.add_argument("--figures", action="store_true", help="also write plots and renders beside the archive")


def main(args) -> int:
    scene = load_scene(args.scene, args.overrides)
    t0 = time.perf_counter()
    ds = run_scene(scene, static=False if args.no_static else None, dynamic=False if args.no_dynamic else None)
    results.write_netcdf(ds, args.output)
    print_summary(ds, args.output, time.perf_counter() - t0)
    if args.figures:
        from study.report.figures import make_figures
        for path in make_figures(ds, Path(args.output).parent):
            print(f"  figure: {path}")
    return 0


def print_summary(ds: xr.Dataset, path, wall: float) -> None:
    s = summarize(ds)
    w = sys.stdout.write
    w(f"{ds.attrs.get('title', '')}\n  archive: {path}\n")
    w(f"  contact ratio {ds.attrs['contact_ratio']:.3f}, backlash offset {ds.attrs['backlash_offset_um']:.3f} um\n")
    if "ste" in s or "ste_mean" in s:
        w(f"  STE: mean {s['ste_mean']:.3f} um (elastic part {s['ste_elastic_mean']:.3f} um), "
          f"peak-to-peak {s['ste_p2p']:.3f} um over {float(ds['angle'][-1]):.4g} deg\n")
    if "dte_rms" in s:
        w(f"  DTE after {ds.attrs['spectrum_start_s']:.3g} s: mean {s['dte_mean']:.3f} um, RMS {s['dte_rms']:.3f} um, "
          f"peak-to-peak {s['dte_p2p']:.3f} um, max tooth force {s['tooth_force_max']:.1f} N "
          f"({ds.attrs['dynamic_status']}, dt {ds.attrs['dt_s'] * 1e6:.3g} us)\n")
        for f, o, a in results.largest_peaks(ds):
            w(f"    peak {a:8.4f} um at {f:8.1f} Hz = order {o:6.2f}\n")
    for what in ("dte", "ste"):
        if f"{what}_peak_amplitude" in ds:
            named = [(str(n), float(a)) for n, a in zip(ds[f"{what}_peak"].values, ds[f"{what}_peak_amplitude"].values)
                     if np.isfinite(a) and not str(n).startswith("other")]
            w(f"  {what.upper()} at named orders [um]: " + ", ".join(f"{n} {a:.3g}" for n, a in named) + "\n")
    w("  wall time: " + ", ".join(f"{k[10:-2]} {ds.attrs[k]:.3f} s" for k in ds.attrs if k.startswith("wall_time_"))
      + f", total {wall:.2f} s\n")

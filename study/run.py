"""Run one scene: scene -> model -> static and dynamic solves -> run archive (xarray).

`lightgear run [SCENE.toml] [-o OUT.nc] [--set key=value ...]` runs the embedded paper
example when no scene is given, writes the archive and prints a summary.
"""
from __future__ import annotations

import math
import time

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.dynamics import simulate
from solver.mbs.implicit import simulate_implicit
from solver.mbs.kernels.layout import R_PV
from solver.mbs.kernels.status import COMPLETED
from solver.mbs.mesh_stiffness import mesh_states
from solver.mbs.model import Model
from solver.mbs.statics import solve_static
from solver.store import STORE, digest
from study import estimate
from study.archive import run_variables
from study.archive.lightening import lightening_variables
from study.archive.mesh import dynamic_factor_reason, dynamic_force_variables, mesh_variables, steady_window
from study.archive.modes import modal_variables
from study.archive.netcdf import provenance
from study.errors import check_argument, check_scene_argument, is_number
from study.inputs.coupling import plain_windup
from study.inputs.gearsetup import gear_setups
from study.inputs.springs import root_stresses
from study.plausibility import critical_speed_warning, report_warnings, scene_warnings
from study.scene import Scene, error_period, static_rotation
from study.scene_model import (
    build_scene_model,
    check_static_memory,
    damping_ratios,
    dynamic_choice,
    kept_scene_model,
    load_table,
    mean_load,
    scene_springs,
    static_angles,
)


def run_static(scene: Scene, model: Model):
    """STE by equilibrium at each angle, or by the paper's slow-ramp transient. Flank friction
    in the equilibria slides as the rigid pair rolling at quasi_static.speed (the transient's
    speed: both methods regularise it alike; the static analysis reads no dynamic.* field)."""
    qs = scene.quasi_static
    angles = static_angles(scene)
    if qs.method == "static":
        return solve_static(model, angles, qs.torque, raise_on_failure=False, friction_speed=qs.speed)
    # slow-ramp transient: the driver reaches qs.speed after ramp_time; sample TE at the angles.
    # The angles the driver passes before the load is whole (speed * ramp_time / 2 of rotation)
    # carry no STE: the samples start a whole number of angle steps past the ramp instead, and
    # the archive's angle axis says so.
    from solver.mbs.dynamics import at_driver_angles, slow_ramp_window
    from solver.mbs.statics import StaticResult
    ramp_angle = 0.5 * qs.speed * qs.ramp_time
    step = math.radians(qs.angle_step)
    angles = angles + math.ceil(ramp_angle / step - 1e-9) * step
    dt_out, t_end = slow_ramp_window(angles, math.radians(qs.angle_step), qs.speed, qs.ramp_time)
    dyn = simulate(model, qs.speed, qs.ramp_time, qs.torque, qs.ramp_time, t_end, output_step=dt_out)
    te, th2, nc = at_driver_angles(dyn, qs.speed, qs.ramp_time, angles)
    it = np.where(np.isfinite(te), 1, -1)
    return StaticResult(angles, te, th2, nc, np.full((angles.size, model.teeth[0]), np.nan), it, qs.torque, np.full(model.n_teeth, np.nan))


def run_dynamic(scene: Scene, model: Model, choice=None, progress: bool = False):
    """DTE run with the scene's integrator: dynamic.method 'explicit', 'implicit' or 'auto'
    (chosen from the stability step; see `solver.mbs.method.choose_method`), or ``choice``
    (a MethodChoice) when already made.
    ``progress``: a bar on stderr when the run is expected to take more than a few seconds."""
    d = scene.dynamic
    table = load_table(scene)
    choice = choice or dynamic_choice(scene, model)
    speed, speed_ramp = (d.speed_end, d.duration) if d.speed_end > 0 else (d.speed, d.ramp_time)   # a run-up: one ramp
    args = (model, speed, speed_ramp, d.torque, d.ramp_time, d.duration)
    bar = estimate.progress_bar(estimate.dynamic_seconds(model, choice, d.duration, scene), d.duration,
                                f"dynamic run ({choice.method})", "s", show=progress)
    watch = None if bar is None else (lambda t: bar.update(max(min(t, bar.total) - bar.n, 0.0)))    # (within the bar)
    try:
        if choice.method == "implicit":
            res = simulate_implicit(*args, dt=choice.dt, output_step=d.output_step, alpha=d.alpha, load_table=table,
                                    progress=watch)
        else:
            # a step from the stability estimate: simulate estimates it again (the same) and checks it
            # against the contact forces the run reaches
            res = simulate(*args, dt=None if choice.estimated else choice.dt, output_step=d.output_step,
                           load_table=table, progress=watch)
    finally:
        if bar is not None:
            bar.close()
    if math.isfinite(choice.omega_max):
        res.omega_max = choice.omega_max
    return res


def static_force_max(scene: Scene, model: Model) -> float:
    """Largest static tooth force [N] under the dynamic run's torque over a whole revolution of
    either gear at the scene's angle step (every tooth of both gears meets the mesh): the
    reference of the dynamic factor K_v. NaN where the statics do not converge."""
    d, qs = scene.dynamic, scene.quasi_static
    z1, z2 = model.teeth
    angles = np.arange(0.0, 2 * math.pi * max(1.0, z2 / z1), math.radians(qs.angle_step))
    st = solve_static(model, angles, d.torque, raise_on_failure=False, friction_speed=max(d.speed, d.speed_end))
    f = st.tooth_force[st.converged]
    return float(np.max(f)) if f.size and st.converged.all() else float("nan")


def contact_loss_attrs(res, d) -> dict:
    """Whether the teeth of dynamic run ``res`` (of the scene's dynamic section ``d``) lost
    contact after the torque ramp: ``contact_lost_fraction`` [1], the share of the output
    instants with no loaded contact, and for a run-up the driver speeds [rad/s] where it
    happened (``contact_lost_speed_rad_s``, first and last). The response then left the
    linear range the modal critical speeds stand for."""
    after = (res.time > d.ramp_time) & np.isfinite(res.te)
    lost = after & (res.n_contacts == 0)
    out = {"contact_lost_fraction": float(lost.sum() / max(after.sum(), 1))}
    if d.speed_end > 0 and lost.any():
        speed = d.speed_end * res.time[lost] / d.duration
        out["contact_lost_speed_rad_s"] = np.array([speed.min(), speed.max()])
    return out


# the springs and model of the last scene run with keep_model
LAST_MODEL = STORE.shelf("last springs and model", 1)


def kept_springs_and_model(scene: Scene):
    """(springs, model) of a scene, the springs and the `kept_scene_model` of the last scene
    that differs from this one only in ``dynamic.*`` fields that leave the model as it is (the
    mean load its damping ratios are converted at: `study.scene_model.model_key`). A study's
    worker runs the points of one model in a row: their springs and model key (both read the
    whole scene) are then made once, not once per point. The objects are shared: not to be
    changed in place."""
    from study.inputs.cache import FE_CACHE

    def make():
        springs = scene_springs(scene)
        return springs, kept_scene_model(scene, springs)
    # the FE cache's folder: springs read from another cache are made again
    return LAST_MODEL.kept(digest(scene.model_sections(), mean_load(scene), str(FE_CACHE.folder)), make)


class RunFields:
    """A run's variables and global attributes before they become its archive (`dataset`),
    read the way `study.archive.summary.summarize` and a study's task read an archive:
    ``name in run``, ``run[name]`` (an xarray.Variable: ``.values``, ``.dims``, ``.attrs``,
    ``float()``), ``run.variables``, ``run.attrs``. A study's task reads a few numbers of a
    run: assembling the run's xarray.Dataset (indexes, alignment, merge) cost it more than any
    other step but the dynamic run itself."""

    def __init__(self, coords: dict, data: dict, attrs: dict):
        self.coords, self.data, self.attrs = coords, data, attrs
        self.variables = {**coords, **data}

    def __contains__(self, name) -> bool:
        return name in self.variables

    def __getitem__(self, name: str) -> xr.Variable:
        var = self.variables.get(name)
        if var is None:
            # a dimension without a coordinate reads as its positions, as in a Dataset
            size = next((v.sizes[name] for v in self.variables.values() if name in v.dims), None)
            if size is None:
                raise KeyError(name)
            return xr.Variable((name,), np.arange(size))
        return var

    def dataset(self) -> xr.Dataset:
        """The run archive."""
        return xr.Dataset(self.data, coords=self.coords, attrs=self.attrs)


def run_scene(scene: Scene, static: bool | None = None, dynamic: bool | None = None, max_time: float | None = None,
              progress: bool = False, springs=None, mesh_outputs: bool = True, warn: bool = True,
              keep_model: bool = False) -> xr.Dataset:
    """Run a scene -> run archive (xarray.Dataset): tooth springs, then the quasi-static STE and
    the dynamic DTE with their spectra. ``static``/``dynamic`` force an analysis on or off
    (None: as the scene's ``quasi_static.enabled`` / ``dynamic.enabled``). Output arrays that
    would not fit in memory, or with ``max_time`` [s] an estimated run time beyond it, raise
    `BudgetError` before any work; ``progress``: bars on stderr for long parts. Plausibility
    warnings (see `study.plausibility_warnings`, and a speed far above the highest critical
    speed of the mesh orders) go to stderr (unless ``warn`` is False) and the archive's
    ``plausibility_warnings`` attribute. The other arguments are those of `run_fields`."""
    check_scene_argument("run_scene", scene)
    for name, v in (("static", static), ("dynamic", dynamic)):
        check_argument(v is None or isinstance(v, bool), "run_scene", name, "True, False or None (as the scene says)", v)
    check_argument(max_time is None or (is_number(max_time) and max_time > 0), "run_scene", "max_time",
                   "a positive number of seconds or None", max_time)
    return run_fields(scene, static, dynamic, springs, max_time, bool(progress), mesh_outputs, warn, keep_model).dataset()


def run_fields(scene: Scene, static: bool | None = None, dynamic: bool | None = None, springs=None,
               max_time: float | None = None, progress: bool = False, mesh_outputs: bool = True,
               warn: bool = True, keep_model: bool = False, archive: bool = True,
               gear_variables: bool = True, modal: bool = True, strength: bool | None = None) -> RunFields:
    """Run the analyses a scene asks for (or those forced by static/dynamic) -> the run
    archive's variables and attributes (`RunFields`; `run_scene` makes the archive of them).

    Before any work: a dynamic run whose output arrays do not fit in memory is refused
    (`study.errors.BudgetError`), and, with ``max_time`` [s], so is a run whose estimated
    time (FE bodies, statics, time steps; `study.estimate`) exceeds it, each before the part
    it concerns starts. ``progress``: bars on stderr for the parts expected to be long.
    ``mesh_outputs``: also the linearised mesh over the STE (mesh stiffness, c', loaded contact
    ratio, tooth forces of both gears; about 1 ms an angle) and the dynamic factor K_v (its static
    reference over a revolution); a study leaves them out unless it asks for them.
    Plausibility warnings (`study.plausibility.scene_warnings`, and a speed far above the
    critical speeds) go to the archive's ``plausibility_warnings`` and, with ``warn``, to stderr.
    ``keep_model``: take the model from `study.scene_model.kept_scene_model` (a study's worker: the
    points of one body share it; with the springs of the last scene when this one differs from
    it only in its dynamic run: `kept_springs_and_model`). A study's task reads a few scalars
    and curves of the run: ``archive=False`` leaves out the attributes that only document an
    archive (the scene's TOML, the provenance) and, without ``mesh_outputs``, the loaded
    contacts of the dynamic run and each tooth's largest force, ``gear_variables=False`` the per-gear mass,
    inertia and root stress, ``modal=False`` the modal variables (mesh mode, critical speeds,
    free decay) and the critical-speed warning they give. ``strength``: the bending strength of
    both gears under the STE's contact forces, with K_v when the run has a dynamic factor
    (`strength_fields`; default: with the statics and the per-gear variables)."""
    static = scene.quasi_static.enabled if static is None else static
    dynamic = scene.dynamic.enabled if dynamic is None else dynamic
    warnings = scene_warnings(scene) if dynamic else [w for w in scene_warnings(scene) if not w.startswith("dynamic.")]
    report_warnings(warnings, warn)
    if dynamic:
        estimate.check_dynamic_memory(scene)
    if static and scene.quasi_static.method == "static":
        check_static_memory(scene)      # the angles' arrays, before the FE bodies are made
    est = estimate.Estimate()
    bounded = max_time is not None      # the estimates serve only the bound
    if springs is None and bounded:
        est.seconds["FE bodies"] = estimate.fe_seconds(scene)
        estimate.check_time(est, max_time)
    # the FE bodies' memory, before any of them is made (a study's worker leaves it to the
    # study's estimate, which counted every body ahead)
    if springs is None and not keep_model:
        line = estimate.check_fe_memory(scene)
        if line:
            report_warnings([line], warn)
            warnings.append(line)
    t0 = time.perf_counter()
    if springs is None:
        estimate.run_fe_bodies(scene, progress)
    if keep_model and springs is None:
        springs, model = kept_springs_and_model(scene)
        t_springs = time.perf_counter() - t0
    else:
        springs = springs or scene_springs(scene)
        t_springs = time.perf_counter() - t0
        model = (kept_scene_model if keep_model else build_scene_model)(scene, springs)
    if not damping_ratios(scene):    # (with ratios the damping conversion has checked it)
        from study.plausibility import carrying_equilibria
        carrying_equilibria(scene, model, mean_load(scene), positions=2)     # SceneError: teeth too soft for the load
    choice = None
    if static and bounded:
        est.seconds["statics"] = estimate.static_seconds(scene, model)
        if mesh_outputs:
            est.seconds["mesh stiffness"] = estimate.mesh_seconds(scene)
    if dynamic:
        choice = dynamic_choice(scene, model)
        if bounded:
            part = f"dynamics ({choice.method}, dt {choice.dt:.3g} s)"
            est.seconds[part] = estimate.dynamic_seconds(model, choice, scene.dynamic.duration, scene)
            est.levers[part] = estimate.dynamic_lever(scene, choice)
    est.seconds["FE bodies"] = 0.0          # done
    estimate.check_time(est, max_time)
    coords, data = run_variables.stiffness_variables((springs[0][0], springs[1][0]), (springs[0][1], springs[1][1]))
    data["tooth_stiffness"].attrs["body_windup"] = (
        "in it: the plain model's spring holds its body's wind-up from the bore" if not model.coupled else
        "not in it: the body spring holds the wind-up from the bore (attribute body_stiffness_N_m_rad)")
    if gear_variables:
        setups = gear_setups(scene)
        c, v = lightening_variables(setups, root_stresses(setups))    # mass, inertia; root stress from the springs' FE
        coords.update(c); data.update(v)
    z1, z2 = model.teeth
    d = scene.dynamic
    driven_speed = d.speed * z1 / z2
    attrs = {
        "title": run_variables.scene_title(scene),
        **({"scene": scene.to_toml()} if archive else {}),
        "backlash_offset_um": model.backlash_offset * units.UM_PER_M,
        "contact_ratio": model.pair.contact_ratio,
        "mesh_order": float(z2),
        "hole_order": float(scene.gear2.body.holes),
        **run_variables.opening_attrs(scene),
        "driven_speed_rad_s": driven_speed,
        "ramp_time_s": d.ramp_time,
        "wall_time_springs_s": t_springs,
        "coupling": scene.coupling_model,
        "coupling_model": scene.coupling_model_name,
        "coupling_model_setting": scene.coupling.model,
        "body_stiffness_N_m_rad": np.array([k if math.isfinite(k) else 0.0 for k in model.body_stiffness]),
        "pivot_radius_mm": model.gear_par[:, R_PV] * units.MM_PER_M,
        "teeth_coupled": int(model.teeth_coupled),
        "te_convention": "TE = rb1*theta1 + rb2*theta2, positive when the driven gear lags, zero at the zero-backlash conjugate position",
        **(provenance() if archive else {}),
    }
    if modal:
        t0 = time.perf_counter()
        c, v, a = modal_variables(model, mean_load(scene), scene.gear2.body.holes, decay=dynamic)
        coords.update(c); data.update(v); attrs.update(a)
        attrs["mesh_damping_ratio_requested"] = damping_ratios(scene).get("contact", float("nan"))
        attrs["wall_time_modes_s"] = time.perf_counter() - t0
    if dynamic and "critical_speed" in data:
        cs = data["critical_speed"]
        line = critical_speed_warning(scene, float(cs.values[list(coords["excitation"].values).index("1Z"), 0]))
        if line:
            report_warnings([line], warn)
            warnings.append(line)
    attrs["plausibility_warnings"] = "\n".join(warnings)
    if static:
        t0 = time.perf_counter()
        st = run_static(scene, model)
        attrs["wall_time_static_s"] = time.perf_counter() - t0
        attrs["static_status"] = getattr(st, "message", "ok")
        attrs["static_method"] = scene.quasi_static.method
        attrs["static_torque_N_m"] = scene.quasi_static.torque
        if scene.has_errors:
            attrs["static_rotation_deg"] = static_rotation(scene)
            attrs["error_period_deg"] = error_period(scene)
        c, v = run_variables.static_variables(st, model.backlash_offset)
        coords.update(c); data.update(v)
        c, v = run_variables.ste_spectrum_variables(c["angle"].values, v["ste"].values, z1, z2, scene.gear2.body.holes,
                                                    revolutions=scene.has_errors)
        coords.update(c); data.update(v)
    if static and mesh_outputs:
        t0 = time.perf_counter()
        # the plain model's springs hold the bodies' wind-up: the FE body's, taken out for the mesh alone
        windup = None if model.coupled else tuple(plain_windup(s) for s in gear_setups(scene))
        states = mesh_states(model, st.angle, scene.quasi_static.torque, windup)
        c, v = mesh_variables(states, model, scene, scene.quasi_static.torque, windup)
        coords.update(c); data.update(v)
        attrs["wall_time_mesh_stiffness_s"] = time.perf_counter() - t0
    if dynamic:
        t0 = time.perf_counter()
        dy = run_dynamic(scene, model, choice, progress)
        attrs["wall_time_dynamic_s"] = time.perf_counter() - t0
        start = d.spectrum_start or 2 * d.ramp_time
        attrs["spectrum_start_s"] = start
        runup = d.speed_end > 0         # no spectrum over a changing speed: its order tracking instead
        c, v, a = run_variables.dynamic_variables(dy, d.duration if runup else start, driven_speed,
                                                  scene.gear2.body.holes, z2,
                                                  (z2 / z1, 1.0) if scene.has_errors else None)
        coords.update(c); data.update(v); attrs.update(a)
        _, periods, short = steady_window(scene, start, to_load_change=False)
        attrs["steady_mesh_periods"] = periods
        attrs["driver_speed_max_rad_s"] = max(d.speed, d.speed_end)
        if short and not runup:     # DTE RMS and peak-to-peak left undefined (`study.archive.summary`)
            attrs["steady_window_note"] = short
        if archive or mesh_outputs:     # (read by no study output but the dynamic factor, a mesh output)
            undefined = dynamic_factor_reason(scene, start)
            end = steady_window(scene, start)[0]
            c, v = dynamic_force_variables(dy, start, z1, z2, static_force_max(scene, model)
                                           if mesh_outputs and undefined is None else math.nan, end, undefined)
            coords.update(c); data.update(v)
        if scene.contact.friction > 0 and not runup and load_table(scene) is None:
            data.update(run_variables.efficiency_variable(dy, d.torque, d.speed, start))
        attrs.update(contact_loss_attrs(dy, d))
        if runup:
            attrs["runup_speed_end_rad_s"] = d.speed_end
            if dy.status in COMPLETED:    # completed: the map is kept, an inaccurate one with its flag
                from study.archive.order_tracking import order_tracking_variables
                c, v = order_tracking_variables(dy.time, dy.te * units.UM_PER_M, d.speed_end, d.duration, z1, z2)
                if dy.status:
                    v["order_amplitude"].attrs["status"] = dy.message
                coords.update(c); data.update(v)
            else:
                attrs["order_tracking_skipped"] = f"the run-up stopped before its end: {dy.message}"
        attrs["dynamic_method"] = choice.method
        attrs["dynamic_method_reason"] = choice.reason
        attrs["hht_alpha"] = d.alpha if choice.method == "implicit" else float("nan")
    if (static and gear_variables) if strength is None else (strength and static):
        t0 = time.perf_counter()
        c, v = strength_fields(scene, model, st, data)
        coords.update(c); data.update(v)
        attrs["wall_time_strength_s"] = time.perf_counter() - t0
    return RunFields(coords, data, attrs)


def strength_fields(scene: Scene, model: Model, st, data: dict) -> tuple[dict, dict]:
    """The strength variables (`study.archive.strength`) of both gears under the static
    result's contact forces ``st`` and, when ``data`` holds a dynamic factor K_v, the dynamic
    run's: the static stresses times (dynamic torque / static torque) K_v."""
    from solver.geometry import pair_geometry
    from study.archive.strength import strength_variables
    from study.inputs.strength import gear_strength, static_loads

    setups = gear_setups(scene)
    pair = pair_geometry(setups[0].geometry, setups[1].geometry)
    torque = scene.quasi_static.torque
    loads = static_loads(model, st) if torque > 0 else None
    if loads is None or not loads[0][0].size:     # nothing to rate: each gear's variables NaN, with the reason
        why = ("quasi_static.torque <= 0: the coast flanks' loads are not rated" if loads is None
               else "no converged static contact force")
        return strength_variables(setups, pair, [why, why], scene, math.nan, "")
    results = [gear_strength(s, pair, ld, st.angle.size, torque / s.geometry.base_radius) for s, ld in zip(setups, loads)]
    scale, note = math.nan, ""
    if "dynamic_factor" in data and torque:
        kv = float(data["dynamic_factor"].values)
        scale = scene.dynamic.torque / torque * kv
        note = (f"dynamic torque {scene.dynamic.torque:g} N·m over static {torque:g} N·m, K_v {kv:.4f}" if math.isfinite(kv)
                else "K_v undefined")     # (a dynamic run that cannot support it: its reason is the K_v's)
    return strength_variables(setups, pair, results, scene, scale, note)

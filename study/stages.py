"""The stages of a run: each takes the run's plan (`study.plan.RunPlan`) and what the stages
before it returned, runs its analysis and returns its archive variables as (coordinates, data
variables, attributes), packed by `study.archive` (which computes nothing). `study.run.run_fields`
runs the stages the plan asks for, in the order of `study.plan.STAGES`:

  gear       mass, inertia and root stress of each gear (`study.archive.lightening`)
  modes      modal analysis at the mean load, with a dynamic run the free decay (`study.archive.modes`)
  static     quasi-static STE and its spectrum (`study.archive.run_variables`)
  mesh       the pair linearised over the STE, ISO 6336-1 beside it (`study.archive.mesh`)
  dynamic    DTE, its spectrum or order tracking, tooth forces and K_v (`study.archive.run_variables`, `mesh`)
  strength   bending strength under the STE's contact forces, K_v with a dynamic run (`study.archive.strength`)

Wall times [s] of each stage go to the attributes as ``wall_time_{stage}_s``.
"""
from __future__ import annotations

import math
import time

import numpy as np

from solver import units
from solver.mbs.kernels.status import COMPLETED
from solver.mbs.statics import solve_static
from solver.peers import iso6336
from study import estimate
from study.archive import run_variables


def compute_fe_bodies(setups, coupling_model: str, show: bool = True) -> None:
    """Compute (into the FE cache) the bodies the springs of gears ``setups`` need, with a bar
    whose unit is the estimated second, when they are expected to take more than
    `study.estimate.PROGRESS_AFTER_S`; else nothing (the springs compute them as they go). The
    coupling fits (``coupling_model`` not 'none') compute their own bodies."""
    if coupling_model != "none":
        return
    bodies = estimate.fe_bodies(setups, coupling_model)
    secs = [estimate.body_seconds(s) for _, s, _ in bodies]
    bar = estimate.progress_bar(sum(secs), sum(secs), "FE bodies", "s (estimated)", show)
    if bar is None:
        return
    from study.inputs.springs import fe_stiffness
    try:
        for (label, setup, teeth), sec in zip(bodies, secs):
            bar.set_postfix_str(label)
            fe_stiffness(setup, teeth)
            bar.update(sec)
    finally:
        bar.close()


# ---------------------------------------------------------------- gear

def gear_stage(plan) -> tuple[dict, dict, dict]:
    """Mass, inertia (geometry) and root stress (from the springs' FE, where they use it) of
    both gears."""
    from solver.inertia import gear_mass
    from study.archive.lightening import lightening_variables
    from study.inputs.springs import root_stresses
    masses = [gear_mass(s.geometry, s.body, s.material.density) for s in plan.setups]
    return (*lightening_variables(plan.setups, masses, root_stresses(plan.setups)), {})


# ---------------------------------------------------------------- modes

def modes_stage(plan) -> tuple[dict, dict, dict]:
    """The modes of the pair at the plan's mean load and equilibria; with a dynamic run the
    simulated free decay of the mesh mode where its modal ratio is nearest its mean."""
    from solver.mbs.modes import modal_analysis
    from study.archive.modes import modal_variables
    t0 = time.perf_counter()
    md = modal_analysis(plan.model, plan.mean_load, equilibria=plan.equilibria)
    decay = None
    if plan.asks("dynamic"):
        from solver.mbs.ringdown import ring_down
        # where the mesh mode's ratio is nearest its mean over the mesh period (the ratio a
        # run-up's resonance sees: at 1Z one mesh period passes per vibration period)
        j = int(np.nanargmin(np.abs(md.damping[0] - np.nanmean(md.damping[0]))))
        decay = j, ring_down(plan.model, plan.mean_load, float(md.frequency[0, j]), float(md.damping[0, j]),
                             driver_angle=float(md.position[j]))
    c, v, a = modal_variables(md, decay, plan.model, plan.mean_load, plan.scene.gear2.body.holes)
    a["mesh_damping_ratio_requested"] = plan.ratios.get("contact", float("nan"))
    a["wall_time_modes_s"] = time.perf_counter() - t0
    return c, v, a


# ---------------------------------------------------------------- static

def run_static(scene, model, angles=None):
    """STE by equilibrium at each angle (``angles`` [rad]; default: the scene's static angles),
    or by the paper's slow-ramp transient. Flank friction in the equilibria slides as the rigid
    pair rolling at quasi_static.speed (the transient's speed: both methods regularise it
    alike; the static analysis reads no dynamic.* field)."""
    qs = scene.quasi_static
    if angles is None:
        from study.scene_model import static_angles
        angles = static_angles(scene)
    if qs.method == "static":
        return solve_static(model, angles, qs.torque, raise_on_failure=False, friction_speed=qs.speed)
    # slow-ramp transient: the driver reaches qs.speed after ramp_time; sample TE at the angles.
    # The angles the driver passes before the load is whole (speed * ramp_time / 2 of rotation)
    # carry no STE: the samples start a whole number of angle steps past the ramp instead, and
    # the archive's angle axis says so.
    from solver.mbs.dynamics import at_driver_angles, simulate, slow_ramp_window
    from solver.mbs.statics import StaticResult
    ramp_angle = 0.5 * qs.speed * qs.ramp_time
    step = math.radians(qs.angle_step)
    angles = angles + math.ceil(ramp_angle / step - 1e-9) * step
    dt_out, t_end = slow_ramp_window(angles, math.radians(qs.angle_step), qs.speed, qs.ramp_time)
    dyn = simulate(model, qs.speed, qs.ramp_time, qs.torque, qs.ramp_time, t_end, output_step=dt_out)
    te, th2, nc = at_driver_angles(dyn, qs.speed, qs.ramp_time, angles)
    it = np.where(np.isfinite(te), 1, -1)
    return StaticResult(angles, te, th2, nc, np.full((angles.size, model.teeth[0]), np.nan), it, qs.torque,
                        np.full(model.n_teeth, np.nan))


def static_stage(plan):
    """The STE over the plan's angles and its spectrum -> (coordinates, data, attributes, the
    `solver.mbs.statics.StaticResult` the mesh and strength stages read)."""
    from study.scene import error_period, static_rotation
    scene = plan.scene
    z1, z2 = plan.model.teeth
    t0 = time.perf_counter()
    st = run_static(scene, plan.model, plan.angles)
    attrs = {"wall_time_static_s": time.perf_counter() - t0, "static_status": getattr(st, "message", "ok"),
             "static_method": scene.quasi_static.method, "static_torque_N_m": scene.quasi_static.torque}
    if scene.has_errors:
        attrs["static_rotation_deg"] = static_rotation(scene)
        attrs["error_period_deg"] = error_period(scene)
    coords, data = run_variables.static_variables(st, plan.model.backlash_offset)
    c, v = run_variables.ste_spectrum_variables(coords["angle"].values, data["ste"].values, z1, z2,
                                                scene.gear2.body.holes, revolutions=scene.has_errors)
    coords.update(c)
    data.update(v)
    return coords, data, attrs, st


# ---------------------------------------------------------------- mesh

def mesh_stage(plan, st) -> tuple[dict, dict, dict]:
    """The pair linearised at each STE angle of ``st`` (mesh stiffness, c', loaded contact
    ratio, static tooth forces), each tooth's stiffness at the pitch point and ISO 6336-1
    Method B beside them."""
    from solver.mbs.mesh_stiffness import body_windup_compliance, mesh_states, pitch_point_stiffness
    from study.archive.mesh import MeshNumbers, mesh_variables
    from study.inputs.coupling import plain_windup
    t0 = time.perf_counter()
    model, torque = plan.model, plan.scene.quasi_static.torque
    # the plain model's springs hold the bodies' wind-up: the FE body's, taken out for the mesh alone
    windup = None if model.coupled else tuple(plain_windup(s) for s in plan.setups)
    states = mesh_states(model, st.angle, torque, windup)
    load = torque if abs(torque) > 1e-9 else 1.0        # the load mesh_states linearises at
    cw = body_windup_compliance(model, windup)
    try:
        alone = units.stiffness_n_per_um(pitch_point_stiffness(model, load / model.base_radii[1],
                                                               (0.0, 0.0) if model.coupled else cw))
    except ValueError:      # a plain spring stiffer than its body's wind-up alone: it cannot hold it
        alone = np.full(sum(model.teeth), np.nan)
    iso = iso_stiffness(plan.scene.gear1, plan.scene.gear2, model.pair.contact_ratio, load)
    c, v = mesh_variables(states, model, MeshNumbers(torque, windup is not None, cw, alone, iso))
    return c, v, {"wall_time_mesh_stiffness_s": time.perf_counter() - t0}


def iso_stiffness(g1, g2, contact_ratio: float, torque: float) -> dict:
    """ISO 6336-1 Method B stiffness of the pair of gear sections ``g1``, ``g2`` (the scene's
    gear1, gear2: mm) at ``torque`` [N·m] on the driven gear:
    no profile shift, C_M 0.8, the basic-rack factor of gear 1, the gear-blank factor C_R of
    each gear's web (mean of the two; the standard has no holes), the low-load factor
    (F_t/b / 100 N/mm)^0.25 below 100 N/mm (F_t = |torque| / r2 at the driven gear's reference
    circle, K_A = 1, b the smaller face width), c_gamma_alpha = c' (0.75 eps_alpha + 0.25) with
    the geometric transverse contact ratio eps_alpha. Returns c_prime, c_gamma_alpha
    [N/(mm·um)] with the factor, the same without it (``*_full_load``) and without C_M either
    (``*_elastic``: the theoretical stiffness of the elastic pair, c'_th C_R C_B), c_r,
    load_per_width [N/mm] and low_load_factor [1]."""
    c_r = 0.5 * sum(iso6336.blank_factor(g.body.web_thickness, g.face_width, g.body.rim_height, g.module)
                    for g in (g1, g2))
    c_full = iso6336.single_stiffness(g1.teeth, g2.teeth, g1.dedendum, g1.pressure_angle, c_r)
    r2 = 0.5 * g2.teeth * g2.module * units.MM          # scene mm -> m
    w = abs(torque) / r2 / (min(g1.face_width, g2.face_width))   # N / mm
    f = iso6336.low_load_factor(w)
    ratio = 0.75 * contact_ratio + 0.25
    return {"c_prime": c_full * f, "c_gamma_alpha": c_full * f * ratio, "c_prime_full_load": c_full,
            "c_gamma_alpha_full_load": c_full * ratio, "c_prime_elastic": c_full / iso6336.C_M,
            "c_gamma_alpha_elastic": c_full / iso6336.C_M * ratio, "c_r": c_r, "load_per_width": w, "low_load_factor": f}


# ---------------------------------------------------------------- dynamic

def run_dynamic(plan):
    """The DTE run of the plan: its integrator and step (`RunPlan.choice`), its load profile;
    a bar on stderr when the run is expected to take more than a few seconds."""
    from solver.mbs.dynamics import simulate
    from solver.mbs.implicit import simulate_implicit
    d, model, choice = plan.scene.dynamic, plan.model, plan.choice
    speed, speed_ramp = (d.speed_end, d.duration) if d.speed_end > 0 else (d.speed, d.ramp_time)   # a run-up: one ramp
    args = (model, speed, speed_ramp, d.torque, d.ramp_time, d.duration)
    bar = estimate.progress_bar(estimate.dynamic_seconds(model, choice, d.duration, d.speed_end > 0), d.duration,
                                f"dynamic run ({choice.method})", "s", show=plan.progress)
    watch = None if bar is None else (lambda t: bar.update(max(min(t, bar.total) - bar.n, 0.0)))    # (within the bar)
    try:
        if choice.method == "implicit":
            res = simulate_implicit(*args, dt=choice.dt, output_step=d.output_step, alpha=d.alpha,
                                    load_table=plan.load_table, progress=watch)
        else:
            # a step from the stability estimate: simulate estimates it again (the same) and checks it
            # against the contact forces the run reaches
            res = simulate(*args, dt=None if choice.estimated else choice.dt, output_step=d.output_step,
                           load_table=plan.load_table, progress=watch)
    finally:
        if bar is not None:
            bar.close()
    if math.isfinite(choice.omega_max):
        res.omega_max = choice.omega_max
    return res


def static_force_max(plan) -> float:
    """Largest static tooth force [N] under the dynamic run's torque over a whole revolution of
    either gear at the scene's angle step (every tooth of both gears meets the mesh): the
    reference of the dynamic factor K_v. NaN where the statics do not converge."""
    d, qs = plan.scene.dynamic, plan.scene.quasi_static
    z1, z2 = plan.model.teeth
    angles = np.arange(0.0, 2 * math.pi * max(1.0, z2 / z1), math.radians(qs.angle_step))
    st = solve_static(plan.model, angles, d.torque, raise_on_failure=False, friction_speed=max(d.speed, d.speed_end))
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


# a load below this [N·m] gives no static tooth force to divide by: K_v is undefined
NO_LOAD_TORQUE = 1e-9


def steady_window(d, z1: int, start: float, to_load_change: bool = True) -> tuple[float, float, str | None]:
    """(end [s], mesh periods covered, reason or None) of the steady part of a dynamic run
    (the scene's dynamic section ``d``, ``z1`` driver teeth) from ``start`` [s] that its dynamic
    factor K_v and DTE RMS / peak-to-peak are taken over: to the end of the run, or for K_v
    (``to_load_change``) with a load change to its start (the forces are then compared at the
    torque of `static_force_max`, dynamic.torque). The reason, when there is one, says why the
    window cannot support them: no static load, the driver standing still, or fewer than one
    mesh period (every tooth pair's whole passage) after the ramp."""
    end = d.duration if d.torque_change_time <= 0 or not to_load_change else min(d.duration, d.torque_change_time)
    speed = d.speed_end if d.speed_end > 0 else d.speed
    periods = max(end - start, 0.0) * speed * z1 / (2 * math.pi)
    if d.speed_end <= 0 and d.speed <= 0:
        return end, periods, "the driver stands still (dynamic.speed = 0): no mesh period to take the forces over"
    if periods < 1.0 - 1e-9:
        load = f" up to the load change at {d.torque_change_time:g} s" if end < d.duration else ""
        return end, periods, (f"the steady part after the ramp ({start:g} to {end:g} s{load}) covers {periods:.3g} of a "
                              f"mesh period ({2 * math.pi / (z1 * speed) if speed > 0 else math.inf:.3g} s at "
                              f"{speed:g} rad/s): lengthen dynamic.duration")
    return end, periods, None


def dynamic_factor_reason(d, z1: int, start: float) -> str | None:
    """Why the dynamic factor K_v of the dynamic run (section ``d``) from ``start`` [s] is
    undefined (archived as NaN with this reason), or None: no static load to divide by, or a
    steady part that misses a mesh period (`steady_window`)."""
    if abs(d.torque) < NO_LOAD_TORQUE:
        return f"no static load (dynamic.torque = {d.torque:g} N·m): no static tooth force to divide by"
    return steady_window(d, z1, start)[2]


def tooth_forces(res, start: float, end: float, teeth: tuple, static_max: float, undefined: str | None):
    """Each tooth's largest dynamic force [N] from ``start`` to ``end`` [s] on both gears of
    ``teeth`` (z1, z2), and the dynamic factor K_v: the largest of them over the largest static
    one ``static_max`` [N] (NaN with the reason where the run cannot support it) ->
    `study.archive.mesh.ToothForces`."""
    from solver.mbs.kernels import layout as L
    from study.archive.mesh import ToothForces
    c = res.contacts
    t1 = c[:, :, L.OC_TOOTH1].astype(np.int32)
    t2 = c[:, :, L.OC_TOOTH2].astype(np.int32)
    f = c[:, :, L.OC_FORCE]
    z1, z2 = teeth
    sel = (res.time >= start) & (res.time <= end + 1e-12)
    fmax = np.full((2, max(z1, z2)), np.nan)
    for g, (t, z) in enumerate(((t1, z1), (t2, z2))):
        per = np.zeros((int(sel.sum()), z))
        rows = np.nonzero(sel)[0]
        for s in range(c.shape[1]):
            ok = t[rows, s] >= 0
            np.add.at(per, (np.nonzero(ok)[0], t[rows, s][ok]), f[rows, s][ok])
        fmax[g, :z] = per.max(axis=0) if per.shape[0] else np.nan
    fdyn = float(np.nanmax(fmax)) if np.isfinite(fmax).any() else float("nan")
    if undefined is None and not static_max > 0:
        undefined = "no static tooth force to divide by (the statics over a revolution did not converge)"
    kv = float("nan") if undefined is not None else fdyn / static_max
    return ToothForces(t1, t2, f, start, end, fmax, fdyn, static_max, kv, undefined)


def dynamic_stage(plan) -> tuple[dict, dict, dict]:
    """The dynamic run -> its DTE and spectrum (or a run-up's order tracking), the tooth forces
    and K_v (with 'mesh' or an archive), the mesh efficiency (with flank friction), the
    contact losses and the integrator's attributes."""
    from study.archive.mesh import dynamic_force_variables
    scene, d, choice = plan.scene, plan.scene.dynamic, plan.choice
    z1, z2 = plan.model.teeth
    t0 = time.perf_counter()
    dy = run_dynamic(plan)
    attrs = {"wall_time_dynamic_s": time.perf_counter() - t0}
    start = d.spectrum_start or 2 * d.ramp_time
    attrs["spectrum_start_s"] = start
    runup = d.speed_end > 0         # no spectrum over a changing speed: its order tracking instead
    coords, data, a = run_variables.dynamic_variables(dy, d.duration if runup else start, d.speed * z1 / z2,
                                                      scene.gear2.body.holes, z2,
                                                      (z2 / z1, 1.0) if scene.has_errors else None)
    attrs.update(a)
    _, periods, short = steady_window(d, z1, start, to_load_change=False)
    attrs["steady_mesh_periods"] = periods
    attrs["driver_speed_max_rad_s"] = max(d.speed, d.speed_end)
    if short and not runup:     # DTE RMS and peak-to-peak left undefined (`study.archive.summary`)
        attrs["steady_window_note"] = short
    if (plan.archive or plan.asks("mesh")) and dy.contacts is not None:     # (K_v is a mesh output)
        undefined = dynamic_factor_reason(d, z1, start)
        end = steady_window(d, z1, start)[0]
        static_max = static_force_max(plan) if plan.asks("mesh") and undefined is None else math.nan
        c, v = dynamic_force_variables(tooth_forces(dy, start, end, (z1, z2), static_max, undefined))
        coords.update(c)
        data.update(v)
    if scene.contact.friction > 0 and not runup and plan.load_table is None:
        data.update(run_variables.efficiency_variable(dy, d.torque, d.speed, start))
    attrs.update(contact_loss_attrs(dy, d))
    if runup:
        attrs.update(_order_tracking(dy, d, (z1, z2), coords, data))
    attrs["dynamic_method"] = choice.method
    attrs["dynamic_method_reason"] = choice.reason
    attrs["hht_alpha"] = d.alpha if choice.method == "implicit" else float("nan")
    return coords, data, attrs


def _order_tracking(dy, d, teeth: tuple, coords: dict, data: dict) -> dict:
    """A run-up's order tracking into ``coords`` and ``data`` (kept for a completed run, an
    inaccurate one with its flag) -> its attributes."""
    attrs = {"runup_speed_end_rad_s": d.speed_end}
    if dy.status in COMPLETED:
        from study.archive.order_tracking import order_tracking_variables
        c, v = order_tracking_variables(dy.time, dy.te * units.UM_PER_M, d.speed_end, d.duration, *teeth)
        if dy.status:
            v["order_amplitude"].attrs["status"] = dy.message
        coords.update(c)
        data.update(v)
    else:
        attrs["order_tracking_skipped"] = f"the run-up stopped before its end: {dy.message}"
    return attrs


# ---------------------------------------------------------------- strength

def strength_stage(plan, st, kv: float | None) -> tuple[dict, dict, dict]:
    """The bending strength of both gears under the static result's contact forces ``st`` and,
    with a dynamic factor ``kv`` [1] (None without a dynamic run, NaN where the run cannot
    support it), the dynamic run's: the static stresses times (dynamic torque / static torque) K_v."""
    from solver.geometry import pair_geometry
    from study.archive.strength import strength_variables
    from study.inputs.rating import gear_rating
    from study.inputs.strength import gear_strength, static_loads
    t0 = time.perf_counter()
    scene, setups = plan.scene, plan.setups
    pair = pair_geometry(setups[0].geometry, setups[1].geometry)
    torque = scene.quasi_static.torque
    loads = static_loads(plan.model, st) if torque > 0 else None
    scale, note = math.nan, ""
    if loads is None or not loads[0][0].size:     # nothing to rate: each gear's variables NaN, with the reason
        why = ("quasi_static.torque <= 0: the coast flanks' loads are not rated" if loads is None
               else "no converged static contact force")
        results = [why, why]
    else:
        results = [gear_strength(s, pair, ld, st.angle.size, torque / s.geometry.base_radius)
                   for s, ld in zip(setups, loads)]
        if kv is not None and torque:
            scale = scene.dynamic.torque / torque * kv
            note = (f"dynamic torque {scene.dynamic.torque:g} N·m over static {torque:g} N·m, K_v {kv:.4f}"
                    if math.isfinite(kv) else "K_v undefined")   # (its reason is the K_v's own)
    ratings = [gear_rating(s, pair, r, scene.gear(s.gear).material, scale) for s, r in zip(setups, results)]
    c, v = strength_variables(ratings, scale, note)
    return c, v, {"wall_time_strength_s": time.perf_counter() - t0}

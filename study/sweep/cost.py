"""Cost of a study before it starts, from its scenes alone: its size (points, memory to list
them), each task's compute seconds (the order and batching of the tasks on dask, the progress
bar's ETA) and the study's estimated time against ``--max-time`` (FE bodies, statics, dynamic
runs). The unit costs are those of a run (`study.estimate`).
"""
from __future__ import annotations

import math

import numpy as np

from study import estimate
from study.errors import BudgetError
from study.estimate import (
    ACTIVE_TEETH_PER_GEAR,
    EXPLICIT_S_PER_STEP,
    EXPLICIT_S_PER_STEP_TOOTH,
    MESH_S_PER_ANGLE,
    RUNUP_RUNS,
    STATIC_S_PER_ANGLE_TOOTH,
    Estimate,
    body_estimate,
    check_fe_memory,
    duration_text,
    dynamic_lever,
    dynamic_seconds,
    fe_bodies,
)
from study.memory import available_memory, bytes_text
from study.scene_model import static_angle_count

# Building and checking one study point (its Scene and the cross-field checks): 20-60 ms on
# 2 shared cores; its Scene and Point hold about 5 KB, its task records as much again.
POINT_CHECK_S = 0.03
POINT_BYTES = 1e4
DYNAMIC_SAMPLES = 3          # dynamic tasks whose model gives the step of the estimate


def study_points(study) -> int:
    """Points of a study (grid product, times the builds of its sample, plus explicit points),
    counted without building them."""
    n = 1
    for a in study.axes:
        n *= len(a.values)
    n = n if study.axes else 0
    if study.sample:        # every grid point (or the base scene alone) gets the whole sample
        n = max(n, 1) * study.sample.builds
    return n + len(study.extra)


def study_sizes(study) -> str:
    """The factors of `study_points` in words: '3 x 4', '1e+06 draws', '2 x 500 draws + 3'."""
    parts = [str(len(a.values)) for a in study.axes]
    if study.sample:
        parts.append(f"{study.sample.builds:.4g} draws" if study.sample.builds >= 1e6 else f"{study.sample.builds} draws")
    return " x ".join(parts) or "0"


def check_study_size(study, max_time: float | None) -> int:
    """Refuse, before its points are built, a study too large to enumerate: memory beyond what
    the machine has, or its checks alone beyond ``max_time`` [s]. Returns its point count
    (grid points and sampled builds alike: `study_points`)."""
    n = study_points(study)
    need = n * POINT_BYTES
    have = available_memory()
    sizes = study_sizes(study)
    field, lever = ("sample.size", "draw fewer (sample.size)") if study.sample else ("grid", "sweep fewer values")
    if need > 0.5 * have:
        raise BudgetError(field, f"the study has {n:.4g} points ({sizes}{f' + {len(study.extra)}' if study.extra else ''}); "
                                 f"only listing them needs about {bytes_text(need)}, more than half the {bytes_text(have)} "
                                 f"of memory available: {lever}, or split the study")
    if max_time is not None and n * POINT_CHECK_S > max_time:
        raise BudgetError(field, f"the study has {n:.4g} points ({sizes}); building and checking them alone takes "
                                 f"about {duration_text(n * POINT_CHECK_S)}, beyond --max-time {max_time:.4g} s: "
                                 f"{lever}, or split the study")
    return n


def _plain(scene):
    """``scene`` with uniform tooth springs (an FE map scales the calibrated spring by a ratio
    near 1) and no body coupling: the model of the estimate, which needs no FE."""
    return scene.replace(**{"gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform",
                            "coupling.model": "none"})


def _undamped_bound(scene) -> bool:
    """Whether the scene's explicit step is the undamped bound 2/omega_max of the loaded pair
    (`solver.mbs.stability.stability_limit` with the tooth-root dampers implicit): linear root
    dampers (n_c = 1) that the scene gives or its damping ratios set, no contact damper (the
    mesh ratio goes to the root dampers) and no flank friction."""
    from study.scene_model import damping_ratios
    ratios = damping_ratios(scene)
    springs = [scene.gear(g).spring for g in (1, 2)]
    c = scene.contact
    root_dampers = bool(ratios) or any(not math.isnan(s.c_phi) and s.c_phi > 0 for s in springs)
    no_contact_damper = "contact" in ratios or (not math.isnan(c.c_con) and c.c_con == 0)
    return (scene.dynamic.method in ("auto", "explicit") and c.friction == 0 and no_contact_damper
            and root_dampers and all(s.n_c == 1.0 for s in springs))


def estimate_choice(scene):
    """(model, `solver.mbs.method.MethodChoice`) of a dynamic task for the study's estimate,
    on its plain model (`_plain`). A given step is taken as it is; where the
    run's step is the undamped bound (`_undamped_bound`), it comes from the pair's laws alone
    (`solver.mbs.stability.pair_frequency_estimate`, within 5 % of the linearised pair's):
    neither statics nor compiled kernels, so the estimate of a cold study costs a fraction of a
    second, not the compile of a static sweep the study's own model may never run. Otherwise the
    run's own choice (`study.scene_model.dynamic_choice`: static equilibria, linearised pair)."""
    from solver.mbs.dynamics import run_loads
    from solver.mbs.method import MethodChoice
    from solver.mbs.stability import IMEX_SAFETY, pair_frequency_estimate
    from study.scene_model import build_scene_model, dynamic_choice, flankless_model, load_table
    plain, d = _plain(scene), scene.dynamic
    if d.time_step > 0:
        return flankless_model(plain), MethodChoice("implicit" if d.method == "implicit" else "explicit",
                                                    d.time_step, math.nan, "step given")
    if _undamped_bound(plain):
        model = flankless_model(plain)
        w = pair_frequency_estimate(model, run_loads(load_table(plain), d.torque)[1])
        return model, MethodChoice("explicit", IMEX_SAFETY * 2.0 / w, w, "estimated from the pair's laws",
                                   estimated=True)
    model = build_scene_model(plain)
    return model, dynamic_choice(plain, model)


# A study's task, costed without a model (for the order and batching of the tasks on dask, not
# for a budget): the dynamic run at a typical step (the paper pair's 1.1 us, the small 20-tooth
# pair's 1.4 us), the fixed part of a task (its run archive, summary and record: 0.015-0.02 s
# measured on the small pair) and the part of the first point of a model (its build, damping
# conversion, modes and step bound), paid once per worker and model and left out here.
TASK_S = 0.02
TYPICAL_STEP_S = 1.2e-6


def task_seconds(scene, outputs) -> float:
    """Estimated compute seconds of one study task (`study.sweep.tasks.Task`: its scene and
    outputs) on a quiet core, from the scene alone: the statics by their angles, the mesh
    outputs, the dynamic run by its duration at TYPICAL_STEP_S (a run-up's teeth all active and
    its run repeated). A relative figure: the order in which a study's tasks start and how
    many share a dask task (`study.sweep.tasks.batches`)."""
    from study.sweep.outputs import MESH_SCALARS
    teeth = scene.gear1.teeth + scene.gear2.teeth
    s = TASK_S
    if outputs.static and scene.quasi_static.method == "static":
        angles = static_angle_count(scene)
        s += angles * STATIC_S_PER_ANGLE_TOOTH * teeth
        if set(outputs.scalars + outputs.curves) & set(MESH_SCALARS):
            s += angles * MESH_S_PER_ANGLE
    if outputs.dynamic:
        runup = scene.dynamic.speed_end > 0
        active = teeth if runup else min(teeth, 2 * ACTIVE_TEETH_PER_GEAR)
        steps = scene.dynamic.duration / (scene.dynamic.time_step or TYPICAL_STEP_S)
        s += steps * (EXPLICIT_S_PER_STEP + EXPLICIT_S_PER_STEP_TOOTH * active) * (RUNUP_RUNS if runup else 1.0)
    return s


GIVEN_STEP_GROUPS = 20      # distinct given steps estimated one by one, the smallest (the others sampled)


def sweep_estimate(tasks) -> Estimate:
    """Estimated seconds of a study's tasks (`study.sweep.tasks.Task`), summed: FE bodies (each
    distinct body the cache lacks), statics (per static task, by its angles) and dynamics
    (per dynamic task, by its duration over the step of up to DYNAMIC_SAMPLES of them)."""
    from study.inputs.cache import FE_CACHE
    est = Estimate()
    bodies, body_s, rims = {}, {}, set()
    static_s = 0.0
    dyn = [t for t in tasks if t.outputs.dynamic]
    for t in tasks:
        try:        # the bodies of its springs or of its coupling model (compliance: fits at three loads)
            from study.inputs.gearsetup import gear_setups
            needed = fe_bodies(gear_setups(t.scene), t.scene.coupling_model)
        except Exception:  # noqa: BLE001 - a scene that cannot be prepared: its task records why
            needed = []
        for label, setup, teeth in needed:
            key = FE_CACHE.key({**setup.settings, "teeth": list(range(setup.teeth)) if teeth is None else teeth})
            if key not in bodies:
                bodies[key] = setup
                body_s[key] = body_estimate(label, setup, t.scene.coupling_model, rims)
        if t.outputs.static and t.scene.quasi_static.method == "static":
            static_s += static_angle_count(t.scene) * STATIC_S_PER_ANGLE_TOOTH * (t.scene.gear1.teeth + t.scene.gear2.teeth)
    est.seconds["FE bodies"] = sum(body_s.values())
    line = check_fe_memory(bodies.values())        # BudgetError beyond the memory available
    if line:
        from study.plausibility import report_warnings
        report_warnings([line], True)
    est.seconds["statics"] = static_s
    # the runs whose step is given (dynamic.time_step) each at their own step, one model per
    # distinct step and pair; the others at the worst step of up to DYNAMIC_SAMPLES of them
    given: dict = {}
    for t in dyn:
        d = t.scene.dynamic
        if d.time_step > 0:
            given.setdefault((d.time_step, d.method, t.scene.gear1.teeth, t.scene.gear2.teeth), []).append(t)
    given = dict(sorted(given.items(), key=lambda kv: kv[0][0])[:GIVEN_STEP_GROUPS])     # the smallest steps
    free = [t for t in dyn if not any(t in g for g in given.values())]
    groups = [(g[0], g) for g in given.values()]
    if free:
        picks = [free[int(i)] for i in sorted({round(k * (len(free) - 1) / max(DYNAMIC_SAMPLES - 1, 1))
                                                for k in range(min(DYNAMIC_SAMPLES, len(free)))})]
        groups += [(t, None) for t in picks]
    rates, dts, choice_of, seconds = [], [], [], 0.0
    for t, group in groups:
        model, choice = estimate_choice(t.scene)
        rate = dynamic_seconds(model, choice, 1.0)      # s of run time per s simulated
        rates.append(rate)
        dts.append(choice.dt)
        choice_of.append(choice)
        if group is not None:
            seconds += rate * sum(u.scene.dynamic.duration for u in group)
    if free:
        seconds += max(r for (_, g), r in zip(groups, rates) if g is None) * sum(t.scene.dynamic.duration for t in free)
    if dyn:
        part = f"dynamics ({len(dyn)} runs, dt down to {min(dts):.3g} s)"
        est.seconds[part] = seconds
        worst = int(np.argmax(rates))
        est.levers[part] = dynamic_lever(groups[worst][0].scene, choice_of[worst]) + ", or fewer grid points"
    return est


# A study task's modal analysis (mesh mode, critical speeds, damping), which `task_seconds`
# leaves out: about 0.5 s on the paper pair (12 mesh positions, 134 teeth), 4 ms a tooth.
MODES_S_PER_TOOTH = 4e-3


def progress_seconds(tasks) -> dict:
    """Estimated seconds of each study task (`study.sweep.tasks.Task`) for a progress bar's ETA:
    `task_seconds` with the modal analysis its outputs need, scaled by `load_factor` ->
    {task key: s}. (The FE bodies it reads are costed apart: `body_seconds`.)"""
    out = {}
    for t in tasks:
        s = task_seconds(t.scene, t.outputs)
        if t.outputs.modes or t.outputs.dynamic:
            s += MODES_S_PER_TOOTH * (t.scene.gear1.teeth + t.scene.gear2.teeth)
        out[t.key] = s * estimate.load_factor()     # the one load factor of a run's and a study's costs
    return out

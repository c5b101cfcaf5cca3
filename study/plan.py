"""A run's plan: everything a scene implies for one run, made once at its start and carried down
to the stages that compute its archive (`study.stages`): both gears' setups and geometry, the
tooth springs, the model and its dampers, the mean load and the loaded equilibria there, the
static angles, the load profile, the integrator and its step, and which stages are asked.

Nothing below the plan derives these from the scene again: a stage reads the plan (and the
scene's sections for the settings it runs with), never re-derives a setup, a model or an
equilibrium. The checks a run makes before any work (memory, the estimated time, the load the
teeth must carry) are made here, each before the part it concerns starts.

Stage names (`STAGES`): 'static' (quasi-static STE), 'mesh' (the linearised mesh over the STE
and the dynamic factor K_v), 'dynamic' (DTE run), 'modes' (modal analysis; with 'dynamic' the
free decay too), 'gear' (per-gear mass, inertia, root stress), 'strength' (bending strength
under the STE's loads). `scene_stages` gives those a whole run makes, `study.sweep.outputs.stages_of`
those a study's outputs need.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from solver.mbs.model import Model
from solver.store import STORE, digest
from study import estimate
from study.inputs.gearsetup import gear_setups
from study.plausibility import report_warnings, scene_warnings
from study.scene import Scene
from study.scene_model import (
    damping_conversion,
    damping_ratios,
    dynamic_choice,
    load_table,
    mean_load,
    scene_model,
    scene_springs,
    static_angles,
)

STAGES = ("gear", "modes", "static", "mesh", "dynamic", "strength")


def scene_stages(scene: Scene, static: bool | None = None, dynamic: bool | None = None) -> frozenset:
    """The stages of a whole run of ``scene`` (`study.run_scene`): the statics and the dynamic
    run as the scene enables them (or as ``static`` / ``dynamic`` force), the per-gear
    variables and the modes always, the linearised mesh and the strength with the statics."""
    static = scene.quasi_static.enabled if static is None else static
    dynamic = scene.dynamic.enabled if dynamic is None else dynamic
    return frozenset({"gear", "modes", "mesh"} | ({"static", "strength"} if static else set())
                     | ({"dynamic"} if dynamic else set()))


@dataclass
class RunPlan:
    """What one run of a scene works with, made once (`make_plan`). SI units but where named."""
    scene: Scene
    stages: frozenset               # the stages asked (`STAGES`)
    setups: tuple                   # both gears' `study.inputs.gearsetup.GearSetup` (geometry, body, material)
    springs: tuple                  # ((k1, r1), (k2, r2)): per-tooth springs [N·mm/rad^n_k] and FE ratios [1]
    model: Model                    # the pair, its dampers converted from the scene's ratios
    mean_load: float                # [N·m]: where the dampers are converted and the modes computed
    ratios: dict                    # the dampers the scene gives as ratios of critical [1] (`damping_ratios`)
    equilibria: list | None         # loaded equilibria at mean_load (12 positions), None where none was needed
    angles: np.ndarray | None       # driver angles of the statics [rad] (None without 'static')
    load_table: np.ndarray | None   # resisting torque profile [s, N·m] (None: the plain ramp)
    choice: object | None           # the dynamic run's method and step (`solver.mbs.method.MethodChoice`)
    warnings: list = field(default_factory=list)    # plausibility lines (stderr and the archive)
    archive: bool = True            # the attributes that only document an archive (scene TOML, provenance)
    warn: bool = True               # warnings to stderr too
    progress: bool = False          # bars on stderr for long parts
    springs_s: float = 0.0          # wall time of the springs and the model [s]
    damping_at: str = ""            # where the dampers given as ratios were converted (`scene_model.damping_conversion`)

    def asks(self, stage: str) -> bool:
        """True when ``stage`` (`STAGES`) is asked."""
        return stage in self.stages

    def warn_also(self, line: str | None) -> None:
        """A warning found during the run: to stderr (with ``warn``) and the archive."""
        if line:
            report_warnings([line], self.warn)
            self.warnings.append(line)

    def equilibria_at(self, torque: float) -> list | None:
        """The plan's loaded equilibria when they are those under ``torque`` [N·m], else None."""
        return self.equilibria if self.equilibria is not None and torque == self.mean_load else None


@dataclass(frozen=True)
class RunOptions:
    """How a run is made (not what it computes): ``max_time`` [s] bound on its estimated time
    (None: none), ``progress`` bars, ``warn`` to stderr, ``keep_model`` (a study's worker: the
    model kept for the points of one body, `kept_springs_and_model`), ``archive`` (the
    attributes that only document an archive), ``springs`` given (no FE for the tooth springs)."""
    max_time: float | None = None
    progress: bool = False
    warn: bool = True
    keep_model: bool = False
    archive: bool = True
    springs: tuple | None = None


def make_plan(scene: Scene, stages, options: RunOptions = RunOptions()) -> RunPlan:
    """The plan of one run of ``scene`` for ``stages`` (see the module), its checks made before
    the work each concerns: the output memory, the static angles, the FE bodies' memory and
    time, then (with the model built) the load the teeth carry and the estimated time of the
    statics and the dynamic run (`study.errors.BudgetError`, `study.scene.SceneError`)."""
    stages = frozenset(stages)
    if not stages <= set(STAGES):
        raise ValueError(f"stages: unknown {', '.join(sorted(stages - set(STAGES)))} (expected some of {', '.join(STAGES)})")
    static, dynamic = "static" in stages, "dynamic" in stages
    warnings = scene_warnings(scene) if dynamic else [w for w in scene_warnings(scene) if not w.startswith("dynamic.")]
    report_warnings(warnings, options.warn)
    if dynamic:
        estimate.check_dynamic_memory(scene)
    angles = static_angles(scene) if static else None     # checked before the FE bodies are made
    setups = gear_setups(scene)
    springs = options.springs
    est = estimate.Estimate()
    bounded = options.max_time is not None      # the estimates serve only the bound
    if springs is None and bounded:
        est.seconds["FE bodies"] = estimate.fe_seconds(setups, scene.coupling_model)
        estimate.check_time(est, options.max_time)
    # the FE bodies' memory, before any of them is made (a study's worker leaves it to the
    # study's estimate, which counted every body ahead)
    if springs is None and not options.keep_model:
        line = estimate.check_fe_memory(s for _, s, _ in estimate.fe_bodies(setups, scene.coupling_model))
        if line:
            report_warnings([line], options.warn)
            warnings.append(line)
    from study.stand_in import start_ahead
    start_ahead(scene)          # a second process compiling the kernels while the FE is built, when asked
    t0 = time.perf_counter()
    if springs is None:
        from study.stages import compute_fe_bodies
        compute_fe_bodies(setups, scene.coupling_model, options.progress)
    springs, model, equilibria = _springs_and_model(scene, setups, springs, options.keep_model)
    springs_s = time.perf_counter() - t0
    load, ratios = mean_load(scene), damping_ratios(scene)
    if equilibria is None and not ratios:
        from study.plausibility import carrying_equilibria
        carrying_equilibria(scene, model, load, positions=2)     # SceneError: teeth too soft for the load
    choice = None
    if static and bounded:
        est.seconds["statics"] = estimate.static_seconds(scene.quasi_static.method, angles.size, model.n_teeth)
        if "mesh" in stages:
            est.seconds["mesh stiffness"] = estimate.mesh_seconds(angles.size, setups, scene.coupling_model)
    table = load_table(scene)
    if dynamic:
        choice = dynamic_choice(scene, model, equilibria, load)
        if bounded:
            part = f"dynamics ({choice.method}, dt {choice.dt:.3g} s)"
            runup = scene.dynamic.speed_end > 0
            est.seconds[part] = estimate.dynamic_seconds(model, choice, scene.dynamic.duration, runup)
            est.levers[part] = estimate.dynamic_lever(scene, choice)
    est.seconds["FE bodies"] = 0.0          # done
    estimate.check_time(est, options.max_time)
    return RunPlan(scene, stages, setups, springs, model, load, ratios, equilibria, angles, table, choice, warnings,
                   options.archive, options.warn, options.progress, springs_s,
                   damping_conversion(scene))


# the springs, model and equilibria of the last scene run with keep_model
LAST_MODEL = STORE.shelf("last springs and model", 1)


def _springs_and_model(scene: Scene, setups: tuple, springs, keep_model: bool):
    """(springs, model, loaded equilibria at the mean load or None) of the scene: built, or with
    ``keep_model`` kept for the scenes that differ only in ``dynamic.*`` fields that leave the
    model as it is (`study.scene_model.model_key`): a study's worker runs the points of one
    model in a row, whose springs and model key (both read the whole scene) are then made once,
    not once per point. The objects are shared: not to be changed in place."""
    if not keep_model:
        springs = springs or scene_springs(scene, setups)
        return (springs, *scene_model(scene, springs, setups))
    if springs is not None:
        return (springs, *scene_model(scene, springs, setups, keep=True))
    from study.inputs.cache import FE_CACHE

    def make():
        made = scene_springs(scene, setups)
        return (made, *scene_model(scene, made, setups, keep=True))
    # the FE cache's folder: springs read from another cache are made again
    return LAST_MODEL.kept(digest(scene.model_sections(), mean_load(scene), str(FE_CACHE.folder)), make)


def kept_springs_and_model(scene: Scene):
    """(springs, model) of a scene kept as a study's worker keeps them (`make_plan` with
    ``keep_model``): those of the last scene that differs from this one only in ``dynamic.*``
    fields that leave the model as it is. The objects are shared: not to be changed in place."""
    return _springs_and_model(scene, gear_setups(scene), None, True)[:2]

"""Cost of a run before it starts: memory of the output arrays, run time of the FE bodies, the
statics and the time integration, checked against what the machine has and a time bound
(`lightgear run|stiffness|reference --max-time`), and the progress bar of a long run.

The costs per unit are CPU seconds measured on the paper pair and the README's small pair
(warm numba cache; a quiet machine's wall time) and are rough (a factor of two either way):
they tell a run of seconds from one of hours, not more. A loaded machine gives each process a
smaller share of a core: every estimate is scaled by `load_factor` (measured under a load of
10-12 on 2 cores: wall times 2 to 4 times the CPU time). What the FE cache holds counts as free.
"""
from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass, field

from solver.mbs.kernels import layout as L
from study.errors import BudgetError
from study.memory import available_memory, bytes_text
from study.scene_model import static_angle_count

DEFAULT_MAX_TIME_S = 3600.0       # --max-time default [s]
PROGRESS_AFTER_S = 5.0            # runs expected to take longer than this show a progress bar [s]
# Measured costs in CPU seconds (a quiet machine's wall time; under load the wall time grows by
# the load per core). Verlet: a step costs a fixed part (contact search, kicks of the hubs) and a
# part per active tooth: paper pair 0.59 s for 180 000 steps with 21 teeth active, the 20-tooth
# example pair 0.03 s for 11 000 steps with 10, the paper run-up 5.7 s for 900 000 steps with
# all 134 active -> 2.8e-6 s + 2.4e-8 s per active tooth. Teeth away from the mesh are frozen
# (about ACTIVE_TEETH_PER_GEAR of each gear stay active), except in a run-up, where the rising
# speed keeps every tooth moving on its spring; a run-up's resonances also raise the contact
# forces beyond the step's load, so its run is repeated at about half the step (measured on
# study/scenes/runup.toml: 900 000 then 1 700 000 steps): counted as RUNUP_RUNS runs.
# HHT-alpha: about 20 x a Verlet step per tooth of the pair (Newton).
DYNAMIC_S_PER_RUN = 0.05         # the step estimate and the output arrays of a run (the small pair: 0.05 s in all)
EXPLICIT_S_PER_STEP = 2.8e-6
EXPLICIT_S_PER_STEP_TOOTH = 2.4e-8
ACTIVE_TEETH_PER_GEAR = 10
RUNUP_RUNS = 3.0
IMPLICIT_S_PER_STEP_TOOTH = 6e-7
STATIC_S_PER_ANGLE_TOOTH = 2e-7   # Newton with continuation: 0.02 s for 1201 angles of 67/67 teeth
# FE body: gmsh mesh, P2 assembly and the Z load cases: the paper's lightened driven gear and
# its solid reference, 23 400 elements each by `body_elements`, 6.7 s for both; the README's
# 20-tooth pair, 3 500 each, 2.3 s for both -> 0.6 s a body (mesher, set-up, the cache file)
# and 1.16e-4 s per element, growing with the size of the factorisation beyond FE_REF_ELEMENTS.
FE_S_PER_BODY = 0.6
FE_S_PER_ELEMENT = 1.16e-4
FE_REF_ELEMENTS = 4e4
OUTPUT_COPIES = 2.5               # the kernel's output array, the result's columns and the archive's


# what makes a part of a run cheaper, by the start of the part's name (`check_time`'s advice)
LEVERS = {
    "FE bodies": "a coarser fe.mesh_size (each body is computed once, then read from the FE cache)",
    "gear": "a coarser fe.mesh_size (the influence coefficients are cached once computed)",
    "statics": "a larger quasi_static.angle_step or a shorter quasi_static.rotation",
    "mesh stiffness": "a larger quasi_static.angle_step or a shorter quasi_static.rotation (one linearisation per "
                      "STE angle)",
    "contact sweep": "a larger angle step (--step, quasi_static.angle_step) or a shorter quasi_static.rotation",
    "dynamics": "a shorter dynamic.duration",
    "sweep": "fewer grid points",
}


@dataclass
class Estimate:
    """What a run will cost: seconds by part, bytes by part (for the messages), and what makes
    a part cheaper (part -> text; default: `LEVERS` by the part name's start)."""
    seconds: dict = field(default_factory=dict)     # part -> s
    memory: dict = field(default_factory=dict)      # part -> bytes
    levers: dict = field(default_factory=dict)      # part -> advice

    def lever(self, part: str) -> str:
        if part in self.levers:
            return self.levers[part]
        return next((v for k, v in LEVERS.items() if part.startswith(k)), "a smaller run")

    @property
    def total_s(self) -> float:
        """Estimated wall time [s] of the whole run (its parts already scaled by `load_factor`)."""
        return float(sum(self.seconds.values()))

    def describe(self) -> str:
        return ", ".join(f"{k} {duration_text(v)}" for k, v in self.seconds.items() if v > 0) or "nothing"


def load_factor() -> float:
    """How much longer than on a quiet machine a run takes now: the square root of the load
    average per core (1 minute; at least 1). Measured under a load of 10-12 on 2 cores: the FE
    bodies, the reference and the dynamics took 2 to 4 times their CPU time (the load average
    counts processes that wait on more than the CPU, hence less than the load per core)."""
    try:
        load = os.getloadavg()[0]
    except (OSError, AttributeError):
        return 1.0
    return max(1.0, math.sqrt(load / (os.cpu_count() or 1)))


def duration_text(s: float) -> str:
    """Seconds as '12 s', '3.4 min', '2.1 h' or '5.6 days'."""
    if s < 90:
        return f"{s:.2g} s"
    if s < 5400:
        return f"{s / 60:.2g} min"
    if s < 2 * 86400:
        return f"{s / 3600:.2g} h"
    return f"{s / 86400:.3g} days"


# ---------------------------------------------------------------- parts

def dynamic_records(scene) -> int:
    """Output records of the scene's dynamic run (t = 0 included)."""
    d = scene.dynamic
    return int(d.duration / d.output_step + 1e-9) + 1


def check_dynamic_memory(scene, field: str = "dynamic.duration") -> None:
    """Refuse, before anything is built, a dynamic run whose output arrays do not fit in memory
    (BudgetError naming ``field``)."""
    if not scene.dynamic.enabled:
        return
    n = dynamic_records(scene)
    need = OUTPUT_COPIES * n * (L.N_OUT + L.CONTACT_SLOTS * L.O_CONTACT_COLS) * 8.0
    have = available_memory()
    if need > 0.8 * have:
        raise BudgetError(field, f"the run's outputs need about {bytes_text(need)} ({n:.3g} records of "
                          f"dynamic.output_step = {scene.dynamic.output_step:.3g} s over {scene.dynamic.duration:.4g} s), "
                          f"more than the {bytes_text(have)} of memory available; shorten the run or raise "
                          "dynamic.output_step")


def dynamic_seconds(model, choice, duration: float, runup: bool = False) -> float:
    """Estimated run time [s] of the time integration with the chosen method and step
    (``runup``: a run-up, whose teeth all stay active and whose run is repeated)."""
    steps = duration / choice.dt
    if choice.method == "implicit":
        return (DYNAMIC_S_PER_RUN + steps * IMPLICIT_S_PER_STEP_TOOTH * model.n_teeth) * load_factor()
    active = model.n_teeth if runup else min(model.n_teeth, 2 * ACTIVE_TEETH_PER_GEAR)
    per_step = EXPLICIT_S_PER_STEP + EXPLICIT_S_PER_STEP_TOOTH * active
    return (DYNAMIC_S_PER_RUN + steps * per_step) * (RUNUP_RUNS if runup else 1.0) * load_factor()


def static_seconds(method: str, angles: int, teeth: int) -> float:
    """Estimated run time [s] of the quasi-static analysis by ``method`` (quasi_static.method)
    over ``angles`` driver angles of a pair of ``teeth`` teeth in all."""
    if method == "static":
        return angles * STATIC_S_PER_ANGLE_TOOTH * teeth * load_factor()
    return 0.0      # the transient's steps are counted like a dynamic run's by the caller when needed


# the linearised mesh at every STE angle (`solver.mbs.mesh_stiffness.mesh_states`: a static
# solve, a contact search and a linearisation an angle): 1.2 ms an angle measured on the paper
# example's 1201 angles (1.4 s), 2 ms with the machine's 2 cores shared
MESH_S_PER_ANGLE = 2e-3


def mesh_seconds(angles: int, setups, coupling_model: str) -> float:
    """Estimated run time [s] of the linearised mesh over ``angles`` STE angles, and for the
    plain model (``coupling_model`` 'none') the FE bodies of the wind-up its springs hold that
    the cache lacks (`study.inputs.coupling.plain_windup`: the mesh alone); ``setups``: both
    gears' `study.inputs.gearsetup.GearSetup`."""
    s = angles * MESH_S_PER_ANGLE
    if coupling_model == "none":
        from study.inputs.coupling import pitch_compliances_cached, windup_body
        bodies = {b.key: b for b in map(windup_body, setups)}
        s += sum(body_seconds(b) for b in bodies.values() if not pitch_compliances_cached(b))
    return s


def error_period_note(scene) -> str | None:
    """A line for the user when pitch errors or an eccentricity stretch the quasi-static range
    beyond quasi_static.rotation (`study.scene_model.static_rotation`) by more than 1.5 times; None otherwise."""
    from study.scene import static_rotation
    qs = scene.quasi_static
    rot = static_rotation(scene)
    if not qs.enabled or rot <= 1.5 * qs.rotation:
        return None
    n = int(static_angle_count(scene))
    sec = (n * STATIC_S_PER_ANGLE_TOOTH * (scene.gear1.teeth + scene.gear2.teeth) * load_factor()
           if qs.method == "static" else float("nan"))
    return (f"quasi-static: the pitch errors and eccentricities repeat after {rot:.6g} deg of driver rotation: the STE "
            f"covers that instead of quasi_static.rotation = {qs.rotation:.6g} deg ({n} angles at {qs.angle_step:g} deg, "
            f"{rot / qs.rotation:.3g} x longer" + (f", about {duration_text(sec)})" if math.isfinite(sec) else ")"))


GRADED_TEETH_RIM = 0.48   # triangles of the graded mesh in teeth and rim over the fine one's (paper body: 16 800 / 35 300)


def body_elements(setup) -> float:
    """Triangles of gear ``setup``'s FE body (`solver.fe.mesh`): outline size h over teeth and
    rim, h/2 on the fillets, about 5 h in web and hub (equilateral triangles, +10 %); the
    graded mesh (``fe.mesh_grading``) has `GRADED_TEETH_RIM` of that in teeth and rim."""
    g, b = setup.geometry, setup.body
    h = setup.mesh_size
    r_rim = g.root_radius - b.rim_height
    r_bore = max(r_rim - b.web_height - b.hub_height, 0.0)
    tri = math.sqrt(3.0) / 4.0
    teeth_rim = 0.5 * math.pi * (g.tip_radius**2 - g.root_radius**2) + math.pi * (g.root_radius**2 - r_rim**2)
    web_hub = math.pi * (r_rim**2 - r_bore**2)
    graded = GRADED_TEETH_RIM if getattr(setup, "mesh_grading", "fine") == "graded" else 1.0
    return 1.1 * (graded * teeth_rim / (tri * h * h) + web_hub / (tri * 25.0 * h * h))


def body_seconds(setup) -> float:
    """Estimated run time [s] of one FE body: mesh, assembly, factorisation and load cases."""
    n = body_elements(setup)
    return (FE_S_PER_BODY + FE_S_PER_ELEMENT * n * max(1.0, n / FE_REF_ELEMENTS) ** 0.25) * load_factor()


# Peak memory of an FE body beyond the process's own (mesh, P2 assembly, factorisation, its
# load cases or influence coefficients) by its elements n: 29 kB an element at FE_REF_ELEMENTS,
# growing as n^0.8 (a body's fixed part weighs less as it grows), the fine grading's elements
# (which `body_elements` counts for the outline's size) FINE_GRADING_COST times as dear. Fitted
# to `lightgear reference` (both bodies held) from an empty FE cache: the small lightened pair
# with a 1.5 mm rim at fe.mesh_size 0.5-0.18 mm and the paper pair with a 2.5 mm rim at
# 0.375-0.25 mm, graded and fine, 0.38-6.2 GB, each estimate 0.85-1.05 x the peak over the
# process (benchmarks/bench_reference_cost.py); a run's compliance-model bodies 0.75-0.85 x.
FE_BYTES_PER_ELEMENT = 2.9e4
FE_BYTES_EXPONENT = -0.2
FINE_GRADING_COST = 1.6
# share of the available memory above which a part is refused, and above which it is warned of
MEMORY_REFUSE, MEMORY_WARN = 0.8, 0.5


def body_bytes(setup) -> float:
    """Estimated peak memory [bytes] of one FE body (`body_elements`)."""
    n = body_elements(setup) * (FINE_GRADING_COST if setup.mesh_grading == "fine" else 1.0)
    return FE_BYTES_PER_ELEMENT * n * (n / FE_REF_ELEMENTS) ** FE_BYTES_EXPONENT


def check_fe_memory(setups, factor: float = 1.0) -> str | None:
    """Refuse, before any FE work, bodies whose estimated memory (`body_bytes`; the two largest
    are held at once, ``factor`` times that: the FE reference's influence coefficients)
    exceeds MEMORY_REFUSE of the memory available (BudgetError naming fe.mesh_size); a line to
    warn with above MEMORY_WARN, else None. ``setups``: the gear setups to count (a run: the
    bodies it needs and the FE cache lacks, `fe_bodies`)."""
    setups = list(setups)
    if not setups:
        return None
    sizes = sorted((body_bytes(s), body_elements(s)) for s in setups)[-2:]
    need = factor * sum(b for b, _ in sizes)
    what = f"the FE bodies need about {bytes_text(need)} ({' and '.join(f'{n:.3g}' for _, n in sizes)} elements)"
    return check_memory(need, "fe.mesh_size", what, "a coarser fe.mesh_size (or fewer teeth)", "a coarser fe.mesh_size")


def check_memory(need: float, field: str, what: str, lever: str, warn_lever: str | None = None) -> str | None:
    """Refuse, before the work, a part that needs ``need`` [bytes], more than MEMORY_REFUSE of
    the memory available (BudgetError naming ``field``, ``what`` needs it, ``lever`` needs
    less); a line to warn with above MEMORY_WARN (its lever ``warn_lever``, default ``lever``),
    else None."""
    have = available_memory()
    text = f"{what}, {{}} the {bytes_text(have)} of memory available"
    if need > MEMORY_REFUSE * have:
        raise BudgetError(field, text.format("more than") + ": " + lever)
    if need > MEMORY_WARN * have:
        return f"{field}: " + text.format("more than half of") + "; " + (warn_lever or lever) + " needs less"
    return None


def fe_bodies(setups, coupling_model: str) -> list:
    """(label, setup, teeth) of the FE bodies the springs of gears ``setups`` (both gears'
    `study.inputs.gearsetup.GearSetup`) under ``coupling_model`` need and the cache lacks."""
    from study.inputs.cache import FE_CACHE
    from study.inputs.springs import uses_fe_springs
    out = []
    for g, setup in zip((1, 2), setups):
        need = []
        if uses_fe_springs(setup):
            need += [(f"gear {g}", setup, None), (f"gear {g} solid reference", setup.solid(), [0])]
        elif coupling_model != "none":
            need.append((f"gear {g}", setup, None))
        for label, s, teeth in need:
            key = FE_CACHE.key({**s.settings, "teeth": list(range(s.teeth)) if teeth is None else teeth})
            if key not in FE_CACHE.stiffness and not (FE_CACHE.folder / f"{key}.nc").exists():
                out.append((label, s, teeth))
    return out


# A body with a web or hub is solved through its teeth and rim condensed once per rim height
# (`study.inputs.compliance.condensed_rim`, on disk as ``rim-*.npz``): the first body of a rim
# pays the rim (its condensation and, for the compliance model, its flank load set), every body
# its web. Measured on the paper gear (`body_seconds` 3.3 s) from an empty FE cache, one
# process, quiet, 2026-11-28: the first body of a rim 5.7 s, the others 0.84-1.0 s (a study's
# workers, both busy: 7-8 s and 1.0-1.1 s).
RIM_SHARE = 1.45
WEB_SHARE = 0.3
WHOLE_COMPLIANCE = 3.0   # a body factorised whole for the compliance model: its fits load it at several profile points


def body_estimate(label: str, setup, coupling_model: str, rims: set) -> float:
    """Estimated run time [s] of one FE body of `fe_bodies` (``label``, gear ``setup``) under
    ``coupling_model``: condensed, its web and, the first time its rim is met (``rims``: the rim
    keys met so far, updated) when the rim is not on disk, the rim; else the whole body (three
    times for the compliance model's gear)."""
    from study.inputs.cache import FE_CACHE
    from study.inputs.compliance import CONDENSE, rim_key
    b = body_seconds(setup)
    if CONDENSE and (setup.body.web_height > 0 or setup.body.hub_height > 0):
        key = rim_key(setup)
        new = key not in rims and not (FE_CACHE.folder / f"rim-{key}.npz").exists()
        rims.add(key)
        return b * (WEB_SHARE + (RIM_SHARE if new else 0.0))
    whole = coupling_model == "compliance" and not label.endswith("solid reference")
    return b * (WHOLE_COMPLIANCE if whole else 1.0)


def fe_seconds(setups, coupling_model: str) -> float:
    """Estimated run time [s] of the FE bodies gears ``setups`` need under ``coupling_model``
    and the cache lacks (`fe_bodies`, each by `body_estimate`)."""
    rims: set = set()
    return sum(body_estimate(label, s, coupling_model, rims) for label, s, _ in fe_bodies(setups, coupling_model))


TEETH_SEARCH_ANGLES = 20000      # more angles than this: the cache is not searched (the bodies counted in full)
# (the FE reference's own cost, time and memory: `study.verify.fe_reference.reference_cost`)


def check_time(est: Estimate, max_time: float | None) -> None:
    """Refuse a run whose estimated time exceeds ``max_time`` [s] (None: no bound)."""
    if max_time is not None and est.total_s > max_time:
        part = max(est.seconds, key=est.seconds.get)
        raise BudgetError("--max-time", f"the run is estimated at {duration_text(est.total_s)} ({est.describe()}), "
                          f"more than the bound of {max_time:.4g} s; raise --max-time to run it anyway, or make "
                          f"the {part.split(' (')[0]} cheaper: {est.lever(part)}")


def dynamic_lever(scene, choice) -> str:
    """What makes a dynamic run cheaper: its duration, and what sets its step."""
    d = scene.dynamic
    text = f"a shorter dynamic.duration ({d.duration:.4g} s)"
    if d.time_step:
        return text + f", or a larger dynamic.time_step ({d.time_step:.3g} s given)"
    cause = ("the stability bound of the pair's stiffest mode: tooth and contact stiffness (contact.k_con, the "
             "tooth springs) over the tooth inertia (material.density, the tooth size)")
    if scene.contact.friction > 0:
        cause += ", and the friction's regularisation (contact.friction_velocity: a smaller one stiffens it)"
    if choice.method == "explicit" and d.method == "auto" and scene.coupling_model == "none":
        cause += "; dynamic.method = 'implicit' takes larger steps at a higher cost per step"
    return text + f"; its step {choice.dt:.3g} s is {cause}"


# ---------------------------------------------------------------- progress

def progress_bar(expected_s: float, total: float, desc: str, unit: str, show: bool = True):
    """A tqdm bar on stderr for a run expected to take more than PROGRESS_AFTER_S, else None."""
    if not show or not expected_s > PROGRESS_AFTER_S:
        return None
    from tqdm import tqdm
    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False, dynamic_ncols=True,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.4g}/{total:.4g} {unit} [{elapsed}<{remaining}]")


# ---------------------------------------------------------------- work-precision study

# The scipy runs of `lightgear precision` integrate plain-Python forces: the DOP853 reference
# at rtol 1e-10 took 6-20 ms per explicit stability step of the window on 2 shared cores (the
# paper pair and the 20-tooth example pair); its four Radau/LSODA runs at most
# SCIPY_RUN_CAP_S each. The static cross-check (scipy.optimize.root on the same forces) about
# 50 ms an angle.
SCIPY_S_PER_BOUND_STEP = 2e-2
SCIPY_RUN_CAP_S = 120.0
SCIPY_RUNS = 4
SCIPY_ROOT_S_PER_ANGLE = 5e-2
# stability steps the numba ladders take per step of the window and per repeat: explicit at
# 1, 2, 4, 8 x finer in three variants and the 1/32 cross-check; HHT at 1/8 .. 2 x coarser, two alphas
PRECISION_EXPLICIT_STEPS = 3 * (1 + 2 + 4 + 8) + 32
PRECISION_IMPLICIT_STEPS = 2 * (1 / 8 + 1 / 4 + 1 / 2 + 1 + 2)


def precision_estimate(scene, model, duration: float, rotation_deg: float, repeats: int, only=None) -> Estimate:
    """Estimated seconds of `lightgear precision`'s dynamic study over ``duration`` [s] and its
    static study over ``rotation_deg`` [deg], ``repeats`` timed runs each (`study.verify.precision`;
    a body-coupled model runs the explicit ladders and the static solver only, no scipy)."""
    from solver.mbs.stability import stable_time_step
    est = Estimate()
    coupled = bool(model.coupled)
    if only in (None, "dynamic"):
        dt_b, _w = stable_time_step(model, scene.dynamic.torque)
        steps = duration / dt_b
        ref = 0.0 if coupled else steps * SCIPY_S_PER_BOUND_STEP
        est.seconds["dynamic: scipy reference and runs"] = ref + SCIPY_RUNS * min(SCIPY_RUN_CAP_S, ref)
        est.seconds["dynamic: numba runs"] = steps * (repeats + 1) * model.n_teeth * (
            PRECISION_EXPLICIT_STEPS * EXPLICIT_S_PER_STEP_TOOTH
            + (0.0 if coupled else PRECISION_IMPLICIT_STEPS * IMPLICIT_S_PER_STEP_TOOTH))
        est.levers["dynamic: scipy reference and runs"] = est.levers["dynamic: numba runs"] = \
            f"a shorter --duration ({duration:g} s = {steps:.3g} stability steps of {dt_b:.3g} s)"
    if only in (None, "static"):
        angles = rotation_deg / scene.quasi_static.angle_step + 1
        est.seconds["static"] = angles * ((0.0 if coupled else SCIPY_ROOT_S_PER_ANGLE)
                                          + (4 * repeats + 1) * STATIC_S_PER_ANGLE_TOOTH * model.n_teeth)
        est.levers["static"] = f"a smaller --rotation ({rotation_deg:g} deg) or a larger quasi_static.angle_step"
    return est

"""A scene's entry kernels and the argument types a run calls them with, found without its FE.

numba compiles a kernel per set of argument types, and the types of a run's kernels do not
depend on what the FE gives (springs, compliances, body stiffness: values in arrays of fixed
dtypes and dimensions) but on what the model has: which optional parts of the contact search
(`layout.ContactParts`: flank deviations, a local compliance in series, pitch errors,
friction), teeth coupled through the body or not, the coupling's body springs (the coupled
stepping loop), the integrator. `stand_in_model` builds a scene's model with the FE's values
replaced by stand-ins of the same shapes (uniform springs, a diagonal tooth compliance, a
constant local compliance, a stiff body), so that it has those parts exactly as the real
model; `entry_jobs` gives the kernels a run of the scene calls from Python, with the types of
the arguments the solver builds for them (`solver.mbs.statics.sweep_arguments`,
`solver.mbs.dynamics.kernel_arguments`): compiled for those types, a run of the scene finds
them in the disk cache. A second process compiles them there while a cold run builds its FE
(`solver.precompile`, `lightgear run`), and a study's first task before the FE of its bodies
(`study.sweep.cluster`).
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np

from study.scene import Scene

STAND_IN_SPRING = 1.0e7     # N·mm/rad, every tooth's spring (any positive value: a value, not a type)
STAND_IN_BODY = 1.0e6       # N·m/rad, the body spring of a coupled model
STAND_IN_COMPLIANCE = 1.0e-7    # rad/(N·m), the diagonal of the stand-in tooth compliance
STAND_IN_LOCAL = 1.0e-12    # m/N, the local compliance in series with the contact (nonzero: the part is there)


@dataclass(frozen=True)
class StandInFit:
    """What the model takes of a foundation coupling's FE fit (`study.inputs.coupling`), with
    stand-in values of the fit's shapes."""
    k_body: float               # N·m/rad
    pivot_radius: float         # m
    compliance: np.ndarray      # (Z, Z) rad/(N·m)
    local_u: np.ndarray         # rolls [-]
    local_compliance: np.ndarray    # m/N at local_u


def _stand_in_fit(setup) -> StandInFit:
    g = setup.geometry
    return StandInFit(STAND_IN_BODY, setup.pivot_radius, np.eye(g.teeth) * STAND_IN_COMPLIANCE,
                      np.array([g.u_form, g.u_tip]), np.full(2, STAND_IN_LOCAL))


def stand_in_model(scene: Scene):
    """The scene's model (`study.scene_model.build_scene_model`) with stand-ins for what the
    FE gives and the dampers as given: the same arrays' dtypes and dimensions, the same
    `ContactParts`, the same coupling; no FE is read or computed."""
    from solver.mbs.model import with_flank_deviations
    from study.scene_model import _build_flankless, _flanks, gear_setups
    setups = gear_setups(scene)
    springs = tuple((np.full(s.geometry.teeth, STAND_IN_SPRING), np.ones(s.geometry.teeth)) for s in setups)
    coupled = scene.coupling_model in ("body-torsion", "compliance")
    flankless = _build_flankless(scene, springs, setups, fit_of=lambda s: _stand_in_fit(s) if coupled else None)
    return with_flank_deviations(flankless, *_flanks(scene))


def stepping_kernel(scene: Scene, model):
    """The time-stepping kernel a dynamic run of the scene calls (`study.scene_model.dynamic_choice`:
    'auto' takes the explicit integrator, `solver.mbs.method.choose_method`)."""
    from solver.mbs.dynamics import explicit_kernel
    if not model.coupled and scene.dynamic.method == "implicit":
        from solver.mbs.kernels.implicit import hht
        return hht
    return explicit_kernel(model)


def entry_jobs(scene: Scene, dynamic: bool | None = None) -> list:
    """[(kernel dispatcher, argument types)] of the kernels a run of the scene calls, in the
    order to compile them ahead: the time stepping (when the run has a dynamic run, ``dynamic``
    None: as the scene says, or the slow-ramp transient statics; the dearest, and the latest
    called), the contact search (`gearmesh.pair_contacts`, which the loops call and the
    statics through `mesh_contacts`, with the model's parts as its own arguments: compiled by
    whichever process reaches it first, `solver.precompile`), then the static sweep (the
    statics and the loaded equilibria of the damping conversion)."""
    from solver.mbs.dynamics import kernel_arguments
    from solver.mbs.kernels.gearmesh import contact_geo, new_contact_buffer, pair_contacts
    from solver.mbs.kernels.statics import static_sweep
    from solver.mbs.statics import sweep_arguments
    from solver.precompile import argument_types
    from study.scene_model import load_table
    model = stand_in_model(scene)
    jobs, late = [], []
    if (scene.dynamic.enabled if dynamic is None else dynamic) or scene.quasi_static.method == "transient":
        from solver.mbs.dynamics import run_loads
        kernel = stepping_kernel(scene, model)
        table = run_loads(load_table(scene), scene.dynamic.torque)[0]
        par = dict(DELTA_MAX=1e-4, PHI_QUIET=1e-9, ENERGY_TOL=0.05, IMEX=0.0, HHT_ALPHA=0.0, NEWTON_TOL=1e-10,
                   MAX_ITER=20)
        args = kernel_arguments(model, (1.0, 1e-3, 1.0, 1e-3, table, 1.0), (1e-6, 1, 1, 2), par, theta2=0.0)
        jobs.append((kernel, argument_types(kernel, args)))
        late = _late_helpers(kernel, args)
    rates = np.zeros(model.n_teeth)
    geo = contact_geo(model.gear_par, model.pair_par, model.law_par)
    args = ((0.0, 0.0, 0.0, 0.0), rates, rates, geo, new_contact_buffer(), *geo[3])     # as the loops call it
    jobs += [(pair_contacts, argument_types(pair_contacts, args)), *late]
    args = sweep_arguments(model, np.zeros(1), 1.0, 0.0)
    jobs.append((static_sweep, argument_types(static_sweep, args)))
    return jobs


def _late_helpers(kernel, args) -> list:
    """[(kernel, argument types)] of the inner kernels the coupled stepping loop
    (`explicit_coupled.verlet_coupled`, called with ``args``) types last, as it calls them: the
    step's end (`stepping.end_step`) and the dissipation power (`mechanics.dissipation_power`).
    A cold run compiles them with the contact search, before its statics, while the second
    process compiles the loop, which then loads them from the cache: about 0.8 s of the loop's
    compile, the longest part of a cold run's first call, moved to the run. Other loops: none."""
    from solver.mbs.kernels import layout as L
    from solver.mbs.kernels.explicit_coupled import verlet_coupled
    from solver.mbs.kernels.mechanics import dissipation_power
    from solver.mbs.kernels.stepping import end_step
    from solver.precompile import argument_types
    if kernel is not verlet_coupled:
        return []
    mdl, ctl, hub, teeth, out, ws = args
    gp, pp, lp, kphi, ctooth, parts = mdl
    n, z = np.int64(0), 0.0         # (counts, statuses; powers)
    tz2 = int(gp[1, L.TOOTH0])
    return [(end_step, argument_types(end_step, (ws, teeth, n, n, n, tz2, (z, z, z), ctl[0], n))),
            (dissipation_power, argument_types(dissipation_power, (teeth[L.RATE], ws.tset[L.T_ACT], n,
                                                                   (gp.copy(), pp, lp, kphi, ctooth, parts),
                                                                   ws.rec, n, parts[1])))]


def shared_kernels(jobs) -> tuple:
    """The kernels of ``jobs`` (`entry_jobs`) that a run does not call from Python but both its
    statics or its stepping loop and the second process's loop link: all but the static sweep
    and the stepping loop (`solver.precompile`: compiled by whichever process reaches one
    first)."""
    from solver.mbs.kernels.explicit import verlet
    from solver.mbs.kernels.explicit_coupled import verlet_coupled
    from solver.mbs.kernels.implicit import hht
    from solver.mbs.kernels.statics import static_sweep
    return tuple(k for k, _ in jobs if k not in (static_sweep, verlet, verlet_coupled, hht))


# the runs asking for their kernels compiled ahead (`compiling_ahead`), each started by its
# plan once the checks made before any work have passed (`start_ahead`)
_ASKED: list = []


@contextlib.contextmanager
def compiling_ahead(scene: Scene, dynamic: bool | None = None):
    """Context manager: within, the scene's entry kernels (`entry_jobs`) that numba's disk
    cache lacks compiled by a second process (`solver.precompile.precompiling`: none is
    started when the cache holds them all; it is always stopped on leaving). Nothing is built
    until the run's plan has made its checks (`start_ahead`): a run refused before any work
    (memory, time) builds no stand-in either. A scene whose stand-in cannot be built starts
    none: the run itself then says what is wrong."""
    ask = {"scene": scene, "dynamic": dynamic, "started": None}
    _ASKED.append(ask)
    try:
        yield
    finally:
        _ASKED.remove(ask)
        if ask["started"] is not None:
            ask["started"].__exit__(None, None, None)       # the child stopped


def start_ahead(scene: Scene) -> None:
    """Start the compile ahead that `compiling_ahead` asked for ``scene`` (the plan of its run,
    its checks passed, before the FE): nothing when none was asked."""
    from solver.precompile import precompiling
    for ask in _ASKED:
        if ask["scene"] is scene and ask["started"] is None:
            try:
                jobs = entry_jobs(scene, ask["dynamic"])
            except Exception:  # noqa: BLE001 - the run reports the scene's problem, with its field
                jobs = []
            ask["started"] = precompiling(jobs, shared=shared_kernels(jobs))
            ask["started"].__enter__()


def compile_kernels(scenes) -> list[str]:
    """Compile in this process (into the disk cache) the entry kernels of runs of ``scenes``
    (`entry_jobs`, each kernel and set of types once); returns their names. A study's first
    task on a cold kernel cache, before any FE (`study.sweep.cluster`). Never raises: a
    kernel that cannot be compiled here is left to the run that calls it."""
    from solver.precompile import kernel_name
    done, names = set(), []
    for scene in scenes:
        try:
            jobs = entry_jobs(scene)
        except Exception:  # noqa: BLE001 - the run says what is wrong with the scene, not this
            continue
        for kernel, types in jobs:
            if (kernel_name(kernel), types) in done:
                continue
            done.add((kernel_name(kernel), types))
            try:
                kernel.compile(types)
            except Exception:  # noqa: BLE001 - compiled (or refused) by the run itself
                continue
            names.append(kernel_name(kernel))
    return names

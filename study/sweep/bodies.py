"""The FE spring maps a study's tasks need, each computed once and before the tasks that read it.

A lightened gear's springs (and its root stress) come from two FE maps cached on disk
(`study.inputs.springs`): the body's own, all teeth, and its solid reference, tooth 0. Many
tasks of a study share a map (every speed of a body, every body with the same rim shares the
solid reference). Left to the tasks, two workers that start tasks of the same body at once
both compute its map; and a worker that meets a new body in the middle of the queue holds up
the tasks behind it. `spring_maps` lists the maps of a scene, `compute_map` computes one into
the cache; the sweep engine (`study.sweep.engine`) runs one `compute_map` per distinct map,
ahead of the tasks, and makes each task wait for the maps it reads.

With the compliance model (``coupling.model = "compliance"``, what 'auto' gives a lightened
gear) a gear's coupling fit reads its bulk compliance (`study.inputs.compliance`, every tooth
loaded along its profile: the dearest FE of a study). `fe_jobs` lists, per gear, one
`compute_body` job that computes the gear's spring map and its compliance in one process, so
that both come from one factorisation of the body, and the solid reference's map as above.
Scenes with the body-torsion model list no job: their tasks compute what they need.

A body with a web or hub is solved through its teeth and rim condensed once per rim height
(`study.inputs.compliance.condensed_rim`: the dearest part of a study's first body, kept on
disk as ``rim-*.npz`` with its products). `job_rim` names the rim a job builds or reads, so
that the engine runs one job per rim first and the rim's other jobs after it: they read the
condensed rim from the disk instead of each worker condensing it again.
"""
from __future__ import annotations

from solver.store import STORE
from study.scene import Scene


def spring_maps(scene: Scene) -> list[tuple[str, object, list | None]]:
    """(cache key, `GearSetup`, teeth or None for all) of each FE map the scene's springs read
    that the disk cache lacks; [] when the scene cannot be prepared (its task reports why)."""
    from study.inputs.cache import FE_CACHE
    from study.inputs.gearsetup import gear_setups
    from study.inputs.springs import uses_fe_springs

    if scene.coupling_model != "none":
        return []
    try:
        setups = gear_setups(scene)
    except Exception:  # noqa: BLE001 - an invalid scene: its task records the error
        return []
    out = []
    for setup in setups:
        if not uses_fe_springs(setup):
            continue
        for s, teeth in ((setup, None), (setup.solid(), [0])):
            key = FE_CACHE.key({**s.settings, "teeth": list(range(s.teeth)) if teeth is None else teeth})
            if key not in FE_CACHE.stiffness and not (FE_CACHE.folder / f"{key}.nc").exists():
                out.append((key, s, teeth))
    return out


def _map_missing(setup, teeth) -> tuple[str, bool]:
    """(cache key, True when neither memory nor disk holds it) of the FE spring map of ``teeth``."""
    from study.inputs.cache import FE_CACHE
    key = FE_CACHE.key({**setup.settings, "teeth": list(range(setup.teeth)) if teeth is None else teeth})
    return key, key not in FE_CACHE.stiffness and not (FE_CACHE.folder / f"{key}.nc").exists()


REACH_SLOTS = 256   # coupling reaches kept [teeth]: one per gear of a pair (a few integers)
REACH = STORE.shelf("coupling reach", REACH_SLOTS)


def _reach(scene: Scene, setups: tuple, g: int) -> int:
    """How many pitches apart the mesh loads gear g's teeth together (`mesh_samples`): the spread
    of a solid body's compliance. Kept by what the rigid mesh reads (both teeth, the pair and
    the flanks), not by the bodies: a study's bodies over one pair of teeth share it."""
    from solver.store import digest
    from study.inputs.coupling import mesh_samples
    from study.scene_model import _flanks, geometry_model
    key = digest(repr(setups[0].tooth), repr(setups[1].tooth), repr(scene.pair), repr(_flanks(scene)), str(g))
    return REACH.kept(key, lambda: max(abs(d) for d in mesh_samples(geometry_model(scene), g)))


def fe_jobs(scene: Scene) -> list[tuple[str, object, tuple]]:
    """(job key, function, arguments) of each FE computation the scene's task reads that the
    disk cache lacks: `compute_map` for the plain model's maps (`spring_maps`); with the
    compliance model a `compute_body` per gear whose spring map or compliance is missing (key
    ``body-`` + the compliance's cache key) and a `compute_map` per missing solid reference.
    [] when the scene cannot be prepared (its task reports why) or for the body-torsion model."""
    from solver.fe.flank_compliance import profile_grid
    from study.inputs.compliance import PROFILE_POINTS, compliance_cached, compliance_key
    from study.inputs.gearsetup import gear_setups
    from study.inputs.springs import uses_fe_springs

    model = scene.coupling_model
    if model == "none":
        return [(key, compute_map, (setup, teeth)) for key, setup, teeth in spring_maps(scene)]
    if model != "compliance":
        return []
    try:
        setups = gear_setups(scene)
        out = []
        for setup in setups:
            fe = uses_fe_springs(setup)
            teeth = list(range(setup.teeth))
            spread = 0 if setup.lightened else _reach(scene, setups, setup.gear)
            ckey, _, _ = compliance_key(setup, teeth, spread, profile_grid(setup.geometry, PROFILE_POINTS))
            if (fe and _map_missing(setup, None)[1]) or not compliance_cached(setup, teeth, spread):
                out.append((f"body-{ckey}", compute_body, (scene, setup.gear)))
            if fe:
                key, missing = _map_missing(setup.solid(), [0])
                if missing:
                    out.append((key, compute_map, (setup.solid(), [0])))
        return out
    except Exception:  # noqa: BLE001 - an invalid scene: its task records the error
        return []


def job_rim(func, args: tuple) -> str | None:
    """Cache key (`study.inputs.compliance.rim_key`) of the condensed teeth and rim that an FE
    job of `fe_jobs` builds or reads; None for a body factorised whole or a job that cannot
    say (its own error comes later, from the job)."""
    from study.inputs.compliance import CONDENSE, rim_key
    from study.inputs.gearsetup import gear_setups
    try:
        setup = gear_setups(args[0])[args[1] - 1] if func is compute_body else args[0]
        body = setup.body
        return rim_key(setup) if CONDENSE and (body.web_height > 0 or body.hub_height > 0) else None
    except Exception:  # noqa: BLE001 - see above
        return None


def compute_body(scene: Scene, g: int, *after) -> None:
    """Compute gear g's FE spring map (when its springs read one) and the compliance its
    coupling fit reads into the cache, one factorisation for both; never raises (see
    `compute_map`). ``after``: the results of the jobs it waits for (its rim's first job)."""
    from study.inputs.gearsetup import gear_setups
    from study.inputs.springs import fe_stiffness, uses_fe_springs
    from study.scene_model import coupling_fit
    try:
        setups = gear_setups(scene)
        setup = setups[g - 1]
        if uses_fe_springs(setup):
            fe_stiffness(setup)
        coupling_fit(scene, g, setups=setups)
    except Exception:  # noqa: BLE001 - see above
        pass


def compute_map(setup, teeth, *after) -> None:
    """Compute one FE map into the cache; never raises (a task that reads a map that failed
    computes it again and reports the error as its own). ``after``: as for `compute_body`."""
    from study.inputs.springs import fe_stiffness
    try:
        fe_stiffness(setup, teeth)
    except Exception:  # noqa: BLE001 - see above
        pass

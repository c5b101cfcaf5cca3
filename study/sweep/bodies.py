"""The FE spring maps a study's tasks need, each computed once and before the tasks that read it.

A lightened gear's springs (and its root stress) come from two FE maps cached on disk
(`study.inputs.springs`): the body's own, all teeth, and its solid reference, tooth 0. Many
tasks of a study share a map (every speed of a body, every body with the same rim shares the
solid reference). Left to the tasks, two workers that start tasks of the same body at once
both compute its map; and a worker that meets a new body in the middle of the queue holds up
the tasks behind it. `spring_maps` lists the maps of a scene, `compute_map` computes one into
the cache; the sweep engine (`study.sweep.engine`) runs one `compute_map` per distinct map,
ahead of the tasks, and makes each task wait for the maps it reads.

Scenes with a foundation coupling (``coupling.model`` not 'none') build other FE bodies (the
coupling fits): none is listed for them, their tasks compute what they need.
"""
from __future__ import annotations

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


def compute_map(setup, teeth) -> None:
    """Compute one FE map into the cache; never raises (a task that reads a map that failed
    computes it again and reports the error as its own)."""
    from study.inputs.springs import fe_stiffness
    try:
        fe_stiffness(setup, teeth)
    except Exception:  # noqa: BLE001 - see above
        pass

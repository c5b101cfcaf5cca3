"""The order in which a study's tasks and FE jobs go to the workers: points of one body apart
(`interleave`), or together in one process (`by_model`), the pilot that compiles the kernels
first (`pilot_tasks`), each condensed rim's first FE job before its others (`rims_first`).
Pure functions of the tasks; no dask here.
"""
from __future__ import annotations

import dataclasses
import itertools
import json

from study.scene import Scene


def body_group(scene: Scene) -> str:
    """What a point's FE spring maps depend on (gears, bodies, material, mesh, FE load torque).

    Points of one group share the disk-cached maps; `interleave` keeps them apart in the queue
    so that two workers rarely compute the same map at once.
    """
    data = dataclasses.asdict(scene)
    keep = {k: data[k] for k in ("gear1", "gear2", "material", "fe")}
    keep["torque"] = scene.quasi_static.torque
    return json.dumps(keep, sort_keys=True, default=str)


def interleave(todo: dict) -> dict:
    """Reorder {key: scene} round-robin over body groups (first point of every body first)."""
    groups: dict[str, list] = {}
    for key, scene in todo.items():
        groups.setdefault(body_group(scene), []).append(key)
    order = [k for round_ in itertools.zip_longest(*groups.values()) for k in round_ if k is not None]
    return {k: todo[k] for k in order}


def by_model(todo: dict) -> dict:
    """Reorder {key: scene} so that the tasks of one model (`study.sweep.tasks.model_group`)
    follow each other, groups in the order of their first task: the order of a study run in
    one process, whose kept model (`study.plan.kept_springs_and_model`: the springs, the
    model and its damping conversion) then serves a model's tasks in a row instead of being
    built again for each (`interleave` spreads a body's points for workers that would
    otherwise compute its FE maps at once; one process has no such race)."""
    from study.sweep.tasks import model_group
    groups: dict[tuple, list] = {}
    for key, scene in todo.items():
        groups.setdefault(model_group(scene), []).append(key)
    return {k: todo[k] for keys in groups.values() for k in keys}


def pilot_tasks(todo: dict, outputs: dict) -> tuple:
    """The keys of the tasks that compile the kernels on a machine whose numba cache lacks
    them, run first by one worker: the study's first task and, when it runs no dynamics, the
    first dynamic task of the same body (a dynamic run compiles the time stepping, and the
    statics for its damping), so that no kernel is left for two workers to compile at once."""
    if not todo:
        return ()
    first = next(iter(todo))
    if outputs[first].dynamic:
        return (first,)
    group = body_group(todo[first])
    dynamic = [k for k in todo if outputs[k].dynamic]
    same = [k for k in dynamic if body_group(todo[k]) == group]
    return (first, *(same or dynamic)[:1])


def rims_first(jobs: dict, rim_of) -> tuple[list, list]:
    """The FE jobs ({key: (function, arguments, priority)}, `study.sweep.bodies.fe_jobs`) in
    the order to submit them, as (job key, function, arguments, priority, leader): the first
    job of each condensed rim (``rim_of(function, arguments)``, `bodies.job_rim`; leader
    None), and the others, each with the key of its rim's first job as leader (None for a job
    without a rim): it runs after that job and reads the rim it left on disk, so that no two
    workers condense the same rim at once (each worker reads it once)."""
    first, rest = [], []
    leaders: dict = {}
    for key, (func, args, priority) in jobs.items():
        rim = rim_of(func, args)
        if rim is not None and rim not in leaders:
            leaders[rim] = key
            first.append((key, func, args, priority, None))
        else:
            rest.append((key, func, args, priority, leaders.get(rim) if rim is not None else None))
    return first, rest

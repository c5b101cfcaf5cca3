"""The analyses a study runs, each once for all the points that agree on the fields it reads.

A point's outputs split into at most two tasks (`Outputs.parts`): the outputs that read no
``dynamic.*`` field (STE, root stress, mass properties) and the ones that do (DTE; the modal
outputs, linearised at the dynamic run's torque). A task is keyed by a hash of the
scene fields its widest analysis reads (`outputs.ANALYSIS_FIELDS`), its outputs and the code
(`study.archive.netcdf.code_fingerprint`): the points of a study that differ only in
``dynamic.*`` share their static task, and an edited study or a resumed one reuses every task
it has in common.

`point_result` puts a point's tasks back together into the record `archive.study_dataset`
reads: the worst status (`WORST_FIRST`), the messages of the tasks not ok, the scalars of both,
their curves or, for a task held without them, the key of the part file that has them, and the
point's share of the compute time (a shared task's time split equally over its points).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from collections import Counter
from dataclasses import dataclass

from solver.store import STORE
from study.scene import GearSection, Scene
from study.sweep.grid import Point, Study
from study.sweep.outputs import Outputs, reads

# a point's status: the first any of its tasks has (inaccurate: a run that completed, its energy
# balance not closed: worse than ok, better than one that stopped)
WORST_FIRST = ("invalid", "failed", "diverged", "inaccurate", "ok")


@dataclass(frozen=True)
class Task:
    key: str
    scene: Scene          # the scene of the first point that runs it (the fields it reads are the same for all)
    outputs: Outputs


def flat_fields(data: dict, prefix: str = "") -> dict:
    """Nested tables -> {dotted path: value}."""
    out = {}
    for k, v in data.items():
        path = f"{prefix}.{k}" if prefix else k
        out.update(flat_fields(v, path) if isinstance(v, dict) else {path: v})
    return out


def scene_fields(obj, prefix: str = "") -> dict:
    """A scene (or one of its sections) -> {dotted path: value}: ``flat_fields(dataclasses.asdict(obj))``
    without asdict's deep copy of every value (a study keys thousands of scenes)."""
    out = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        path = prefix + f.name
        if dataclasses.is_dataclass(v):
            out.update(scene_fields(v, path + "."))
        elif isinstance(v, dict | list | tuple):     # containers: as asdict makes them
            v = dataclasses.asdict(_Box(v)).get("v")
            out.update(flat_fields(v, path) if isinstance(v, dict) else {path: v})
        else:
            out[path] = v
    return out


@dataclasses.dataclass
class _Box:
    v: object


READS = STORE.shelf("fields an analysis reads", 4096)     # (analysis, dotted field) -> whether it reads it


def _reads(analysis: str, path: str) -> bool:
    return READS.kept((analysis, path), lambda: reads(analysis, path))


def task_key(scene: Scene, outputs: Outputs) -> str:
    """Content hash of a task: the scene fields its outputs read, the outputs, the code."""
    from study.archive.netcdf import code_fingerprint
    analysis = outputs.widest
    fields = {k: v for k, v in scene_fields(scene).items() if _reads(analysis, k)}
    blob = json.dumps([fields, list(outputs.scalars), list(outputs.curves), code_fingerprint()],
                      sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:24]


def point_task_keys(point: Point, outputs: Outputs) -> tuple[str, ...]:
    """The keys of the tasks a valid point needs (none for an invalid one), in the order of
    ``outputs.parts()``; computed once per outputs and code (a sweep asks several times)."""
    from study.archive.netcdf import code_fingerprint
    if point.scene is None:
        return ()
    code = code_fingerprint()
    if (outputs, code) not in point._keys:
        point._keys[outputs, code] = tuple(task_key(point.scene, part) for part in outputs.parts())
    return point._keys[outputs, code]


def plan(study: Study, points: list[Point]) -> tuple[dict[str, Task], dict[tuple, tuple[str, ...]]]:
    """The tasks of a study ({key: Task}, first point first) and each valid point's task keys
    ({point index: keys})."""
    tasks: dict[str, Task] = {}
    of_point = {}
    for p in points:
        if p.scene is None:
            continue
        keys = point_task_keys(p, study.outputs)
        for key, part in zip(keys, study.outputs.parts()):
            tasks.setdefault(key, Task(key, p.scene, part))
        of_point[p.index] = keys
    return tasks, of_point


# Tasks per dask task: a cheap task (a 10 ms dynamic run of a small pair) costs dask and the
# client about as much as its physics (submit, schedule, transfer, its part file), so on dask
# the tasks of one model (`model_group`) are run in batches of about BATCH_S estimated
# compute seconds (`study.sweep.cost.task_seconds`): under 1 % of overhead, and a worker's
# kept model and its model-only analyses (`study.scene_model.kept_scene_model`, `solver.mbs.memo`)
# serve the whole batch. At least BATCHES_PER_WORKER batches per worker are kept, so that the
# end of a study still spreads over the workers; a study with fewer tasks is not batched.
BATCH_S = 2.0
BATCHES_PER_WORKER = 4


def model_group(scene: Scene) -> tuple:
    """What a task's model depends on: every scene field but ``dynamic.*`` and the gears'
    ``modification`` and ``errors`` (the points of one group share the model a worker keeps,
    the sampled builds of a tolerance study its model without those:
    `study.scene_model.flankless_model`)."""
    return tuple(dataclasses.replace(s, modification=None, errors=None) if isinstance(s, GearSection) else s
                 for s in scene.model_sections())


def batches(tasks: list[Task], workers: int) -> list[tuple[Task, ...]]:
    """The tasks grouped into dask tasks, dearest first: tasks of one `model_group`, dearest
    first, up to BATCH_S estimated seconds and at most len(tasks) / (BATCHES_PER_WORKER x
    workers) tasks a batch (one task a batch for a small study)."""
    from study.sweep.cost import task_seconds
    cost = {t.key: task_seconds(t.scene, t.outputs) for t in tasks}
    cap = max(1, len(tasks) // (BATCHES_PER_WORKER * max(workers, 1)))
    groups: dict[tuple, list[Task]] = {}
    for t in tasks:
        groups.setdefault(model_group(t.scene), []).append(t)
    out = []
    for members in groups.values():
        members.sort(key=lambda t: cost[t.key], reverse=True)
        batch, seconds = [], 0.0
        for t in members:
            if batch and (seconds + cost[t.key] > BATCH_S or len(batch) >= cap):
                out.append(tuple(batch))
                batch, seconds = [], 0.0
            batch.append(t)
            seconds += cost[t.key]
        if batch:
            out.append(tuple(batch))
    out.sort(key=lambda b: sum(cost[t.key] for t in b), reverse=True)     # stable: the study's order among equals
    return out


def point_result(keys: tuple[str, ...], results: dict, shared: Counter) -> dict | None:
    """A point's record from its tasks' results (None while one is missing: the point is pending).
    ``shared``: how many points use each task (its compute time is split over them). A task's
    result held without its curves (`engine.without_curves`: ``curve_names`` only) gives them as
    ``curve_keys`` ({curve: task key}), read from its part file when the archive is written."""
    parts = [results.get(k) for k in keys]
    if not parts or any(r is None for r in parts):
        return None
    status = next(s for s in WORST_FIRST if any(r["status"] == s for r in parts))
    messages = list(dict.fromkeys(r["message"] for r in parts if r["status"] != "ok"))
    scalars, curves, curve_keys = {}, {}, {}
    for k, r in zip(keys, parts):
        scalars.update(r["scalars"])
        if "curves" in r:
            curves.update(r["curves"])
        else:
            curve_keys.update(dict.fromkeys(r.get("curve_names", ()), k))
    out = {"status": status, "message": "; ".join(messages) if messages else "ok",
           "wall_time": sum(r["wall_time"] / shared[k] for k, r in zip(keys, parts)),
           "scalars": scalars, "curves": curves}
    if curve_keys:
        out["curve_keys"] = curve_keys
    return out

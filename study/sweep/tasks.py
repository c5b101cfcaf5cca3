"""The analyses a study runs, each once for all the points that agree on the fields it reads.

A point's outputs split into at most two tasks (`Outputs.parts`): the outputs of no dynamic run
(STE, root stress, mass properties) and the dynamic ones (DTE). A task is keyed by a hash of the
scene fields its widest analysis reads (`outputs.ANALYSIS_FIELDS`), its outputs and the code
(`results.code_fingerprint`): the points of a study that differ only in ``dynamic.*`` share
their static task, and an edited study or a resumed one reuses every task it has in common.

`point_result` puts a point's tasks back together into the record `archive.study_dataset`
reads: the worst status, the messages of the tasks not ok, the scalars and curves of both, and
the point's share of the compute time (a shared task's time split equally over its points).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from collections import Counter
from dataclasses import dataclass

from study.scene import Scene
from study.sweep.grid import Point, Study
from study.sweep.outputs import Outputs, reads

WORST_FIRST = ("invalid", "failed", "diverged", "ok")   # a point's status: the first any of its tasks has


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


def task_key(scene: Scene, outputs: Outputs) -> str:
    """Content hash of a task: the scene fields its outputs read, the outputs, the code."""
    from study.report.results import code_fingerprint
    analysis = outputs.widest
    fields = {k: v for k, v in flat_fields(dataclasses.asdict(scene)).items() if reads(analysis, k)}
    blob = json.dumps([fields, list(outputs.scalars), list(outputs.curves), code_fingerprint()],
                      sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:24]


def point_task_keys(point: Point, outputs: Outputs) -> tuple[str, ...]:
    """The keys of the tasks a valid point needs (none for an invalid one)."""
    if point.scene is None:
        return ()
    return tuple(task_key(point.scene, part) for part in outputs.parts())


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


def point_result(keys: tuple[str, ...], results: dict, shared: Counter) -> dict | None:
    """A point's record from its tasks' results (None while one is missing: the point is pending).
    ``shared``: how many points use each task (its compute time is split over them)."""
    parts = [results.get(k) for k in keys]
    if not parts or any(r is None for r in parts):
        return None
    status = next(s for s in WORST_FIRST if any(r["status"] == s for r in parts))
    messages = list(dict.fromkeys(r["message"] for r in parts if r["status"] != "ok"))
    scalars, curves = {}, {}
    for r in parts:
        scalars.update(r["scalars"])
        curves.update(r["curves"])
    return {"status": status, "message": "; ".join(messages) if messages else "ok",
            "wall_time": sum(r["wall_time"] / shared[k] for k, r in zip(keys, parts)),
            "scalars": scalars, "curves": curves}

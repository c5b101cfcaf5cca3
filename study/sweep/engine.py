"""Parametric sweeps: at most two tasks per study point, shared by the points that agree on
what they read, run in process or with dask.distributed.

`run_point(scene, outputs)` runs only the analyses the outputs need and never raises: it
returns a status (ok / diverged / invalid / failed / inaccurate), a message, its wall time [s], the
requested scalars and curves (`study.sweep.outputs`).

`run_sweep(study, output)` computes the tasks of the study that are not finished yet
(`study.sweep.tasks`: a point's outputs that read no ``dynamic.*`` field are one task shared by
every point that differs only in fields they do not read, its dynamic and modal outputs
another), stores each result as it arrives (one small file per task in ``.OUT.nc.parts/``,
written atomically), and writes the study archive (`study.sweep.archive`) atomically at the
end. The client holds only each task's status and scalars: the curves are read back from the
part files of the tasks that produced them in bounded blocks while the archive is written, and
dask releases each result once it is stored, so neither the client's nor the workers' memory
grows with the study. A task dask could not compute (its worker died more often than
`distributed.scheduler.allowed-failures` allows) leaves its points pending, its cause in the
archive's message. Re-running the same study after an interruption (Ctrl-C, a killed worker
or process) computes only the missing tasks. Tasks are keyed by a hash of the scene fields
they read, their outputs and the code (`study.archive.netcdf.code_fingerprint`), so an edited
study reuses the tasks it shares, and a changed code computes them all again.

This module is the driver; the point is `study.sweep.point`, the part files and the archive's
reading `study.sweep.store`, the dask side `study.sweep.cluster`, the order of the work
`study.sweep.schedule` (their names stay importable from here).

Execution: ``workers=0`` runs in this process (debugging, tests, small studies), the tasks of
one model in a row (`by_model`: its kept model serves them); otherwise a dask
`LocalCluster` (processes, one thread each, NUMBA_NUM_THREADS=1; workers = cores by default)
that is always closed, or an existing scheduler (``scheduler="tcp://host:8786"``) whose workers
can import this package. On dask the FE spring maps the tasks read go first, each once
(`study.sweep.bodies`), and each task waits for its maps: no two workers compute the same map,
and no task holds a worker up with a map in the middle of the study. The first FE job of each
condensed rim (`bodies.job_rim`) goes first, the rim's other jobs after it: they read the rim
from the disk instead of condensing it again on each worker (`rims_first`). On a local cluster
whose numba cache lacks the kernels, the pilot (a static and a dynamic task of the first body,
`pilot_tasks`) runs first and compiles them into the disk cache; the other tasks wait for it and
load them, so the machine compiles once, not once per worker (the other workers compute the FE
meanwhile). The tasks go to dask dearest first
(`study.sweep.cost.task_seconds`), the cheap ones of one model in batches
(`study.sweep.tasks.batches`: a 10 ms dynamic run costs dask about as much as its physics);
on a local cluster a batch's worker stores each of its tasks as it finishes, so that an
interrupted batch loses only its unfinished tasks.
"""
from __future__ import annotations

import contextlib
import os
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import xarray as xr

from study.errors import check_argument, checked_workers, is_path
from study.sweep import cluster
from study.sweep.archive import study_dataset
from study.sweep.cluster import (  # noqa: F401 - the dask side, importable from here as before
    CONNECT_TIMEOUT_S,
    WORKER_ENV,
    MainGuardMissing,
    SchedulerUnreachable,
    check_main_guard,
    dask_client,
    kernel_cache_folder,
    kernels_cached,
    local_cluster,
    lost_cause,
    quiet_on_interrupt,
    run_after,
    stop_kernels_plugin,
    with_dask,
)
from study.sweep.grid import Point, Study, check_points
from study.sweep.outputs import Outputs
from study.sweep.point import invalid_result, point_values, run_point  # noqa: F401 - importable from here
from study.sweep.schedule import body_group, by_model, interleave, pilot_tasks, rims_first  # noqa: F401
from study.sweep.store import (  # noqa: F401 - the part files, importable from here as before
    PartStore,
    complete_archive,
    open_archive,
    parts_folder,
    without_curves,
)
from study.sweep.tasks import plan, point_result


def _in_process(todo: dict, outputs: dict):
    """(key, `run_point` result) of each task of ``todo`` ({key: scene}), run in this process."""
    for key, scene in todo.items():
        yield key, run_point(scene, outputs[key])


def study_progress(title: str, points: int, tasks: list, in_process: bool, workers: int | None, show: bool):
    """The study's progress bar (`study.sweep.progress.StudyProgress`): its analyses and the FE
    jobs they read, with their estimated costs, on the workers that run them."""
    from study import estimate
    from study.inputs.gearsetup import gear_setups
    from study.sweep import cost
    from study.sweep.bodies import compute_body, fe_jobs
    from study.sweep.progress import COMPILE_S, START_S, StudyProgress
    costs = cost.progress_seconds(tasks) if show else {t.key: 1.0 for t in tasks}
    fe_costs, first_reader = {}, {}
    for t in tasks if show else ():
        for fe_key, func, args in fe_jobs(t.scene):
            if fe_key not in fe_costs:
                # a compliance body loads every tooth at 8 profile points: about 1.5 spring maps
                if func is compute_body:
                    fe_costs[fe_key] = 1.5 * estimate.body_seconds(gear_setups(args[0])[args[1] - 1])
                else:       # a spring map: its load cases, one a tooth (a solid reference loads one)
                    setup, teeth = args[0], args[1]
                    share = 1.0 if teeth is None else max(0.1, len(teeth) / setup.teeth)
                    fe_costs[fe_key] = share * estimate.body_seconds(setup)
                first_reader.setdefault(t.key, []).append(fe_key)
    coupled = any(t.scene.coupling_model != "none" for t in tasks if t.outputs.dynamic) if tasks else None
    startup = (0.0 if in_process else START_S) + (0.0 if cluster.kernels_cached(coupled) else COMPILE_S)
    parallel = 1 if in_process else (workers or os.cpu_count() or 1)
    return StudyProgress(title, points, fe_costs, costs, parallel, startup, show,
                         fe_in_tasks=first_reader if in_process else None)


@dataclass
class SweepResult:
    """What `run_sweep` did: the study archive and how its tasks were obtained (a task is one
    point's dynamic run (with its modal outputs), or the static analysis shared by the points
    that differ only in ``dynamic.*``: `study.sweep.tasks`)."""
    dataset: xr.Dataset
    computed: int        # tasks computed by this call
    reused: int          # finished tasks found on disk (or in the complete archive)
    invalid: int         # invalid combinations (points recorded, not computed)
    pending: int         # tasks still missing (lost)
    wall_time: float     # s
    points: int = 0      # points of the study


def run_sweep(study: Study, output: str | Path, workers: int | None = None, scheduler: str | None = None,
              progress: bool = True, keep_parts: bool = False, max_time: float | None = None) -> SweepResult:
    """Compute the study's missing tasks, store each as it arrives, write the archive atomically.

    ``workers=0``: in this process; None: one dask worker per core; ``scheduler``: an existing
    dask cluster. The part files are removed once the archive holds every point (unless
    ``keep_parts``). ``max_time`` [s]: refuse (`study.errors.BudgetError`, before any work) a
    study too large to list or whose missing tasks are estimated to take longer in all
    (`study.sweep.cost.sweep_estimate`, CPU seconds summed over the tasks). The returned
    SweepResult has ``.dataset`` (the archive as written, its curves read from the file when
    used), ``.computed``, ``.reused``, ``.invalid``, ``.pending`` and ``.wall_time`` [s]. Finished
    points are kept on disk, so the same call after an interruption computes only the missing
    ones. Worker processes import the calling script again: a script needs
    ``if __name__ == "__main__":``.
    """
    from study import estimate
    from study.archive.netcdf import write_netcdf
    from study.sweep import cost

    check_argument(isinstance(study, Study), "run_sweep", "study", "a Study (study.make_study(scene, grid={...}) or "
                   "study.load_study(path or name))", study)
    check_argument(is_path(output), "run_sweep", "output", "the archive's path ending in .nc (str or os.PathLike)", output)
    workers = checked_workers("run_sweep", workers)
    check_argument(scheduler is None or isinstance(scheduler, str), "run_sweep", "scheduler",
                   "a dask scheduler address such as 'tcp://host:8786', or None", scheduler)
    progress, keep_parts = bool(progress), bool(keep_parts)
    t0 = time.perf_counter()
    cost.check_study_size(study, max_time)
    points = check_points(study)
    out = study.outputs
    n_invalid = sum(p.scene is None for p in points)
    tasks, of_point = plan(study, points)
    done = complete_archive(study, points, output)
    if done is not None:
        return SweepResult(done, 0, len(tasks), n_invalid, 0, time.perf_counter() - t0, len(points))
    store = PartStore(parts_folder(output))
    results, todo = {}, {}
    for key, task in tasks.items():
        found = store.get(key)
        if found is not None:
            results[key] = without_curves(found)
        else:
            todo[key] = task.scene
    reused = len(results)
    if max_time is not None and todo:
        estimate.check_time(cost.sweep_estimate([tasks[k] for k in todo]), max_time)
    lost = {}
    how = _Execution(workers, scheduler, progress)
    todo = by_model(todo) if how.in_process else interleave(todo)
    if todo:
        lost = _compute(study.title, todo, tasks, of_point, store, how, results)
    per_point, lost_points = _point_records(points, of_point, results, lost, out)
    ds = study_dataset(study, points, per_point, read=store.get, lost=lost_points)
    ds.attrs["plausibility_warnings"] = sweep_warnings(points, out, progress)
    if out.static or out.dynamic or out.modes:
        from study.scene_model import study_damping_conversion
        ds.attrs["damping_conversion"] = study_damping_conversion(p.scene for p in points)
    import dask
    with dask.config.set(scheduler="synchronous"):   # the curves are read from the part files here, block by block
        write_netcdf(ds, output)
    if not lost and not keep_parts:
        store.clear()
    return SweepResult(open_archive(output), len(todo) - len(lost), reused, n_invalid, len(lost),
                       time.perf_counter() - t0, len(points))


@dataclass(frozen=True)
class _Execution:
    """Where a sweep's tasks run: ``workers`` dask processes (0: this process; None: one per
    core) or an existing ``scheduler``; ``progress``: show the bar."""
    workers: int | None
    scheduler: str | None
    progress: bool

    @property
    def in_process(self) -> bool:
        return self.workers == 0 and not self.scheduler


def _compute(title: str, todo: dict, tasks: dict, of_point: dict, store: PartStore, how: _Execution,
             results: dict) -> dict:
    """Compute the tasks ``todo`` ({key: scene}) of ``tasks`` (`study.sweep.tasks.plan`), store
    each as it arrives and keep its record without curves in ``results``; the progress bar
    counts points (``of_point``: point index -> its task keys; a point is done when all its
    tasks are, a task may serve many points). Returns the tasks dask lost {key: cause}."""
    lost = {}
    outs = {k: tasks[k].outputs for k in todo}
    run = _in_process(todo, outs) if how.in_process else with_dask(todo, outs, how.scheduler, how.workers,
                                                                   store.folder)
    waiting = {idx: {k for k in keys if k in todo} for idx, keys in of_point.items()}
    waiting = {idx: w for idx, w in waiting.items() if w}
    users: dict[str, list] = {}
    for idx, w in waiting.items():
        for k in w:
            users.setdefault(k, []).append(idx)
    with contextlib.closing(run), study_progress(title, len(waiting), [tasks[k] for k in todo], how.in_process,
                                                 how.workers, how.progress) as bar, quiet_on_interrupt():
        for key, res in run:
            if res.get("fe_done"):
                bar.fe_done(key)
                continue
            if "lost" in res:
                lost[key] = res["lost"]
            else:
                if not res.pop("stored", False):      # (a batch's worker stored it as it finished)
                    store.put(key, res)
                results[key] = without_curves(res)
            finished = 0
            for idx in users.get(key, ()):
                waiting[idx].discard(key)
                finished += not waiting[idx]
            bar.task_done(key, res.get("wall_time"), finished)
    return lost


def _point_records(points: list[Point], of_point: dict, results: dict, lost: dict, outputs: Outputs):
    """({point index: its record}, {point index: why it is pending}) from the tasks' records:
    an invalid point's record says so; a point whose tasks dask lost is pending, with their
    causes."""
    shared = Counter(k for keys in of_point.values() for k in keys)
    per_point = {p.index: invalid_result(p, outputs) for p in points if p.scene is None}
    lost_points = {}
    for idx, keys in of_point.items():
        r = point_result(keys, results, shared)
        if r is not None:
            per_point[idx] = r
        elif causes := [lost[k] for k in keys if k in lost]:
            lost_points[idx] = "; ".join(dict.fromkeys(causes))
    return per_point, lost_points


def sweep_warnings(points: list[Point], outputs: Outputs, show: bool) -> str:
    """The plausibility warnings of the study's points (`study.plausibility.scene_warnings`),
    each once with the number of points it concerns; printed on stderr when ``show``."""
    from study.plausibility import report_warnings, scene_warnings
    counts = Counter(w for p in points if p.scene is not None for w in scene_warnings(p.scene)
                     if outputs.dynamic or not w.startswith("dynamic."))
    return report_warnings([f"{w} ({n} of {len(points)} points)" for w, n in counts.items()], show)

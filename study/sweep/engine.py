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

Execution: ``workers=0`` runs in this process (debugging, tests); otherwise a dask
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

import asyncio
import contextlib
import dataclasses
import itertools
import json
import logging
import math
import os
import pickle
import shutil
import sys
import time
import traceback
import uuid
import warnings
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import xarray as xr

from study.errors import BudgetError, check_argument, checked_workers, is_path
from study.scene import Scene, SceneError
from study.sweep.archive import study_dataset, study_key
from study.sweep.grid import Point, Study, check_points
from study.sweep.outputs import CURVES, Outputs, analysis_of, stages_of
from study.sweep.tasks import plan, point_result

WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


# ---------------------------------------------------------------- one point

def run_point(scene: Scene | dict | str, outputs: Outputs) -> dict:
    """Run one scene (a Scene, scene data or TOML text) for ``outputs``; never raises.

    Returns ``{"status", "message", "wall_time" [s], "scalars": {name: value},
    "curves": {name: (axis name, axis values, axis attrs, values, attrs)}}``; scalars of an
    analysis that failed are NaN. The run is not assembled into a run archive
    (`study.run.run_fields`: its variables only, without the attributes and per-gear
    variables the outputs do not read); its numbers are read as from the archive
    (`point_values`).
    """
    from study.plan import RunOptions
    from study.run import run_fields
    from study.scene import loads_scene, scene_from_dict

    t0 = time.perf_counter()
    scalars = {k: math.nan for k in outputs.scalars}
    curves: dict = {}
    status, message = "ok", "ok"
    try:
        if isinstance(scene, dict):
            scene = scene_from_dict(scene)
        elif isinstance(scene, str):
            scene = loads_scene(scene)
        if outputs.static or outputs.dynamic or outputs.modes:
            # the sweep warns once; a body's points share its model
            run = run_fields(scene, stages_of(outputs), RunOptions(warn=False, keep_model=True, archive=False))
        else:   # geometry (and root stress) only: no model, no solve
            from study.inputs.springs import lightening_dataset
            run = lightening_dataset(scene, stress=outputs.fe)
        status, message, scalars, curves = point_values(run, outputs)
    except (SceneError, BudgetError) as e:
        status, message = "invalid", str(e)
    except Exception as e:  # noqa: BLE001 - a point must never stop the sweep
        from solver.geometry import GeometryError
        from solver.mbs.dynamics import DivergenceError
        if isinstance(e, DivergenceError):
            status, message = "diverged", str(e)
        elif isinstance(e, GeometryError):
            status, message = "invalid", f"{e.field}: {e.reason}"
        else:
            status = "failed"
            where = traceback.extract_tb(e.__traceback__)[-1]
            message = f"{type(e).__name__}: {e} ({Path(where.filename).name}:{where.lineno})"
    return {"status": status, "message": message, "wall_time": time.perf_counter() - t0,
            "scalars": scalars, "curves": curves}


def point_values(run, outputs: Outputs) -> tuple[str, str, dict, dict]:
    """(status, message, scalars, curves) of a point from its run: a run archive (xarray.Dataset)
    or its variables (`study.run.RunFields`), read alike. The scalars are
    `study.archive.summary.summarize`'s; those of an analysis whose numbers are not to be
    trusted (statics not converged, a dynamic run that stopped) are NaN and its curves left out."""
    from study.archive.summary import summarize
    status, message = "ok", "ok"
    s = summarize(run)
    bad = set()          # analyses whose numbers are not to be trusted
    problems = []
    if outputs.static:
        conv = run["ste_converged"].values
        if not conv.all():
            bad.add("static")
            problems.append(f"static equilibrium not reached at {int((conv == 0).sum())} of {conv.size} angles")
    dyn_status = run.attrs.get("dynamic_status", "ok") if outputs.dynamic else "ok"
    if dyn_status.startswith("inaccurate"):
        status, message = "inaccurate", dyn_status
    elif dyn_status != "ok":
        bad.add("dynamic")
        problems.append(f"dynamic run stopped: {dyn_status}")
    if problems:
        status, message = "diverged", "; ".join(problems)
    scalars = {k: float(s.get(k, math.nan)) if analysis_of(k) not in bad else math.nan for k in outputs.scalars}
    curves = {}
    for name in outputs.curves:
        if name in run and analysis_of(name) not in bad:
            var = run[name]
            axis = var.dims[0]
            curves[name] = (axis, run[axis].values.copy(), dict(run[axis].attrs), var.values.copy(), dict(var.attrs))
    return status, message, scalars, curves


def invalid_result(point: Point, outputs: Outputs) -> dict:
    """The record of a point whose combination of values is invalid (nothing computed)."""
    return {"status": "invalid", "message": point.error, "wall_time": 0.0,
            "scalars": {k: math.nan for k in outputs.scalars}, "curves": {}}


# ---------------------------------------------------------------- finished tasks on disk

class PartStore:
    """Finished tasks of a study, one pickle per task key, each written atomically."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)

    def get(self, key: str) -> dict | None:
        try:
            with open(self.folder / f"{key}.pkl", "rb") as f:
                return pickle.load(f)
        except FileNotFoundError:
            return None
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ValueError):
            return None  # unreadable record: the point is computed again

    def put(self, key: str, result: dict) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        tmp = self.folder / f".{key}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp"
        with open(tmp, "wb") as f:
            pickle.dump(result, f, protocol=pickle.HIGHEST_PROTOCOL)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.folder / f"{key}.pkl")

    def clear(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def parts_folder(output: str | Path) -> Path:
    output = Path(output)
    return output.with_name(f".{output.name}.parts")


# ---------------------------------------------------------------- executors

CONNECT_TIMEOUT_S = 10.0   # s, to reach an existing scheduler (dask's default retries for 30 s)


class SchedulerUnreachable(ConnectionError):
    """The scheduler given by address did not answer."""


class MainGuardMissing(SystemExit):
    """A script without ``if __name__ == "__main__":`` asked for worker processes, which would
    run it again on import: the script stops at once with one line saying what to add."""


def _has_main_guard(source: str) -> bool:
    """True when module source has a top-level ``if __name__ == "__main__":``."""
    import ast
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return True          # not ours to judge
    for node in tree.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Compare):
            names = [node.test.left, *node.test.comparators]
            if any(isinstance(n, ast.Name) and n.id == "__name__" for n in names) and \
                    any(isinstance(n, ast.Constant) and n.value == "__main__" for n in names):
                return True
    return False


def check_main_guard() -> None:
    """Stop a script that starts worker processes without a main guard, before any is started.

    dask's LocalCluster starts its workers with multiprocessing's 'spawn', which imports the
    main script again in every worker: a script that calls `run_sweep` at module level would
    start a cluster from each worker (dask then fails with pages of tracebacks about the
    bootstrapping phase). An interactive session or ``python -c`` has no script to import."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if not path or not str(path).endswith(".py") or getattr(main, "__name__", "") != "__main__":
        return
    try:
        source = Path(path).read_text()
    except (OSError, UnicodeDecodeError):
        return
    if not _has_main_guard(source):
        raise MainGuardMissing(
            f"lightgear: run_sweep with worker processes imports {Path(path).name} again in each worker: put the "
            f"script's work under `if __name__ == \"__main__\":` (or pass workers=0 to run in this process)")


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None):
    """A dask Client: to ``scheduler`` (SchedulerUnreachable after CONNECT_TIMEOUT_S), or to a
    LocalCluster started (and always closed) here."""
    from distributed import Client, LocalCluster
    if scheduler:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as e:
            raise SchedulerUnreachable(f"no dask scheduler answered at {scheduler} within {CONNECT_TIMEOUT_S:g} s "
                                       f"({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})") from None
        with client:
            yield client
        return
    if workers is not None and workers < 0:
        raise ValueError(f"workers: must be >= 0 (0 runs in this process), got {workers}")
    check_main_guard()
    n = workers or os.cpu_count() or 1
    # the scheduler's HTTP endpoint (health, metrics; no dashboard) moves to a free port when
    # 8787 is taken, another user's cluster say: not worth a warning
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Port 8787 is already in use", category=UserWarning)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.ERROR, env=dict(WORKER_ENV))
    with cluster, Client(cluster) as client:
        client.register_plugin(stop_kernels_plugin(), name="lightgear-stop-kernels")
        yield client


@contextlib.contextmanager
def local_cluster(workers: int | None = None):
    """A dask LocalCluster for several sweeps in a row, as a context manager that yields its
    scheduler address (give it to `run_sweep` as ``scheduler``); ``workers``: processes (None:
    one per core; 0: yields None, the sweeps then run in this process)."""
    workers = checked_workers("local_cluster", workers)
    if workers == 0:
        yield None
        return
    check_main_guard()
    with dask_client(None, workers) as client:
        yield client.scheduler.address


def stop_kernels_plugin():
    """Dask worker plugin: a worker of the LocalCluster that closes (its client stopped by
    Ctrl-C or SIGTERM) stops the kernel it runs (`solver.mbs.interrupt.stop_all`) instead of
    finishing the point first. (Not installed on an existing cluster: its workers outlive the
    client, and the scheduler drops the client's tasks.)"""
    from distributed import WorkerPlugin

    class StopKernels(WorkerPlugin):
        def teardown(self, worker):
            import gc

            import study.sweep.engine as engine
            from solver.mbs import interrupt
            engine._CLOSING = True      # before the kernels stop: a stopped point is not a result to store
            interrupt.stop_all()
            gc.freeze()     # the process ends: no final collection of every object (seconds)
    return StopKernels()


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


def _in_process(todo: dict, outputs: dict):
    for key, scene in todo.items():
        yield key, run_point(scene, outputs[key])


_CLOSING = False     # set in a worker whose cluster closes (`stop_kernels_plugin`): its results are not stored


def run_after(batch: tuple, *maps, parts: str | None = None) -> list:
    """[(key, `run_point` result)] of a batch of tasks ((key, scene, outputs) each,
    `study.sweep.tasks.batches`), once the FE maps they read (``maps``: their futures'
    results) are cached.

    ``parts``: the study's part folder, on a disk the client shares (a local cluster): each
    task's result is stored there as soon as it is finished (`PartStore`; the result comes back
    marked ``stored``), so that a batch cut short (Ctrl-C, its worker lost) keeps its finished
    tasks for the resume, and dask's retry of a batch whose worker died computes only the tasks
    it had not finished. A task that ends while the worker is closing is not stored: its kernel
    was stopped (`solver.mbs.interrupt`), its record says so, not what the point gives."""
    store = PartStore(parts) if parts is not None else None
    out = []
    for key, scene, outputs in batch:
        result = store.get(key) if store is not None else None     # (stored by a first try of the batch)
        if result is not None:
            out.append((key, {**result, "stored": True}))
            continue
        result = run_point(scene, outputs)
        if store is not None and not _CLOSING:
            store.put(key, result)
            result = {**result, "stored": True}
        out.append((key, result))
    return out


def kernel_cache_folder() -> Path:
    """Where numba keeps the compiled kernels of this checkout (`solver.mbs.kernels`: a folder
    per kernel-source hash; in it numba files a source folder's kernels under '<folder
    name>_<SHA-1 of its absolute path>', so another checkout's kernels are elsewhere)."""
    import hashlib

    import numba

    from solver.mbs import kernels
    source = Path(kernels.__file__).resolve().parent
    top = Path(numba.config.CACHE_DIR or source / "__pycache__") / f"kernels-{kernels.KERNELS_FINGERPRINT}"
    return top / f"{source.name}_{hashlib.sha1(str(source).encode()).hexdigest()}"


def kernels_cached(coupled: bool | None = None) -> bool:
    """True when this machine's numba disk cache holds compiled kernels of the current sources
    and, for ``coupled`` True or False (the study's model couples the teeth through the bodies
    or not), the explicit time stepping of that model: a cache filled by runs of the other
    model lacks it, and every worker would then compile it at the same time."""
    folder = kernel_cache_folder()
    if not (folder.is_dir() and any(folder.glob("*.nbi"))):
        return False
    if coupled is None:
        return True
    if coupled:
        from solver.mbs.kernels.explicit_coupled import verlet_coupled as stepping
    else:
        from solver.mbs.kernels.explicit import verlet as stepping
    return (folder / stepping._cache._cache_file._index_name).exists()


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


def _with_dask(todo: dict, outputs: dict, scheduler: str | None, workers: int | None, parts: Path | None = None):
    from distributed import as_completed

    from study.sweep.bodies import compute_body, fe_jobs, job_rim
    from study.sweep.tasks import Task, batches
    with dask_client(scheduler, workers) as client:
        # each FE map or body once, ahead of the tasks (higher priority; the bodies, dearest,
        # first), and each task after the FE it reads
        dynamic = [todo[k] for k in todo if outputs[k].dynamic]
        coupled = any(sc.coupling_model != "none" for sc in dynamic) if dynamic else None
        pilot = pilot_tasks(todo, outputs) if scheduler is None and not kernels_cached(coupled) else ()
        jobs, reads = {}, {}            # FE job key -> (function, arguments, priority); task key -> its jobs
        for key in sorted(todo, key=lambda k: k not in pilot):      # the pilot's jobs first
            for fe_key, func, args in fe_jobs(todo[key]):
                if fe_key not in jobs:
                    jobs[fe_key] = (func, args, 3 if key in pilot else 2 if func is compute_body else 1)
                reads.setdefault(key, []).append(fe_key)
        maps = {}
        firsts, rest = rims_first(jobs, job_rim)
        for fe_key, func, args, priority, leader in [*((*j[:3], max(j[3], 3), j[4]) for j in firsts), *rest]:
            # (each rim's first job goes with the pilot's FE: the rim's other jobs wait for it)
            maps[fe_key] = client.submit(func, *args, *([maps[leader]] if leader else ()), key=f"lightgear-fe-{fe_key}",
                                         pure=False, priority=priority)
        after = {key: [maps[k] for k in fe_keys] for key, fe_keys in reads.items()}
        futures = {}

        def stored_here(keys):      # a local cluster's workers store a batch's tasks as each finishes (`run_after`)
            return str(parts) if parts is not None and scheduler is None and len(keys) > 1 else None
        if pilot:       # compiles the kernels into the disk cache; the other tasks load them
            waits = list(dict.fromkeys(f for k in pilot for f in after.get(k, ())))
            first = client.submit(run_after, tuple((k, todo[k], outputs[k]) for k in pilot), *waits,
                                  key=f"lightgear-pilot-{pilot[0]}", pure=False, priority=3, parts=stored_here(pilot))
            futures[first] = pilot
            for key in todo:
                after.setdefault(key, []).append(first)
        # the rest in batches of one model, dearest first (dask starts ready tasks in the order
        # they were submitted)
        n_workers = len(client.scheduler_info().get("workers", ())) or workers or os.cpu_count() or 1
        for batch in batches([Task(k, todo[k], outputs[k]) for k in todo if k not in pilot], n_workers):
            keys = tuple(t.key for t in batch)
            waits = list(dict.fromkeys(f for k in keys for f in after.get(k, ())))
            name = f"lightgear-task-{keys[0]}" if len(keys) == 1 else f"lightgear-tasks-{keys[0]}-{len(keys)}"
            fut = client.submit(run_after, tuple((t.key, t.scene, t.outputs) for t in batch), *waits, key=name,
                                pure=False, parts=stored_here(keys))
            futures[fut] = keys
        fe_done = {f: k for k, f in maps.items()}      # said as each ends (the progress bar counts them)
        del maps, after     # the tasks hold the maps' futures now; dask forgets each map once its tasks ran
        try:
            for fut in as_completed([*futures, *fe_done]):
                if fut in fe_done:
                    key = fe_done.pop(fut)
                    fut.release()
                    yield key, {"fe_done": True}
                    continue
                keys = futures.pop(fut)
                try:
                    done = fut.result()
                except (Exception, asyncio.CancelledError) as e:  # noqa: BLE001 - lost task (killed worker...): stays pending
                    done = [(key, {"lost": lost_cause(e)}) for key in keys]
                fut.release()       # the worker drops the result: its memory does not grow with the study
                yield from done
        finally:
            client.cancel(list(futures))
            fe_done.clear()


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
    startup = (0.0 if in_process else START_S) + (0.0 if kernels_cached(coupled) else COMPILE_S)
    parallel = 1 if in_process else (workers or os.cpu_count() or 1)
    return StudyProgress(title, points, fe_costs, costs, parallel, startup, show,
                         fe_in_tasks=first_reader if in_process else None)


@contextlib.contextmanager
def quiet_on_interrupt():
    """Within: a Ctrl-C (KeyboardInterrupt) first silences dask's loggers, then goes on: the
    cluster then closes under the running tasks, and its connection errors (CommClosedError
    tracebacks) are no news to the user, who gets the one line of the command."""
    try:
        yield
    except KeyboardInterrupt:
        import logging
        for name in ("distributed", "tornado", "asyncio"):
            logging.getLogger(name).setLevel(logging.CRITICAL + 1)
        raise


def lost_cause(e: BaseException) -> str:
    """One line on why dask gave no result for a point (a worker died running it: KilledWorker)."""
    text = str(e).strip().splitlines()[0] if str(e).strip() else ""
    return f"{type(e).__name__}: {text[:300]}" if text else type(e).__name__


# ---------------------------------------------------------------- the sweep

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
    done = _complete_archive(study, points, output)
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
    todo = interleave(todo)
    if todo:
        outs = {k: tasks[k].outputs for k in todo}
        run = _in_process(todo, outs) if workers == 0 and not scheduler else _with_dask(todo, outs, scheduler, workers, store.folder)
        # the bar counts points (a point is done when all its tasks are); a task may serve many points
        waiting = {idx: {k for k in keys if k in todo} for idx, keys in of_point.items()}
        waiting = {idx: w for idx, w in waiting.items() if w}
        users: dict[str, list] = {}
        for idx, w in waiting.items():
            for k in w:
                users.setdefault(k, []).append(idx)
        in_process = workers == 0 and not scheduler
        with contextlib.closing(run), study_progress(study.title, len(waiting), [tasks[k] for k in todo], in_process,
                                                     workers, progress) as bar, quiet_on_interrupt():
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
    shared = Counter(k for keys in of_point.values() for k in keys)
    per_point = {p.index: invalid_result(p, out) for p in points if p.scene is None}
    lost_points = {}
    for idx, keys in of_point.items():
        r = point_result(keys, results, shared)
        if r is not None:
            per_point[idx] = r
        elif causes := [lost[k] for k in keys if k in lost]:
            lost_points[idx] = "; ".join(dict.fromkeys(causes))
    ds = study_dataset(study, points, per_point, read=store.get, lost=lost_points)
    ds.attrs["plausibility_warnings"] = sweep_warnings(points, out, progress)
    import dask
    with dask.config.set(scheduler="synchronous"):   # the curves are read from the part files here, block by block
        write_netcdf(ds, output)
    if not lost and not keep_parts:
        store.clear()
    return SweepResult(open_archive(output), len(todo) - len(lost), reused, n_invalid, len(lost),
                       time.perf_counter() - t0, len(points))


def sweep_warnings(points: list[Point], outputs: Outputs, show: bool) -> str:
    """The plausibility warnings of the study's points (`study.plausibility.scene_warnings`),
    each once with the number of points it concerns; printed on stderr when ``show``."""
    from study.plausibility import report_warnings, scene_warnings
    counts = Counter(w for p in points if p.scene is not None for w in scene_warnings(p.scene)
                     if outputs.dynamic or not w.startswith("dynamic."))
    return report_warnings([f"{w} ({n} of {len(points)} points)" for w, n in counts.items()], show)


def without_curves(result: dict) -> dict:
    """A task's record without its curves, only their names (they stay in its part file until
    the merge)."""
    out = {k: v for k, v in result.items() if k != "curves"}
    out["curve_names"] = tuple(result.get("curves", ()))
    return out


def open_archive(path) -> xr.Dataset:
    """A study archive with its per-point variables in memory; the curves (study dimensions x
    their axis: the bulk of a large study) are read from the file when used."""
    ds = xr.open_dataset(path, engine="netcdf4")
    for name, var in ds.data_vars.items():
        if name not in CURVES:
            var.load()
    return ds


def _complete_archive(study: Study, points: list[Point], output) -> xr.Dataset | None:
    """The archive at ``output`` when it already holds every point of this very study."""
    if not Path(output).is_file() or parts_folder(output).exists():
        return None
    try:
        ds = open_archive(output)
    except (OSError, KeyError, ValueError):
        return None
    if ds.attrs.get("study_key") == study_key(study, points) and "status" in ds and not (ds["status"].values == 0).any():
        return ds
    ds.close()
    return None

"""The sweep on dask.distributed: the client (a `LocalCluster` started and always closed here,
or an existing scheduler), the worker side (`run_after`: a batch of tasks once the FE maps they
read are cached, each stored as it finishes; `stop_kernels_plugin`), whether the kernels are
compiled already (`kernels_cached`), and the submission of the FE jobs and the tasks
(`with_dask`), the order of which is `study.sweep.schedule`'s.
"""
from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import sys
import warnings
from pathlib import Path

from study.errors import checked_workers
from study.sweep.point import run_point
from study.sweep.schedule import pilot_tasks, rims_first
from study.sweep.store import PartStore

WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


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
    # the workers' own log lines are connection news (a heartbeat that found the scheduler gone
    # while a stopped sweep closes it, on a loaded machine): what a point did, failed or lost
    # is recorded from its future, with its cause, so nothing below CRITICAL goes to the terminal
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Port 8787 is already in use", category=UserWarning)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.CRITICAL, env=dict(WORKER_ENV))
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

            import study.sweep.cluster as cluster
            from solver.mbs import interrupt
            cluster._CLOSING = True      # before the kernels stop: a stopped point is not a result to store
            interrupt.stop_all()
            gc.freeze()     # the process ends: no final collection of every object (seconds)
    return StopKernels()


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

    from solver.mbs import kernels
    source = Path(kernels.__file__).resolve().parent
    top = Path(kernels.cache_root()) / f"kernels-{kernels.KERNELS_FINGERPRINT}"
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


def with_dask(todo: dict, outputs: dict, scheduler: str | None, workers: int | None, parts: Path | None = None):
    from distributed import as_completed

    from study.stand_in import compile_kernels
    from study.sweep.bodies import compute_body, fe_jobs, job_rim
    from study.sweep.tasks import Task, batches
    with dask_client(scheduler, workers) as client:
        # each FE map or body once, ahead of the tasks (higher priority; the bodies, dearest,
        # first), and each task after the FE it reads
        dynamic = [todo[k] for k in todo if outputs[k].dynamic]
        coupled = any(sc.coupling_model != "none" for sc in dynamic) if dynamic else None
        pilot = pilot_tasks(todo, outputs) if scheduler is None and not kernels_cached(coupled) else ()
        if pilot:
            # the pilot's entry kernels compiled from a stand-in of its scenes first, without
            # their FE (`study.stand_in`): the compile overlaps the rims and bodies on the other
            # workers, and the pilot, once its FE is there, loads them from the disk cache
            ahead = client.submit(compile_kernels, tuple(todo[k] for k in pilot), key=f"lightgear-compile-{pilot[0]}",
                                  pure=False, priority=4)
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
            waits = [ahead, *dict.fromkeys(f for k in pilot for f in after.get(k, ()))]
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

"""Stopping a compiled loop on Ctrl-C (SIGINT), SIGTERM or a closing dask worker.

A numba loop never returns to Python while it runs, and Python runs its signal handlers only
between bytecodes, in the main thread: a loop called directly would let Ctrl-C wait until it
ends (minutes, hours). So `call` runs the kernel in a helper thread (the loops release the
GIL: ``nogil=True``) while the calling thread waits on it in short polls, in which a
KeyboardInterrupt is delivered at once. The caller then sets the kernel's abort flag (one
element of a float control array the kernel reads: `layout` ABORT in the time-stepping loops,
S_ABORT in the static sweep), the kernel returns at the end of its step (stepping loops) or
before its next driver angle (statics), and the KeyboardInterrupt goes on up: nothing is half-written, the
caller's ``finally`` blocks run, and the command line exits 130.

A dask worker has no Ctrl-C of its own: when its cluster closes, `stop_all` (called from the
worker plugin `study.sweep.cluster.stop_kernels_plugin`) aborts the kernels running in that process and
those started after, which then raise `Interrupted`, so the worker closes at once instead of
waiting for the point to finish.
"""
from __future__ import annotations

import threading

POLL_S = 0.1                 # how often the waiting thread wakes [s]

_lock = threading.Lock()
_running: list = []          # (flag array, index) of the kernels running now
_stopping = threading.Event()


class Interrupted(RuntimeError):
    """A kernel stopped because its process is being stopped (`stop_all`: a closing dask
    worker). An ordinary exception, not a KeyboardInterrupt: the worker's task ends as a
    failure that nobody collects, and the worker's event loop closes normally."""


def stop_all() -> None:
    """Abort every kernel running in this process and every one started later."""
    _stopping.set()
    with _lock:
        for flag, index in _running:
            flag[index] = 1.0


def call(kernel, args: tuple, flag, index: int, poll=None, period_s: float = 0.25):
    """``kernel(*args)``, stoppable: run in a helper thread while this one waits.

    ``flag[index]`` (a float array the kernel reads) is set to 1 on a KeyboardInterrupt in
    this thread or on `stop_all`; the kernel then returns within a step and the
    interrupt is raised again (`Interrupted` after `stop_all`). ``poll``: None, or a
    callable (no arguments) called about every ``period_s`` [s] while the kernel runs and
    once when it ends (a progress bar's update). An exception of the kernel is raised in this thread.
    A kernel that a second process is compiling (`solver.precompile`) is waited for first.
    """
    if _stopping.is_set():
        raise Interrupted("stopped: the process is closing")
    from solver import precompile
    precompile.ready(kernel)        # (compiled by a second process: wait for it rather than compile it here)
    ret, err = [], []

    def target():
        try:
            ret.append(kernel(*args))
        except BaseException as e:  # noqa: BLE001 - handed to the waiting thread
            err.append(e)
    entry = (flag, index)
    with _lock:
        _running.append(entry)
    th = threading.Thread(target=target, name="lightgear-kernel", daemon=True)
    try:
        th.start()
        waited = 0.0
        while th.is_alive():
            th.join(POLL_S)
            waited += POLL_S
            if poll is not None and (waited >= period_s or not th.is_alive()):
                waited = 0.0
                poll()      # (and once at the end: a bar reaches its total)
    except BaseException:
        flag[index] = 1.0       # the kernel returns at its next check; wait for it (a second Ctrl-C leaves it)
        th.join()
        raise
    finally:
        with _lock:
            _running.remove(entry)
    if err:
        raise err[0]
    if flag[index] != 0.0:
        raise Interrupted("stopped: the process is closing")
    return ret[0]

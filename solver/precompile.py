"""Kernels compiled into numba's disk cache by a second process while this one works.

A process whose disk cache lacks the kernels it will call hands the dearest of them (given by
their argument types, `study.stand_in`) to a child process (`Precompiler`), which compiles
them one after the other into the cache on another core while the parent goes on (FE,
statics). Before the first call of an entry kernel (`ready`, from `solver.mbs.interrupt.call`:
the static sweep and the stepping loops) the parent asks where the child stands with it:
done, the call loads it from the disk cache; being compiled, the parent waits for it instead
of compiling it a second time; not begun yet, the child is told to skip it and the parent
compiles it itself; the child gone (failed, killed), the parent compiles as it would without
one. Nothing changes in what is computed: the kernels are the same machine code, from the
cache.

The child ends when its list is done, or at once when its standard input closes: the parent
closes it when it leaves `precompiling` (normally, on an error, on Ctrl-C or SIGTERM), and the
operating system closes it when the parent dies, so that no child outlives its parent.

Protocol (lines): parent -> child, first the jobs [(name, module, qualname, argument types)],
pickled and base64-encoded, then ``skip NAME`` for each kernel the parent compiles itself;
child -> parent: ``start NAME``, ``done NAME`` or ``fail NAME`` for each kernel.

The child is started only when a core is idle (`spare_core`): on a machine busy with other
work it would compile on the same cores, and the duplicated work of the inner kernels both
processes compile (a few seconds of CPU) would make the run slower, not faster.
"""
from __future__ import annotations

import base64
import contextlib
import os
import pickle
import subprocess
import sys
import threading
from pathlib import Path

HELPER = [sys.executable, "-m", "solver.precompile"]      # the child's command (the tests replace it)
CLOSE_WAIT_S = 2.0      # s, how long a child told to stop may take before it is killed
POLL_S = 0.1            # s, how often a waiting parent wakes (Ctrl-C is delivered between waits)
LOADAVG = Path("/proc/loadavg")     # Linux: its 4th field, processes ready to run / all

_active: list = []      # the `Precompiler`s of this process now


def kernel_name(kernel) -> str:
    """A dispatcher's name in the protocol: module.qualname of its Python function."""
    f = kernel.py_func
    return f"{f.__module__}.{f.__qualname__}"


def cached(kernel, argtypes: tuple) -> bool:
    """True when numba's disk cache holds ``kernel`` compiled for ``argtypes`` (numba types),
    read from the kernel's cache index without loading or compiling anything."""
    cache = getattr(kernel, "_cache", None)
    try:
        key = cache._index_key(tuple(argtypes), kernel.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except (AttributeError, OSError, EOFError, pickle.UnpicklingError):
        return False        # no disk cache (or one that cannot be read): counts as not compiled


def spare_core() -> bool:
    """True when a core is idle now: fewer processes ready to run (Linux's count in
    /proc/loadavg, this one included; the least of three looks 10 ms apart) than the cores
    this process may run on. On a machine busy with other work a second process would only
    take its share of the same cores: the compile then stays in this process. Elsewhere than
    on Linux: True."""
    import time
    try:
        running = []
        for i in range(3):
            running.append(int(LOADAVG.read_text().split()[3].split("/")[0]))
            if i < 2:
                time.sleep(0.01)
    except (OSError, ValueError, IndexError):
        return True
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return min(running) < cores


def argument_types(kernel, args: tuple) -> tuple:
    """The numba types ``kernel`` is compiled for when called with ``args`` (its dispatcher's
    own typing of each argument)."""
    return tuple(kernel.typeof_pyval(a) for a in args)


class Precompiler:
    """A child process compiling ``jobs`` [(kernel dispatcher, argument types)] in that order
    into the disk cache, and what the parent knows of it (see the module docstring).
    ``shared``: the kernels of the jobs that the parent's entry kernels call (the contact
    search, which the statics and the time stepping both link): before its first call of any
    kernel of the jobs, the parent waits for those the child is compiling, and loads them from
    the cache when it compiles its caller, instead of compiling them too."""

    def __init__(self, jobs: list, shared=()):
        self.names = [kernel_name(k) for k, _ in jobs]
        self.shared = [n for n in map(kernel_name, shared) if n in self.names]
        self.state = dict.fromkeys(self.names, "queued")      # -> started, done, fail, skipped, gone
        self.waited_s = 0.0
        self._cond = threading.Condition()
        payload = [(kernel_name(k), k.py_func.__module__, k.py_func.__qualname__, tuple(t)) for k, t in jobs]
        root = str(Path(__file__).resolve().parents[1])
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([root, *filter(None, [os.environ.get("PYTHONPATH")])]))
        import numba
        if numba.config.CACHE_DIR:          # (set in this process, the environment's or not)
            env["NUMBA_CACHE_DIR"] = os.path.abspath(numba.config.CACHE_DIR)
        self.proc = subprocess.Popen(HELPER, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     env=env, text=True, bufsize=1)
        self._send(base64.b64encode(pickle.dumps(payload)).decode())
        self._reader = threading.Thread(target=self._read, name="lightgear-precompile", daemon=True)
        self._reader.start()

    def _send(self, line: str) -> None:
        try:
            self.proc.stdin.write(line + "\n")
            self.proc.stdin.flush()
        except (OSError, ValueError):       # the child is gone: the reader says so
            pass

    def _read(self) -> None:
        for line in self.proc.stdout:
            what, _, name = line.strip().partition(" ")
            with self._cond:
                if name in self.state and what in ("start", "done", "fail"):
                    self.state[name] = {"start": "started"}.get(what, what)
                    self._cond.notify_all()
        with self._cond:        # the child ended: what it did not finish, the parent compiles
            for name, st in self.state.items():
                if st in ("queued", "started"):
                    self.state[name] = "gone"
            self._cond.notify_all()

    def ready(self, kernel) -> None:
        """Before this process's first call of ``kernel``: wait while the child compiles it;
        tell the child to skip it when it has not begun it (this process compiles it). The
        shared callees first, alike."""
        name = kernel_name(kernel)
        if name not in self.state:
            return
        for callee in self.shared:
            self._ready(callee)
        self._ready(name)

    def _ready(self, name: str) -> None:
        with self._cond:
            st = self.state.get(name)
            if st == "queued":
                self.state[name] = "skipped"
                self._send(f"skip {name}")
                return
            if st != "started":
                return
            import time
            t0 = time.perf_counter()
            while self.state[name] == "started":
                self._cond.wait(POLL_S)
            self.waited_s += time.perf_counter() - t0

    def close(self) -> None:
        """Stop the child (its standard input closed, then SIGTERM, then SIGKILL) and wait for it."""
        with contextlib.suppress(OSError, ValueError):
            self.proc.stdin.close()
        try:
            self.proc.wait(CLOSE_WAIT_S)
        except subprocess.TimeoutExpired:
            self.proc.terminate()
            try:
                self.proc.wait(CLOSE_WAIT_S)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(CLOSE_WAIT_S)


def ready(kernel) -> None:
    """Before a first call of an entry kernel in this process: see `Precompiler.ready`
    (nothing when no child compiles)."""
    for p in list(_active):
        p.ready(kernel)


@contextlib.contextmanager
def precompiling(jobs: list, shared=()):
    """Within: the kernels of ``jobs`` [(dispatcher, argument types)] not yet in the disk
    cache compiled by a child process (`Precompiler`, with its ``shared`` callees; yields it,
    or None when the cache holds them all, or no core is idle (`spare_core`), and no process was
    started). The child is always stopped on leaving."""
    todo = [(k, t) for k, t in jobs if not cached(k, t)]
    if not todo or not spare_core():
        yield None
        return
    try:
        p = Precompiler(todo, shared)
    except OSError:         # no process could be started: this one compiles
        yield None
        return
    _active.append(p)
    try:
        yield p
    finally:
        _active.remove(p)
        p.close()


# ---------------------------------------------------------------- the child

def _child() -> int:
    import importlib
    jobs = pickle.loads(base64.b64decode(sys.stdin.readline()))
    skip, lock = set(), threading.Lock()

    def listen():           # 'skip NAME' lines; the parent gone or done (end of input): stop at once
        for line in sys.stdin:
            what, _, name = line.strip().partition(" ")
            if what == "skip":
                with lock:
                    skip.add(name)
        sys.stdout.flush()
        os._exit(0)
    threading.Thread(target=listen, daemon=True).start()
    for name, module, qualname, argtypes in jobs:
        with lock:
            if name in skip:
                continue
        print("start", name, flush=True)
        try:
            kernel = importlib.import_module(module)
            for part in qualname.split("."):
                kernel = getattr(kernel, part)
            kernel.compile(tuple(argtypes))
        except Exception:  # noqa: BLE001 - said to the parent, which compiles it itself
            print("fail", name, flush=True)
            continue
        print("done", name, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(_child())

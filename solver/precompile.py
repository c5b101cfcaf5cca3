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

A *shared* kernel (the contact search, which the statics and the stepping loops both link; an
inner kernel of the loop that the parent can compile ahead) is compiled by whichever process
reaches it first, the other waiting for it and loading it from the cache: the child when its
compile of a loop reaches it before the parent's first entry kernel call, else the parent, at
that call (the child, its loop's compile reaching the kernel, then waits for the parent's word).
The child compiles the stepping loop first and the shared kernels within it: with the FE read
from its cache the parent reaches its statics first and compiles them before its static sweep,
so that the two processes compile about as much each (the stepping loop there, the search, a
few of the loop's helpers and the static sweep here) instead of the parent waiting for the
search the child compiled before its loop.

The child ends when its list is done, or at once when its standard input closes: the parent
closes it when it leaves `precompiling` (normally, on an error, on Ctrl-C or SIGTERM), and the
operating system closes it when the parent dies, so that no child outlives its parent.

Protocol (lines): parent -> child, first the jobs ``{"jobs": [(name, module, qualname, argument
types)], "shared": [name]}``, pickled and base64-encoded, then ``skip NAME`` for each kernel
the parent compiles itself, and for a shared one then ``done NAME`` or ``fail NAME`` when its
compile ends; child -> parent: ``start NAME``, ``done NAME`` or ``fail NAME`` for each kernel.

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
    ``shared``: the kernels of the jobs that the parent's entry kernels and the child's other
    jobs both call (the contact search, which the statics and the time stepping both link):
    compiled by whichever process reaches one first, the other loading it from the cache;
    before its first call of any kernel of the jobs, the parent compiles (or waits for) them."""

    def __init__(self, jobs: list, shared=()):
        self.names = [kernel_name(k) for k, _ in jobs]
        self.jobs = {kernel_name(k): (k, tuple(t)) for k, t in jobs}
        self.shared = [n for n in map(kernel_name, shared) if n in self.names]
        self.state = dict.fromkeys(self.names, "queued")      # -> started, done, fail, skipped, gone
        self.waited_s = 0.0
        self.heard: list[str] = []      # the child's lines, in order
        self._cond = threading.Condition()
        payload = {"jobs": [(kernel_name(k), k.py_func.__module__, k.py_func.__qualname__, tuple(t)) for k, t in jobs],
                   "shared": self.shared}
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
                self.heard.append(line.strip())
                # (a kernel this process took over stays its own, whatever the child began)
                if self.state.get(name) not in (None, "skipped") and what in ("start", "done", "fail"):
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
        if st == "queued":
            if name in self.shared:     # compiled here now, and the child (which may reach it) told
                self._compile_shared(name)
            return
        with self._cond:
            if st != "started":
                return
            import time
            t0 = time.perf_counter()
            while self.state[name] == "started":
                self._cond.wait(POLL_S)
            self.waited_s += time.perf_counter() - t0

    def _compile_shared(self, name: str) -> None:
        """Compile the shared kernel ``name`` here (into the cache) and say so to the child,
        which waits for it when its own compile reaches it; on a failure the child compiles
        it (and this process again, at its call)."""
        kernel, types = self.jobs[name]
        try:
            kernel.compile(types)
        except Exception:  # noqa: BLE001 - the call compiles it again and raises what is wrong
            self._send(f"fail {name}")
            return
        self._send(f"done {name}")

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
    given = pickle.loads(base64.b64decode(sys.stdin.readline()))
    jobs, shared = given["jobs"], set(given["shared"])
    skip, theirs, mine = set(), {}, set()       # skip told; shared kernels the parent ended: done/fail
    cond = threading.Condition()

    def listen():           # the parent's lines; the parent gone or done (end of input): stop at once
        for line in sys.stdin:
            what, _, name = line.strip().partition(" ")
            with cond:
                if what == "skip":
                    skip.add(name)
                elif what in ("done", "fail"):
                    theirs[name] = what
                cond.notify_all()
        sys.stdout.flush()
        os._exit(0)
    threading.Thread(target=listen, daemon=True).start()

    def kernel_of(module, qualname):
        kernel = importlib.import_module(module)
        for part in qualname.split("."):
            kernel = getattr(kernel, part)
        return kernel

    def claim(name) -> bool:
        """True: this process compiles the shared kernel ``name`` (said to the parent); False:
        the parent has compiled it (then loaded from the cache)."""
        with cond:
            if name in mine:
                return True
            if name in skip:
                while name not in theirs:
                    cond.wait()
                if theirs[name] == "done":
                    return False
            mine.add(name)
        print("start", name, flush=True)
        return True

    def guarded(name, compile_):
        said = []

        def compile(sig):       # (numba asks a callee's dispatcher for it when it types a call of it)
            if not claim(name) or said:
                return compile_(sig)
            try:
                entry = compile_(sig)
            except Exception:
                said.append(True)
                print("fail", name, flush=True)
                raise
            said.append(True)
            print("done", name, flush=True)
            return entry
        return compile

    for name, module, qualname, _ in jobs:
        if name in shared:
            try:
                kernel = kernel_of(module, qualname)
                kernel.compile = guarded(name, kernel.compile)
            except Exception:  # noqa: BLE001 - left as it is: compiled by whoever calls it
                pass
    for name, module, qualname, argtypes in jobs:
        with cond:
            if name in skip:
                continue
        if name not in shared:
            print("start", name, flush=True)
        try:
            kernel_of(module, qualname).compile(tuple(argtypes))
        except Exception:  # noqa: BLE001 - said to the parent, which compiles it itself
            if name not in shared:
                print("fail", name, flush=True)
            continue
        if name not in shared:
            print("done", name, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(_child())

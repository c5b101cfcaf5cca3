"""Kernels compiled by a second process (`solver.precompile`): the parent loads what the child
compiled instead of compiling it again, compiles itself what the child skipped, failed or left
when it died, starts nothing when the disk cache holds the kernels, and never leaves the child
behind."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import numba
import pytest

from solver import precompile

TOY = """
import numba

@numba.njit(cache=True)
def twice(x):
    return 2.0 * x
"""


@pytest.fixture
def toy(tmp_path, monkeypatch):
    """A one-line kernel in a module of its own, its disk cache in an empty folder; the
    child finds both through the environment."""
    (tmp_path / "toy_kernels.py").write_text(TOY)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "numba"))
    monkeypatch.setattr(precompile, "spare_core", lambda: True)     # (the test machine may be busy)
    sys.modules.pop("toy_kernels", None)
    import toy_kernels
    yield toy_kernels.twice
    sys.modules.pop("toy_kernels", None)


def fake_helper(monkeypatch, tmp_path, script: str):
    """The child replaced by ``script`` (Python; reads the jobs line first)."""
    path = tmp_path / "helper.py"
    path.write_text(textwrap.dedent(script))
    monkeypatch.setattr(precompile, "HELPER", [sys.executable, str(path)])


def began(p, name, timeout=30.0):
    """Wait until the child has begun (or finished) ``name``."""
    t_end = time.monotonic() + timeout
    while p.state[name] == "queued" and time.monotonic() < t_end:
        time.sleep(0.02)


JOBS = lambda k: [(k, (numba.float64,))]  # noqa: E731

# a kernel (outer) and a callee of it that the parent's own kernels call too (inner): shared
PAIR = TOY + """

@numba.njit(cache=True)
def inner(x):
    return x + 1.0


@numba.njit(cache=True)
def outer(x):
    return inner(x) * 3.0
"""


@pytest.fixture
def pair(toy, tmp_path):
    """(outer, inner, jobs, shared) of `PAIR`, in the toy's module and cache."""
    (tmp_path / "toy_kernels.py").write_text(PAIR)
    sys.modules.pop("toy_kernels", None)
    import toy_kernels
    sig = (numba.float64,)
    yield toy_kernels.outer, toy_kernels.inner, [(toy_kernels.outer, sig), (toy_kernels.inner, sig)], (toy_kernels.inner,)


def test_the_child_compiles_into_the_disk_cache_and_the_parent_loads_it(toy):
    assert not precompile.cached(toy, (numba.float64,))
    with precompile.precompiling(JOBS(toy)) as p:
        assert p is not None
        began(p, "toy_kernels.twice")
        precompile.ready(toy)           # waits for the child's compile (or finds it done)
        assert p.state["toy_kernels.twice"] == "done"
        assert toy(1.5) == 3.0
    # loaded from the cache the child wrote, not compiled here
    assert toy.stats.cache_hits and not toy.stats.cache_misses
    assert p.proc.returncode is not None
    # warm: no process at all
    with precompile.precompiling(JOBS(toy)) as p2:
        assert p2 is None


def test_no_child_on_a_machine_without_an_idle_core(toy, monkeypatch):
    monkeypatch.setattr(precompile, "spare_core", lambda: False)
    with precompile.precompiling(JOBS(toy)) as p:
        assert p is None
        assert toy(1.0) == 2.0
    assert toy.stats.cache_misses


def test_an_idle_core_is_one_no_process_is_ready_to_run_on(monkeypatch, tmp_path):
    """(read from Linux's count of the processes ready to run)"""
    cores = len(os.sched_getaffinity(0))
    loadavg = tmp_path / "loadavg"
    monkeypatch.setattr(precompile, "LOADAVG", loadavg)
    for running, spare in ((cores - 1, True), (cores, False), (cores + 5, False)):
        loadavg.write_text(f"0.50 0.40 0.30 {running}/200 12345\n")
        assert precompile.spare_core() is spare


def test_a_child_that_fails_leaves_the_parent_compiling(toy, tmp_path, monkeypatch):
    fake_helper(monkeypatch, tmp_path, "import sys; sys.stdin.readline(); sys.exit(3)")
    with precompile.precompiling(JOBS(toy)) as p:
        p._reader.join(10)
        precompile.ready(toy)
        assert p.state["toy_kernels.twice"] == "gone"
        assert toy(2.0) == 4.0
    assert toy.stats.cache_misses        # compiled here


def test_a_child_that_dies_while_compiling_releases_the_waiting_parent(toy, tmp_path, monkeypatch):
    fake_helper(monkeypatch, tmp_path, """
        import sys, time
        sys.stdin.readline()
        print("start toy_kernels.twice", flush=True)
        time.sleep(120)
    """)
    with precompile.precompiling(JOBS(toy)) as p:
        began(p, "toy_kernels.twice")
        killer = subprocess.Popen([sys.executable, "-c", f"import os, time; time.sleep(1.0); os.kill({p.proc.pid}, 9)"])
        t0 = time.monotonic()
        precompile.ready(toy)           # released by the child's death
        assert 0.5 < time.monotonic() - t0 < 20
        killer.wait()
        assert p.state["toy_kernels.twice"] == "gone"
        assert toy(1.0) == 2.0
    assert toy.stats.cache_misses


def test_a_kernel_the_child_has_not_begun_is_compiled_here_and_skipped_there(toy, tmp_path, monkeypatch):
    fake_helper(monkeypatch, tmp_path, f"""
        import sys
        sys.stdin.readline()
        open({str(tmp_path / "told.txt")!r}, "w").write(sys.stdin.readline())
    """)
    with precompile.precompiling(JOBS(toy)) as p:
        t0 = time.monotonic()
        precompile.ready(toy)
        assert time.monotonic() - t0 < 1.0 and p.state["toy_kernels.twice"] == "skipped"
        p.proc.wait(10)
    assert (tmp_path / "told.txt").read_text() == "skip toy_kernels.twice\n"


def test_the_child_is_stopped_when_the_parent_leaves_on_an_error(toy, tmp_path, monkeypatch):
    fake_helper(monkeypatch, tmp_path, """
        import signal, sys, time
        signal.signal(signal.SIGTERM, signal.SIG_IGN)     # deaf even to SIGTERM: killed
        sys.stdin.readline()
        time.sleep(120)
    """)
    monkeypatch.setattr(precompile, "CLOSE_WAIT_S", 0.5)
    with pytest.raises(KeyboardInterrupt):
        with precompile.precompiling(JOBS(toy)) as p:
            raise KeyboardInterrupt
    assert p.proc.returncode == -signal.SIGKILL
    assert not precompile._active


def test_the_child_ends_when_its_parent_is_killed(tmp_path):
    """The real child, its parent killed (no clean-up): the child's input closes and it ends."""
    # the kernel's module takes a minute to import: the child is still at it when its parent dies
    (tmp_path / "toy_kernels.py").write_text(TOY + "\nimport time\ntime.sleep(60)\n")
    parent = subprocess.Popen([sys.executable, "-c", textwrap.dedent("""
        import time
        import numba
        from solver import precompile
        kernel = type("K", (), {"py_func": type("F", (), {"__module__": "toy_kernels", "__qualname__": "twice"})})()
        p = precompile.Precompiler([(kernel, (numba.float64,))])
        print(p.proc.pid, flush=True)
        time.sleep(120)
    """)], stdout=subprocess.PIPE, text=True, env=dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), *sys.path])))
    child = int(parent.stdout.readline())
    assert os.path.exists(f"/proc/{child}")
    parent.kill()
    parent.wait()
    t_end = time.monotonic() + 20
    while time.monotonic() < t_end:
        try:
            with open(f"/proc/{child}/stat") as f:
                if f.read().split(")")[-1].split()[0] == "Z":
                    break       # ended, not yet reaped by its new parent
        except FileNotFoundError:
            break
        time.sleep(0.1)
    else:
        os.kill(child, signal.SIGKILL)
        pytest.fail("the child outlived its parent")


def test_a_shared_kernel_the_parent_reaches_first_is_compiled_there_and_the_child_waits_for_it(pair, monkeypatch):
    """The parent's first entry call takes the shared callee the child has not begun: it
    compiles it, and the child, its compile of the caller reaching it meanwhile, waits for it
    and loads it from the cache instead of compiling it too."""
    outer, inner, jobs, shared = pair
    compile_, seen = inner.compile, []

    def slow(sig):      # begun 3 s late here: the child meanwhile reaches inner within outer
        time.sleep(3.0)
        seen.extend(p.heard)
        return compile_(sig)
    monkeypatch.setattr(inner, "compile", slow, raising=False)
    with precompile.precompiling(jobs, shared) as p:
        precompile.ready(outer)     # inner: taken and compiled here; then outer: waits for the child's
        assert p.state["toy_kernels.inner"] == "skipped" and p.state["toy_kernels.outer"] == "done"
        assert inner.stats.cache_misses         # compiled here
        assert outer(1.0) == 6.0
    assert "start toy_kernels.outer" in seen    # the child was in outer while inner was compiled here
    # the child compiled outer with inner loaded from the cache the parent wrote: it never began inner
    assert "done toy_kernels.outer" in p.heard, p.heard
    assert not any(line.endswith("toy_kernels.inner") for line in p.heard), p.heard
    assert outer.stats.cache_hits and not outer.stats.cache_misses


def test_a_shared_kernel_the_child_reaches_first_is_compiled_there_and_the_parent_waits_for_it(pair):
    outer, inner, jobs, shared = pair
    with precompile.precompiling(jobs, shared) as p:
        t_end = time.monotonic() + 60
        while "start toy_kernels.inner" not in p.heard and time.monotonic() < t_end:
            time.sleep(0.01)
        precompile.ready(outer)     # waits for the child's inner (begun within outer), then for outer
        assert p.state["toy_kernels.inner"] == "done" and p.state["toy_kernels.outer"] == "done"
        assert outer(1.0) == 6.0
    assert p.heard.index("start toy_kernels.outer") < p.heard.index("start toy_kernels.inner") \
        < p.heard.index("done toy_kernels.inner") < p.heard.index("done toy_kernels.outer")
    # nothing compiled here: both loaded from the child's cache
    assert outer.stats.cache_hits and not outer.stats.cache_misses and not inner.stats.cache_misses


def test_a_shared_kernel_the_parent_fails_to_compile_is_compiled_by_the_child(pair, monkeypatch):
    outer, inner, jobs, shared = pair

    held = []

    def refused(sig):
        # (fails once the child has begun outer, whose typing reaches inner, taken here: on a
        # busy machine the child may still be starting when this process takes inner)
        began(held[0], "toy_kernels.outer")
        raise RuntimeError("refused")
    monkeypatch.setattr(inner, "compile", refused, raising=False)
    with precompile.precompiling(jobs, shared) as p:
        held.append(p)
        precompile.ready(outer)     # inner: taken, failed here, said so; then waits for the child's outer
        assert p.state["toy_kernels.inner"] == "skipped"
        precompile.ready(outer)
        t_end = time.monotonic() + 60
        while "done toy_kernels.outer" not in p.heard and time.monotonic() < t_end:
            time.sleep(0.05)
    # the child compiled inner itself (within outer) once told the parent's failed
    assert "start toy_kernels.inner" in p.heard and "done toy_kernels.outer" in p.heard, p.heard

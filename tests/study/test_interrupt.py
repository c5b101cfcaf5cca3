"""Ctrl-C (SIGINT) and SIGTERM stop the compiled loops: `run` and `sweep` (in process and on
two dask workers) exit 130 within seconds, and a sweep keeps its finished tasks."""
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from solver.mbs import interrupt

ROOT = Path(__file__).resolve().parents[2]
# the example study's 20-tooth pair (uniform springs: no FE) at a time step a thousand times
# below its stability bound: one run would take hours
SMALL = """
"gear1.teeth" = 20
"gear2.teeth" = 20
"gear1.body" = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0}
"gear2.body" = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0, holes = 0}
"gear1.spring.stiffness" = "uniform"
"gear2.spring.stiffness" = "uniform"
"quasi_static" = {rotation = 6.0, angle_step = 0.5}
"""
STEP = "1e-10"
STOP_WITHIN_S = 5.0


def slow_study(folder: Path, step: str = STEP, speeds: str = "50.0, 60.0, 70.0") -> Path:
    path = folder / "slow.toml"
    path.write_text(f'title = "slow"\n[scene]\n{SMALL}"dynamic" = {{duration = 0.01, ramp_time = 0.002, time_step = {step}}}\n'
                    f'[grid]\n"dynamic.speed" = [{speeds}]\n[outputs]\nscalars = ["ste_p2p", "dte_rms"]\n')
    return path


def small_scene(folder: Path) -> Path:
    from study.sweep.grid import load_study
    path = folder / "small.toml"
    st = load_study(slow_study(folder, "0.0"))
    path.write_text(st.points()[0].scene.to_toml())
    return path


def cli(args, cwd):
    """``lightgear ARGS`` in a child process; its stdout and stderr go to cwd/out.txt, err.txt."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    with open(cwd / "out.txt", "w") as out, open(cwd / "err.txt", "w") as err:
        return subprocess.Popen([sys.executable, "-m", "study.cli", *map(str, args)], cwd=cwd, env=env,
                                stdout=out, stderr=err, text=True)


def stop_after(proc, ready, sig, timeout=240.0):
    """Wait until ``ready()`` (the loop is running), send ``sig``; (exit code, seconds to exit).
    A command that never gets there is killed before the test fails: at its time step it would
    run on for hours after the test."""
    t_end = time.monotonic() + timeout
    while not ready():
        if proc.poll() is None and time.monotonic() >= t_end:
            proc.kill()
            proc.wait()
            pytest.fail("the command never reached its time integration")
        assert proc.poll() is None, "the command ended before it was stopped"
        time.sleep(0.2)
    time.sleep(1.0)         # well inside the loop
    t0 = time.monotonic()
    proc.send_signal(sig)
    try:
        proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        pytest.fail(f"{sig!r} did not stop the command within 60 s")
    return proc.returncode, time.monotonic() - t0


@pytest.fixture(autouse=True)
def ctrl_c_as_a_shell_gives_it():
    """Each test starts with SIGINT as a terminal delivers it: Python's KeyboardInterrupt here,
    the default action in the commands started (children inherit an ignored SIGINT). In a full
    run from empty caches an earlier test of the same process left SIGINT ignored (the
    test processes' children then ignored Ctrl-C too); it is said as a warning, so that it
    can be traced, and undone, so that these tests check lightgear and not that test."""
    import warnings
    found = signal.getsignal(signal.SIGINT)
    ignored = int(next(line.split()[1] for line in open("/proc/self/status") if line.startswith("SigIgn:")), 16) \
        & (1 << (signal.SIGINT - 1)) if Path("/proc/self/status").exists() else 0
    if found is not signal.default_int_handler or ignored:
        warnings.warn(f"SIGINT was {found!r}{' (ignored by the OS)' if ignored else ''} before this test: reset", stacklevel=2)
        signal.signal(signal.SIGINT, signal.default_int_handler)
    yield


# ---------------------------------------------------------------- the mechanism, in process

def ctrl_c():
    os.kill(os.getpid(), signal.SIGINT)


def ctrl_c_after(seconds: float, monkeypatch):
    """Ctrl-C in ``seconds`` [s], and a watchdog: should the interrupt be lost, `stop_all` ends
    the kernel 20 s later, so that the test fails (Interrupted, not KeyboardInterrupt) naming
    the SIGINT handler in place instead of waiting out the kernel's hours."""
    monkeypatch.setattr(interrupt, "_stopping", threading.Event())
    handler = signal.getsignal(signal.SIGINT)
    threading.Timer(seconds, ctrl_c).start()
    watchdog = threading.Timer(seconds + 20.0, interrupt.stop_all)
    watchdog.daemon = True
    watchdog.start()
    return handler, watchdog


def test_an_interrupt_stops_the_time_integration_within_a_step(paper_solid_model, monkeypatch):
    from solver.mbs.dynamics import simulate
    t0 = time.monotonic()
    handler, watchdog = ctrl_c_after(1.5, monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        try:    # about 40 min of stepping at this step
            simulate(paper_solid_model, 100.0, 0.01, 50.0, 0.01, 0.2, dt=1e-10, output_step=1e-4)
        except interrupt.Interrupted:
            pytest.fail(f"Ctrl-C was lost (the SIGINT handler in place: {handler!r})")
    watchdog.cancel()
    assert time.monotonic() - t0 < 1.5 + 1.0


def test_an_interrupt_stops_the_statics_before_the_next_angle(paper_solid_model, monkeypatch):
    from solver.mbs.statics import solve_static
    angles = np.radians(np.arange(0.0, 3600.0, 1e-3))        # 3.6 million angles: minutes
    t0 = time.monotonic()
    handler, watchdog = ctrl_c_after(1.0, monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        try:
            solve_static(paper_solid_model, angles, 50.0, raise_on_failure=False)
        except interrupt.Interrupted:
            pytest.fail(f"Ctrl-C was lost (the SIGINT handler in place: {handler!r})")
    watchdog.cancel()
    assert time.monotonic() - t0 < 1.0 + 1.0


def test_stop_all_ends_a_running_kernel_and_refuses_new_ones(paper_solid_model, monkeypatch):
    """What a closing dask worker does (`study.sweep.cluster.stop_kernels_plugin`)."""
    from solver.mbs.dynamics import simulate
    monkeypatch.setattr(interrupt, "_stopping", threading.Event())
    threading.Timer(1.0, interrupt.stop_all).start()
    t0 = time.monotonic()
    with pytest.raises(interrupt.Interrupted):
        simulate(paper_solid_model, 100.0, 0.01, 50.0, 0.01, 0.2, dt=1e-10, output_step=1e-4)
    assert time.monotonic() - t0 < 2.0
    with pytest.raises(interrupt.Interrupted):
        simulate(paper_solid_model, 100.0, 0.01, 50.0, 0.01, 0.2, output_step=1e-4)


# ---------------------------------------------------------------- the command line

@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_run_stops_on_a_signal(tmp_path, sig):
    scene = small_scene(tmp_path)
    proc = cli(["run", scene, "--no-static", "--set", f"dynamic.time_step={STEP}", "--max-time", "1e9",
                "-o", tmp_path / "r.nc"], tmp_path)
    # the progress bar of the time integration is on stderr
    code, took = stop_after(proc, lambda: "dynamic run" in (tmp_path / "err.txt").read_text(), sig)
    assert code == 130 and took < STOP_WITHIN_S
    assert "interrupted" in (tmp_path / "err.txt").read_text() and not (tmp_path / "r.nc").exists()


def test_sigterm_is_still_handled_once_the_mesher_has_run(tmp_path, monkeypatch):
    """gmsh puts its own C signal handlers in place at each initialize: a run whose FE body was
    meshed in the same process still stops on SIGTERM with exit 130 and its line, in the dynamic
    run after the FE."""
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "cache"))      # an empty FE cache: gmsh runs
    scene = small_scene(tmp_path)
    proc = cli(["run", scene, "--no-static", "--set", "gear2.spring.stiffness=fe-ratio", "--set",
                f"dynamic.time_step={STEP}", "--max-time", "1e9", "-o", tmp_path / "r.nc"], tmp_path)
    code, took = stop_after(proc, lambda: "dynamic run" in (tmp_path / "err.txt").read_text(), signal.SIGTERM)
    err = (tmp_path / "err.txt").read_text()
    assert any((tmp_path / "cache" / "fe").glob("*.nc")), "no FE body was meshed"
    assert code == 130 and took < STOP_WITHIN_S, err
    assert "interrupted" in err and not (tmp_path / "r.nc").exists()


def test_the_mesher_leaves_the_processs_signal_handlers_in_place():
    """(in a child process: without the handler SIGTERM ends it with 143)"""
    code = ("import os, signal, sys, time\n"
            "from solver.fe.mesh import mesh_annulus\n"
            "signal.signal(signal.SIGTERM, lambda s, f: sys.exit(130))\n"
            "mesh_annulus(0.01, 0.02, 0.03, 0.005)\n"
            "os.kill(os.getpid(), signal.SIGTERM)\n"
            "time.sleep(5)\n")
    done = subprocess.run([sys.executable, "-c", code], env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=120)
    assert done.returncode == 130


@pytest.mark.parametrize("workers", [0, 2])
def test_sweep_stops_on_sigint_and_sigterm_and_resumes(tmp_path, workers, capsys):
    # one speed: on two workers the dearest tasks go first, so the static task (milliseconds)
    # starts at once beside the dynamic one only while a worker is free for it
    study = slow_study(tmp_path, speeds="50.0")
    fast = tmp_path / "fast"
    fast.mkdir()
    fast = slow_study(fast, "0.0", speeds="50.0")
    for sig in (signal.SIGINT, signal.SIGTERM):
        out = tmp_path / f"{sig.name}.nc"
        parts = tmp_path / f".{sig.name}.nc.parts"
        proc = cli(["sweep", study, "-o", out, "--workers", workers, "--no-progress"], tmp_path)
        # the static task is stored first; the dynamic one runs (minutes at this step)
        code, took = stop_after(proc, lambda: parts.is_dir() and any(parts.glob("*.pkl")), sig)
        err = (tmp_path / "err.txt").read_text()
        assert code == 130 and took < STOP_WITHIN_S, err
        assert "interrupted" in err and not out.exists()
        assert len(list(parts.glob("*.pkl"))) == 1
        # one line, saying what was really kept (no dask traceback)
        lines = [line for line in err.splitlines() if line.strip()]
        assert lines == [f"lightgear sweep: interrupted: 1 finished analysis kept in {parts}; the same command "
                         "resumes from them"], err
        # resumable: the same study at a sane step reuses the stored static task (run here, in
        # this process: the resumption, not a signal, is checked, and a process start costs
        # some 3 s of CPU)
        from study.cli import main
        capsys.readouterr()
        assert main(["sweep", str(fast), "-o", str(out), "--workers", "0", "--no-progress"]) == 0
        text = capsys.readouterr().out
        assert "computed 1, reused 1" in text and "ok 1" in text


def test_an_interrupt_before_any_analysis_finished_says_nothing_was_kept(tmp_path, monkeypatch, capsys):
    """Ctrl-C before the first analysis is stored: one line, and no claim of kept points in a
    folder that does not exist."""
    import study.sweep.engine as engine
    from study.cli import main

    def put(self, key, result):
        raise KeyboardInterrupt
    monkeypatch.setattr(engine.PartStore, "put", put)
    study = slow_study(tmp_path, "0.0", speeds="50.0, 60.0")
    out = tmp_path / "s.nc"
    assert main(["sweep", str(study), "-o", str(out), "--workers", "0", "--no-progress"]) == 130
    err = capsys.readouterr().err
    assert [line for line in err.splitlines() if line.strip()] == [
        "lightgear sweep: interrupted: no analysis had finished: nothing kept (the same command starts the study again)"]
    assert not out.exists() and "kept in" not in err

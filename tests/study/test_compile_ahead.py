"""`lightgear run` on an empty kernel cache: a second process compiles the time stepping from
the stand-in model while the run builds its statics, the run loads it from the disk cache
instead of compiling it, a second run starts no process and compiles nothing, and
no process is left behind when the run is killed."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest
from helpers import scene_overrides

ROOT = Path(__file__).resolve().parents[2]
# the small pair, the paper model (no FE), a short run
SCENE = {**scene_overrides("small_pair"), "coupling.model": "paper", "quasi_static.rotation": 6.0,
         "quasi_static.angle_step": 1.0, "dynamic.duration": 0.004, "dynamic.ramp_time": 0.001}

# the command in a child process, with the kernels it compiles (numba's compile events: a
# kernel loaded from the disk cache is not compiled) and the second process's record
CHILD = r'''
import json, sys
from numba.core import event
from solver import precompile
precompile.spare_core = lambda: True        # (the test machine may be busy)
compiled, helpers = [], []
class Compiles(event.Listener):
    def on_start(self, ev):
        compiled.append(precompile.kernel_name(ev.data["dispatcher"]))
    def on_end(self, ev):
        pass
init = precompile.Precompiler.__init__
def recorded(self, *args):
    init(self, *args)
    helpers.append(self)
precompile.Precompiler.__init__ = recorded
from study.cli import main
with event.install_listener("numba:compile", Compiles()):
    rc = main(sys.argv[1:])
print("RESULT", json.dumps({"rc": rc, "compiled": compiled, "helper": helpers[0].state if helpers else None,
                            "exit": helpers[0].proc.returncode if helpers else None}))
'''


def scene_file(tmp_path: Path) -> Path:
    import study
    path = tmp_path / "small.toml"
    path.write_text(study.load_scene(None, SCENE).to_toml())
    return path


def env_for(tmp_path: Path) -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg", NUMBA_CACHE_DIR=str(tmp_path / "numba"),
                LIGHTGEAR_CACHE=str(tmp_path / "cache"))


def run(tmp_path: Path, out: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", CHILD, "run", scene_file(tmp_path), "-o", tmp_path / out],
                          cwd=tmp_path, env=env_for(tmp_path), capture_output=True, text=True, timeout=540)
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert line, proc.stderr[-3000:]
    return json.loads(line[7:])


def test_a_cold_run_loads_the_time_stepping_the_second_process_compiled(tmp_path):
    import xarray as xr
    cold = run(tmp_path, "cold.nc")
    assert cold["rc"] == 0
    stepping, sweep = "solver.mbs.kernels.explicit.verlet", "solver.mbs.kernels.statics.static_sweep"
    # the second process compiled the time stepping for the types of the real run: the run
    # found it in the disk cache (it compiled the statics itself, which it reached first)
    assert cold["helper"][stepping] == "done", cold["helper"]
    assert stepping not in cold["compiled"] and sweep in cold["compiled"]
    assert cold["exit"] is not None             # stopped and reaped when the run ended
    # the contact search, compiled ahead from the stand-in as the loops call it (by the process
    # that reached it first): one signature in the cache (a second would be the loops' own or
    # the statics', compiled again)
    assert cold["helper"]["solver.mbs.kernels.gearmesh.pair_contacts"] in ("done", "skipped")
    assert len(list((tmp_path / "numba").rglob("gearmesh.pair_contacts-*.nbc"))) == 1
    assert len(list((tmp_path / "numba").rglob("gearmesh.mesh_contacts-*.nbc"))) == 1
    # warm: no second process and nothing compiled at all (every kernel the two processes
    # wrote at the same time is in the cache, its index entry kept), the same numbers to the bit
    warm = run(tmp_path, "warm.nc")
    assert warm["rc"] == 0 and warm["helper"] is None
    assert warm["compiled"] == []
    with xr.open_dataset(tmp_path / "cold.nc") as a, xr.open_dataset(tmp_path / "warm.nc") as b:
        for name in ("dte", "ste", "tooth_stiffness"):
            if name in a:
                assert a[name].equals(b[name]), name


def helper_of(proc: subprocess.Popen, timeout: float = 120.0):
    """The second process the command started (its child running solver.precompile)."""
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        assert proc.poll() is None, "the command ended before its second process was seen"
        for c in psutil.Process(proc.pid).children():
            try:
                if "solver.precompile" in c.cmdline():
                    return c
            except psutil.NoSuchProcess:
                pass
        time.sleep(0.1)
    proc.kill()
    pytest.fail("no second process was started on an empty kernel cache")


def test_no_process_is_left_when_a_cold_run_is_killed(tmp_path):
    """Killed outright (no clean-up in the run): the second process ends by itself. (Stopped by
    Ctrl-C or SIGTERM, the run stops it on its way out: tests/solver/test_precompile.py; here
    that would wait for the compile the run is in.)"""
    sig = signal.SIGKILL
    with open(tmp_path / "err.txt", "w") as err:
        proc = subprocess.Popen([sys.executable, "-c", CHILD, "run", scene_file(tmp_path), "-o", tmp_path / "r.nc"],
                                cwd=tmp_path, env=env_for(tmp_path), stdout=subprocess.DEVNULL, stderr=err)
    helper = helper_of(proc)
    proc.send_signal(sig)
    try:
        code = proc.wait(timeout=90)
    except subprocess.TimeoutExpired:
        proc.kill()
        helper.kill()
        pytest.fail("the run did not stop")
    assert code == -signal.SIGKILL
    try:
        helper.wait(timeout=20)         # (reaped here when the killed run could not)
    except psutil.TimeoutExpired:
        helper.kill()
        pytest.fail("the second process outlived the run")

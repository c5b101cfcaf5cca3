"""`lightgear run` on an empty kernel cache: a second process compiles the time stepping from
the stand-in model while the run builds its statics, the run loads it from the disk cache
instead of compiling it, a second run starts no process and compiles nothing, and
no process is left behind when the run is killed. And what the kernels compile on a first run:
each kernel for one argument list, no coupled code for the plain (paper) model, the default
model's coupled kernels beside the plain ones in the same cache (one empty cache filled in that
order: the cold run, the warm one, then a process running the default model)."""
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

# what a process compiles, as lines of the file $COMPILE_LOG: each compile (numba's compile
# events: a kernel loaded from the disk cache is not compiled) with the kernel being compiled
# when it began (its entry: a kernel calls others), and when an entry is compiled, the kernels
# the process holds by then (loaded or compiled) with their argument types
RECORDER = r'''
import importlib, json, os, pkgutil
from numba.core import event
import solver.mbs.kernels as K
from solver import precompile
MODULES = [K] + [importlib.import_module(f"{K.__name__}.{m.name}") for m in pkgutil.iter_modules(K.__path__)]
def held():
    return {precompile.kernel_name(f): ["|".join(map(str, sig)) for sig in f.overloads] for mod in MODULES
            for f in vars(mod).values() if getattr(f, "overloads", None) and f.py_func.__module__ == mod.__name__}
def write(line):
    with open(os.environ["COMPILE_LOG"], "a") as log:
        log.write(json.dumps(line) + "\n")
class Compiles(event.Listener):
    def __init__(self, process):
        self.process, self.within = process, []
    def on_start(self, ev):
        name = precompile.kernel_name(ev.data["dispatcher"])
        self.within.append(name)
        write({"process": self.process, "kernel": name, "entry": self.within[0],
               "args": "|".join(map(str, ev.data["args"]))})
    def on_end(self, ev):
        entry = self.within.pop()
        if not self.within:
            write({"process": self.process, "entry": entry, "held": held()})
'''
# the second process as the command starts it (`solver.precompile`), its compiles recorded
HELPER = RECORDER + r'''
import sys
event.register("numba:compile", Compiles("helper"))
sys.exit(precompile._child())
'''
# the command in a child process, with the kernels it compiles and the second process's record;
# with $COMPILE_LOG, both processes' compiles recorded there, and the kernels the command's
# process holds at its end
CHILD = RECORDER + r'''
import sys
precompile.spare_core = lambda: True        # (the test machine may be busy)
if "COMPILE_LOG" in os.environ:
    precompile.HELPER = [sys.executable, "-c", os.environ["RECORDING_HELPER"]]
compiled, helpers = [], []
class Named(event.Listener):
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
with event.install_listener("numba:compile", Named()):
    if "COMPILE_LOG" in os.environ:
        event.register("numba:compile", Compiles("run"))
    rc = main(sys.argv[1:])
print("RESULT", json.dumps({"rc": rc, "compiled": compiled, "helper": helpers[0].state if helpers else None,
                            "exit": helpers[0].proc.returncode if helpers else None, "held": held()}))
'''


def scene_file(tmp_path: Path) -> Path:
    import study
    path = tmp_path / "small.toml"
    path.write_text(study.load_scene(None, SCENE).to_toml())
    return path


def env_for(tmp_path: Path) -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg", NUMBA_CACHE_DIR=str(tmp_path / "numba"),
                LIGHTGEAR_CACHE=str(tmp_path / "cache"))


def run(tmp_path: Path, out: str, log: Path | None = None) -> dict:
    """The command on the small scene in a child process (kernel cache tmp_path/numba); ``log``:
    its compiles and its second process's, recorded there."""
    env = env_for(tmp_path)
    if log is not None:
        env.update(COMPILE_LOG=str(log), RECORDING_HELPER=HELPER)
    proc = subprocess.run([sys.executable, "-c", CHILD, "run", scene_file(tmp_path), "-o", tmp_path / out],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=540)
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert line, proc.stderr[-3000:]
    return json.loads(line[7:])


# the default model's first run in a process of its own: the kernels it holds at its end with
# their argument types (loaded from the disk cache or compiled), and what numba compiled
DEFAULT_RUN = RECORDER + r'''
import numpy as np
from study.scene import default_scene
from study.scene_model import build_scene_model
from solver.mbs.statics import solve_static
from solver.mbs.dynamics import simulate
with event.install_recorder("numba:compile") as rec:
    m = build_scene_model(default_scene().solid(gears=(2,)).replace(**{"coupling.model": "auto"}))
    solve_static(m, np.radians(np.arange(0.0, 1.0, 0.1)), 50.0)
    simulate(m, 100.0, 1e-4, 50.0, 1e-4, 2e-4)
print("RESULT", json.dumps({"held": held(), "compiled": [ev.data["dispatcher"].py_func.__qualname__
                                                         for _t, ev in rec.buffer if ev.is_start]}))
'''


def default_run(tmp_path: Path) -> dict:
    """`DEFAULT_RUN` with the kernel cache tmp_path/numba (the suite's FE cache)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", DEFAULT_RUN], cwd=ROOT, env=env, capture_output=True, text=True)
    line = next((x for x in out.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert out.returncode == 0 and line, out.stderr[-3000:]
    return json.loads(line[7:])


@pytest.fixture(scope="module")
def first_runs(tmp_path_factory):
    """One empty kernel cache, filled by: the command on the small scene (the paper model), cold,
    both processes' compiles recorded; the same command again, warm; then the default model
    (`DEFAULT_RUN`), whose coupled kernels no run before compiled."""
    tmp = tmp_path_factory.mktemp("first_runs")
    log = tmp / "compiles.jsonl"
    cold = run(tmp, "cold.nc", log)
    cold["compiles"] = [json.loads(x) for x in log.read_text().splitlines()]
    cold["contact_search_files"] = {k: len(list((tmp / "numba").rglob(f"gearmesh.{k}-*.nbc")))
                                    for k in ("pair_contacts", "mesh_contacts")}
    warm = run(tmp, "warm.nc")
    return {"tmp": tmp, "cold": cold, "warm": warm, "default": default_run(tmp)}


def test_a_cold_run_loads_the_time_stepping_the_second_process_compiled(first_runs):
    import xarray as xr
    tmp_path, cold = first_runs["tmp"], first_runs["cold"]
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
    assert cold["contact_search_files"] == {"pair_contacts": 1, "mesh_contacts": 1}
    # warm: no second process and nothing compiled at all (every kernel the two processes
    # wrote at the same time is in the cache, its index entry kept), the same numbers to the bit
    warm = first_runs["warm"]
    assert warm["rc"] == 0 and warm["helper"] is None
    assert warm["compiled"] == []
    with xr.open_dataset(tmp_path / "cold.nc") as a, xr.open_dataset(tmp_path / "warm.nc") as b:
        for name in ("dte", "ste", "tooth_stiffness"):
            if name in a:
                assert a[name].equals(b[name]), name


# compiled in neither model's first run: numba's string machinery (an array copied into a slice
# compiles its shape-error message) and the contact search's parts the scenes lack (no friction,
# flank deviation or pitch error in either, no tip edge in either: sharp corners)
STRINGS = ("raise_with_shape_context", "unicode", "str_generic")


def short(name: str) -> str:
    return name.rsplit(".", 1)[1]


def test_the_plain_models_first_run_compiles_each_kernel_once_and_no_coupled_code(first_runs):
    """Compile time, the plain (paper) model: its cold run (the statics compiled in its process,
    the time stepping in the second one) holds each kernel for one argument list only, in
    either process (the second one's stand-in has the run's types): no second version for a
    literal-0 argument (numba specialises callees on Literal[int](0)) nor for another tuple; and
    the statics and the time stepping reach none of the coupled-teeth kernels (pruned from the
    plain static sweep) and no series compliance (the compliance model's identification reads
    the flank deviations from Python, in its FE contact); nothing it holds came from elsewhere."""
    cold = first_runs["cold"]
    compiles = [c for c in cold["compiles"] if "kernel" in c]
    helds = {(c["process"], short(c["entry"])): c["held"] for c in cold["compiles"] if "held" in c}
    # what the statics (the first kernel the run compiles) and the time stepping reach
    reached = {short(k) for k in {**helds[("run", "static_sweep")], **helds[("helper", "verlet")]}}
    assert {"static_sweep", "mesh_contacts", "pair_contacts", "mesh_energies", "dissipation_power",
            "end_step", "record_output", "verlet", "arrowhead_accelerations"} <= reached
    assert not {"_friction", "edge_compliance", "set_stiffness", "set_moment", "local_compliance", "series_contact",
                "flank_deviation", "verlet_coupled", "coupled_energies"} & reached
    sigs = {}
    for kernels in [*helds.values(), cold["held"]]:
        for name, held in kernels.items():
            sigs.setdefault(name, set()).update(held)
    assert not {name: s for name, s in sigs.items() if len(s) > 1}
    assert not [name for name, s in sigs.items() for sig in s if "Literal" in sig]
    assert not [c for c in compiles if any(s in c["kernel"] for s in STRINGS)]
    compiled = {(c["kernel"], c["args"]) for c in compiles}
    assert {(name, sig) for name, s in sigs.items() for sig in s} <= compiled


def test_the_default_models_first_run_compiles_its_coupled_kernels_once_beside_the_plain_ones(first_runs):
    """Compile time, the default model (auto: teeth coupled through the body) run after the plain
    one filled the cache: it adds its own variant of a kernel the plain one compiled for other
    `layout.ContactParts`, never two, and reuses the plain one's where the arguments are the same;
    no string machinery, no friction, no tip edge; the coupled kernels and the series compliance."""
    run = first_runs["default"]
    plain = {(short(c["kernel"]), c["args"]) for c in first_runs["cold"]["compiles"] if "kernel" in c}
    added = {}                                                  # the overloads this model adds
    for name, sigs in run["held"].items():
        added.setdefault(short(name), []).extend(sig for sig in sigs if (short(name), sig) not in plain)
    added = {name: s for name, s in added.items() if s}
    names = {short(name) for name in run["held"]}               # what the process holds
    assert {"static_sweep", "mesh_contacts", "pair_contacts", "mesh_energies", "dissipation_power"} <= set(added)
    assert {"end_step", "record_output"} <= names - set(added)       # the plain one's, loaded from the cache
    assert not [sig for s in added.values() for sig in s if "Literal" in sig]
    assert not {name: s for name, s in added.items() if len(s) > 1}
    assert not [c for c in run["compiled"] if any(s in c for s in STRINGS)]
    assert "_friction" not in names and "edge_compliance" not in names
    # (set_moment: inlined into its callers, numba's inline="always", no compile of its own)
    assert {"verlet_coupled", "coupled_energies", "set_stiffness"} <= set(added)
    assert {"local_compliance", "series_contact"} <= set(added)


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

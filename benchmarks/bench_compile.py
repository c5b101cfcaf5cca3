"""First-call compile taken apart: a cold `lightgear run` (the paper example, default model;
``--paper``: the paper model) in a child process with an empty numba cache, each compiled
function's CPU exclusive of the callees it compiles, split into numba's type inference, numba
IR -> LLVM IR (the CPython wrapper apart: 0 for a kernel compiled without it), LLVM parse +
function passes (numba runs them inside the two before, so this column is part of theirs, not
added to them), and the finalisation (the callees' modules linked in, module O3, machine code).
Process CPU, not wall: the figures stand under load. The FE cache is the user's (fill it with
one run first). ``--all``: every compiled function (default: the 25 dearest).
"""
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import common

COLUMNS = ("function", "compiles", "cpu_s", "type_inference_s", "lowering_s", "wrapper_s", "llvm_parse_s",
           "finalize_s")
PARTS = COLUMNS[2:]

# run in the child: numba's compile events and four of its passes timed in process CPU, each
# net of the compiles nested in it; one line per function on stdout
CHILD = r'''
import collections, sys, time
from numba.core import codegen, event, lowering, typed_passes
acc = collections.defaultdict(lambda: collections.defaultdict(float))
stack = []
class Compiles(event.Listener):
    def on_start(self, ev):
        stack.append([ev.data["dispatcher"].py_func.__qualname__, 0.0, time.process_time()])
    def on_end(self, ev):
        name, child, t0 = stack.pop()
        d = time.process_time() - t0
        acc[name]["cpu_s"] += d - child
        acc[name]["compiles"] += 1
        if stack:
            stack[-1][1] += d
def timed(cls, method, key):
    orig = getattr(cls, method)
    def run(self, *a, **k):
        t0, c0 = time.process_time(), (stack[-1][1] if stack else 0.0)
        try:
            return orig(self, *a, **k)
        finally:
            if stack:
                acc[stack[-1][0]][key] += time.process_time() - t0 - (stack[-1][1] - c0)
    setattr(cls, method, run)
timed(typed_passes.NopythonTypeInference, "run_pass", "type_inference_s")
timed(lowering.Lower, "lower", "lowering_s")
timed(lowering.Lower, "create_cpython_wrapper", "wrapper_s")
timed(codegen.CPUCodeLibrary, "add_ir_module", "llvm_parse_s")
timed(codegen.CPUCodeLibrary, "finalize", "finalize_s")
from study.cli import main
with event.install_listener("numba:compile", Compiles()):
    rc = main(sys.argv[1:])
for name, v in acc.items():
    print("ROW", name, *(v[k] for k in ("compiles", "cpu_s", "type_inference_s", "lowering_s", "wrapper_s",
                                        "llvm_parse_s", "finalize_s")))
sys.exit(rc)
'''


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    paper = "--paper" in argv
    every = "--all" in argv
    root = Path(__file__).resolve().parents[1]
    args = ["run", "-o", "results/benchmarks/compile_run.nc"] + (["--set", "coupling.model=paper"] if paper else [])
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=str(root))
        out = subprocess.run([sys.executable, "-c", CHILD, *args], cwd=root, env=env, capture_output=True, text=True)
    if out.returncode:
        print(out.stderr[-3000:], file=sys.stderr)
        return 1
    rows = []
    for line in out.stdout.splitlines():
        if line.startswith("ROW "):
            _, name, n, *vals = line.split()
            rows.append(dict(function=name, compiles=int(float(n)), **dict(zip(PARTS, map(float, vals)))))
    rows.sort(key=lambda r: -r["cpu_s"])
    total = {k: sum(r[k] for r in rows) for k in PARTS}
    rows.insert(0, dict(function=f"all {len(rows)} functions", compiles=sum(r["compiles"] for r in rows), **total))
    model = "paper" if paper else "default (compliance)"
    common.write_table("compile", f"First-call compile of `lightgear run`, {model} model, per function (CPU s, "
                       "exclusive of nested compiles)", rows if every else rows[:26], COLUMNS)
    return 0


if __name__ == "__main__":
    sys.exit(main())

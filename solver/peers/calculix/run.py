"""Run CalculiX (`ccx`) on a deck in a temporary directory and read the rigid body's rotation.

One thread (``OMP_NUM_THREADS=1``: the machine is usually shared); the directory and its large
result files (.frd) are removed afterwards. `CalculixMissing` when ``ccx`` is not installed;
`CalculixFailed` (one line: why, and how far the load got) when ccx stops without converging or
runs past its CPU-time limit (the kernel stops it: a deck that chatters cannot hang a study).
"""
from __future__ import annotations

import math
import os
import re
import resource
import shutil
import signal
import subprocess
import tempfile
import time
from dataclasses import dataclass

INSTALL_HINT = "install it with `apt-get install calculix-ccx` (or `make sysdeps` as root)"


class CalculixMissing(RuntimeError):
    """The CalculiX executable is not on the PATH."""


class CalculixFailed(RuntimeError):
    """CalculiX ran but did not converge or wrote no result; ``cpu_time_s``: what it used [s]."""

    def __init__(self, message: str, cpu_time_s: float = 0.0):
        super().__init__(message)
        self.cpu_time_s = cpu_time_s


@dataclass(frozen=True)
class CcxResult:
    rotation: float        # rad, U3 of the rigid body's rotation node (counter-clockwise)
    reaction: tuple        # (RF1, RF2, RF3) at the reference node [N]
    wall_time_s: float
    cpu_time_s: float      # of the ccx process (children's user + system time)


def ccx_path() -> str:
    """Path of the ``ccx`` executable; `CalculixMissing` (one line, how to install) if absent."""
    path = shutil.which(os.environ.get("LIGHTGEAR_CCX", "ccx"))
    if path is None:
        raise CalculixMissing(f"CalculiX (ccx) is not installed: {INSTALL_HINT}")
    return path


def ccx_version() -> str:
    """The CalculiX version string, e.g. '2.20' ('' if ccx prints none)."""
    try:
        out = subprocess.run([ccx_path(), "-v"], capture_output=True, text=True, timeout=30).stdout
    except subprocess.TimeoutExpired:
        return ""
    m = re.search(r"Version\s+([0-9.]+)", out)
    return m.group(1) if m else ""


def run_deck(text: str, rot_node: int, ref_node: int, timeout_s: float = 3600.0, keep: str | None = None,
             cpu_limit_s: float | None = None, end_time: float = 1.0) -> CcxResult:
    """Solve one deck; ``cpu_limit_s``: CPU seconds ccx may use (the kernel stops it beyond:
    `CalculixFailed`), ``timeout_s``: wall seconds (a machine this loaded gives no answer in
    time either); ``end_time``: the total time at the end of the deck's last step (one per
    step); ``keep``: a directory to copy the deck and its .dat/.sta/.cvg into (debugging)."""
    exe = ccx_path()
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1", CCX_NPROC_EQUATION_SOLVER="1")
    limit = None if cpu_limit_s is None else max(1, int(math.ceil(cpu_limit_s)))

    def cpu_limit():
        # in the child before exec: SIGXCPU at the soft limit, SIGKILL 5 s later
        resource.setrlimit(resource.RLIMIT_CPU, (limit, limit + 5))
    with tempfile.TemporaryDirectory(prefix="lightgear-ccx-") as tmp:
        with open(os.path.join(tmp, "pair.inp"), "w") as f:
            f.write(text)
        t0, c0 = time.perf_counter(), os.times()
        try:
            proc = subprocess.run([exe, "-i", "pair"], cwd=tmp, env=env, capture_output=True, text=True, timeout=timeout_s,
                                  preexec_fn=cpu_limit if limit else None)
        except subprocess.TimeoutExpired:
            c1 = os.times()
            raise CalculixFailed(f"ccx ran longer than {timeout_s:.0f} s of wall time{reached(tmp, end_time)}",
                                 (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)) from None
        c1 = os.times()
        wall, cpu = time.perf_counter() - t0, (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)
        dat = os.path.join(tmp, "pair.dat")
        text_dat = open(dat).read() if os.path.exists(dat) else ""
        got = reached(tmp, end_time)
        if keep:
            os.makedirs(keep, exist_ok=True)
            for name in ("pair.inp", "pair.dat", "pair.sta", "pair.cvg"):
                if os.path.exists(os.path.join(tmp, name)):
                    shutil.copy(os.path.join(tmp, name), keep)
            with open(os.path.join(keep, "ccx.log"), "w") as f:
                f.write(proc.stdout + proc.stderr)
    log = proc.stdout + proc.stderr
    if limit and proc.returncode in (-signal.SIGXCPU, -signal.SIGKILL):
        raise CalculixFailed(f"ccx did not converge within its CPU-time limit of {limit} s{got}", cpu)
    if "*ERROR" in log or proc.returncode != 0:
        lines = [ln.strip() for ln in log.splitlines() if "ERROR" in ln]
        raise CalculixFailed(f"ccx failed (exit {proc.returncode}): {lines[0] if lines else log.strip()[-300:]}{got}", cpu)
    try:
        rotation, reaction = read_dat(text_dat, rot_node, end_time)
    except CalculixFailed as e:
        raise CalculixFailed(str(e), cpu) from None
    return CcxResult(rotation, reaction, wall, cpu)


def reached(folder: str, end_time: float) -> str:
    """', having converged up to X of the deck' from the deck's .sta file (its last converged
    increment's total time over ``end_time``), '' when there is none."""
    path = os.path.join(folder, "pair.sta")
    if not os.path.exists(path):
        return ""
    done = 0.0
    for ln in open(path).read().splitlines():
        parts = ln.split()
        # converged increments: STEP INC ATT ITRS TOT-TIME STEP-TIME INC-TIME, ATT without a U
        if len(parts) == 7 and parts[0].isdigit() and parts[2].isdigit():
            done = max(done, float(parts[4]))
    return f", having converged up to {done / end_time:.2g} of the deck"


_FLOAT = r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?"


def read_dat(text: str, rot_node: int, end_time: float = 1.0) -> tuple[float, tuple]:
    """(U3 of ``rot_node`` [rad] at the end of the step, total RF at the reference node [N] in
    the deck's units) from a .dat file written by ``*NODE PRINT`` (U of ROT, RF totals of REF);
    the last block of each is the converged end of the last step (total time ``end_time``)."""
    u_blocks = re.findall(r"displacements \(vx,vy,vz\) for set ROT and time\s+(" + _FLOAT + r")\s*\n\s*\n((?:\s*\d+(?:\s+" + _FLOAT + r"){3}\s*\n)+)", text)
    if not u_blocks:
        raise CalculixFailed("ccx wrote no rotation of the driven gear (no converged increment)")
    time_, rows = u_blocks[-1]
    if abs(float(time_) - end_time) > 1e-6:
        raise CalculixFailed(f"ccx stopped at {float(time_) / end_time:.3g} of the deck")
    vals = {int(r.split()[0]): [float(v) for v in r.split()[1:]] for r in rows.strip().splitlines()}
    if rot_node not in vals:
        raise CalculixFailed(f"no displacement of node {rot_node} in the .dat file")
    rf = re.findall(r"total force \(fx,fy,fz\) for set REF and time\s+" + _FLOAT + r"\s*\n\s*\n\s*(" + _FLOAT + r")\s+(" + _FLOAT + r")\s+(" + _FLOAT + ")", text)
    reaction = tuple(float(v) for v in rf[-1]) if rf else (float("nan"),) * 3
    return vals[rot_node][2], reaction

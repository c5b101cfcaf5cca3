"""Numba kernels against slow plain-numpy versions of the same formulas."""

import numpy as np
import pytest
from helpers import assert_forces_are_minus_the_energy_gradient, loaded_mesh_state

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.laws import contact_energy, contact_force, contact_tangent, spring_energy, spring_tangent, spring_torque


def test_spring_law_against_numpy():
    rng = np.random.default_rng(1)
    for _ in range(200):
        phi, dphi = rng.normal(scale=3e-3), rng.normal(scale=10.0)
        k, n, c, nc = 1060.0, rng.uniform(1, 1.5), 6e-5, rng.uniform(0.5, 2)
        ref = -k * np.sign(phi) * abs(phi) ** n - c * np.sign(dphi) * abs(dphi) ** nc
        assert spring_torque(phi, dphi, k, n, c, nc) == pytest.approx(ref, rel=1e-13)
        h = 1e-9
        assert spring_tangent(phi, k, n) == pytest.approx(
            -(spring_torque(phi + h, 0, k, n, 0, 1) - spring_torque(phi - h, 0, k, n, 0, 1)) / (2 * h), rel=1e-5)
        assert spring_energy(phi, k, n) == pytest.approx(k * abs(phi) ** (n + 1) / (n + 1))
    assert spring_tangent(0.0, 1.0, 1.1) == 0.0 and spring_tangent(0.0, 5.0, 1.0) == 5.0


def test_contact_law_against_numpy_and_clipped_at_zero():
    k, m1, c, m2, m3 = 3.0e9, 1.24, 1.15e11, 1.0, 1.5
    for d in np.linspace(-1e-6, 5e-6, 31):
        for v in (-0.05, 0.0, 0.03):
            ref = 0.0 if d <= 0 else max(0.0, k * d**m1 + c * np.sign(v) * abs(v) ** m2 * d**m3)
            assert contact_force(d, v, k, m1, c, m2, m3) == pytest.approx(ref, rel=1e-13, abs=1e-300)
    # the damping term pulls at fast separation: clipped, never negative
    assert contact_force(1e-8, -100.0, k, m1, c, m2, 1.0) == 0.0
    assert contact_tangent(2e-6, k, m1) == pytest.approx(m1 * k * 2e-6 ** (m1 - 1))
    h = 1e-12
    assert contact_tangent(2e-6, k, m1) == pytest.approx(
        (contact_energy(2e-6 + h, k, m1) - 2 * contact_energy(2e-6, k, m1) + contact_energy(2e-6 - h, k, m1)) / h**2, rel=1e-3)


def test_generalized_forces_are_minus_the_energy_gradient(paper_solid_model):
    m = paper_solid_model
    assert_forces_are_minus_the_energy_gradient(m, *loaded_mesh_state(m, 3.85, 1e-3))


def test_static_kernel_matches_its_plain_python_run(paper_solid_model):
    """The compiled static sweep (plain model: ctooth None, the coupled code pruned) gives
    what its source gives when run as plain Python (its wrapper-less callees too)."""
    from solver.mbs.kernels import python_calls
    from solver.mbs.kernels.gearmesh import contact_parts
    from solver.mbs.kernels.statics import static_sweep, static_work
    m = paper_solid_model
    angles = np.radians(np.arange(0.0, 3.0, 0.5))
    theta2 = float(m.theta2_for_te(angles[0], m.backlash_offset))
    out = []
    for f in (static_sweep, static_sweep.py_func):
        n = angles.size
        res = (np.zeros((n, L.N_S_OUT)), np.zeros((n, m.teeth[0])))
        phi = np.zeros(m.n_teeth)
        ctl = (np.array([50.0, theta2, 1e-10, 0.0, 0.0]), np.array([60]))     # (S_ABORT last)
        mdl = (m.gear_par, m.pair_par, m.law_par, m.k_phi, contact_parts(m.gear_par, m.pair_par, m.law_par))
        with python_calls():
            fails = f(mdl, None, ctl, angles, phi, *res, static_work(m.n_teeth))
        assert fails == 0
        out.append((*res, phi))
    for a, b in zip(*out):
        np.testing.assert_array_equal(a, b)


def test_the_kernel_cache_is_keyed_by_every_kernel_source(tmp_path):
    """numba checks only a kernel's own file: the cache folder is named after all kernel sources,
    so an edit of the contact search (called by the stepping loops) cannot leave a stale loop."""
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    import solver.mbs.kernels as K
    from solver.mbs.kernels.explicit import verlet
    from solver.mbs.kernels.statics import static_sweep
    for f in (verlet, static_sweep):
        assert f"kernels-{K.KERNELS_FINGERPRINT}" in f._cache._cache_path
    copy = tmp_path / "kernels"
    shutil.copytree(Path(K.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert K.sources_fingerprint(copy) == K.KERNELS_FINGERPRINT
    (copy / "gearmesh.py").write_text((copy / "gearmesh.py").read_text() + "\n# edited\n")
    assert K.sources_fingerprint(copy) != K.KERNELS_FINGERPRINT
    # the user's numba setting is left as it was
    code = ("import numba, solver.mbs.kernels as K; from solver.mbs.kernels.explicit import verlet; "
            "print(numba.config.CACHE_DIR); print(verlet._cache._cache_path)")
    root = Path(__file__).resolve().parents[3]
    env = {**__import__("os").environ, "NUMBA_CACHE_DIR": str(tmp_path / "nc"), "PYTHONPATH": str(root)}
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True, text=True, check=True)
    user, path = out.stdout.split()
    assert user == str(tmp_path / "nc") and path.startswith(str(tmp_path / "nc" / f"kernels-{K.KERNELS_FINGERPRINT}"))


def _kernel_modules():
    import importlib
    import pkgutil

    import solver.mbs.kernels as K
    return [importlib.import_module(f"solver.mbs.kernels.{m.name}") for m in pkgutil.iter_modules(K.__path__)]


def _wrapperless(f) -> bool:
    return bool(getattr(f, "targetoptions", {}).get("no_cpython_wrapper"))


def test_a_wrapperless_kernel_called_from_python_names_itself_or_runs_its_source():
    """A kernel that only kernels call has no Python wrapper: a Python call raises a TypeError
    naming it (numba would jump to a null address), runs its source inside `python_calls`,
    and its machine code through a compiled caller gives the same moment."""
    from helpers import compiled_call

    from solver.mbs.kernels import python_calls
    from solver.mbs.kernels.toothcoupling import set_moment, set_stiffness
    assert _wrapperless(set_moment)
    rng = np.random.default_rng(3)
    a = rng.normal(size=(4, 4))
    ctooth = a @ a.T + 4.0 * np.eye(4)          # SPD compliance [rad/(N m)]
    lst, n, ks, phi = np.array([2, 0, 3, 1]), 3, np.zeros((4, 8)), rng.normal(size=4)
    compiled_call(set_stiffness)(ctooth, lst, n, ks)
    with pytest.raises(TypeError, match="toothcoupling.set_moment"):
        set_moment(ks, lst, n, phi, 1)
    with python_calls():
        plain = set_moment(ks, lst, n, phi, 1)
    with pytest.raises(TypeError):                # the block ends, the guard is back
        set_moment(ks, lst, n, phi, 1)
    expect = (np.linalg.inv(ctooth[np.ix_(lst[:n], lst[:n])]) @ phi[lst[:n]])[1]
    assert plain == pytest.approx(expect, rel=1e-12)
    assert compiled_call(set_moment)(ks, lst, n, phi, 1) == pytest.approx(plain, rel=1e-14)


def test_every_kernel_python_calls_keeps_its_wrapper():
    """The kernels that the solver, the study, the workflows and the benchmarks import and call
    (the stepping loops, the statics, the contact search, ...) keep their Python wrapper; one
    that is used only as ``kernel.py_func`` or handed on uncalled (compiled ahead for given
    types, `study.stand_in`) may go without, but then no wrapper-less kernel may be called from
    its source (that call would come from Python too)."""
    import ast
    from pathlib import Path
    root = Path(__file__).resolve().parents[3]
    kernels = {(mod.__name__, name): f for mod in _kernel_modules() for name, f in vars(mod).items()
               if hasattr(f, "py_func") and getattr(f, "__module__", None) == mod.__name__}
    assert sum(map(_wrapperless, kernels.values())) >= 30      # the inner kernels are wrapper-less
    bad, checked = [], 0
    files = [p for d in ("solver", "study", "workflows", "benchmarks") for p in (root / d).rglob("*.py")
             if "kernels" not in p.relative_to(root).parts]
    for path in files:
        src = path.read_text()
        tree = ast.parse(src)
        calls = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
        for node in ast.walk(tree):
            if not (isinstance(node, ast.ImportFrom) and (node.module or "").startswith("solver.mbs.kernels.")):
                continue
            for alias in node.names:
                f = kernels.get((node.module, alias.name))
                if f is None:
                    continue
                checked += 1
                local = alias.asname or alias.name
                if _wrapperless(f) and local in calls:
                    bad.append(f"{path.name}: {alias.name} (called from Python)")
                if src.count(f"{local}.py_func"):
                    called = [n for n in f.py_func.__code__.co_names if _wrapperless(f.py_func.__globals__.get(n))]
                    bad += [f"{path.name}: {alias.name}.py_func calls {n}" for n in called]
    assert checked >= 15 and not bad, bad


def test_without_numba_cache_dir_the_kernels_are_cached_beside_the_fe_cache(tmp_path):
    """Without NUMBA_CACHE_DIR the kernels are cached under $LIGHTGEAR_CACHE/numba (the folder
    the Makefile gives, so that what `make run` compiled a `lightgear run` loads), and the study
    engine looks for them there, also after the process moved its FE cache elsewhere."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import solver.mbs.kernels as K
    root = Path(__file__).resolve().parents[3]
    code = ("import os; from solver.mbs.kernels.explicit import verlet; from study.sweep.engine import kernel_cache_folder; "
            "print(verlet._cache._cache_path); print(kernel_cache_folder()); "
            f"os.environ['LIGHTGEAR_CACHE'] = {str(tmp_path / 'moved')!r}; print(kernel_cache_folder())")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(root), LIGHTGEAR_CACHE=str(tmp_path / "lc"))
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True, text=True, check=True)
    path, folder, after_move = out.stdout.split()
    top = tmp_path / "lc" / "numba" / f"kernels-{K.KERNELS_FINGERPRINT}"
    assert Path(path).parent == top and Path(folder) == Path(path) == Path(after_move)


def test_kernels_pickle_for_another_process():
    """A stepping loop and a wrapper-less kernel pickle (as a dask task that holds them is sent
    to a worker) and load in a fresh process as the same kernels."""
    import pickle
    import subprocess
    import sys
    from pathlib import Path

    from solver.mbs.kernels.explicit_coupled import verlet_coupled
    from solver.mbs.kernels.toothcoupling import set_moment
    blob = pickle.dumps((verlet_coupled, set_moment))
    assert pickle.loads(blob)[1] is set_moment
    root = Path(__file__).resolve().parents[3]
    code = ("import pickle, sys; a, b = pickle.loads(sys.stdin.buffer.read()); "
            "print(type(a).__name__, a.py_func.__qualname__, type(b).__name__, b.py_func.__qualname__)")
    env = {**__import__("os").environ, "PYTHONPATH": str(root)}
    out = subprocess.run([sys.executable, "-c", code], input=blob, env=env, cwd=root, capture_output=True, check=True)
    assert out.stdout.decode().split() == ["CPUDispatcher", "verlet_coupled", "KernelOnlyDispatcher", "set_moment"]

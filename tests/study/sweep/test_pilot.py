"""A local dask sweep on a machine whose numba cache lacks the kernels compiles them once: the
pilot's entry kernels from a stand-in of its scenes at once, then one task (the pilot), then the
others after it."""
from pathlib import Path

import numba
import numpy as np
import pytest
from helpers import scene_overrides

from study.sweep import cluster
from study.sweep.engine import kernel_cache_folder, kernels_cached, run_sweep
from study.sweep.grid import loads_study
from study.sweep.outputs import STATUS

pytestmark = pytest.mark.usefixtures("private_fe_cache")

SCENE = "\n".join(f'"{k}" = {v!r}' for k, v in {**scene_overrides("small_pair"), "coupling.model": "paper", "quasi_static.rotation": 6.0,
                                                 "quasi_static.angle_step": 1.0, "dynamic.duration": 0.004,
                                                 "dynamic.ramp_time": 0.001}.items())
STUDY = f"""title = "pilot"
[scene]
{SCENE}
[grid]
"dynamic.speed" = [50.0, 60.0, 70.0]
[outputs]
scalars = ["ste_p2p", "dte_rms"]
"""


def test_the_kernel_cache_counts_as_warm_only_with_kernels_of_this_checkout(tmp_path, monkeypatch):
    # (imported before the cache folder moves below: numba fixes a kernel's folder at import)
    from solver.mbs.kernels.explicit import verlet
    from solver.mbs.kernels.explicit_coupled import verlet_coupled
    from solver.mbs.kernels.statics import solve_dense
    # the folder is the one numba itself files this checkout's kernels in
    assert kernel_cache_folder() == Path(solve_dense._cache._cache_path)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert not kernels_cached()
    stale = tmp_path / "kernels-0000000000000000" / kernel_cache_folder().name / "statics.nbi"   # other sources
    other = kernel_cache_folder().parent / "kernels_0123456789abcdef0123456789abcdef01234567" / "statics.nbi"
    for f in (stale, other):                                                   # another checkout's
        f.parent.mkdir(parents=True)
        f.write_bytes(b"")
    assert not kernels_cached()
    own = kernel_cache_folder() / "statics.solve_dense-31.py311.nbi"
    own.parent.mkdir(parents=True)
    own.write_bytes(b"")
    assert kernels_cached()
    # a cache filled by the paper model's runs lacks the coupled time stepping (and the reverse)
    assert not kernels_cached(coupled=True) and not kernels_cached(coupled=False)
    (kernel_cache_folder() / verlet._cache._cache_file._index_name).write_bytes(b"")
    assert kernels_cached(coupled=False) and not kernels_cached(coupled=True)
    (kernel_cache_folder() / verlet_coupled._cache._cache_file._index_name).write_bytes(b"")
    assert kernels_cached(coupled=True)


def test_a_cold_kernel_cache_runs_one_pilot_task_before_the_others(tmp_path, monkeypatch):
    import distributed
    st = loads_study(STUDY)
    submitted, batches, compiled = [], [], []
    real = distributed.Client.submit

    def submit(self, func, *args, **kw):
        future = real(self, func, *args, **kw)
        submitted.append((future.key, [a.key for a in args if isinstance(a, distributed.Future)]))
        batches.append(args[0])
        if future.key.startswith("lightgear-compile-"):
            future.add_done_callback(lambda f: compiled.append(f.result()))
        return future
    monkeypatch.setattr(distributed.Client, "submit", submit)
    monkeypatch.setattr(cluster, "kernels_cached", lambda coupled=None: False)
    res = run_sweep(st, tmp_path / "cold.nc", workers=2, progress=False)
    # first the pilot's kernels, compiled from a stand-in of its scenes without waiting for anything
    # (no FE: it overlaps a study's FE jobs), then the pilot after it, then the rest after the pilot
    (ahead, first), (pilot, before), *rest = submitted
    assert ahead.startswith("lightgear-compile-") and first == []
    assert before == [ahead] and len(rest) == len(submitted) - 2 >= 2
    assert all(after == [pilot] for _, after in rest)
    assert batches[0] == tuple(scene for _, scene, _ in batches[1])
    assert compiled == [["solver.mbs.kernels.explicit.verlet", "solver.mbs.kernels.gearmesh.pair_contacts",
                         "solver.mbs.kernels.statics.static_sweep"]]
    # the pilot runs the statics and a dynamic run of one body: every kernel compiled before the fan-out
    assert sorted(outputs.dynamic for _, _, outputs in batches[1]) == [False, True]
    assert len({scene.dynamic.speed for _, scene, _ in batches[1]}) == 1
    assert (res.dataset["status"] == STATUS.index("ok")).all()
    # a warm cache: no pilot, no waiting, the same numbers
    submitted.clear()
    monkeypatch.setattr(cluster, "kernels_cached", lambda coupled=None: True)
    warm = run_sweep(st, tmp_path / "warm.nc", workers=2, progress=False)
    assert all(after == [] for _, after in submitted)
    for name in ("ste_p2p", "dte_rms"):
        np.testing.assert_array_equal(res.dataset[name].values, warm.dataset[name].values)

"""A batch of tasks on dask stores each task's result as it finishes: a batch cut short (Ctrl-C,
its worker lost) keeps its finished tasks, and the resume computes only the others."""
import pickle

import numpy as np
import pytest
import xarray as xr
from sweep_cases import count_points, swept, tiny_study  # noqa: F401  (swept: the sweep, run once per session)

import study.sweep.cluster as cluster
from study.sweep.engine import PartStore, parts_folder, run_after, run_sweep
from study.sweep.grid import check_points
from study.sweep.outputs import STATUS
from study.sweep.tasks import batches, plan


def same_archive(a: xr.Dataset, b: xr.Dataset) -> None:
    """Equal but for each point's measured compute time and the write's date and command."""
    xr.testing.assert_identical(a.drop_vars("wall_time").assign_attrs(created="", history=""),
                                b.drop_vars("wall_time").assign_attrs(created="", history=""))


def test_a_batch_cut_short_keeps_its_finished_tasks_and_the_resume_computes_the_rest(swept, tmp_path, monkeypatch):
    res, _ = swept
    st = tiny_study()
    tasks, _ = plan(st, check_points(st))
    batch = tuple((t.key, t.scene, t.outputs) for t in list(tasks.values())[:3])
    out = tmp_path / "resumed.nc"
    count_points(monkeypatch, stop_after=2)          # Ctrl-C in the batch's third task
    with pytest.raises(KeyboardInterrupt):
        run_after(batch, parts=str(parts_folder(out)))
    stored = {f.stem for f in parts_folder(out).glob("*.pkl")}
    assert stored == {batch[0][0], batch[1][0]}
    for key, _, _ in batch[:2]:
        with open(parts_folder(out) / f"{key}.pkl", "rb") as f:
            part = pickle.load(f)
        assert part["status"] == "ok" and "stored" not in part
    monkeypatch.undo()
    # the batch tried again (dask's retry when its worker died) runs only its unfinished task
    calls = count_points(monkeypatch)
    retried = run_after(batch, parts=str(parts_folder(out)))
    assert len(calls) == 1 and [k for k, _ in retried] == [k for k, _, _ in batch]
    assert all(r["stored"] and r["status"] == "ok" for _, r in retried)
    # the resume of the study computes the tasks no batch finished
    calls.clear()
    again = run_sweep(st, out, workers=0, progress=False)
    assert again.reused == 3 and again.computed == len(tasks) - 3 == len(calls)
    same_archive(again.dataset, res.dataset)


def test_a_closing_worker_stores_nothing_and_a_remote_batch_leaves_the_store_to_the_client(tmp_path, monkeypatch):
    st = tiny_study()
    t = next(iter(plan(st, check_points(st))[0].values()))
    folder = tmp_path / "parts"
    # a worker whose cluster closes: its kernels were stopped, what it returns is no result to keep
    monkeypatch.setattr(cluster, "_CLOSING", True)
    [(key, r)] = run_after(((t.key, t.scene, t.outputs),), parts=str(folder))
    assert key == t.key and "stored" not in r and not folder.exists()
    monkeypatch.setattr(cluster, "_CLOSING", False)
    # no part folder given (a scheduler elsewhere, whose workers may not share this disk)
    [(_, r)] = run_after(((t.key, t.scene, t.outputs),))
    assert "stored" not in r and not folder.exists()
    [(_, r)] = run_after(((t.key, t.scene, t.outputs),), parts=str(folder))
    assert r.pop("stored") is True
    np.testing.assert_equal(PartStore(folder).get(t.key), r)


GRID = """
[grid]
gear2.body.holes = [0, 4]
"dynamic.speed" = {start = 50.0, stop = 100.0, num = 8}
[outputs]
scalars = ["ste_p2p", "dte_rms"]
"""


def test_on_a_local_cluster_the_workers_store_the_tasks_of_their_batches(tmp_path, monkeypatch):
    st = tiny_study(GRID)
    tasks, _ = plan(st, check_points(st))
    grouped = batches(list(tasks.values()), workers=2)
    assert len(tasks) == 2 + 16 and any(len(b) > 1 for b in grouped)
    by_client = []
    real_put = PartStore.put
    monkeypatch.setattr(PartStore, "put", lambda self, key, result: by_client.append(key) or real_put(self, key, result))
    monkeypatch.setattr(cluster, "kernels_cached", lambda coupled=None: True)     # no pilot task: the batches above
    out = tmp_path / "dask.nc"
    res = run_sweep(st, out, workers=2, progress=False, keep_parts=True)
    assert (res.dataset["status"] == STATUS.index("ok")).all()
    # every task stored once: the client stores the lone tasks, the workers those of their batches
    assert {f.stem for f in parts_folder(out).glob("*.pkl")} == set(tasks)
    assert len(by_client) == len(set(by_client)) == sum(len(b) == 1 for b in grouped) < len(tasks)
    same_archive(res.dataset, run_sweep(st, tmp_path / "here.nc", workers=0, progress=False).dataset)

"""The tiny study the sweep, grid and archive tests share, and its sweep run once per session."""
import contextlib

import pytest

from study.sweep.engine import run_sweep
from study.sweep.grid import loads_study

# A 20-tooth solid-driver pair with small bodies, uniform springs (no FE), a few degrees of STE
# and 12 ms of DTE (8 ms after the ramps: more than a mesh period at 50 rad/s, which the DTE RMS
# needs): about a third of a second per point.
BASE = """
[scene]
gear1.teeth = 20
gear2.teeth = 20
gear1.body = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0}
gear2.body = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0, holes = 0, hole_radius = 1.5, hole_circle_radius = 8.1, web_thickness = 17.0}
gear2.spring.stiffness = "uniform"
coupling.model = "paper"                # the engine's tests: no FE, the paper's springs
quasi_static = {rotation = 6.0, angle_step = 0.5}
dynamic = {duration = 0.012, ramp_time = 0.002}
"""
GRID = """
[grid]
gear2.body.holes = [0, 4]
"dynamic.speed" = {start = 50.0, stop = 100.0, num = 2}
gear2.body.web_thickness = [12.0, 17.0]
[outputs]
curves = ["ste", "dte_amplitude"]
"""


def tiny_study(grid=GRID, base=BASE, title="tiny"):
    return loads_study(f'title = "{title}"\n' + base + grid)




@pytest.fixture(scope="session")
def swept(tmp_path_factory):
    """The tiny study swept in process, once per test session -> (SweepResult, archive path).
    Tests only read it (and copy the archive before they change anything)."""
    out = tmp_path_factory.mktemp("sweep") / "tiny.nc"
    return run_sweep(tiny_study(), out, workers=0, progress=False), out


def count_points(monkeypatch, stop_after: int | None = None) -> list:
    """Patch `run_point` where the sweep calls it (`study.sweep.engine` in process,
    `study.sweep.cluster.run_after` in a batch) to record each point's scene in the returned
    list, and, with ``stop_after``, to raise KeyboardInterrupt (a Ctrl-C mid-study) when that
    many points have run."""
    import study.sweep.cluster as cluster
    import study.sweep.engine as engine
    real = engine.run_point
    calls = []

    def run(scene, outputs):
        if stop_after is not None and len(calls) == stop_after:
            raise KeyboardInterrupt
        calls.append(scene)
        return real(scene, outputs)

    monkeypatch.setattr(engine, "run_point", run)
    monkeypatch.setattr(cluster, "run_point", run)
    return calls


@contextlib.contextmanager
def ctrl_c_after_stored(monkeypatch, n: int):
    """Within: the client's `PartStore.put` raises KeyboardInterrupt once ``n`` parts are stored
    (a Ctrl-C mid-study, with workers); after: the real put again."""
    import study.sweep.engine as engine
    real_put = engine.PartStore.put
    stored = []

    def put(self, key, result):
        if len(stored) == n:
            raise KeyboardInterrupt
        stored.append(key)
        real_put(self, key, result)

    monkeypatch.setattr(engine.PartStore, "put", put)
    try:
        yield stored
    finally:
        monkeypatch.setattr(engine.PartStore, "put", real_put)


def assert_refused_before_any_work(monkeypatch, make_study, text: str, field: str, reason: str) -> None:
    """``make_study(text)`` raises a SceneError naming ``field``, with ``reason`` in its message,
    and no point of the study starts to run."""
    import study.sweep.engine as engine
    from study.scene import SceneError
    monkeypatch.setattr(engine, "run_point", lambda *a: pytest.fail("work started"))
    with pytest.raises(SceneError) as e:
        make_study(text)
    assert e.value.field == field and reason in str(e.value), str(e.value)

"""FE spring maps of a study: each listed once per distinct body, computed first on dask, and the
sweep's numbers unchanged by it."""
import numpy as np
import pytest
from helpers import scene_overrides

from solver.store import STORE
from study.inputs.cache import FE_CACHE
from study.inputs.gearsetup import gear_setup
from study.inputs.springs import tooth_springs
from study.sweep import cluster, engine
from study.sweep.bodies import compute_body, compute_map, fe_jobs, job_rim, spring_maps
from study.sweep.engine import run_sweep
from study.sweep.grid import loads_study
from study.sweep.outputs import STATUS
from study.sweep.tasks import plan

pytestmark = pytest.mark.usefixtures("private_fe_cache")

SCENE = "\n".join(f'"{k}" = {v!r}' if not isinstance(v, str) else f'"{k}" = "{v}"' for k, v in {
    **scene_overrides("small_pair"), "gear2.body.hole_radius": 3.0, "gear2.body.hole_circle_radius": 19.5,
    "quasi_static.rotation": 6.0, "quasi_static.angle_step": 1.0, "dynamic.duration": 0.004,
    "dynamic.ramp_time": 0.001, "fe.mesh_size": 1.5,
    "coupling.model": "paper"}.items())     # the maps computed ahead are the paper model's springs
# 3 lightened bodies (holes and/or a 12 mm web) and the solid one (no holes, 20 mm web): the
# lightened ones share one solid reference (same rim), so 4 maps for the 9 tasks that read them
STUDY = f"""title = "maps"
[scene]
{SCENE}
[grid]
"gear2.body.holes" = [0, 4]
"gear2.body.web_thickness" = [12.0, 20.0]
"dynamic.speed" = [50.0, 60.0]
[outputs]
scalars = ["ste_p2p", "dte_rms", "root_stress_max_gear2"]
"""


def maps_of(study):
    tasks, _ = plan(study, list(study.points()))
    return {key: spring_maps(t.scene) for key, t in tasks.items()}


def test_each_lightened_body_needs_its_map_and_the_shared_solid_reference():
    st = loads_study(STUDY)
    per_task = maps_of(st)
    distinct = {k for maps in per_task.values() for k, _, _ in maps}
    lightened = [t for t, maps in per_task.items() if maps]
    assert len(per_task) == 4 * 3 and len(lightened) == 3 * 3     # 4 bodies: a static task and 2 speeds each
    assert all(len(maps) == 2 for t, maps in per_task.items() if maps)   # the body's map and the solid reference
    assert len(distinct) == 3 + 1
    # a map already on disk is not listed again
    key, setup, teeth = next(iter(per_task[lightened[0]]))
    compute_map(setup, teeth)
    assert key not in {k for maps in maps_of(st).values() for k, _, _ in maps}
    # uniform springs read no map
    uniform = loads_study(STUDY.replace("[grid]", '"gear2.spring.stiffness" = "uniform"\n[grid]'))
    assert not any(maps_of(uniform).values())


def test_a_dask_sweep_computes_each_map_once_before_the_tasks_that_read_it(tmp_path, monkeypatch):
    import distributed
    st = loads_study(STUDY)
    submitted = []
    real = distributed.Client.submit

    def submit(self, func, *args, **kw):
        future = real(self, func, *args, **kw)
        submitted.append((func.__name__, future.key, [a.key for a in args if isinstance(a, distributed.Future)]))
        return future
    monkeypatch.setattr(distributed.Client, "submit", submit)
    monkeypatch.setattr(cluster, "kernels_cached", lambda coupled=None: True)     # no pilot task (test_pilot)
    res = run_sweep(st, tmp_path / "dask.nc", workers=2, progress=False)
    maps = [key for name, key, _ in submitted if name == "compute_map"]
    assert len(maps) == len(set(maps)) == 4
    waits = {key: after for name, key, after in submitted if name == "run_after"}
    assert len(waits) == 12 and sum(bool(a) for a in waits.values()) == 9
    assert all(set(a) <= set(maps) and len(a) == 2 for a in waits.values() if a)
    assert (res.dataset["status"] == STATUS.index("ok")).all()
    # the same numbers as the study run in this process from an empty FE cache (the maps then
    # computed by the tasks themselves), to the last bit: here one process condenses the rim
    # once and joins each later web to it; on dask the rim's first job condenses it and the
    # other jobs read it, its nodes included, from the disk
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "another cache"))
    STORE.clear()
    alone = run_sweep(st, tmp_path / "alone.nc", workers=0, progress=False)
    for name in ("ste_p2p", "dte_rms", "root_stress_max_gear2"):
        np.testing.assert_array_equal(res.dataset[name].values, alone.dataset[name].values, err_msg=name)


def test_the_listed_maps_are_the_ones_the_springs_read():
    st = loads_study(STUDY)
    scene = next(p.scene for p in st.points() if p.scene.gear2.body.holes == 4)
    listed = {k for k, _, _ in spring_maps(scene)}
    tooth_springs(gear_setup(scene, 2))          # the springs compute (and cache) what they read
    assert set(FE_CACHE.stiffness) == listed and len(listed) == 2
    assert spring_maps(scene) == []              # now on disk


# the compliance model ('auto' for a lightened gear): its coupling fit reads the body's bulk
# compliance, computed with the body's spring map in one job per body
COMPLIANCE = STUDY.replace('"coupling.model" = "paper"', '"coupling.model" = "compliance"')


def jobs_of(study):
    tasks, _ = plan(study, list(study.points()))
    return {key: fe_jobs(t.scene) for key, t in tasks.items()}


def test_the_compliance_model_lists_one_body_job_per_gear_body_and_the_solid_references():
    st = loads_study(COMPLIANCE)
    per_task = jobs_of(st)
    bodies = {k for jobs in per_task.values() for k, f, _ in jobs if f is compute_body}
    maps = {k for jobs in per_task.values() for k, f, _ in jobs if f is compute_map}
    # gear 2's 3 lightened bodies, and one solid body: gear 1's, which the solid gear 2 (same
    # 24-tooth gear) shares; one solid reference map shared by the 3 lightened bodies
    assert len(bodies) == 3 + 1 and len(maps) == 1
    assert all(len(jobs) == 3 for jobs in per_task.values() if any(f is compute_map for _, f, _ in jobs))
    # what one job computes, the tasks of that body no longer list
    scene = next(t for t in plan(st, list(st.points()))[0].values() if t.scene.gear2.body.holes == 4).scene
    for _key, func, args in fe_jobs(scene):
        func(*args)
    assert fe_jobs(scene) == []
    STORE.clear()                      # and it is on disk, not only in this process
    assert fe_jobs(scene) == []


def test_a_compliance_sweep_on_dask_equals_the_one_that_computes_its_fe_in_the_tasks(tmp_path, monkeypatch):
    import distributed
    st = loads_study(COMPLIANCE)
    submitted = []
    real = distributed.Client.submit

    def submit(self, func, *args, **kw):
        future = real(self, func, *args, **kw)
        submitted.append((func.__name__, future.key, [a.key for a in args if isinstance(a, distributed.Future)]))
        return future
    monkeypatch.setattr(distributed.Client, "submit", submit)
    monkeypatch.setattr(cluster, "kernels_cached", lambda coupled=None: True)     # no pilot task (test_pilot)
    res = run_sweep(st, tmp_path / "dask.nc", workers=2, progress=False)
    names = [name for name, _, _ in submitted]
    assert names.count("compute_body") == 4 and names.count("compute_map") == 1
    # the FE jobs go first; each rim's first job waits for nothing, the rim's other jobs for it
    fe = {key: after for name, key, after in submitted if name != "run_after"}
    assert names.index("run_after") == len(fe)
    first = {key for key, after in fe.items() if not after}
    assert first and all(set(after) <= first and len(after) == 1 for after in fe.values() if after)
    assert (res.dataset["status"] == STATUS.index("ok")).all()
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "another cache"))
    STORE.clear()
    alone = run_sweep(st, tmp_path / "alone.nc", workers=0, progress=False)
    # equal to round-off: the compliance comes from another process (and the disk) in one, the
    # same factorisation in the other: they differ in the last digits (2e-10 relative measured)
    for name in ("ste_p2p", "dte_rms", "root_stress_max_gear2"):
        np.testing.assert_allclose(res.dataset[name].values, alone.dataset[name].values, rtol=1e-8)


def test_each_rim_is_condensed_by_one_job_and_the_other_jobs_of_the_rim_read_it_after():
    from study import parse_overrides
    from study.inputs.compliance import rim_key
    from study.inputs.gearsetup import gear_setups
    st = loads_study(COMPLIANCE)
    jobs = {k: (f, a, 2) for per in jobs_of(st).values() for k, f, a in per}
    rims = {k: job_rim(f, a) for k, (f, a, _) in jobs.items()}
    # gear 1 (solid) and gear 2's 3 lightened bodies, one rim height, and the solid reference
    # (the same 24-tooth gear): all five read one rim; another rim height, another rim
    scene = next(iter(st.points())).scene
    g1, g2 = gear_setups(scene)
    assert set(rims.values()) == {rim_key(g1)} == {rim_key(g2)} and len(jobs) == 5
    deeper = scene.replace(**parse_overrides([f"gear2.body.rim_height={scene.gear2.body.rim_height + 1.0}"]))
    assert job_rim(compute_body, (deeper, 2)) not in (None, rim_key(g2))
    firsts, rest = engine.rims_first(jobs, job_rim)
    assert [rims[k] for k, *_ in firsts] == [rim_key(g2)] and all(leader is None for *_, leader in firsts)
    assert len(rest) == 4 and all(leader == firsts[0][0] for *_, leader in rest)
    # the rim's first job leaves it on disk: the others read it there
    _, func, args, _, _ = firsts[0]
    func(*args)
    assert (FE_CACHE.folder / f"rim-{rim_key(g2)}.npz").is_file()

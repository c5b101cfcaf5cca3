"""Estimates count what the caches already hold as free: the FE bodies of the springs and the
FE reference's influence coefficients."""
import study
from study import estimate


def small_fe_scene():
    """The README's small pair with FE springs on the lightened driven gear, coarse mesh."""
    return study.load_study("example_study").base_scene().replace(**{
        "gear2.spring.stiffness": "fe-ratio", "gear2.body.holes": 4, "gear2.body.hole_radius": 1.8,
        "fe.mesh_size": 0.75, "quasi_static.rotation": 3.0,
        "coupling.model": "paper"})     # the spring maps alone (the compliance model also loads gear 1's body)


def test_cached_fe_bodies_and_influence_coefficients_are_free(private_fe_cache):
    from study.inputs.gearsetup import gear_setups
    scene = small_fe_scene()
    setups, coupling = gear_setups(scene), scene.coupling_model
    labels = [label for label, _s, _t in estimate.fe_bodies(setups, coupling)]
    assert labels == ["gear 2", "gear 2 solid reference"] and estimate.fe_seconds(setups, coupling) > 0
    study.stiffness(scene)
    assert estimate.fe_bodies(setups, coupling) == [] and estimate.fe_seconds(setups, coupling) == 0.0
    from study.scene_model import static_angles
    from study.verify.fe_reference import reference_cost
    angles = static_angles(scene)
    before = reference_cost(scene, angles).seconds
    assert before["gear 1 FE body"] > 0 and before["gear 2 FE body"] > 0
    ds = study.reference(scene)
    after = reference_cost(scene, angles).seconds
    assert after["gear 1 FE body"] == 0.0 and after["gear 2 FE body"] == 0.0
    assert after["contact sweep"] > 0       # the contact problems are solved each time
    # a finer angle step reads other teeth only if new ones enter the mesh: here none, still free
    assert reference_cost(scene, static_angles(scene, 0.25)).seconds["gear 2 FE body"] == 0.0
    assert ds.sizes["angle"] == angles.size
    private_fe_cache.clear()                  # memory dropped: the disk cache still answers
    assert reference_cost(scene, angles).seconds["gear 1 FE body"] == 0.0


def test_a_rim_is_counted_once_and_free_once_on_disk(private_fe_cache):
    """Bodies solved through their condensed teeth and rim: the first body of a rim counts the
    rim and its web, every other body of the rim (another web, other holes) its web alone, and
    a rim the disk cache holds counts for nothing: the standard study's 36 bodies on three rims
    cost about what a study's workers take (50-60 s of CPU, not the six times that of bodies
    counted whole)."""
    from study.inputs.compliance import rim_key
    from study.inputs.gearsetup import gear_setups
    from study.sweep.cost import sweep_estimate
    from study.sweep.grid import check_points
    from study.sweep.tasks import plan
    scene = small_fe_scene()
    bodies = [gear_setups(scene.replace(**{"gear2.body.holes": n}))[1] for n in (3, 4, 5)]
    b = estimate.body_seconds(bodies[0])
    rims: set = set()
    costs = [estimate.body_estimate("gear 2", s, "compliance", rims) for s in bodies]
    assert rims == {rim_key(bodies[0])}
    assert costs[0] == b * (estimate.RIM_SHARE + estimate.WEB_SHARE)
    assert costs[1:] == [estimate.body_seconds(s) * estimate.WEB_SHARE for s in bodies[1:]]
    from study.inputs.cache import FE_CACHE
    FE_CACHE.folder.mkdir(parents=True, exist_ok=True)
    (FE_CACHE.folder / f"rim-{rim_key(bodies[0])}.npz").write_bytes(b"")
    assert estimate.body_estimate("gear 2", bodies[0], "compliance", set()) == b * estimate.WEB_SHARE
    st = study.load_study("sensitivity")
    tasks, _ = plan(st, check_points(st))
    assert 40.0 < sweep_estimate(list(tasks.values())).seconds["FE bodies"] < 80.0

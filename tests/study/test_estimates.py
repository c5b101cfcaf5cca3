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

"""The FE inputs of a study through the condensed teeth and rim: the spring map, its root stress
and the bulk compliance equal those of the whole-body factorisation, one rim serves every web
of its rim height (in memory and from the disk cache), and another rim height gets its own."""
import numpy as np
import pytest

from solver.store import STORE
from study.inputs import compliance, springs
from study.inputs.cache import FE_CACHE
from study.inputs.gearsetup import gear_setup
from study.scene import load_scene

pytestmark = pytest.mark.usefixtures("private_fe_cache")


def small_scene(**kw):
    """The small 24-tooth pair (the small_pair scene), the driven gear with a web of 8 mm and 4 holes,
    on a coarse FE mesh (1.5 mm, half the module: what is checked is the condensation and the
    caches, which any mesh size exercises, not the FE's accuracy)."""
    return load_scene("small_pair").replace(**{"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4,
                                      "gear2.body.hole_radius": 3.0, "gear2.body.hole_circle_radius": 19.5, "fe.mesh_size": 1.5, **kw})


def _inputs(setup):
    """(spring map [N m/rad], root stress [Pa], compliance [m/N]) of a gear, from empty memory."""
    for held in (FE_CACHE.stiffness, FE_CACHE.root_stress, FE_CACHE.compliance, FE_CACHE.bodies):
        held.clear()
    teeth = list(range(setup.teeth))
    k = springs.fe_stiffness(setup)
    s = springs.root_stress(setup)
    c, _ = compliance.gear_compliance(setup, teeth, 0, n_u=4, u=None)
    return k, s, c.g


def test_condensed_inputs_equal_the_whole_body(monkeypatch, tmp_path):
    """The condensed body solves as the whole-body factorisation of its own (joined) mesh to
    rounding; against the body meshed whole (whose web gmsh triangulates a little otherwise)
    within the mesh's own scatter, far inside the FE tolerances (0.5 % stiffness)."""
    from solver.fe import body as fe
    bodies = [small_scene(), small_scene(**{"gear2.body.holes": 0, "gear2.body.web_thickness": 5.0})]
    got = []
    for scene in bodies:
        setup = gear_setup(scene, 2)
        got.append(_inputs(setup))
        model = list(FE_CACHE.bodies.values())[-1]
        assert model.condensed is not None
        same_mesh = fe.assemble(model.mesh, setup.geometry.spec.face_width, setup.body.web_thickness, setup.material)
        k_whole, _ = fe.tooth_stiffness(same_mesh, setup.geometry, setup.pivot_radius, range(setup.teeth),
                                        setup.force, setup.patch)
        assert np.abs(got[-1][0] / k_whole - 1).max() < 1e-9
    assert len(FE_CACHE.rims) == 1                          # both webs on one rim
    assert len(list((tmp_path / "cache" / "fe").glob("rim-*.npz"))) == 2   # its S_R and one load set
    monkeypatch.setattr(compliance, "CONDENSE", False)
    for scene, (k, s, g) in zip(bodies, got):
        for f in (tmp_path / "cache" / "fe").glob("*"):
            if not f.name.startswith("rim-"):
                f.unlink()
        k0, s0, g0 = _inputs(gear_setup(scene, 2))
        assert list(FE_CACHE.bodies.values())[-1].condensed is None
        assert np.abs(k / k0 - 1).max() < 1e-5
        assert np.abs(s / s0 - 1).max() < 1e-5
        assert np.abs(g - g0).max() < 1e-5 * np.abs(g0).max()


def test_a_rim_read_from_disk_gives_the_same_inputs_and_another_rim_height_its_own(tmp_path):
    setup = gear_setup(small_scene(), 2)
    first = _inputs(setup)
    # the same body again, its web now meshed alone and joined to the kept rim: the same bits
    for f in (tmp_path / "cache" / "fe").glob("*"):
        if not f.name.startswith("rim-"):
            f.unlink()
    for a, b in zip(first, _inputs(setup)):
        assert np.array_equal(a, b)
    STORE.clear()                                        # a new process: the rim from disk
    for f in (tmp_path / "cache" / "fe").glob("*"):
        if not f.name.startswith("rim-"):
            f.unlink()
    again = _inputs(setup)
    rim = next(iter(FE_CACHE.rims.values()))
    assert rim.split is None                                # S_R and the products came from disk
    for a, b in zip(first, again):
        assert np.array_equal(a, b)
    deeper = gear_setup(small_scene(**{"gear2.body.rim_height": 5.0}), 2)
    assert compliance.rim_key(deeper) != compliance.rim_key(setup)
    assert compliance.rim_key(gear_setup(small_scene(**{"gear2.body.holes": 6}), 2)) == compliance.rim_key(setup)
    k = springs.fe_stiffness(deeper)
    assert len(FE_CACHE.rims) == 2 and k.shape == (setup.teeth,)


def test_a_body_gets_the_same_bits_whichever_body_of_its_rim_came_first(tmp_path, monkeypatch):
    """Two bodies' meshes hold the same rim elements with nodes up to a few 1e-16 m apart (a
    fifth of the shared nodes at this mesh; 1e-13 in the spring map at the default one): the rim is condensed from a body of its own, so a body's inputs are the
    same bits alone in a fresh cache, after another body of its rim (in memory, or from disk in
    a new process), and computed again after that body when it came first."""
    first, other = (gear_setup(small_scene(**kw), 2) for kw in ({}, {"gear2.body.holes": 0, "gear2.body.web_thickness": 5.0}))
    assert compliance.rim_key(first) == compliance.rim_key(other)

    def fresh(name):                                    # an empty disk cache and an empty memory
        monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / name))
        STORE.clear()
    fresh("alone")
    alone = _inputs(other)
    fresh("after")
    _inputs(first)                                      # the rim condensed for the first body
    after = {"in memory": _inputs(other)}
    STORE.clear()                                       # a new process: the rim from disk
    after["from disk"] = _inputs(other)
    fresh("before")
    _inputs(other)
    _inputs(first)
    STORE.clear()
    for f in (tmp_path / "before" / "fe").glob("*"):     # only the rim stays on disk
        if not f.name.startswith("rim-"):
            f.unlink()
    after["again after the other"] = _inputs(other)
    for how, got in after.items():
        for name, a, b in zip(("spring map", "root stress", "compliance"), alone, got):
            assert np.array_equal(a, b), f"{name} {how}: {np.abs(a / b - 1).max():.1e} from the body alone"

"""Gear setups (scene -> FE settings, once) and the FE cache object: keys, disk layout, memory."""
import math

import numpy as np
import pytest

from solver.geometry import gear_geometry
from solver.store import STORE
from study.inputs.cache import BODY_SLOTS, FECache
from study.inputs.gearsetup import gear_setup, gear_setups
from study.scene import default_scene


def test_setup_holds_the_scene_in_si_and_the_shared_fe_load():
    s = default_scene()
    g1, g2 = gear_setups(s)
    assert (g1.gear, g2.gear) == (1, 2) and g2 == gear_setup(s, 2)
    assert g2.tooth == s.tooth_spec(2) and g2.body == s.body_spec(2) and g2.material == s.material_spec()
    assert g2.geometry == gear_geometry(s.tooth_spec(2)) and g2.pivot_radius == g2.geometry.root_radius
    assert g2.lightened and not g1.lightened
    # the reference load sets the same torque on both bodies: F = T / rb
    assert g2.force * g2.geometry.base_radius == pytest.approx(s.quasi_static.torque, rel=1e-15)
    assert g2.mesh_size == pytest.approx(1.5e-3 / 4) and g2.settings["size"] is None
    # the patch is the Hertz half-width, which grows as the root of the load, or half an element
    g2x4 = gear_setup(s.replace(**{"quasi_static.torque": 4 * s.quasi_static.torque}), 2)
    assert g2x4.hertz_half_width == pytest.approx(2 * g2.hertz_half_width, rel=1e-12)
    assert g2.patch == max(g2.hertz_half_width, g2.mesh_size / 2)
    # the start of the active profile lies on the flank, between the form circle and the pitch point
    assert g2.geometry.u_form < g2.sap_roll < math.tan(g2.tooth.pressure_angle)


def test_cache_keys_stay_those_of_the_stored_files():
    """The keys name the files of existing caches: the paper pair's driven gear, its solid
    reference and the solid driver keep their names (change them only with FE_VERSION, as for
    version 4: the webs condensed by compiled sparse solves); fine and graded meshes have their
    own."""
    def keys(scene):
        g2 = gear_setups(scene)[1]
        return {FECache.key({**g.settings, "teeth": t}) for g, t in ((g2, list(range(67))), (g2.solid(), [0]))}
    assert keys(default_scene().replace(**{"fe.mesh_grading": "fine"})) == {"d53efe139f0bf584cd0c", "09d2b32774445de087fb"}
    assert keys(default_scene()) == {"bf5824bad98188be653d", "23306a44fac7d2cbb612"}
    g1, g2 = gear_setups(default_scene())
    # a solid body's hole sizes do not matter, whichever way the body was made solid
    s = default_scene().solid()
    assert gear_setup(s, 2).key == g2.solid().key == g1.key != g2.key
    assert gear_setup(s.replace(**{"gear2.body.hole_radius": 2.0}), 2).key == g2.solid().key


def test_fe_cache_reads_back_from_disk_and_forgets_memory_on_clear(tmp_path, monkeypatch):
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path))
    cache = FECache()
    assert cache.folder == tmp_path / "fe" and cache.read_stiffness("k") is None
    k = np.array([1.0, 2.0, 3.0])
    cache.write_stiffness("k", k, {"what": "test"})
    got = cache.read_stiffness("k")
    got[0] = 99.0                                   # callers get copies
    assert np.array_equal(cache.read_stiffness("k"), k)
    STORE.clear()
    assert not cache.stiffness and np.array_equal(cache.read_stiffness("k"), k)    # from disk
    (tmp_path / "fe" / "bad.nc").write_text("not NetCDF")
    assert cache.read_stiffness("bad") is None      # unreadable: recomputed by the caller


def test_fe_cache_keeps_the_last_bodies_and_fits():
    cache = FECache()
    built = []
    for key in ("a", "b", "a", "c", "a", "b"):
        cache.body(key, lambda key=key: built.append(key) or key)
    # "a" stays the most recently used: "b" was dropped for "c", then "c" for "b"
    assert built == ["a", "b", "c", "b"] and len(cache.bodies) == BODY_SLOTS
    assert cache.fit(("x", 1), lambda: [1]) is cache.fit(("x", 1), lambda: [2])
    STORE.clear()
    assert not cache.bodies and not cache.fits

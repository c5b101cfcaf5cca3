"""The FE cache's files: every kind read by one reader, a damaged file computed again with a
warning naming it (never an error that stops every later run until it is deleted by hand)."""
import warnings

import numpy as np
import pytest

from solver.fe.body import BodyField
from solver.fe.flank_compliance import BodyCompliance
from study.inputs.cache import FE_CACHE


def _fields():
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    return [BodyField(pts, np.array([[0, 1, 2]]), np.ones(3), np.zeros(3, bool), np.zeros((3, 2)), np.ones(1), 0, 10.0,
                      np.zeros(2), np.array([1.0, 0.0]))]


def _write_each_kind(cache):
    cache.write_stiffness("k1", np.array([1.0, 2.0]), {"a": 1}, root_stress=np.array([3.0, 4.0]))
    cache.write_compliance("c1", BodyCompliance(np.ones(2), np.array([0]), np.array([0]), np.ones((1, 2, 1, 2)), True, 2))
    cache.write_fields("f1", _fields())
    cache.write_arrays("rim-r1", S=np.eye(2))


def _read_each_kind(cache):
    return {"k1.nc": cache.read_stiffness("k1"), "ltca-c1.npz": cache.read_compliance("c1"),
            "fields-f1.npz": cache.read_fields("f1"), "rim-r1.npz": cache.read_arrays("rim-r1")}


@pytest.mark.parametrize("damage", ["truncated", "empty"])
def test_a_damaged_cache_file_of_any_kind_is_computed_again_with_a_warning(private_fe_cache, damage):
    cache = FE_CACHE
    _write_each_kind(cache)
    private_fe_cache.clear()      # memory dropped: the files answer
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert all(v is not None for v in _read_each_kind(cache).values())      # the round trip
    np.testing.assert_array_equal(cache.read_stiffness("k1"), [1.0, 2.0])
    for name in _read_each_kind(cache):
        path = cache.folder / name
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2] if damage == "truncated" else b"")
    private_fe_cache.clear()      # memory dropped: the files answer
    with pytest.warns(RuntimeWarning) as caught:
        read = _read_each_kind(cache)
    assert all(v is None for v in read.values()), read
    said = " ".join(str(w.message) for w in caught)
    for name in read:
        assert f"damaged FE cache file {cache.folder / name}" in said and "computing it again" in said


def test_a_map_without_its_stresses_is_no_damage(private_fe_cache):
    cache = FE_CACHE
    cache.write_stiffness("k2", np.array([1.0]), {"a": 2})
    private_fe_cache.clear()      # memory dropped: the files answer
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cache.read_root_stress("k2") is None and cache.read_stiffness("k2") is not None

"""The one store of computed results (`solver.store`): a shelf holds its last results up to its
bound, the least recently used going first and before a new one is made; one clear empties
every shelf; the key of a result is its content (arrays in full, dataclasses by their fields)."""
import dataclasses

import numpy as np
import pytest

from solver.store import STORE, Shelf, Store, digest


def test_a_shelf_keeps_its_last_results_up_to_its_bound_least_recently_used_first():
    shelf = Shelf("test", 2)
    made = []

    def make(v):
        def build():
            assert len(shelf) < 2              # room is made before the new result is built
            made.append(v)
            return v * 10
        return build
    assert shelf.kept("a", make(1)) == 10 and shelf.kept("b", make(2)) == 20
    assert shelf.kept("a", make(99)) == 10           # held: not made again, now the most recent
    assert shelf.kept("c", make(3)) == 30            # "b", the least recently used, goes
    assert list(shelf) == ["a", "c"] and made == [1, 2, 3]
    shelf["d"] = 40                                  # put directly: the bound holds too
    assert list(shelf) == ["c", "d"]
    with pytest.raises(ZeroDivisionError):
        shelf.kept("e", lambda: 1 / 0)               # a failure keeps nothing
    assert "e" not in shelf
    with pytest.raises(ValueError, match="slots must be >= 1"):
        Shelf("none", 0)


def test_one_clear_empties_every_shelf_and_a_name_is_one_shelf():
    store = Store()
    a, b = store.shelf("a", 2), store.shelf("b", 3)
    assert store.shelf("a", 2) is a
    with pytest.raises(ValueError, match="holds 2 results"):
        store.shelf("a", 5)
    a.kept(1, lambda: "x")
    b.kept(2, lambda: "y")
    assert store.sizes() == {"a": 1, "b": 1}
    store.clear()
    assert store.sizes() == {"a": 0, "b": 0}


def test_the_process_store_holds_the_fe_results_models_and_equilibria():
    import solver.mbs.equilibria  # noqa: F401
    import solver.mbs.memo  # noqa: F401
    import study.inputs.cache  # noqa: F401
    import study.scene_model  # noqa: F401
    assert {"FE tooth stiffness maps", "FE bulk compliances", "FE factorised bodies", "FE condensed rims",
            "coupling fits", "scene models", "loaded equilibria", "model-only analyses"} <= set(STORE.shelves)


@dataclasses.dataclass(frozen=True)
class Section:
    values: tuple
    k: float


def test_a_key_is_the_content():
    big = np.arange(2000.0)
    other = big.copy()
    other[1000] += 1e-12                             # beyond what NumPy's shortened repr shows
    assert digest(big) == digest(big.copy()) and digest(big) != digest(other)
    assert digest({"a": big}) != digest({"a": other})           # arrays inside in full
    assert digest(big) != digest(big.astype(np.float32)) != digest(big.reshape(40, 50))
    assert digest({"x": 1, "y": 2}) == digest({"y": 2, "x": 1})
    assert digest(Section((1, 2), 3.0)) == digest(Section((1, 2), 3.0)) != digest(Section((1, 2), 3.0000001))
    assert digest("a", "b") != digest("ab") and len(digest(1)) == 32

"""Shared fixtures: a private FE cache, the example study's small scene as a file, the paper pair
with a solid driven gear and its model.
The scenes and checks the tests share are in helpers.py."""
import os

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pytest  # noqa: E402
import tiers  # noqa: E402
from helpers import solid_scene  # noqa: E402


def pytest_collection_modifyitems(config, items):
    """Markers of what each test reaches (FE, solver, processes): `tiers`, which ``make test-fast`` leaves out."""
    tiers.mark(items, pytest)


@pytest.fixture
def private_fe_cache(tmp_path, monkeypatch):
    """FE results of the test go to a fresh disk cache, and nothing the process holds in memory
    (the shelves of `solver.store.STORE`: spring maps, compliances, factorised bodies, rims,
    coupling fits, models, equilibria, model-only analyses) leaks in or out. Yields the store:
    ``private_fe_cache.clear()`` drops what memory holds, the disk cache stays."""
    from solver.store import STORE
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(tmp_path / "cache"))
    STORE.clear()
    yield STORE
    STORE.clear()


@pytest.fixture(scope="module")
def example_scene_file(tmp_path_factory):
    """The example study's 20-tooth base scene (uniform springs: no FE) as a scene file."""
    import study
    path = tmp_path_factory.mktemp("scene") / "small.toml"
    path.write_text(study.load_study("example_study").base_scene().to_toml())
    return path


@pytest.fixture(scope="session")
def paper_solid_scene():
    return solid_scene()


@pytest.fixture(scope="session")
def paper_solid_model(paper_solid_scene):
    from study.scene_model import build_scene_model
    return build_scene_model(paper_solid_scene)

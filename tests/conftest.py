"""Shared fixtures: a private FE cache, the example study's small scene as a file, the paper pair
with a solid driven gear and its model.
The scenes and checks the tests share are in helpers.py."""
import os

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pytest  # noqa: E402
import tiers  # noqa: E402
from helpers import solid_scene  # noqa: E402

# The test files that take longest from a fresh clone, about longest first (CPU seconds on two
# shared cores at a load of about 15: benchmarks/README.md, "Test tiers"). `make test` hands
# whole files to its two processes in the order collected (``--no-loadscope-reorder``): these
# first, so that neither process starts a long file while the other is nearly done; the rest
# follow in their usual order. The first two start at once, one per process: the README's first
# run compiles the kernels while the CalculiX test meshes and runs its peer, and finds them in the
# kernel cache when it needs them. The two that first use the all-teeth kernel (the scipy peer's
# reference) stand apart, so that the second reads it from the cache instead of compiling it too.
LONGEST_FIRST = (
    "tests/study/test_doc_first_run.py",               # 97 s, the kernels' first compile included
    "tests/solver/peers/test_calculix.py",             # 59 s, most of it the ccx peer
    "tests/study/test_compile_ahead.py",               # 45 s, a cold run, a warm one and the default model in one empty kernel cache
    "tests/study/sweep/test_bodies.py",                # 45 s, two dask clusters and FE bodies
    "tests/study/test_interrupt.py",                   # 36 s, most of it the commands started
    "tests/study/sweep/test_cluster.py",               # 36 s, and its dask workers' start-up
    "tests/solver/peers/test_scipy_dynamics.py",       # 33 s
    "tests/study/report/test_figures.py",              # 25 s
    "tests/study/test_runup_scene.py",                 # 21 s
    "tests/study/archive/test_mesh_outputs.py",        # 21 s
    "tests/study/inputs/test_body_strength.py",        # 17 s
    "tests/study/inputs/test_springs.py",              # 17 s
    "tests/study/sweep/test_sample.py",                # 17 s
    "tests/workflows/test_lightest_gear.py",           # 16 s
    "tests/study/test_reliability.py",                 # 13 s
    "tests/solver/mbs/test_load_profile.py",           # 13 s, the implicit and all-teeth kernels' compile
)


def pytest_collection_modifyitems(config, items):
    """Markers of what each test reaches (FE, solver, processes): `tiers`, which ``make test-fast``
    leaves out (read only where tests are chosen by marker, ``-m``: reading every test's source
    costs some 3 s of CPU a process); the longest test files first (`LONGEST_FIRST`), each
    file's tests in their order."""
    if config.getoption("markexpr", ""):
        tiers.mark(items, pytest)
    rank = {path: i for i, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))     # stable


@pytest.fixture(scope="module", autouse=True)
def collect_in_the_main_thread():
    """Each test file's dropped archives are collected here, in the main thread: an xarray
    dataset left open (a sweep result's lazy curves) is otherwise closed by whichever thread
    the garbage collector next runs in (a dask client's IO loop among them), outside the
    HDF5 lock, while the main thread may be reading or writing another NetCDF file; HDF5 is
    not thread-safe and such a close once took a test process down."""
    yield
    import gc
    gc.collect()


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

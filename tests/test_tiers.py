"""The test tiers (`tiers`): a test is marked by what its code, its fixtures and the helpers it
calls reach, so that ``make test-fast`` leaves out exactly the tests that run the FE, the solver
or other processes."""
import subprocess
import types

import pytest
import tiers

import study
from solver.mbs.statics import solve_static
from study.cli import main
from study.scene import load_scene


def _pure():
    return load_scene("small_pair").gear1.teeth


def _runs():
    return study.run_scene(load_scene("small_pair"))


def _helper_solves(model):
    return solve_static(model, [0.0], 1.0)


def _imports_study_inside():
    import study as api  # a name the test file's globals do not hold
    return api.run_scene(load_scene("small_pair"))


def _imports_the_function_inside():
    from study import run_scene
    return run_scene(load_scene("small_pair"))


def _imports_study_inside_and_loads_a_scene():
    import study as api
    return api.load_scene("small_pair").gear1.teeth


def _calls_helper():
    return _helper_solves(None)


def _starts_a_process():
    return subprocess.run(["true"])


def _command_line():
    return main(["scenes"])


def _fe_fixture():
    from study.inputs.springs import tooth_springs
    return tooth_springs


class _Item:
    """What `tiers.mark` reads of a collected test: its function, its fixture closure and defs."""

    def __init__(self, function, fixtures=None):
        self.function = function
        self.fixturenames = list(fixtures or {})
        defs = {name: [types.SimpleNamespace(func=f)] for name, f in (fixtures or {}).items()}
        self._fixtureinfo = types.SimpleNamespace(name2fixturedefs=defs)
        self.markers = []

    def add_marker(self, marker):
        self.markers.append(marker.name)


@pytest.mark.parametrize("function, fixtures, markers", [
    (_pure, None, []),
    (_runs, None, ["solver"]),                            # study.run_scene -> study.run
    (_imports_study_inside, None, ["solver"]),            # `import study` in the test itself
    (_imports_the_function_inside, None, ["solver"]),     # `from study import run_scene`
    (_imports_study_inside_and_loads_a_scene, None, []),
    (_calls_helper, None, ["solver"]),                    # through a helper of the test file
    (_starts_a_process, None, ["process"]),
    (_command_line, None, ["solver"]),                    # the command line runs whatever it is given
    (_pure, {"bodies": _fe_fixture}, ["fe"]),             # through a fixture
    (_pure, {"private_fe_cache": _pure}, ["fe"]),
])
def test_a_test_is_marked_by_what_it_reaches(function, fixtures, markers):
    item = _Item(function, fixtures)
    tiers.mark([item], pytest)
    assert sorted(item.markers) == markers


def test_the_longest_files_make_test_hands_out_first_exist():
    """A renamed or removed file in conftest's LONGEST_FIRST would silently go back to the usual order."""
    from pathlib import Path

    from conftest import LONGEST_FIRST
    root = Path(__file__).resolve().parents[1]
    assert len(set(LONGEST_FIRST)) == len(LONGEST_FIRST)
    assert [f for f in LONGEST_FIRST if not (root / f).is_file()] == []

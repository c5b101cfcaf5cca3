"""The test tiers, read from what each test uses: ``make test-fast`` runs the tests that neither
run the multibody solver (its numba kernels compile on first use), nor the FE, nor start
processes; ``make test`` runs them all.

`mark` gives each collected test the markers of what it reaches: the names its function, its
fixtures (the whole fixture closure) and the functions of the test files and ``helpers`` they
call refer to, each resolved to the module that defines it (``study.X`` through `study._OFFERED`):

- ``fe``: the FE (`solver.fe`, the FE-derived inputs `study.inputs`, the FE reference and the
  model checks `study.verify`, the FE commands), or the ``private_fe_cache`` fixture;
- ``solver``: the multibody model or its kernels (`solver.mbs`, `solver.peers`, a run, a
  sweep, the scene's model, the estimates that build one, the command line and the scripts,
  which run whatever they are given: the first run of a fresh clone compiles the kernels);
- ``process``: another process (``subprocess``, a dask cluster, ``multiprocessing``);
- ``slow``: marked by hand (`pytest.mark.slow`): the longest of the others.
"""
from __future__ import annotations

import ast
import collections
import inspect
import sys
import textwrap
import types

# module prefixes -> marker; the first that matches wins
REACHES = (
    ("solver.fe", "fe"), ("solver.identify", "fe"), ("study.inputs", "fe"), ("study.verify", "fe"),
    ("study.commands", "fe"), ("study.cli_fe", "fe"), ("study.sweep.bodies", "fe"),
    ("solver.mbs", "solver"), ("solver.peers", "solver"), ("study.run", "solver"), ("study.sweep.engine", "solver"),
    ("study.sweep.point", "solver"), ("study.sweep.cluster", "solver"),
    ("study.sweep.tasks", "solver"), ("study.scene_model", "solver"), ("study.estimate", "solver"),
    ("study.report.figures", "solver"), ("study.archive.modes", "solver"), ("study.archive.mesh", "solver"),
    ("workflows", "solver"), ("study.cli", "solver"), ("study.process", "solver"),
    ("subprocess", "process"), ("multiprocessing", "process"), ("distributed", "process"), ("dask", "process"),
    ("concurrent.futures", "process"),
)
FIXTURES = {"private_fe_cache": "fe", "paper_solid_model": "solver"}
MARKERS = ("fe", "solver", "process")


def _reached(module: str) -> str | None:
    for prefix, marker in REACHES:
        if module == prefix or module.startswith(prefix + "."):
            return marker
    return None


def _own(obj) -> bool:
    """A function of the tests themselves (a test file or helpers), whose body counts too."""
    module = getattr(obj, "__module__", "") or ""
    return inspect.isfunction(obj) and not module.startswith(("solver", "study", "workflows"))


def _resolve(base, attribute: str | None):
    """The module a name (``base``, or ``base.attribute``) comes from, and the object when it is a
    function of the tests."""
    if attribute is not None and isinstance(base, types.ModuleType):
        if base.__name__ == "study" and attribute in getattr(base, "_OFFERED", {}):
            return base._OFFERED[attribute][0], None
        inner = base.__dict__.get(attribute)
        if inner is None:
            return f"{base.__name__}.{attribute}", None
        base = inner
    if isinstance(base, types.ModuleType):
        return base.__name__, None
    return getattr(base, "__module__", "") or "", base if _own(base) else None


def _imported_here(tree) -> dict:
    """The names the function's own imports bind (``import study`` inside a test) to the modules
    and objects they name, as far as the process holds them already (nothing is imported here):
    ``study.run_scene`` after a function-level ``import study`` reaches `study.run` as it does
    after a module-level one."""
    bound = {}
    for node in ast.walk(tree):
        for a in node.names if isinstance(node, ast.Import | ast.ImportFrom) else ():
            if isinstance(node, ast.Import):
                top = a.name if a.asname else a.name.split(".")[0]
                if top in sys.modules:
                    bound[a.asname or top] = sys.modules[top]
            elif node.level == 0 and node.module in sys.modules:
                value = vars(sys.modules[node.module]).get(a.name)     # not getattr: no lazy import
                if value is not None:
                    bound[a.asname or a.name] = value
    return bound


def _uses(function, seen: dict) -> set:
    """The markers a function of the tests reaches, through the names it uses."""
    function = inspect.unwrap(function)
    key = getattr(function, "__code__", function)
    if key in seen:
        return seen[key]
    seen[key] = found = set()
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(function)))
    except (OSError, TypeError, SyntaxError):
        return found
    names = collections.ChainMap(_imported_here(tree), getattr(function, "__globals__", {}))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            for a in node.names:
                mod = a.name if isinstance(node, ast.Import) else f"{node.module or ''}.{a.name}"
                offered = {}        # `from study import run_scene`: the module that does the work
                if isinstance(node, ast.ImportFrom):
                    offered = getattr(sys.modules.get(node.module or ""), "_OFFERED", {})
                if marker := _reached(offered[a.name][0] if a.name in offered else mod):
                    found.add(marker)
            continue
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            base, attribute = names.get(node.value.id), node.attr
        elif isinstance(node, ast.Name):
            base, attribute = names.get(node.id), None
        else:
            continue
        if base is None:
            continue
        module, own = _resolve(base, attribute)
        if marker := _reached(module):
            found.add(marker)
        if own is not None and own is not function:
            found |= _uses(own, seen)
    return found


def mark(items, pytest) -> None:
    """Add to each test the markers of what it reaches (see the module's docstring)."""
    seen: dict = {}
    for item in items:
        found = set()
        function = getattr(item, "function", None)
        if function is not None:
            found |= _uses(function, seen)
        info = getattr(item, "_fixtureinfo", None)
        for name in getattr(item, "fixturenames", ()):
            if name in FIXTURES:
                found.add(FIXTURES[name])
            for fixturedef in (info.name2fixturedefs.get(name, ()) if info else ()):
                if _own(fixturedef.func):
                    found |= _uses(fixturedef.func, seen)
        for marker in sorted(found):
            item.add_marker(getattr(pytest.mark, marker))

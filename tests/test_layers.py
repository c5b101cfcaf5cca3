"""The layers of the code, read from the import statements (every import, deferred ones too):

- `solver` never imports `study` (nor the workflows): the solver runs without the study layer;
- the numba kernels (`solver/mbs/kernels`) import only numpy, math, numba and each other
  (their package also hashes its own sources with hashlib, os and pathlib for the disk cache, and
  the layout names the work tuples with collections.namedtuple);
- the base solver modules (solver/*.py, solver/fe, solver/identify) import no `solver.mbs`: the
  multibody model is built from them, not the other way round. The FE reference
  (`solver/fe/ltca.py`) and the peers (`solver/peers`) stand above the model they check;
- the pictures (`study/report/`) import only the run archive and its NetCDF I/O, the scene,
  the solver's units and geometry, each other and libraries: they draw what an archive holds
  and start no run, sweep or FE solve;
- the run archive (`study/archive/`) imports only the solver, the scene and itself;
- no cycle between packages (a subpackage or a top-level module of `solver`/`study`) through
  the imports a module runs when it is loaded;
- no cycle between modules through any import, those inside functions included (a deferred
  import hides a cycle from the interpreter, not from the design), and the names `study`
  offers through its table ``_OFFERED`` (imported on first use). Only imports under
  ``if TYPE_CHECKING:`` never run and do not count.

The workflows' rule (only `study`'s public API) is tests/workflows/test_imports.py.
"""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROJECT = ("solver", "study", "workflows", "benchmarks")

# The run archive, which the pictures read: its schema, variables, NetCDF I/O and provenance.
ARCHIVE = ("study.archive",)

# Imports that break a rule today, (rule, importing file, imported module), each to delete when
# its import goes; the test fails on an entry that no longer happens.
KNOWN: set = set()


def _module(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _files(root: Path, tops=("solver", "study")) -> dict:
    """module name -> source file of every module under the packages ``tops`` of ``root``."""
    return {_module(p, root): p for top in tops for p in sorted((root / top).rglob("*.py"))}


FILES = _files(ROOT)


def _imports(path: Path, loaded_only: bool = False, files: dict = FILES, root: Path = ROOT):
    """(line, imported module) of each import in the file; ``from a import b`` gives ``a.b`` when
    that is a module of the project, else ``a``. ``loaded_only``: the imports run when the
    module is loaded (not those in functions or under TYPE_CHECKING); else every import that can
    run (those under TYPE_CHECKING left out)."""
    tree = ast.parse(path.read_text())
    me = _module(path, root)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]

    def statements(body):
        for node in body:
            if isinstance(node, ast.Import | ast.ImportFrom):
                yield node
            elif isinstance(node, ast.If) and "TYPE_CHECKING" not in ast.unparse(node.test):
                yield from statements(node.body + node.orelse)
            elif isinstance(node, ast.Try):
                yield from statements(node.body + node.orelse + node.finalbody + [s for h in node.handlers for s in h.body])
            elif isinstance(node, ast.With):
                yield from statements(node.body)

    def every(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import | ast.ImportFrom):
                yield child
            elif not (isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test)):
                yield from every(child)

    nodes = statements(tree.body) if loaded_only else every(tree)
    if not loaded_only:
        yield from _offered(tree, files)
    for node in nodes:
        if isinstance(node, ast.Import):
            yield from ((node.lineno, a.name) for a in node.names)
            continue
        base = node.module or ""
        if node.level:
            up = package.split(".")[: len(package.split(".")) - node.level + 1]
            base = ".".join(up + ([node.module] if node.module else []))
        for a in node.names:
            yield node.lineno, f"{base}.{a.name}" if f"{base}.{a.name}" in files else base


def _offered(tree, files: dict):
    """(line, module) of each entry of a module-level table ``_OFFERED = {name: (module,
    attribute)}``: the names a package offers and imports on first use (`study`'s API)."""
    for node in tree.body:
        if (isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "_OFFERED" for t in node.targets)
                and isinstance(node.value, ast.Dict)):
            for value in node.value.values:
                module, attribute = ast.literal_eval(value)
                yield value.lineno, f"{module}.{attribute}" if f"{module}.{attribute}" in files else module


def _under(name: str, *prefixes: str) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def _is_base(module: str) -> bool:
    """solver's own modules (solver/*.py) and the FE and identification packages, less the FE reference."""
    if _under(module, "solver.fe", "solver.identify"):
        return module != "solver.fe.ltca"
    return module == "solver" or (module.count(".") == 1 and module.startswith("solver.")
                                  and FILES[module].name != "__init__.py")


def _kernels_refuse(name: str, module: str) -> bool:
    if module == "solver.mbs.kernels" and name in ("hashlib", "os", "pathlib", "contextlib", "threading"):
        return False        # the package hashes the kernel sources for its disk-cache folder (and
        #                     switches the wrapper-less kernels' Python calls per thread, `python_calls`)
    if module == "solver.mbs.kernels.layout" and name == "collections":
        return False        # the named work tuples are namedtuples, which numba passes as tuples
    return not _under(name, "numpy", "math", "numba", "solver.mbs.kernels")


PICTURES_READ = ("study.report", *ARCHIVE, "study.scene", "study.errors", "solver.units", "solver.geometry",
                 "solver.mbs.kernels.status")

# rule -> (the modules it binds, the imports it refuses (imported name, importing module), what it says)
RULES = {
    "solver": (lambda m: _under(m, "solver"), lambda name, m: _under(name, "study", "workflows", "benchmarks"),
               "solver never imports study"),
    "kernels": (lambda m: _under(m, "solver.mbs.kernels"), _kernels_refuse,
                "the kernels import only numpy, math, numba and kernels"),
    "base": (_is_base, lambda name, m: _under(name, "solver.mbs"),
             "the base solver modules (solver/*.py, solver/fe, solver/identify) import no solver.mbs"),
    "pictures": (lambda m: _under(m, "study.report"),
                 lambda name, m: _under(name, *PROJECT) and not _under(name, *PICTURES_READ),
                 "the pictures (study/report) import only the archive and its I/O, the scene, "
                 "solver units and geometry"),
    "archive": (lambda m: _under(m, *ARCHIVE),
                lambda name, m: _under(name, "study", "workflows", "benchmarks") and not _under(name, *ARCHIVE, "study.scene", "study.errors"),
                "the run archive (study/archive) imports only the solver, the scene and itself: run, sweep, inputs, "
                "verify and the pictures import it, not the other way round"),
}


def _breaks(rule: str):
    binds, refuses, _text = RULES[rule]
    for module, path in FILES.items():
        if not binds(module):
            continue
        for line, name in _imports(path):
            if refuses(name, module):
                yield str(path.relative_to(ROOT)), line, name


@pytest.mark.parametrize("rule", list(RULES))
def test_a_layer_imports_only_what_lies_below(rule):
    found = list(_breaks(rule))
    known = {(f, n) for r, f, n in KNOWN if r == rule}
    new = [f"{f}:{line} imports {name}, against the rule \"{rule}\": {RULES[rule][2]}" for f, line, name in found if (f, name) not in known]
    gone = [f"{f} no longer imports {n}: delete it from KNOWN" for f, n in sorted(known - {(f, n) for f, _l, n in found})]
    if new + gone:
        pytest.fail("\n".join(new + gone), pytrace=False)


def _unit(module: str) -> str:
    """The package a module counts in: its subpackage or top-level module of solver/study (the
    kernels a package of their own, the bottom layer)."""
    return "solver.mbs.kernels" if _under(module, "solver.mbs.kernels") else ".".join(module.split(".")[:2])


def test_no_import_cycle_between_packages():
    edges = {}     # (unit, unit) -> first 'file:line' of an import that makes it
    for module, path in FILES.items():
        for line, name in _imports(path, loaded_only=True):
            if _under(name, "solver", "study") and _unit(module) != _unit(name):
                edges.setdefault((_unit(module), _unit(name)), f"{path.relative_to(ROOT)}:{line} imports {name}")
    graph = {}
    for a, b in edges:
        graph.setdefault(a, set()).add(b)

    def path_back(start, goal, seen):
        for nxt in sorted(graph.get(start, ())):
            if nxt == goal:
                return [start, nxt]
            if nxt not in seen:
                seen.add(nxt)
                rest = path_back(nxt, goal, seen)
                if rest:
                    return [start] + rest
        return None

    for a in sorted(graph):
        cycle = path_back(a, a, set())
        if cycle:
            pytest.fail("import cycle between packages:\n" + "\n".join(
                edges[(u, v)] for u, v in zip(cycle, cycle[1:], strict=False)), pytrace=False)


def _module_graph(files: dict, root: Path) -> dict:
    """module -> {imported module of ``files``: 'file:line' of the first import of it}, every
    import counted (deferred ones too); a name inside a module counts as that module."""
    graph: dict = {}
    for module, path in files.items():
        for line, name in _imports(path, files=files, root=root):
            while name not in files and "." in name:
                name = name.rpartition(".")[0]
            if name in files and name != module:
                graph.setdefault(module, {}).setdefault(name, f"{path.relative_to(root)}:{line} imports {name}")
    return graph


def _module_cycles(graph: dict) -> list:
    """The strongly connected groups of more than one module (Tarjan), each as a sorted list."""
    index: dict = {}
    low: dict = {}
    stack: list = []
    found = []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while not group or group[-1] != v:
                group.append(stack.pop())
            if len(group) > 1:
                found.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _cycle_report(graph: dict, group: list) -> str:
    inside = set(group)
    return "import cycle between modules (deferred imports included):\n" + "\n".join(
        f"  {where}" for a in group for b, where in sorted(graph.get(a, {}).items()) if b in inside)


def test_no_import_cycle_between_modules():
    graph = _module_graph(FILES, ROOT)
    cycles = _module_cycles(graph)
    if cycles:
        pytest.fail("\n".join(_cycle_report(graph, g) for g in cycles), pytrace=False)


def test_a_planted_deferred_import_cycle_is_found(tmp_path):
    """The cycle check sees a cycle made only of imports inside functions or through an
    ``_OFFERED`` table, and not one that lies under TYPE_CHECKING."""
    pkg = tmp_path / "study"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def f():\n    from study.b import g\n    return g()\n")
    (pkg / "b.py").write_text("from study import c\n\ndef g():\n    return c.h()\n")
    (pkg / "c.py").write_text("def h():\n    from . import a\n    return a\n")
    (pkg / "d.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from study.a import f\n")
    (pkg / "e.py").write_text("from study.d import TYPE_CHECKING\n")
    (pkg / "f.py").write_text("_OFFERED = {'g': ('study.g', 'g')}\n")
    (pkg / "g.py").write_text("def g():\n    import study.f\n    return study.f\n")
    files = _files(tmp_path, ("study",))
    graph = _module_graph(files, tmp_path)
    assert _module_cycles(graph) == [["study.a", "study.b", "study.c"], ["study.f", "study.g"]]
    assert "study/c.py:2 imports study.a" in _cycle_report(graph, ["study.a", "study.b", "study.c"])
    (pkg / "c.py").write_text("def h():\n    return 1\n")
    (pkg / "g.py").write_text("def g():\n    return 1\n")
    assert _module_cycles(_module_graph(_files(tmp_path, ("study",)), tmp_path)) == []

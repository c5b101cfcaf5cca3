"""The workflows are examples of the Python API: each uses only what `import study` offers
(plus the standard library, NumPy, xarray and matplotlib), never a module behind it."""
import ast
import sys
from pathlib import Path

import pytest

import study

WORKFLOWS = sorted((Path(__file__).resolve().parents[2] / "workflows").glob("*.py"))
ALLOWED = {"numpy", "xarray", "matplotlib"}


@pytest.mark.parametrize("path", [p for p in WORKFLOWS if p.name != "__init__.py"], ids=lambda p: p.name)
def test_a_workflow_imports_only_the_public_api(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                top = alias.name.split(".")[0]
                assert alias.name == "study" or top in ALLOWED or top in sys.stdlib_module_names, \
                    f"{path.name}:{node.lineno} imports {alias.name}"
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            top = module.split(".")[0]
            if module == "study":
                for alias in node.names:
                    assert alias.name in study.__all__, f"{path.name}:{node.lineno} imports study.{alias.name}"
            else:
                assert top in ALLOWED or top in sys.stdlib_module_names, f"{path.name}:{node.lineno} imports {module}"
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "study":
            assert node.attr in study.__all__, f"{path.name}:{node.lineno} uses study.{node.attr}, not in the API"


def test_every_name_of_the_api_exists():
    for name in study.__all__:
        assert getattr(study, name) is not None

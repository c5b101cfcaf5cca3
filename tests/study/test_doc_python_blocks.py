"""Every Python block of the README and docs/ runs from an empty directory (the parsing of the
pages in test_doc_blocks.py)."""
import pytest
from test_doc_blocks import blocks

# Python blocks that another test runs with checks of its results
RUN_ELSEWHERE = {"README.md": "tests/study/test_api.py runs the README's first study and checks its numbers"}
# the blocks cheap enough to run on every test run (seconds); the others are slow
CHEAP_PYTHON = {"docs/tolerance.md"}


def python_params():
    out = []
    for b in blocks("python"):
        marks = []
        if b.page not in CHEAP_PYTHON:
            marks.append(pytest.mark.slow)
        out.append(pytest.param(b, id=str(b), marks=marks))
    return out


@pytest.mark.parametrize("block", python_params())
def test_a_python_block_runs_from_an_empty_directory(block, tmp_path, monkeypatch):
    if block.page in RUN_ELSEWHERE:
        from test_api import SCRIPT
        assert block.text.strip() == SCRIPT.strip(), RUN_ELSEWHERE[block.page]
        return
    monkeypatch.chdir(tmp_path)
    exec(compile(block.text, str(block), "exec"), {"__name__": "doc_block"})

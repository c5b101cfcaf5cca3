"""Every fenced block of the README and docs/ is code that works: Python blocks run in a
temporary directory, TOML blocks load as the scene or study they show, and every command line
of a shell block names a command and options that exist (the cheap ones run). Nothing in the
repository points outside it. The blocks that take long run from files of their own, so that the
two test processes of ``make test`` take them at once: the Python blocks in
test_doc_python_blocks.py, the README's first run and study in test_doc_first_run.py."""
from __future__ import annotations

import math
import re
import shlex
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
LANGUAGES = {"python", "toml", "sh", "text"}      # text: a map or a table, nothing to run; sh: also an unlabelled block of commands


@dataclass(frozen=True)
class Block:
    page: str
    line: int
    lang: str
    text: str

    def __str__(self):
        return f"{self.page}:{self.line}"


PROGRAMS = ("lightgear ", "python -m ", "make ", "dask ")


def looks_like_commands(text: str) -> bool:
    """Every line a command of a known program, a continuation or a comment."""
    lines = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    return bool(lines) and all(line.startswith(PROGRAMS) or line[:1].isspace() or re.match(r"[A-Z_]+=", line)
                               for line in lines)


def blocks(lang: str | None = None) -> list[Block]:
    """The fenced blocks of the pages (of language ``lang``); a block without a language that
    holds only command lines counts as a shell block."""
    out = []
    for page in PAGES:
        text = page.read_text()
        for m in FENCE.finditer(text):
            kind = m.group(1) or ("sh" if looks_like_commands(m.group(2)) else "")
            b = Block(str(page.relative_to(ROOT)), text.count("\n", 0, m.start()) + 1, kind, m.group(2))
            if lang is None or b.lang == lang:
                out.append(b)
    return out


def commands(block: Block) -> list[str]:
    """The command lines of a shell block: comments dropped, continued lines joined."""
    joined, out = block.text.replace("\\\n", " "), []
    for line in joined.splitlines():
        code = line.split(" #")[0].rstrip() if not line.lstrip().startswith("#") else ""
        if not code:
            continue
        if line[:1].isspace() and out:     # an indented line continues the synopsis above
            out[-1] += " " + code.strip()
        else:
            out.append(code.strip())
    return out


def is_synopsis(cmd: str) -> bool:
    """A usage line with placeholders (SCENE, OUT.nc, [--option ...]) rather than a command to run."""
    return "[" in cmd or any(re.fullmatch(r"[A-Z][A-Z_.]*(\.nc|\.toml)?", t) for t in cmd.split())


def options_of(cmd: str) -> list[str]:
    return [t.split("=")[0] for t in cmd.replace("[", " ").replace("]", " ").split() if t.startswith("-")]


def test_every_block_says_what_it_holds():
    assert blocks(), "no fenced blocks found"
    unlabelled = [str(b) for b in blocks() if b.lang not in LANGUAGES]
    assert unlabelled == [], f"fenced blocks to label with one of the languages {sorted(LANGUAGES)}"


@pytest.mark.parametrize("block", [pytest.param(b, id=str(b)) for b in blocks("toml")])
def test_a_toml_block_loads_as_a_study(block, tmp_path):
    import study
    data = tomllib.loads(block.text)
    if isinstance(data.get("scene"), str) and not study.scenes().get(data["scene"]):
        # the block's own scene file, as the text around it describes it: any scene will do
        (tmp_path / data["scene"]).write_text(study.load_scene("paper").to_toml())
    path = tmp_path / "study.toml"
    path.write_text(block.text)
    st = study.load_study(path)
    swept = set(data.get("grid", {})) | {k for k, v in data.get("sample", {}).items() if isinstance(v, dict)}
    assert swept and swept <= set(st.fields) | set(st.sample.paths if st.sample else ())


def shell_lines():
    return [pytest.param(b, cmd, id=f"{b}:{cmd[:40]}") for b in blocks("sh") for cmd in commands(b)]


@pytest.mark.parametrize("block,cmd", shell_lines())
def test_a_command_line_names_a_command_and_options_that_exist(block, cmd, capsys):
    words = shlex.split(cmd.replace("[", " ").replace("]", " "))
    while words and re.fullmatch(r"[A-Z_]+=\S*", words[0]):   # environment settings before the program
        words.pop(0)
    program = words[0]
    if program == "make":
        targets = re.findall(r"^([\w-]+):", (ROOT / "Makefile").read_text(), re.M)
        assert set(words[1:]) <= set(targets), cmd
    elif program == "lightgear":
        from study.cli import COMMANDS, build_parser
        assert words[1] in COMMANDS, cmd
        sub = build_parser()._subparsers._group_actions[0].choices[words[1]]
        known = {o for a in sub._actions for o in a.option_strings}
        assert set(options_of(cmd)) <= known, f"{cmd}: unknown options {set(options_of(cmd)) - known}"
        if not is_synopsis(cmd):
            build_parser().parse_args(words[1:])          # exits (SystemExit) on a bad value
    elif program == "python":
        if words[1].startswith("benchmarks/"):      # a benchmark script, run from the repository root
            assert (ROOT / words[1]).is_file(), cmd
            target, rest = [words[1]], words[2:]
        else:
            assert words[1] == "-m" and words[2].startswith("workflows."), cmd
            target, rest = ["-m", words[2]], words[3:]
        usage = subprocess.run([sys.executable, *target, "--help"], cwd=ROOT, capture_output=True,
                               text=True, timeout=120)
        assert usage.returncode == 0, usage.stderr
        missing = [o for o in options_of(" ".join(rest)) if o not in usage.stdout]
        assert missing == [], f"{cmd}: options not in {' '.join(target)} --help"
    elif program == "dask":       # dask's own command line, installed with the pinned stack
        assert (Path(sys.executable).parent / "dask").exists()
    else:
        pytest.fail(f"{block}: {cmd!r}: a program the docs test does not know")


CHEAP_COMMANDS = {"scenes", "fields", "outputs"}


@pytest.mark.parametrize("cmd", sorted({c for b in blocks("sh") for c in commands(b)
                                        if c.startswith("lightgear ") and not is_synopsis(c)
                                        and c.split()[1] in CHEAP_COMMANDS}))
def test_a_cheap_command_of_the_docs_runs(cmd, capsys):
    from study.cli import main
    assert main(shlex.split(cmd)[1:]) == 0
    assert capsys.readouterr().out.strip()


def tracked_files() -> list[Path]:
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return [ROOT / f for f in out.splitlines()]


def test_nothing_in_the_repository_points_outside_it():
    # (spelled in pieces, so that this file does not hold the paths it looks for)
    pattern = re.compile("|".join(["/" + "work/", r"\.\./" + "shared/", "shared/" + r"design\.md"]))
    here = Path(__file__).resolve()
    hits = []
    for path in tracked_files():
        if path.resolve() == here or not path.is_file():
            continue
        try:
            text = path.read_text()
        except UnicodeDecodeError:
            continue
        hits += [f"{path.relative_to(ROOT)}:{i}" for i, line in enumerate(text.splitlines(), 1) if pattern.search(line)]
    assert hits == []


def test_the_links_between_pages_lead_to_files_of_the_repository():
    broken = []
    for page in PAGES:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
            if not target.startswith("http") and not (page.parent / target).exists():
                broken.append(f"{page.relative_to(ROOT)} -> {target}")
    assert broken == []


def test_the_fe_mesh_size_the_docs_give_is_the_code_default():
    from solver.fe.mesh import default_mesh_size
    sizes = re.findall(r"default module/(\d+)", (ROOT / "docs" / "cli.md").read_text())
    assert sizes and all(math.isclose(default_mesh_size(1.0), 1.0 / int(n)) for n in sizes)


def test_the_mesh_mode_names_of_numbers_md_are_those_of_a_run_archive():
    """Every `mesh_mode_*` name docs/numbers.md gives is an attribute or a variable of a dynamic
    run's archive, or a sweep output."""
    import study
    from study.sweep.outputs import SCALARS
    names = set(re.findall(r"`(mesh_mode_\w+)`", (ROOT / "docs" / "numbers.md").read_text()))
    assert "mesh_mode_damping_at_decay" in names
    scene = study.load_study("example_study").base_scene().replace(**{"dynamic.duration": 0.02})
    ds = study.run_scene(scene, static=False)
    assert names - set(ds.attrs) - set(ds.data_vars) - set(SCALARS) == set()


def test_the_runup_scene_names_the_critical_speeds_of_its_model():
    """The comment of study/scenes/runup.toml gives the modal critical speeds of the mesh mode
    that the scene (its default model) has, within 1 rad/s."""
    import study
    text = (ROOT / "study" / "scenes" / "runup.toml").read_text()
    said = dict(re.findall(r"(\dZ) (\d+(?:\.\d+)?)", text.split("title")[0]))
    assert set(said) == {"1Z", "2Z", "3Z"}
    ds = study.run_scene(study.load_scene("runup"), static=False, dynamic=False)    # the modes only
    cs = ds["critical_speed"].isel(mode=0)
    for order, value in said.items():
        assert abs(float(cs.sel(excitation=order)) - float(value)) < 1.0, order
    assert ds.attrs["coupling_model"] in text.split("title")[0]

"""The scene field and sweep output reference, generated from the declarations the validation
uses (`study.scene` fields, `study.sweep.outputs.SCALARS` and `CURVES`), so it cannot drift
from what the code accepts; and the list of the embedded scenes and studies (study/scenes/).

    lightgear fields [PREFIX]          # every scene field: unit, default, range, meaning
    lightgear outputs                  # the sweep scalars and curves with their units
    python -m study.docs               # rewrite the generated tables in docs/*.md
    python -m study.docs --check       # exit 1 when the committed tables are out of date

In the Markdown files the generated part sits between ``<!-- generated: NAME -->`` and
``<!-- end generated: NAME -->`` (NAME: ``fields``, ``outputs`` or ``scenes``); the rest is hand-written.
"""
from __future__ import annotations

import dataclasses
import math
import sys
import typing
from dataclasses import dataclass
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"
GENERATED = {"fields": "scenes.md", "outputs": "numbers.md", "scenes": "scenes.md"}    # block name -> file in docs/


@dataclass(frozen=True)
class FieldRow:
    path: str       # dotted scene path
    kind: str       # 'number', 'integer', 'true/false', 'text', 'list of numbers'
    unit: str       # '' for none
    default: str    # as TOML would write it; 'not given' for an optional field left out
    range: str      # allowed values ('' when any)
    doc: str


def _kind(typ) -> str:
    return {float: "number", int: "integer", bool: "true/false", str: "text"}.get(typ, "list of numbers")


def _number(x) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def _range(md: dict) -> str:
    if md.get("choices"):
        return " \\| ".join(f"'{c}'" for c in md["choices"])
    lo, hi = md.get("lo"), md.get("hi")
    if lo is not None and hi is not None:
        return f"{'(' if md.get('lo_open') else '['}{_number(lo)}, {_number(hi)}{')' if md.get('hi_open') else ']'}"
    if lo is not None:
        return f"{'>' if md.get('lo_open') else '>='} {_number(lo)}"
    if hi is not None:
        return f"{'<' if md.get('hi_open') else '<='} {_number(hi)}"
    return ""


def _default(value, md: dict) -> str:
    if md.get("optional") and isinstance(value, float) and math.isnan(value):
        return "not given"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, tuple):
        return "[" + ", ".join(_number(v) for v in value) + "]"
    return _number(value)


def field_rows(prefix: str = "") -> list[FieldRow]:
    """Every value field of a scene whose dotted path starts with ``prefix`` (a section such as
    ``gear2.body`` or ``dynamic``, or a field), in declaration order. SceneError when no field
    matches."""
    from study.errors import SceneError, check_argument
    from study.scene import Scene
    check_argument(isinstance(prefix, str), "fields", "prefix", "a dotted path such as 'gear2.body'", prefix)

    def walk(cls, path: str):
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            p = f"{path}.{f.name}" if path else f.name
            if dataclasses.is_dataclass(hints[f.name]):
                yield from walk(hints[f.name], p)
            else:
                md = dict(f.metadata)
                yield FieldRow(p, _kind(hints[f.name]), md.get("unit", "") if md.get("unit") != "1" else "",
                               _default(f.default, md), _range(md), md.get("doc", ""))

    rows = [r for r in walk(Scene, "") if not prefix or r.path == prefix or r.path.startswith(prefix.rstrip(".") + ".")]
    if not rows:
        from study.scene import scene_field
        scene_field(prefix)          # names the closest field when the prefix is misspelled
        raise SceneError(prefix, "no scene field starts with this prefix")
    return rows


def output_rows() -> list[tuple[str, str, str, str, str]]:
    """(name, 'scalar' or 'curve over AXIS', units, analysis, meaning) of every sweep output."""
    from study.sweep.outputs import CURVES, SCALARS
    curve_units = {"ste": ("um", "static transmission error against the driver angle [degree]"),
                   "dte": ("um", "dynamic transmission error against time [s]"),
                   "dte_amplitude": ("um", "amplitude spectrum of the DTE after the ramp against frequency [Hz]")}
    out = [(k, "scalar", s.units, s.analysis, s.long_name) for k, s in SCALARS.items()]
    for k, c in CURVES.items():
        unit, doc = curve_units.get(k, ("", ""))
        out.append((k, f"curve over {c.axis}", unit, c.analysis, doc + (f"; {c.comment}" if c.comment else "")))
    return out


# ---------------------------------------------------------------- text (the command line)

def fields_text(prefix: str = "") -> str:
    """The field reference as plain text, one block per field."""
    lines = []
    for r in field_rows(prefix):
        head = f"{r.path}  [{r.unit}]" if r.unit else r.path
        extra = ", ".join(x for x in (f"default {r.default}", f"range {r.range.replace(chr(92), '')}" if r.range else "",
                                     r.kind) if x)
        lines += [head, f"    {r.doc}" if r.doc else "", f"    ({extra})"]
    return "\n".join(x for x in lines if x) + "\n"


def outputs_text() -> str:
    """The sweep outputs as plain text: name, units, kind, the analysis it needs, meaning."""
    lines = ["name                          units    kind              analysis  meaning"]
    for name, kind, unit, analysis, doc in output_rows():
        lines.append(f"{name:29s} {unit or '1':8s} {kind:17s} {analysis:9s} {doc}")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- Markdown (docs/)

def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def fields_markdown() -> str:
    """The field reference as Markdown tables, one per scene section."""
    out = []
    section = None
    for r in field_rows():
        head = r.path.rsplit(".", 1)[0] if "." in r.path else "(top level)"
        if head != section:
            section = head
            out += ["", f"#### `{head}`" if "." in r.path else "#### top level", "",
                    "| field | unit | default | range | meaning |", "|---|---|---|---|---|"]
        name = r.path.rsplit(".", 1)[-1]
        out.append(f"| `{name}` | {r.unit} | `{r.default}` | {r.range} | {_cell(r.doc)} |")
    return "\n".join(out[1:]) + "\n"


def outputs_markdown() -> str:
    """The sweep outputs as one Markdown table."""
    out = ["| name | kind | units | analysis | meaning |", "|---|---|---|---|---|"]
    for name, kind, unit, analysis, doc in output_rows():
        out.append(f"| `{name}` | {kind} | {unit} | {analysis} | {_cell(doc)} |")
    return "\n".join(out) + "\n"


def scenes_markdown() -> str:
    """The embedded scenes and studies as one Markdown table: name, kind, title."""
    from study.scene import embedded_scenes
    out = ["| name | kind | title |", "|---|---|---|"]
    for name, (_path, kind, title) in embedded_scenes().items():
        out.append(f"| `{name}` | {kind} | {_cell(title)} |")
    return "\n".join(out) + "\n"


BLOCKS = {"fields": fields_markdown, "outputs": outputs_markdown, "scenes": scenes_markdown}


def _markers(name: str) -> tuple[str, str]:
    return f"<!-- generated: {name} (python -m study.docs) -->", f"<!-- end generated: {name} -->"


def with_block(text: str, name: str) -> str:
    """``text`` with its generated block ``name`` rewritten; ValueError when the markers are missing."""
    begin, end = _markers(name)
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        raise ValueError(f"the markers of the generated block {name!r} are missing")
    return text[: i + len(begin)] + "\n" + BLOCKS[name]() + text[j:]


def stale_blocks(folder: Path = DOCS) -> list[str]:
    """The generated blocks of ``folder``'s Markdown files that differ from the declarations."""
    out = []
    for name, file in GENERATED.items():
        text = (folder / file).read_text()
        if with_block(text, name) != text:
            out.append(f"{file}: {name}")
    return out


def write_blocks(folder: Path = DOCS) -> list[Path]:
    """Rewrite every generated block in ``folder`` -> the files changed."""
    changed = []
    for name, file in GENERATED.items():
        path = folder / file
        text = path.read_text()
        new = with_block(text, name)
        if new != text:
            path.write_text(new)
            changed.append(path)
    return changed


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--check" in argv:
        stale = stale_blocks()
        for s in stale:
            print(f"out of date: docs/{s} (run python -m study.docs)", file=sys.stderr)
        return 1 if stale else 0
    for path in write_blocks():
        print(f"rewrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

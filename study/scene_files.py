"""Scene and study files: reading their TOML text, telling a study's tables from a scene's, and
the embedded scenes and studies (``study/scenes/``), found by name.
"""
from __future__ import annotations

import difflib
import tomllib
from pathlib import Path

from study.errors import SceneError

SCENES_DIR = Path(__file__).parent / "scenes"


def toml_tables(text: str, source: str) -> dict:
    """The tables of TOML ``text``; SceneError naming ``source`` where it is no valid TOML."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(source, f"not valid TOML: {e}") from None


def read_text(path: str | Path, field: str = "scene") -> str:
    """The text of a scene or study file; SceneError naming ``field`` when it cannot be read as
    UTF-8 text (TOML files are UTF-8) or at all."""
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise SceneError(field, f"{p} is not UTF-8 text (byte {e.start}: {e.reason}); TOML files are UTF-8") from None
    except OSError as e:
        raise SceneError(field, f"cannot read {p}: {e.strerror or e}") from None


# the tables that make a TOML file a study (`study.sweep.grid`), and those only a scene has
STUDY_SECTIONS = ("grid", "points", "sample")


def is_study_table(data: dict) -> bool:
    """A TOML file's tables are a study's: a [grid], [[points]] or [sample], or a [scene] table
    of overrides (a scene has no section of that name)."""
    return any(k in data for k in STUDY_SECTIONS) or isinstance(data.get("scene"), dict)


def embedded_scenes() -> dict[str, tuple[Path, str, str]]:
    """The scenes and studies that ship with lightgear: name -> (file, 'scene' or 'study', title)."""
    out = {}
    for p in sorted(SCENES_DIR.glob("*.toml")):
        try:
            raw = tomllib.loads(p.read_text())
        except (OSError, tomllib.TOMLDecodeError):
            continue
        kind = "study" if is_study_table(raw) else "scene"
        out[p.stem] = (p, kind, str(raw.get("title", "")))
    return out


def scene_path(name: str | Path, what: str = "scene") -> Path:
    """The file of a scene or study given by path or by the name of an embedded one
    (``"runup"``, ``"runup.toml"``; a file that exists wins). SceneError names both ways."""
    p = Path(name)
    if p.is_file():
        return p
    stem = p.stem if p.suffix == ".toml" else p.name
    known = embedded_scenes()
    if len(p.parts) == 1 and stem in known:
        return known[stem][0]
    names = ", ".join(k for k, v in known.items() if v[1] == what) or ", ".join(known)
    close = difflib.get_close_matches(stem, list(known), n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise SceneError(what, f"no such file or embedded {what}: {name} (embedded {'studies' if what == 'study' else 'scenes'}: {names}; "
                     f"`lightgear scenes` lists them){hint}")


def default_scene_text() -> str:
    """TOML text of the embedded paper example (``study/scenes/paper.toml``)."""
    return (SCENES_DIR / "paper.toml").read_text()

"""Typed values from TOML tables: a frozen dataclass built from its table (`build_section`),
each key known, each value of its field's type and within its declared range
(`study.scene_sections.declare`), else a SceneError naming the dotted field.
"""
from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import typing
from dataclasses import fields

from study.damping import resolve_exclusive
from study.errors import SceneError

# the integers a scene field or a study's seed may hold: those a NetCDF archive stores (int64)
INT_MIN, INT_MAX = -2 ** 63, 2 ** 63 - 1


def _coerce(value, typ, path):
    """``value`` as ``typ`` (bool, int, float or str), else SceneError; a bool is no number.
    NumPy scalars and arrays count as the Python numbers and lists they hold."""
    value = _python_value(value)
    if typ == tuple[float, ...]:    # a list of numbers (a table's column)
        if not isinstance(value, list | tuple):
            raise SceneError(path, f"must be a list of numbers, got {value!r}")
        return tuple(_coerce(x, float, path) for x in value)
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if (typ is bool and isinstance(value, bool)) or (typ is str and isinstance(value, str)):
        return value
    if typ is int and number and (isinstance(value, int) or (math.isfinite(value) and value.is_integer())):
        # (a Python int as it is: 2^53 + 1 has no float of its own)
        if not INT_MIN <= int(value) <= INT_MAX:
            raise SceneError(path, f"must fit in 64 bits (the archive's integers), from {INT_MIN} to {INT_MAX}, "
                                   f"got {int(value)}")
        return int(value)
    if typ is float and number and math.isfinite(value):
        return float(value)
    what = "finite" if typ is float and number else {bool: "true or false", int: "an integer",
                                                     float: "a number", str: "a string"}[typ]
    raise SceneError(path, f"must be {what}, got {value!r}")


def _python_value(value):
    """A NumPy scalar or array as the Python number, bool or list it holds; anything else as is."""
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):
        return value.tolist()
    return value


# the section classes never change: resolve their annotations once (a sampled study builds
# thousands of scenes, and resolving them took two thirds of each build)
type_hints = functools.cache(typing.get_type_hints)


def build_section(cls, table, path: str):
    """A ``cls`` (a scene section, or the Scene) from its ``table``, its subsections built
    alike; ``path``: the dotted name of the table ('' at the top), for the errors."""
    if not isinstance(table, dict):
        raise SceneError(path or "scene", f"must be a table, got {table!r}")
    hints = type_hints(cls)
    known = {f.name: f for f in fields(cls)}
    for key in table:
        if key not in known:
            where = f"{path}.{key}" if path else key
            close = difflib.get_close_matches(str(key), list(known), n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise SceneError(where, f"unknown key (expected one of: {', '.join(known)}){hint}")
    kwargs = {}
    for name, f in known.items():
        where = f"{path}.{name}" if path else name
        typ = hints[name]
        if dataclasses.is_dataclass(typ):
            kwargs[name] = build_section(typ, table.get(name, {}), where)
            continue
        if name not in table:
            continue
        md = f.metadata
        if md.get("optional") and isinstance(table[name], float) and math.isnan(table[name]):
            continue      # left out (a saved scene writes nan)
        v = _coerce(table[name], typ, where)
        unit = f" {md['unit']}" if md.get("unit") not in (None, "", "1") else ""
        if md.get("choices") and v not in md["choices"]:
            raise SceneError(where, f"must be one of {', '.join(map(repr, md['choices']))}, got {v!r}")
        lo, hi = md.get("lo"), md.get("hi")
        for x in (v if isinstance(v, tuple) else (v,)):     # (a list: each of its numbers)
            if lo is not None and (x < lo or (md.get("lo_open") and x == lo)):
                rel = ">" if md.get("lo_open") else ">="
                raise SceneError(where, f"must be {rel} {lo}{unit}, got {x}{unit}")
            if hi is not None and (x > hi or (md.get("hi_open") and x == hi)):
                rel = "<" if md.get("hi_open") else "<="
                raise SceneError(where, f"must be {rel} {hi}{unit}, got {x}{unit}")
        kwargs[name] = v
    resolve_exclusive(cls, kwargs, path)
    return cls(**kwargs)

"""A minimal TOML writer for scenes and studies (the standard library reads TOML, `tomllib`,
but does not write it): scalars, inline arrays and tables, nested tables."""
from __future__ import annotations


def toml_value(v) -> str:
    """A value as TOML: a scalar, a list (inline array) or a dict (inline table)."""
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    raise TypeError(f"cannot write {type(v)} to TOML")


def dumps_toml(data: dict, prefix: str = "") -> str:
    """Minimal TOML writer for nested tables of scalars (what scenes hold)."""
    out = [f"{k} = {toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            name = f"{prefix}.{k}" if prefix else k
            out += [f"\n[{name}]", dumps_toml(v, name)]
    return "\n".join(x for x in out if x) + ("\n" if not prefix else "")


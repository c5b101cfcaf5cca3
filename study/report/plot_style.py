"""What every plot of an archive shares: the Agg backend, resolution, colours, unit labels,
the archive's scene, titles and PNG writing.

The colours: C_LIGHT the lightened pair (and mesh orders), C_SOLID the solid reference, C_HOLE
the holes (and hole orders), C_SIDE sidebands, C_OTHER unexplained spectrum peaks.
"""
from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import xarray as xr  # noqa: E402

DPI = 110
_PRETTY_UNITS = {"um": "µm", "degree": "°", "N mm rad-1": "N·mm/rad", "N m rad-1": "N·m/rad",
                 "N m": "N·m", "1": "–", "Hz": "Hz", "s": "s", "N": "N", "J": "J", "mm": "mm",
                 "rad s-1": "rad/s", "MPa": "MPa", "N um-1": "N/µm",
                 "N mm-1 um-1": "N/(mm·µm)"}
C_LIGHT, C_SOLID, C_HOLE, C_SIDE, C_OTHER = "#c0392b", "#2c3e50", "#2980b9", "#27ae60", "#7d3c98"
C_REV = "#d68910"     # once-per-revolution orders of gears with pitch errors or eccentricity
C_DEFAULT = "#16a085"  # the default model's curve beside another model's (the paper example)


def pretty_unit(unit: str | None) -> str:
    """The unit as printed on an axis (UDUNITS spelling -> symbols); '–' for none."""
    if unit is None:
        return "–"
    return _PRETTY_UNITS.get(unit, unit)


def unit_text(v: xr.DataArray) -> str:
    """The unit of a variable as printed: its ``unit_symbol`` where the CF unit cannot say it
    (k_phi in N·mm/rad^n_k), else `pretty_unit` of ``units``."""
    return str(v.attrs["unit_symbol"]) if "unit_symbol" in v.attrs else pretty_unit(v.attrs.get("units"))


def axis_label(v: xr.DataArray, name: str | None = None) -> str:
    """'long name [unit]' of a variable or coordinate; a long name's remark in parentheses is
    left out (it belongs in the archive, not on an axis or a legend title)."""
    ln = str(v.attrs.get("long_name", name or v.name or ""))
    if len(ln) > 40 and " (" in ln:
        ln = ln.split(" (", 1)[0]
    return f"{ln} [{unit_text(v)}]"


def param_label(ds: xr.Dataset, dim: str, n: int = 38) -> str:
    """The one label of a swept parameter on every study figure: 'long name [unit]', or, when
    that is longer than ``n`` characters, its symbol and the dimension's name
    ('N: n_holes [–]' for 'N: number of lightening holes in the web')."""
    if dim not in ds.coords:
        return dim
    label = axis_label(ds[dim], dim)
    if len(label) <= n:
        return label
    ln = str(ds[dim].attrs.get("long_name", ""))
    symbol = f"{ln.split(':', 1)[0]}: " if ":" in ln and len(ln.split(":", 1)[0]) <= 6 else ""
    return f"{symbol}{dim} [{pretty_unit(ds[dim].attrs.get('units'))}]"


def integer_ticks(ax, values, axis: str = "x") -> None:
    """Ticks at whole numbers only when ``values`` are counts (an integer coordinate)."""
    import numpy as np
    from matplotlib.ticker import MaxNLocator
    if np.asarray(values).dtype.kind in "iu":
        (ax.xaxis if axis == "x" else ax.yaxis).set_major_locator(MaxNLocator(integer=True))


def need(ds: xr.Dataset, *names: str) -> None:
    """Raise ``KeyError`` naming the variables a plot needs and the dataset lacks."""
    missing = [n for n in names if n not in ds.variables]
    if missing:
        raise KeyError(f"dataset lacks {', '.join(missing)}")


def archive_scene(ds: xr.Dataset):
    """The scene stored in the archive's ``scene`` attribute (TOML), or None without one."""
    if "scene" not in ds.attrs:
        return None
    from study.scene import loads_scene
    return loads_scene(ds.attrs["scene"], "archive attribute 'scene'")


def archive_title(ds: xr.Dataset) -> str:
    """The title of what the archive holds: for a run archive made from the scene it stores
    (`study.archive.run_variables.scene_title`: the scene as run, not its free text); else its
    ``title`` attribute (a study's title)."""
    sc = archive_scene(ds)
    if sc is not None:
        from study.archive.run_variables import scene_title
        return scene_title(sc)
    return str(ds.attrs.get("title", ""))


def save_figure(fig, path) -> Path:
    """Write the figure as PNG at ``DPI`` (parent folders made), close it, return the path.
    The figure's title goes into the PNG's ``Title`` text field too."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    title = fig._suptitle.get_text() if getattr(fig, "_suptitle", None) is not None else ""
    fig.savefig(path, dpi=DPI, metadata={"Title": title.replace("\n", " / ")} if title else None)
    plt.close(fig)
    return path


def figure_title(fig, ds, what: str, width: int | None = None) -> None:
    """Figure title: what is shown, then the archive's title; wrapped to ``width`` characters."""
    t = archive_title(ds)
    text = f"{what}\n{t}" if t else what
    if width:
        text = "\n".join(textwrap.fill(line, width) for line in text.split("\n"))
    fig.suptitle(text, fontsize=12 if not width else 10)

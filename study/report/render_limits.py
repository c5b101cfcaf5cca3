"""``lightgear render --limit OUTPUT=VALUE``: the limits checked against the archive before any work."""
from __future__ import annotations

import math
from pathlib import Path


def checked_limits(path: Path, items: list[str]) -> dict[str, float]:
    """{output: limit} from ``OUTPUT=VALUE`` items; `study.errors.UsageError` (exit 2) for a malformed
    item, a value that is no finite number, an archive with no sample dimension or an output
    that is not one of its sampled outputs."""
    from study.errors import UsageError
    if not items:
        return {}
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        try:
            v = float(value)
        except ValueError:
            v = math.nan
        if not sep or not name or not math.isfinite(v):
            raise UsageError("--limit", f"expected OUTPUT=VALUE with a finite number, e.g. dte_rms=0.5, got {item!r}")
        out[name] = v
    import xarray as xr

    from study.report.distributions import sample_outputs
    with xr.open_dataset(path, engine="netcdf4") as ds:
        if "sample" not in ds.dims:
            raise UsageError("--limit", f"{path} is not a sampled study (no sample dimension): a limit's exceedance "
                                        "probability needs the distribution of builds")
        known = sample_outputs(ds)
    for name in out:
        if name not in known:
            raise UsageError("--limit", f"{name!r} is not a sampled output of {path} (outputs: {', '.join(known)})")
    return out

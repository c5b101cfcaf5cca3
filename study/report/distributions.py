"""What a sampled study says (`study.sweep.sample`), computed from its archive alone: per output
and grid point the mean and percentiles with confidence intervals, the probability of exceeding
a limit, how the mean and P95 converge with the number of builds and the compute time spent,
and first-order and total Sobol indices of the drawn fields. No solver, no plotting
(`study.report.sample_views` draws them).

Which builds count: those whose ``status`` is 'ok' and whose value is finite (`effects.kept`).

Confidence intervals (level `CONFIDENCE`). A percentile's interval is distribution-free: the
order statistics X_(l) <= x_q <= X_(u) of the independent builds whose binomial coverage
P(l <= B < u), B ~ Binomial(n, q), is at least the level (`quantile_interval`). Where the
sample cannot support one (8 builds cannot bound a P95 at 95 %: even their largest value lies
below the P95 with probability 0.95^8 = 0.66) the interval is NaN, and `min_builds` says how
many builds it takes. The mean's interval comes from a bootstrap over the sample's independent
draws, `N_BOOT` resamples, percentile method. A plain design's builds are independent draws (for
'lhs' and 'sobol' more evenly spread than that, so the intervals are on the safe side); in the
Saltelli design the d + 2 builds of one row (A, B and every AB_i) share their draws, so a
resample takes whole rows, a percentile's interval takes the A and B builds (2 x size
independent draws), and every build counts in the estimates (each build's inputs follow the
distributions). The probability of exceeding a limit takes the Clopper-Pearson interval with
the number of rows as the number of independent trials, so that no exceedance in n rows still
says how large the probability may be.

Sobol indices (Saltelli design only; Saltelli et al. 2010, Comput. Phys. Commun. 181, the
estimators of `scipy.stats.sobol_indices`): with f_A, f_B, f_AB_i the outputs of the rows of
A, B and AB_i, centred on the mean of A and B, and V the variance of A and B together,
  S_i  = mean(f_B (f_AB_i - f_A)) / V             first order: share of V from field i alone
  ST_i = mean((f_A - f_AB_i)^2) / (2 V)           total: with all its interactions
A row with a build not ok is left out of every index of that output.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from study.report.effects import kept

CONFIDENCE = 0.95
N_BOOT = 999
QUANTILES = (0.05, 0.50, 0.95)
BOUNDS = ("estimate", "low", "high")
SAMPLE_VARS = {"status", "message", "wall_time", "sample_block", "sample_row"}


# ---------------------------------------------------------------- the archive's pieces

def drawn_fields(ds: xr.Dataset) -> list[str]:
    """The archive variables that hold the drawn values (dotted paths in their ``scene_field``),
    in the order of the archive's ``sample_fields`` attribute."""
    order = ds.attrs.get("sample_fields", "").split()
    names = [str(v) for v in ds.data_vars if ds[v].dims == ("sample",) and "scene_field" in ds[v].attrs]
    return sorted(names, key=lambda v: order.index(ds[v].attrs["scene_field"])
                  if ds[v].attrs["scene_field"] in order else len(order))


def sample_outputs(ds: xr.Dataset) -> list[str]:
    """The scalar outputs of a sampled study: numeric, over ``sample`` and grid dimensions only."""
    drawn = set(drawn_fields(ds))
    grid = set(grid_dims(ds))
    return [str(v) for v in ds.data_vars if v not in SAMPLE_VARS and v not in drawn and "sample" in ds[v].dims
            and ds[v].dtype.kind in "fiu" and set(ds[v].dims) <= grid | {"sample"}]


def grid_dims(ds: xr.Dataset) -> list[str]:
    """The dimensions of the grid the sample is run at (the status's, less ``sample``)."""
    return [d for d in ds["status"].dims if d != "sample"]


def grid_points(ds: xr.Dataset) -> list[dict]:
    """Every grid point as {dimension: index} (one empty dict for a sample without a grid)."""
    dims = grid_dims(ds)
    shape = [ds.sizes[d] for d in dims]
    return [dict(zip(dims, idx)) for idx in np.ndindex(*shape)] if dims else [{}]


def point_label(ds: xr.Dataset, at: dict) -> str:
    """'gear1.errors.grade = 5' for a grid point ({} -> 'all builds')."""
    if not at:
        return "all builds"
    return ", ".join(f"{ds[d].attrs.get('scene_field', d)} = {ds[d].values[i]!s}" if d in ds.coords else f"{d} = {i}"
                     for d, i in at.items())


def rows_of(ds: xr.Dataset) -> np.ndarray:
    """Independent draw (row) of each build: its Saltelli row, or the build itself."""
    return ds["sample_row"].values if "sample_row" in ds else np.arange(ds.sizes["sample"])


def independent_builds(ds: xr.Dataset) -> np.ndarray:
    """Which builds are independent draws (a boolean mask over ``sample``): every build of a plain
    design, the A and B builds of a Saltelli design (the AB_i builds repeat their draws)."""
    if "sample_block" in ds:
        return ds["sample_block"].values <= 1
    return np.ones(ds.sizes["sample"], bool)


def grouped(values: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Values over the builds -> (rows, builds per row) in row order, NaN where a row has fewer."""
    values = np.asarray(values, dtype=float)
    order = np.argsort(rows, kind="stable")
    uniq, counts = np.unique(rows, return_counts=True)
    out = np.full((uniq.size, counts.max()), np.nan)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    pos = np.arange(rows.size) - np.repeat(start, counts)
    out[np.repeat(np.arange(uniq.size), counts), pos] = values[order]
    return out


def output_at(ds: xr.Dataset, var: str, at: dict) -> np.ndarray:
    """The kept values of ``var`` over the builds at grid point ``at`` (NaN: not ok)."""
    da = kept(ds, var)
    da = da.broadcast_like(ds["status"]) if set(da.dims) != set(ds["status"].dims) else da
    return da.isel(at).transpose("sample").values


# ---------------------------------------------------------------- statistics of one output

def _resample(groups: np.ndarray, n_boot: int, rng) -> np.ndarray:
    """``n_boot`` bootstrap resamples of whole rows, flattened: (n_boot, rows x builds per row)."""
    idx = rng.integers(0, groups.shape[0], (n_boot, groups.shape[0]))
    return groups[idx].reshape(n_boot, -1)


def row_quantiles(values: np.ndarray, qs) -> np.ndarray:
    """Quantiles ``qs`` of each row of ``values`` (NaN left out; linear interpolation, as
    `numpy.quantile`) -> (len(qs), rows); NaN for a row with no finite value. np.nanquantile
    loops over the rows in Python: this sorts once."""
    v = np.sort(values, axis=1)                    # NaN sort last
    n = np.isfinite(v).sum(axis=1)
    out = np.full((len(qs), v.shape[0]), np.nan)
    ok = n > 0
    v, n = v[ok], n[ok]
    for k, q in enumerate(qs):
        pos = q * (n - 1)
        lo = np.floor(pos).astype(int)
        hi = np.minimum(lo + 1, n - 1)
        frac = pos - lo
        rows = np.arange(v.shape[0])
        out[k, ok] = v[rows, lo] * (1.0 - frac) + v[rows, hi] * frac
    return out


def _interval(boot: np.ndarray, level: float) -> tuple[float, float]:
    a = (1.0 - level) / 2.0
    finite = boot[np.isfinite(boot)]
    if finite.size == 0:
        return np.nan, np.nan
    lo, hi = np.quantile(finite, [a, 1.0 - a])
    return float(lo), float(hi)


def _order_indices(n: int, q: float, level: float) -> tuple[int, int]:
    """1-based indices (l, u) of the order statistics that bound the ``q`` quantile of ``n``
    independent values with coverage at least ``level``, each tail at most (1 - level) / 2:
    l the largest with P(B <= l - 1) <= a, u the smallest with P(B >= u) <= a, B ~ Binomial(n, q).
    l < 1 or u > n: the sample cannot support that end."""
    from scipy.stats import binom
    a = (1.0 - level) / 2.0
    lower = int(binom.ppf(a, n, q))                       # smallest k with P(B <= k) >= a: P(B <= lower - 1) < a
    if lower >= 1 and binom.cdf(lower, n, q) <= a:            # ppf's rounding: the largest l that keeps the tail
        lower += 1
    u = int(binom.ppf(1.0 - a, n, q)) + 1             # P(B <= u - 1) >= 1 - a
    return lower, u


def quantile_interval(values: np.ndarray, q: float, level: float = CONFIDENCE) -> tuple[float, float]:
    """Distribution-free ``level`` interval of the ``q`` quantile from independent ``values``
    (NaN left out): the order statistics of `_order_indices`. (NaN, NaN) where the sample cannot
    support one (too few values for that quantile and level: `min_builds`)."""
    v = np.sort(np.asarray(values, dtype=float)[np.isfinite(values)])
    if v.size == 0:
        return np.nan, np.nan
    lower, u = _order_indices(v.size, q, level)
    if lower < 1 or u > v.size:
        return np.nan, np.nan
    return float(v[lower - 1]), float(v[u - 1])


def min_builds(q: float, level: float = CONFIDENCE, limit: int = 100_000) -> int:
    """The fewest independent builds whose order statistics bound the ``q`` quantile at
    ``level`` (e.g. 72 for a P95 at 95 %, 6 for the median)."""
    from scipy.stats import binom
    a = (1.0 - level) / 2.0
    n = np.arange(1, limit + 1)
    ok = (binom.cdf(0, n, q) <= a) & (binom.sf(n - 1, n, q) <= a)     # X_(1) below and X_(n) above often enough
    return int(n[np.argmax(ok)]) if ok.any() else limit


def interval_note(n: int, q: float, level: float = CONFIDENCE) -> str:
    """Why a percentile has no interval: '8 independent builds cannot bound the P95 at 95 % (it takes 72)'."""
    return (f"{n} independent builds cannot bound the P{100 * q:g} at {100 * level:g} % "
            f"(it takes {min_builds(q, level)})")


def summary_statistics(values: np.ndarray, rows: np.ndarray | None = None, quantiles=QUANTILES,
                       level: float = CONFIDENCE, n_boot: int = N_BOOT, seed: int = 0,
                       independent: np.ndarray | None = None) -> dict:
    """Mean and ``quantiles`` of ``values`` (NaN left out): the mean with a bootstrap interval
    over ``rows`` (the independent draw of each value; default: each value its own), each
    quantile with its distribution-free interval from the ``independent`` values (a boolean mask;
    default: the first value of each row) -> ``{"n": count, "n_independent": count,
    "mean": (est, lo, hi), q: (est, lo, hi) ...}``; an interval the sample cannot support is NaN."""
    values = np.asarray(values, dtype=float)
    rows = np.arange(values.size) if rows is None else np.asarray(rows)
    if independent is None:
        independent = np.zeros(values.size, bool)
        independent[np.unique(rows, return_index=True)[1]] = True
    finite = np.isfinite(values)
    free = values[finite & np.asarray(independent, bool)]
    out: dict = {"n": int(finite.sum()), "n_independent": int(free.size)}
    if finite.sum() < 2:
        out["mean"] = (np.nan,) * 3
        out.update({q: (np.nan,) * 3 for q in quantiles})
        return out
    groups = grouped(np.where(finite, values, np.nan), rows)
    groups = groups[np.isfinite(groups).any(axis=1)]
    boot = _resample(groups, n_boot, np.random.default_rng(seed))
    v = values[finite]
    with np.errstate(all="ignore"):
        out["mean"] = (float(v.mean()), *_interval(np.nanmean(boot, axis=1), level))
    for q in quantiles:
        out[q] = (float(np.quantile(v, q)), *quantile_interval(free, q, level))
    return out


def exceedance(values: np.ndarray, limit: float, rows: np.ndarray | None = None,
               level: float = CONFIDENCE) -> tuple[float, float, float]:
    """Probability that ``values`` (NaN left out) exceed ``limit`` with its Clopper-Pearson
    interval, the number of independent rows taken as the number of trials -> (p, lo, hi)."""
    from scipy.stats import beta
    values = np.asarray(values, dtype=float)
    finite = np.isfinite(values)
    if not finite.any():
        return np.nan, np.nan, np.nan
    p = float(np.mean(values[finite] > limit))
    n = np.unique(np.asarray(rows)[finite]).size if rows is not None else int(finite.sum())
    k = p * n
    a = (1.0 - level) / 2.0
    lo = 0.0 if k <= 0 else float(beta.ppf(a, k, n - k + 1))
    hi = 1.0 if k >= n else float(beta.ppf(1.0 - a, k + 1, n - k))
    return p, lo, hi


def convergence(values: np.ndarray, wall_time: np.ndarray, rows: np.ndarray | None = None, q: float = 0.95,
                level: float = CONFIDENCE, n_boot: int = 400, seed: int = 0,
                independent: np.ndarray | None = None) -> dict:
    """Mean and the ``q`` quantile with their intervals over the first 2^k rows (k = 2, 3, ...,
    then all), and the compute time those builds took (sum of their ``wall_time`` [s]) ->
    {"rows", "builds", "time", "mean", "quantile": arrays, the last two (prefixes, 3)}."""
    values = np.asarray(values, dtype=float)
    rows = np.arange(values.size) if rows is None else np.asarray(rows)
    n_rows = int(rows.max()) + 1
    sizes = [int(n) for n in 2 ** np.arange(2, 31) if n < n_rows] + [n_rows]
    mean, quant, time, builds = [], [], [], []
    for n in sizes:
        sel = rows < n
        s = summary_statistics(values[sel], rows[sel], (q,), level, n_boot, seed,
                               None if independent is None else np.asarray(independent)[sel])
        mean.append(s["mean"])
        quant.append(s[q])
        time.append(float(np.nansum(wall_time[sel])))
        builds.append(int(sel.sum()))
    return {"rows": np.array(sizes), "builds": np.array(builds), "time": np.array(time),
            "mean": np.array(mean), "quantile": np.array(quant)}


# ---------------------------------------------------------------- Sobol indices

def saltelli_indices(f_a: np.ndarray, f_b: np.ndarray, f_ab: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First-order and total indices (Saltelli 2010) from the outputs at A and B (..., n) and at
    AB_i (..., d, n) -> (S1, ST), each (..., d). NaN where the output does not vary."""
    mean = np.mean(np.concatenate([f_a, f_b], axis=-1), axis=-1, keepdims=True)
    f_a, f_b = f_a - mean, f_b - mean
    f_ab = f_ab - mean[..., None, :]
    var = np.var(np.concatenate([f_a, f_b], axis=-1), axis=-1)[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        s1 = np.mean(f_b[..., None, :] * (f_ab - f_a[..., None, :]), axis=-1) / var
        st = 0.5 * np.mean((f_a[..., None, :] - f_ab) ** 2, axis=-1) / var
    bad = ~(var > 0)
    return np.where(bad, np.nan, s1), np.where(bad, np.nan, st)


def sobol_indices(values: np.ndarray, block: np.ndarray, row: np.ndarray, level: float = CONFIDENCE,
                  n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """Sobol indices of the drawn fields from the outputs ``values`` of a Saltelli design
    (``block``: 0 A, 1 B, 2 + i AB_i; ``row``) with bootstrap intervals over the rows ->
    {"first": (d, 3), "total": (d, 3) as (estimate, low, high), "rows": rows used}."""
    values = np.asarray(values, dtype=float)
    d = int(block.max()) - 1
    n = int(row.max()) + 1
    table = np.full((d + 2, n), np.nan)
    table[block, row] = values
    use = np.isfinite(table).all(axis=0)
    table = table[:, use]
    out = {"rows": int(use.sum())}
    if table.shape[1] < 4:
        out["first"] = out["total"] = np.full((d, 3), np.nan)
        return out
    s1, st = saltelli_indices(table[0], table[1], table[2:])
    idx = np.random.default_rng(seed).integers(0, table.shape[1], (n_boot, table.shape[1]))
    b1, bt = saltelli_indices(table[0][idx], table[1][idx], np.moveaxis(table[2:][:, idx], 0, 1))
    out["first"] = np.array([(s1[i], *_interval(b1[:, i], level)) for i in range(d)])
    out["total"] = np.array([(st[i], *_interval(bt[:, i], level)) for i in range(d)])
    return out


# ---------------------------------------------------------------- the tables of a study

def _over_grid(ds: xr.Dataset, arrays: dict, dims_after: tuple, coords_after: dict, attrs: dict) -> dict:
    """{name: array over (grid..., *dims_after)} -> DataArrays with the grid's coordinates."""
    gd = grid_dims(ds)
    coords = {d: ds[d] for d in gd if d in ds.coords}
    coords.update(coords_after)
    return {k: xr.DataArray(v, dims=(*gd, *dims_after), coords=coords, attrs=attrs.get(k, {}))
            for k, v in arrays.items()}


def sample_tables(ds: xr.Dataset, outputs: list[str] | None = None, limits: dict | None = None,
                  level: float = CONFIDENCE) -> xr.Dataset:
    """The tables of a sampled study: per output (and grid point) ``sample_mean``,
    ``sample_percentile`` (over ``quantile``), ``sample_count``; per limit
    ``exceedance_probability`` (over ``limit``, its value in ``limit_value``); the convergence
    of the mean and P95 (``convergence_mean``, ``convergence_p95`` over ``rows``, with
    ``convergence_builds`` and ``convergence_time`` [s]); with the Saltelli design
    ``sobol_first`` and ``sobol_total`` over ``field``. Estimates and interval ends lie over
    ``bound`` (estimate, low, high)."""
    outputs = sample_outputs(ds) if outputs is None else outputs
    limits = dict(limits or {})
    for name in limits:
        if name not in ds.data_vars or "sample" not in ds[name].dims:
            raise ValueError(f"limit {name!r}: no sampled output of that name (outputs: {', '.join(sample_outputs(ds))})")
    r = _statistics(ds, outputs, limits, level)
    mean, pct, count, exc, free = r["mean"], r["pct"], r["count"], r["exc"], r["free"]
    bound = {"bound": xr.DataArray(list(BOUNDS), dims="bound")}
    out_c = {"output": xr.DataArray(outputs, dims="output")}
    note = f"bound: the estimate and the ends of its {100 * level:g} % confidence interval"
    arrays = _over_grid(ds, {"sample_mean": mean}, ("output", "bound"), {**out_c, **bound},
                        {"sample_mean": {"long_name": "mean of the output over the builds", "comment": note}})
    arrays |= _over_grid(ds, {"sample_percentile": pct}, ("output", "quantile", "bound"),
                         {**out_c, "quantile": xr.DataArray(list(QUANTILES), dims="quantile",
                                                            attrs={"units": "1", "long_name": "probability"}), **bound},
                         {"sample_percentile": {"long_name": "percentile of the output over the builds",
                                                "comment": note + " (order statistics of the independent builds, "
                                                "binomial coverage; NaN where the sample cannot support one)"}})
    arrays |= _over_grid(ds, {"sample_count": count}, ("output",), out_c,
                         {"sample_count": {"units": "1", "long_name": "builds ok with a finite value"}})
    if limits:
        arrays |= _over_grid(ds, {"exceedance_probability": exc}, ("limit", "bound"),
                             {"limit": xr.DataArray(list(limits), dims="limit"),
                              "limit_value": xr.DataArray([float(v) for v in limits.values()], dims="limit",
                                                          attrs={"comment": "in the units of the output named by limit"}),
                              **bound},
                             {"exceedance_probability": {"units": "1", "long_name": "probability that the output "
                                                         "exceeds limit_value", "comment": note + " (Clopper-Pearson)"}})
    if r["conv"] is not None:
        arrays |= _convergence_arrays(ds, r, out_c, bound, note)
    if r["saltelli"]:
        arrays |= _sobol_arrays(ds, r, out_c, bound, note)
    # each output's units on its statistics
    units = {v: ds[v].attrs.get("units", "") for v in outputs}
    tab = xr.Dataset(arrays)
    tab["output_units"] = xr.DataArray([units[v] for v in outputs], dims="output",
                                       attrs={"long_name": "units of the output (and of its mean and percentiles)"})
    tab["sample_percentile"].attrs["min_independent_builds"] = np.array([min_builds(q, level) for q in QUANTILES])
    return tab.assign_attrs(confidence_level=level, bootstrap_resamples=N_BOOT, independent_builds=int(free.sum()))


def _statistics(ds: xr.Dataset, outputs: list[str], limits: dict, level: float) -> dict:
    """The statistics of `sample_tables` as arrays over (grid..., output, ...): ``mean``,
    ``pct``, ``count``, ``exc`` (per limit), ``conv`` (the convergence of the mean and P95; None
    without points) with ``conv_builds``, ``conv_rows`` and ``conv_time`` [s], ``s1`` and ``st``
    (Sobol indices, with the Saltelli design: ``saltelli``) over the drawn ``fields``; ``free``:
    the independent builds."""
    points = grid_points(ds)
    gshape = tuple(ds.sizes[d] for d in grid_dims(ds))
    rows = rows_of(ds)
    wall = ds["wall_time"].broadcast_like(ds["status"])
    no, nq, nb = len(outputs), len(QUANTILES), len(BOUNDS)
    mean = np.full(gshape + (no, nb), np.nan)
    pct = np.full(gshape + (no, nq, nb), np.nan)
    count = np.zeros(gshape + (no,), np.int64)
    exc = np.full(gshape + (len(limits), nb), np.nan)
    conv = conv_builds = conv_rows = conv_time = None
    saltelli = "sample_block" in ds
    fields = drawn_fields(ds)
    s1 = np.full(gshape + (no, len(fields), nb), np.nan)
    st = np.full_like(s1, np.nan)
    free = independent_builds(ds)
    for at in points:
        pos = tuple(at[d] for d in grid_dims(ds))
        wt = wall.isel(at).transpose("sample").values
        for j, var in enumerate(outputs):
            y = output_at(ds, var, at)
            s = summary_statistics(y, rows, QUANTILES, level, independent=free)
            mean[pos + (j,)] = s["mean"]
            count[pos + (j,)] = s["n"]
            for k, q in enumerate(QUANTILES):
                pct[pos + (j, k)] = s[q]
            c = convergence(y, wt, rows, 0.95, level, independent=free)
            if conv is None:
                nr = c["rows"].size
                conv = {k: np.full(gshape + (no, nr, nb), np.nan) for k in ("mean", "quantile")}
                conv_builds = c["builds"]
                conv_rows = c["rows"]
                conv_time = np.full(gshape + (nr,), np.nan)
            conv["mean"][pos + (j,)] = c["mean"]
            conv["quantile"][pos + (j,)] = c["quantile"]
            conv_time[pos] = c["time"]
            if saltelli:
                ind = sobol_indices(y, ds["sample_block"].values, rows, level)
                s1[pos + (j,)] = ind["first"]
                st[pos + (j,)] = ind["total"]
        for k, (var, lim) in enumerate(limits.items()):
            exc[pos + (k,)] = exceedance(output_at(ds, var, at), lim, rows, level)
    return dict(mean=mean, pct=pct, count=count, exc=exc, conv=conv, conv_builds=conv_builds, conv_rows=conv_rows,
                conv_time=conv_time, s1=s1, st=st, saltelli=saltelli, fields=fields, free=free)


def _convergence_arrays(ds: xr.Dataset, r: dict, out_c: dict, bound: dict, note: str) -> dict:
    """The convergence tables of `sample_tables` (over ``rows``) from `_statistics`' ``r``."""
    conv, conv_rows, conv_time, conv_builds = r["conv"], r["conv_rows"], r["conv_time"], r["conv_builds"]
    rows_c = {"rows": xr.DataArray(conv_rows, dims="rows", attrs={"units": "1", "long_name": "first rows of the sample used"})}
    arrays = _over_grid(ds, {"convergence_mean": conv["mean"], "convergence_p95": conv["quantile"]},
                         ("output", "rows", "bound"), {**out_c, **rows_c, **bound},
                         {"convergence_mean": {"long_name": "mean of the output over the first rows", "comment": note},
                          "convergence_p95": {"long_name": "95th percentile of the output over the first rows",
                                              "comment": note}})
    arrays |= _over_grid(ds, {"convergence_time": conv_time}, ("rows",), rows_c,
                         {"convergence_time": {"units": "s", "long_name": "compute time of the builds of the "
                                                                         "first rows (sum of their wall_time)"}})
    arrays["convergence_builds"] = xr.DataArray(conv_builds, dims="rows", coords=rows_c,
                                                attrs={"units": "1", "long_name": "builds in the first rows"})
    return arrays


def _sobol_arrays(ds: xr.Dataset, r: dict, out_c: dict, bound: dict, note: str) -> dict:
    """The Sobol tables of `sample_tables` (over ``field``) from `_statistics`' ``r``."""
    fields, s1, st = r["fields"], r["s1"], r["st"]
    f_c = {"field": xr.DataArray([ds[f].attrs["scene_field"] for f in fields], dims="field")}
    return _over_grid(ds, {"sobol_first": s1, "sobol_total": st}, ("output", "field", "bound"),
                         {**out_c, **f_c, **bound},
                         {"sobol_first": {"units": "1", "long_name": "first-order Sobol index of the drawn field",
                                          "comment": note + " (bootstrap over the rows)"},
                          "sobol_total": {"units": "1", "long_name": "total Sobol index of the drawn field",
                                          "comment": note + " (bootstrap over the rows)"}})

"""What a whole study says, computed from its archive alone (an xarray.Dataset over the swept
dimensions): main effects, a variance-based sensitivity ranking and the Pareto set of the
mass-saving / TE trade-off. No solver, no plotting (`study.report.study_views` draws them).

Which points count: a point whose ``status`` is not 'ok', or whose value is NaN, is left out
of every mean, variance and Pareto set here (treated as missing, never as zero).

Sensitivity (functional ANOVA on the full-factorial grid, equal weight per grid point):
  V          variance of the output over the grid points kept
  V_i        variance over parameter i of the output's mean over the other parameters
  V_ij       variance over (i, j) of the mean over the others, minus V_i and V_j
  shares     V_i / V and the largest V_ij / V; 'rest' = 1 - their sum (higher interactions)
On a complete grid this is the exact Sobol'/ANOVA split of the grid's variance. With points left
out, the means are over the points kept, the split is approximate, and 'rest' absorbs the
difference (it can then be slightly negative); the number of points used is stored.
"""
from __future__ import annotations

from itertools import combinations

import numpy as np
import xarray as xr

from solver.mbs.kernels.status import POINT_OK

NOT_OUTPUTS = {"status", "message", "wall_time"}
STRESS_RATIO = "root_stress_ratio_gear2"
STRESS_LIMIT = 1.15                  # root stress relative to the solid gear, default Pareto limit
MASS_SAVING = "mass_saving_gear2"
TE_MEASURES = ("ste_p2p", "dte_rms")


def _is_table(name: str) -> bool:
    return name.startswith("pareto_") or name.startswith("sensitivity_")


def kept(ds: xr.Dataset, var: str) -> xr.DataArray:
    """``ds[var]`` as float with NaN where the point is not ok (``status`` != 1) or not finite."""
    da = ds[var].astype(float)
    if "status" in ds:
        da = da.where(ds["status"] == POINT_OK)
    return da.where(np.isfinite(da))


def varies(ds: xr.Dataset, var: str, rtol: float = 1e-9) -> bool:
    """Whether ``var`` takes different values over the points kept: its spread exceeds ``rtol``
    times its magnitude (a ratio converted to 0.05 +- 1e-14 does not vary)."""
    v = kept(ds, var).values
    v = v[np.isfinite(v)]
    return v.size > 1 and float(np.ptp(v)) > rtol * max(float(np.max(np.abs(v))), 1e-300)


def study_outputs(ds: xr.Dataset, swept: list[str]) -> list[str]:
    """The scalar outputs of a study archive: the requested ones (attribute ``outputs``) that are
    numeric and lie over swept dimensions only, else every such variable but the bookkeeping."""
    requested = [s.strip() for s in ds.attrs.get("outputs", "").split(",") if s.strip()]
    names = requested or [str(v) for v in ds.data_vars]
    return [v for v in names if v in ds.data_vars and v not in NOT_OUTPUTS and not _is_table(v)
            and ds[v].dtype.kind in "fiu" and ds[v].dims and set(ds[v].dims) <= set(swept)]


def main_effect(ds: xr.Dataset, var: str, dim: str) -> xr.Dataset:
    """Mean, min and max of ``var`` over every dimension but ``dim`` (points kept only), as a
    Dataset over ``dim`` with variables ``mean``, ``min``, ``max`` and ``count``."""
    da = kept(ds, var)
    if dim not in da.dims:
        da = da.expand_dims({dim: ds[dim].values}).assign_coords({dim: ds[dim]})
    other = [d for d in da.dims if d != dim]
    return xr.Dataset({"mean": da.mean(other), "min": da.min(other), "max": da.max(other),
                       "count": da.notnull().sum(other)})


def variance_split(da: xr.DataArray, dims: list[str]) -> dict:
    """ANOVA split of ``da`` (NaN = left out) over ``dims``: {'total': V, 'count': points used,
    name: V_i for each dim, (a, b): V_ij for each pair of dims}. Dims of ``dims`` that ``da``
    does not depend on get V_i = 0 (the output is constant along them)."""
    out = {"total": float(da.var(skipna=True)) if int(da.notnull().sum()) else np.nan,
           "count": int(da.notnull().sum())}
    own = [d for d in dims if d in da.dims]
    for d in dims:
        out[d] = float(da.mean([o for o in own if o != d]).var(skipna=True)) if d in own else 0.0
    for a, b in combinations(dims, 2):
        if a in own and b in own:
            v = float(da.mean([o for o in own if o not in (a, b)]).var(skipna=True))
            out[(a, b)] = max(v - out[a] - out[b], 0.0) if np.isfinite(v) else np.nan
        else:
            out[(a, b)] = 0.0           # no interaction with a parameter the output ignores
    return out


def sensitivity_table(ds: xr.Dataset, swept: list[str], outputs: list[str] | None = None) -> xr.Dataset:
    """``sensitivity_share`` over (output, term) and ``sensitivity_points`` over output.

    Terms: each swept parameter, then each interaction 'a x b' that is the largest two-way
    interaction of some output, then 'rest'. A pair term is NaN for the outputs whose largest
    interaction is another pair. An output constant over the points kept (V = 0) has NaN shares.
    """
    outputs = study_outputs(ds, swept) if outputs is None else outputs
    splits, largest = {}, {}
    for var in outputs:
        s = variance_split(kept(ds, var), swept)
        pairs = [(k, s[k]) for k in s if isinstance(k, tuple) and np.isfinite(s[k])]
        splits[var] = s
        largest[var] = max(pairs, key=lambda kv: kv[1])[0] if pairs else None
    pair_terms = []
    for p in largest.values():
        if p is not None and p not in pair_terms:
            pair_terms.append(p)
    terms = list(swept) + [f"{a} x {b}" for a, b in pair_terms] + ["rest"]
    share = np.full((len(outputs), len(terms)), np.nan)
    for i, var in enumerate(outputs):
        s = splits[var]
        if not (np.isfinite(s["total"]) and s["total"] > 0):
            continue
        for j, d in enumerate(swept):
            share[i, j] = s[d] / s["total"]
        used = share[i, :len(swept)].sum()
        if largest[var] is not None:
            j = len(swept) + pair_terms.index(largest[var])
            share[i, j] = s[largest[var]] / s["total"]
            used += share[i, j]
        share[i, -1] = 1.0 - used
    coords = {"output": xr.Variable("output", np.array(outputs, dtype=object), {"long_name": "study output"}),
              "term": xr.Variable("term", np.array(terms, dtype=object),
                                  {"long_name": "swept parameter, two-way interaction 'a x b', or rest"})}
    return xr.Dataset({
        "sensitivity_share": xr.Variable(("output", "term"), share, {
            "units": "1", "long_name": "share of the output's variance over the study grid",
            "comment": "functional ANOVA on the full-factorial grid: main effect of a parameter = variance over it "
                       "of the mean over the others; 'a x b' = the output's largest two-way interaction "
                       "(NaN for the other outputs); rest = 1 - the others (higher interactions). Points "
                       "not ok or NaN are left out of the means (then the split is approximate)."}),
        "sensitivity_points": xr.Variable("output", np.array([splits[v]["count"] for v in outputs], np.int32), {
            "units": "1", "long_name": "study points used in the sensitivity share (ok and finite)"}),
    }, coords=coords)


def pareto_mask(gain: np.ndarray, cost: np.ndarray, feasible: np.ndarray) -> np.ndarray:
    """True where a point is feasible, has finite gain and cost, and no other such point has
    at least its gain for at most its cost with one of them strictly better (the most gain for
    the least cost)."""
    gain, cost = np.asarray(gain, float).ravel(), np.asarray(cost, float).ravel()
    ok = np.asarray(feasible, bool).ravel() & np.isfinite(gain) & np.isfinite(cost)
    out = np.zeros(gain.shape, bool)
    idx = np.flatnonzero(ok)
    # sort by cost ascending, gain descending: a point is optimal iff its gain beats every cheaper one
    order = idx[np.lexsort((-gain[idx], cost[idx]))]
    best = -np.inf
    for k in order:
        if gain[k] > best:
            out[k] = True
            best = gain[k]
    return out


def pareto_table(ds: xr.Dataset, stress_ratio: float = STRESS_LIMIT, skip=None) -> xr.Dataset:
    """``pareto_<te>`` for each TE measure of ``TE_MEASURES`` in ``ds``: 1 where the point is in
    the Pareto set of most mass saved (``mass_saving_gear2``) for least TE, among the ok points
    with ``root_stress_ratio_gear2 <= stress_ratio`` (a point whose ratio is NaN, a lightened gear on
    uniform springs say, is left out); int8 CF flags over the study's dims.
    ``skip(what, why)`` is told what cannot be computed."""
    skip = skip or (lambda what, why: None)
    missing = [v for v in (MASS_SAVING, STRESS_RATIO) if v not in ds]
    te = [t for t in TE_MEASURES if t in ds]
    if missing or not te:
        skip("trade-off view", f"the archive has no {', '.join(missing or ['ste_p2p or dte_rms'])}")
        return xr.Dataset()
    gain = kept(ds, MASS_SAVING)
    ratio = kept(ds, STRESS_RATIO)
    out = {}
    for t in te:
        cost = kept(ds, t)
        g, c, r = xr.broadcast(gain, cost, ratio)
        c, r = c.transpose(*g.dims), r.transpose(*g.dims)
        mask = pareto_mask(g.values, c.values, (r <= stress_ratio).values).reshape(g.shape)
        out[f"pareto_{t}"] = xr.Variable(g.dims, mask.astype(np.int8), {
            "units": "1", "long_name": f"in the Pareto set of mass saving against {t}",
            "flag_values": np.array([0, 1], np.int8), "flag_meanings": "not_pareto pareto",
            "comment": f"most {MASS_SAVING} for least {t} among the ok points with {STRESS_RATIO} <= "
                       f"{stress_ratio:g}; 0 also for points not ok, NaN or over the stress limit",
            "stress_limit": float(stress_ratio)})
    return xr.Dataset(out, coords={d: ds[d] for d in gain.dims if d in ds.coords})


def with_study_tables(ds: xr.Dataset, swept: list[str], stress_limit: float = STRESS_LIMIT) -> xr.Dataset:
    """``ds`` with ``sensitivity_share``/``sensitivity_points`` (grid layout, an output present)
    and ``pareto_*`` (mass saving, root stress ratio and a TE measure present) added."""
    add = []
    if swept and "point" not in swept and study_outputs(ds, swept):
        add.append(sensitivity_table(ds, swept))
    add.append(pareto_table(ds, stress_limit))
    return xr.merge([ds, *add], combine_attrs="override")

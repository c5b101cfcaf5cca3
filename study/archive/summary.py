"""The summary scalars of a run archive: STE mean and peak-to-peak, DTE RMS, the amplitudes at
the mesh and hole orders, mesh stiffness, modes, mass and stress per gear (what a study
archives per point and `lightgear run` prints)."""
from __future__ import annotations

import numpy as np
import xarray as xr

from study.archive.schema import GEAR_VARIABLES, STRENGTH_VARIABLES


def summarize(ds: xr.Dataset) -> dict:
    """Scalars a sensitivity study needs (NaN where the archive lacks the analysis)."""
    out = {}
    nan = float("nan")
    off = ds.attrs.get("backlash_offset_um", 0.0)
    if "ste" in ds:
        ste = ds["ste"].values
        out["ste_mean"] = float(np.nanmean(ste))
        out["ste_elastic_mean"] = float(np.nanmean(ste) - flank_side(ds) * off)
        out["ste_p2p"] = float(np.nanmax(ste) - np.nanmin(ste))
    for name in ("mesh_stiffness_mean", "mesh_stiffness_p2p", "c_prime", "c_gamma_alpha", "c_prime_iso6336",
                 "c_gamma_alpha_iso6336", "loaded_contact_ratio", "dynamic_factor"):
        if name in ds:
            out[name] = float(ds[name])
    if "dte" in ds:
        t = ds["time"].values
        sel = t >= ds.attrs.get("spectrum_start_s", 0.0)
        dte = ds["dte"].values[sel]
        out["dte_mean"] = float(np.mean(dte)) if dte.size else nan
        out["dte_rms"] = float(np.sqrt(np.mean((dte - dte.mean()) ** 2))) if dte.size else nan
        out["dte_p2p"] = float(np.ptp(dte)) if dte.size else nan
        out["tooth_force_max"] = float(np.max(ds["contact_force_max"].values[sel])) if dte.size else nan
        out["mesh_efficiency"] = float(ds["mesh_efficiency"]) if "mesh_efficiency" in ds else nan
    if "dte_amplitude" in ds:
        z = ds.attrs["mesh_order"]
        named = named_amplitudes(ds)
        for name, label, order in (("mesh", "Z", z), ("mesh2", "2Z", 2 * z), ("mesh3", "3Z", 3 * z),
                                   ("hole", "N", ds.attrs["hole_order"])):
            if not order > 0:
                out[f"amp_{name}_order"] = nan
            elif label in named:    # the value the summary prints (`spectra.named_peaks`)
                out[f"amp_{name}_order"] = named[label]
            else:
                out[f"amp_{name}_order"] = amplitude_at_order(ds, order)
    if "mode_frequency" in ds:
        out["mesh_mode_frequency"] = float(ds.attrs["mesh_mode_frequency_hz"])
        out["mesh_mode_damping"] = float(ds.attrs["mesh_mode_damping"])
        out["mesh_mode_damping_decay"] = float(ds.attrs.get("mesh_mode_damping_decay", nan))
        for k in (1, 2, 3):
            out[f"critical_speed_{k if k > 1 else ''}z"] = float(_at(ds, "critical_speed", excitation=f"{k}Z", mode=0))
    if "mass" in ds:
        for g in (1, 2):
            for name in GEAR_VARIABLES:
                out[f"{name}_gear{g}"] = float(_at(ds, name, gear=g)) if name in ds else nan
    if "bending_stress" in ds:
        out.update(strength_scalars(ds))
    for k in ("wall_time_springs_s", "wall_time_static_s", "wall_time_dynamic_s"):
        if k in ds.attrs:
            out[k] = float(ds.attrs[k])
    return out



def strength_scalars(ds) -> dict:
    """The per-gear strength scalars of a run (`study.archive.strength`): `STRENGTH_VARIABLES`
    as ``{name}_gear{g}``, the failure mode as its index in `solver.strength.FAILURE_MODES`, the
    root's tensile stress, and S_F at each location and the smallest of them."""
    from solver.strength import FAILURE_MODES
    out = {}
    locations = [str(x) for x in ds["location"].values]
    for g in (1, 2):
        for name in STRENGTH_VARIABLES:
            out[f"{name}_gear{g}"] = float(_at(ds, name, gear=g))
        mode = str(_at(ds, "failure_mode", gear=g))
        out[f"failure_mode_gear{g}"] = float(FAILURE_MODES.index(mode)) if mode in FAILURE_MODES else float("nan")
        out[f"bending_stress_root_gear{g}"] = float(_at(ds, "bending_stress", gear=g, location="root"))
        sf = np.asarray(_at(ds, "bending_safety", gear=g), float)
        for loc, v in zip(locations, sf):
            out[f"bending_safety_{loc}_gear{g}"] = float(v)
        out[f"bending_safety_gear{g}"] = float(np.nanmin(sf)) if np.isfinite(sf).any() else float("nan")
    return out


def _at(ds: xr.Dataset, name: str, **where):
    """``ds[name].sel(**where)`` by position in the plain arrays (a study's task summarises
    every point: xarray's label lookup cost more than the rest of the summary)."""
    var = ds.variables[name]
    index = tuple(list(ds.variables[d].values).index(where[d]) if d in where else slice(None) for d in var.dims)
    return var.values[index]

def flank_side(ds: xr.Dataset) -> float:
    """+1 when the static load drives on the drive flanks, -1 on the coast flanks (a negative
    torque): the side of the backlash offset the elastic TE is measured from."""
    return -1.0 if ds.attrs.get("static_torque_N_m", 1.0) < 0 else 1.0


def named_amplitudes(ds: xr.Dataset) -> dict:
    """DTE amplitude [um] of each named order of the archive's peak table (NaN where no peak
    is resolved), by name ('Z', '2Z', 'N', ...); {} without the table."""
    if "dte_peak_amplitude" not in ds:
        return {}
    return {str(n): float(a) for n, a in zip(ds["dte_peak"].values, ds["dte_peak_amplitude"].values)}


def amplitude_at_order(ds: xr.Dataset, order: float, half_width: float = 0.5) -> float:
    """Largest DTE amplitude [um] within +-half_width orders of ``order``."""
    o = ds["order"].values
    sel = np.abs(o - order) <= half_width
    return float(ds["dte_amplitude"].values[sel].max()) if sel.any() else float("nan")

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
    for name in ("mesh_stiffness_mean", "mesh_stiffness_p2p", "c_prime", "c_gamma_alpha", "mesh_stiffness_mesh_mean",
                 "c_prime_mesh", "c_gamma_alpha_mesh", "c_prime_iso6336", "c_gamma_alpha_iso6336",
                 "loaded_contact_ratio", "dynamic_factor"):
        if name in ds:
            out[name] = float(ds[name])
    if "dte" in ds:
        t = ds["time"].values
        sel = t >= ds.attrs.get("spectrum_start_s", 0.0)
        dte = ds["dte"].values[sel]
        out["dte_mean"] = float(np.mean(dte)) if dte.size else nan
        # (undefined where the steady part misses a mesh period: its note says why)
        whole = dte.size and "steady_window_note" not in ds.attrs
        out["dte_rms"] = float(np.sqrt(np.mean((dte - dte.mean()) ** 2))) if whole else nan
        out["dte_p2p"] = float(np.ptp(dte)) if whole else nan
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


# ---------------------------------------------------------------- a second model beside

def add_default_model(ds: xr.Dataset, default: xr.Dataset) -> xr.Dataset:
    """Store the default model's run ``default`` beside the run archive ``ds`` of another model
    of the same scene (the paper example runs the paper's model): ``ste_default(angle)`` and
    ``dte_default(time)`` [um] and its modes as attributes (``default_coupling_model``,
    ``default_mesh_mode_frequency_hz``, ``default_critical_speed_1z_rad_s``). Returns ``ds``."""
    from study.errors import check_argument
    check_argument(hasattr(ds, "data_vars") and hasattr(default, "data_vars"), "add_default_model", "ds, default",
                   "two run archives (xarray.Dataset)", (ds, default))
    name = str(default.attrs.get("coupling_model", "default"))
    ds.attrs["default_coupling_model"] = name
    if "ste" in ds and "ste" in default and default.sizes["angle"] == ds.sizes["angle"]:
        ds["ste_default"] = ("angle", default["ste"].values, {
            "units": "um", "long_name": f"static transmission error of the default model ({name})"})
    if "dte" in ds and "dte" in default:
        t, td = ds["time"].values, default["time"].values
        dte = default["dte"].values if td.shape == t.shape and np.allclose(td, t) else np.interp(t, td, default["dte"].values)
        ds["dte_default"] = ("time", dte, {
            "units": "um", "long_name": f"dynamic transmission error of the default model ({name})"})
    if "mesh_mode_frequency_hz" in default.attrs:
        ds.attrs["default_mesh_mode_frequency_hz"] = float(default.attrs["mesh_mode_frequency_hz"])
        ds.attrs["default_critical_speed_1z_rad_s"] = float(_at(default, "critical_speed", excitation="1Z", mode=0))
    return ds


def _te_numbers(ds: xr.Dataset, ste: str, dte: str) -> dict:
    """STE peak-to-peak and elastic mean, DTE mean, RMS and peak-to-peak after the ramp [um] of
    the curves ``ste`` and ``dte`` of a run archive (NaN where it lacks one)."""
    nan = float("nan")
    out = dict.fromkeys(("ste_p2p", "ste_elastic_mean", "dte_mean", "dte_rms", "dte_p2p"), nan)
    if ste in ds:
        v = ds[ste].values
        out["ste_p2p"] = float(np.nanmax(v) - np.nanmin(v))
        out["ste_elastic_mean"] = float(np.nanmean(v) - flank_side(ds) * ds.attrs.get("backlash_offset_um", 0.0))
    if dte in ds:
        v = ds[dte].values[ds["time"].values >= ds.attrs.get("spectrum_start_s", 0.0)]
        if v.size:
            out.update(dte_mean=float(v.mean()), dte_rms=float(np.sqrt(np.mean((v - v.mean()) ** 2))),
                       dte_p2p=float(np.ptp(v)))
    return out


COMPARED = (("ste_p2p", "STE peak-to-peak", "um"), ("ste_elastic_mean", "STE mean, elastic part", "um"),
            ("dte_rms", "DTE RMS after the ramp", "um"), ("dte_p2p", "DTE peak-to-peak after the ramp", "um"),
            ("mesh_mode_frequency", "mesh mode", "Hz"), ("critical_speed_z", "1Z critical driver speed", "rad/s"))


def model_comparison(ds: xr.Dataset) -> list[tuple[str, str, float, float]]:
    """The default model's numbers beside those of the model the archive ran (after
    `add_default_model`): [(quantity, unit, default's value, archive model's value)]; [] for an
    archive with no second model."""
    if "default_coupling_model" not in ds.attrs:
        return []
    ran, dflt = _te_numbers(ds, "ste", "dte"), _te_numbers(ds, "ste_default", "dte_default")
    nan = float("nan")
    ran["mesh_mode_frequency"] = float(ds.attrs.get("mesh_mode_frequency_hz", nan))
    dflt["mesh_mode_frequency"] = float(ds.attrs.get("default_mesh_mode_frequency_hz", nan))
    ran["critical_speed_z"] = float(_at(ds, "critical_speed", excitation="1Z", mode=0)) if "critical_speed" in ds else nan
    dflt["critical_speed_z"] = float(ds.attrs.get("default_critical_speed_1z_rad_s", nan))
    return [(what, unit, dflt[key], ran[key]) for key, what, unit in COMPARED
            if np.isfinite(dflt[key]) or np.isfinite(ran[key])]

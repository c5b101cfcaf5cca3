"""Summary scalars of a run archive and the one-screen summary `lightgear run` prints."""
from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from study.report import results


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
        from study.sweep.outputs import GEAR_VARIABLES
        for g in (1, 2):
            for name in GEAR_VARIABLES:
                out[f"{name}_gear{g}"] = float(_at(ds, name, gear=g)) if name in ds else nan
    for k in ("wall_time_springs_s", "wall_time_static_s", "wall_time_dynamic_s"):
        if k in ds.attrs:
            out[k] = float(ds.attrs[k])
    return out


def _at(ds: xr.Dataset, name: str, **where):
    """``ds[name].sel(**where)`` by position in the plain arrays (a study's task summarises
    every point: xarray's label lookup cost more than the rest of the summary)."""
    var = ds.variables[name]
    index = tuple(list(ds.variables[d].values).index(where[d]) if d in where else slice(None) for d in var.dims)
    return var.values[index]


def summarize_sweep(ds: xr.Dataset) -> dict:
    """The scalars of a sweep archive: {name: DataArray over the swept dimensions}, NaN where
    the point's status is not ok (an output not over every swept dimension is broadcast)."""
    from study.sweep.outputs import SCALARS, STATUS
    ok = ds["status"] == STATUS.index("ok")
    return {k: ds[k].where(ok) for k in SCALARS if k in ds.data_vars}


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


NAMED_SHOWN = 0.01      # named peaks printed: those above this fraction of the largest


def print_summary(ds: xr.Dataset, path, wall: float) -> None:
    s = summarize(ds)
    w = sys.stdout.write
    w(f"{ds.attrs.get('title', '')}\n  archive: {path}\n")
    line = f"  contact ratio {ds.attrs['contact_ratio']:.3f} (geometric)"
    if "loaded_contact_ratio" in s:
        line += f", {s['loaded_contact_ratio']:.3f} loaded (mean loaded pairs, tip corners included)"
    w(line + f", backlash offset {ds.attrs['backlash_offset_um']:.3f} um\n")
    if "coupling_model" in ds.attrs:
        w(f"  model: {ds.attrs['coupling_model']} (coupling.model = {ds.attrs.get('coupling_model_setting', '?')})\n")
    if "ste" in s or "ste_mean" in s:
        w(f"  STE: mean {s['ste_mean']:.3f} um (elastic part {s['ste_elastic_mean']:.3f} um), "
          f"peak-to-peak {s['ste_p2p']:.3f} um over {float(ds['angle'][-1]):.4g} deg\n")
    if "mesh_stiffness_mean" in s:
        w(f"  mesh stiffness (tangent, along the line of action): mean {s['mesh_stiffness_mean']:.1f} N/um, "
          f"peak-to-peak {s['mesh_stiffness_p2p']:.1f} N/um\n")
        w("    per face width [N/(mm·um)]   model   ISO 6336-1 B   ratio\n")
        for name, what in (("c_prime", "c' single pair"), ("c_gamma_alpha", "c_gamma_alpha mesh")):
            m, iso = s[name], s[f"{name}_iso6336"]
            w(f"    {what:<28s} {m:6.2f}   {iso:12.2f}   {m / iso:5.3f}\n")
    if "tooth_stiffness_pitch" in ds:
        k = ds["tooth_stiffness_pitch"]
        w("  tooth stiffness at the pitch point [N/um]: " + ", ".join(
            f"gear {g} {float(k.sel(gear=g).min()):.1f}-{float(k.sel(gear=g).max()):.1f}" for g in (1, 2)) + "\n")
    runup = "order_amplitude" in ds
    if "dte_rms" in s and not runup:
        w(f"  DTE after {ds.attrs['spectrum_start_s']:.3g} s: mean {s['dte_mean']:.3f} um, RMS {s['dte_rms']:.3f} um, "
          f"peak-to-peak {s['dte_p2p']:.3f} um, largest contact force {s['tooth_force_max']:.1f} N "
          f"({ds.attrs['dynamic_status']}, dt {ds.attrs['dt_s'] * 1e6:.3g} us)\n")
        if np.isfinite(s["mesh_efficiency"]):
            w(f"  mesh efficiency after the ramp {s['mesh_efficiency'] * 100:.3f} % (flank friction and dampers)\n")
        for f, o, a in results.largest_peaks(ds):
            w(f"    peak {a:8.4f} um at {f:8.1f} Hz = order {o:6.2f}\n")
    if "dynamic_factor" in s:
        fm = ds["dte_tooth_force_max"]
        w(f"  dynamic tooth force after {ds.attrs.get('spectrum_start_s', 0.0):.3g} s: largest "
          f"{float(fm.sel(gear=1).max()):.1f} N on the driver, {float(fm.sel(gear=2).max()):.1f} N on the driven gear; "
          f"dynamic factor K_v {s['dynamic_factor']:.3f} ({ds['dynamic_factor'].attrs.get('comment', '')})\n")
    if "mesh_mode_frequency_hz" in ds.attrs:
        a = ds.attrs
        line = (f"  mesh mode: {a['mesh_mode_frequency_hz']:.0f} Hz, damping {a['mesh_mode_damping']:.4f} of critical "
                f"(modal, mean over the mesh period)")
        if "mesh_mode_damping_decay" in a:
            line += f", {a['mesh_mode_damping_decay']:.4f} from the free decay ({a['mesh_mode_damping_at_decay']:.4f} modal there)"
        w(line + "\n")
        cs = ds["critical_speed"].sel(mode=0)
        w("    critical driver speeds [rad/s]: " + ", ".join(f"{e} {v:.0f}" for e, v in zip(ds["excitation"].values, cs.values)
                                                          if v < 1000) + "\n")
    if "order_amplitude" in ds:
        sp, order, amp = ds["runup_speed"].values, ds["tracked_order"].values, ds["order_amplitude"].values
        z = ds.attrs["mesh_order"]
        parts = []
        for k in (1, 2, 3):
            sel = np.abs(order - k * z) <= 0.5
            cut = amp[:, sel].max(axis=1)
            parts.append(f"{k}Z at {sp[np.argmax(cut)]:.0f} rad/s {cut.max():.3g} um")
        w(f"  run-up {sp[0]:.0f}-{sp[-1]:.0f} rad/s ({ds.attrs['dynamic_status']}, dt {ds.attrs['dt_s'] * 1e6:.3g} us), "
          "resonance peaks (order, driver speed, DTE amplitude): " + ", ".join(parts) + "\n")
    if "mass" in ds:
        for g in (1, 2):
            line = (f"  gear {g}: mass {s[f'mass_gear{g}']:.4f} kg ({s[f'mass_saving_gear{g}']:.1f} % saved against "
                    f"solid), inertia {s[f'inertia_gear{g}']:.5g} kg mm2")
            if np.isfinite(s[f"root_stress_max_gear{g}"]):
                line += (f", root stress max {s[f'root_stress_max_gear{g}']:.1f} MPa "
                         f"(x{s[f'root_stress_ratio_gear{g}']:.3f} solid)")
            else:
                line += ", root stress not computed (its springs need no FE)"
            w(line + "\n")
    for what in ("dte", "ste"):
        if f"{what}_peak_amplitude" in ds:
            named = [(str(n), float(a)) for n, a in zip(ds[f"{what}_peak"].values, ds[f"{what}_peak_amplitude"].values)
                     if np.isfinite(a) and not str(n).startswith("other")]
            top = max((a for _, a in named), default=0.0)
            shown = [(n, a) for n, a in named if a >= NAMED_SHOWN * top]
            more = f" (and {len(named) - len(shown)} below {NAMED_SHOWN:.0%} of the largest: {what}_peak_*)" \
                if len(shown) < len(named) else ""
            w(f"  {what.upper()} at named orders [um]: " + ", ".join(f"{n} {a:.3g}" for n, a in shown) + more + "\n")
    w("  wall time: " + ", ".join(f"{k[10:-2]} {ds.attrs[k]:.3f} s" for k in ds.attrs if k.startswith("wall_time_"))
      + f", total {wall:.2f} s\n")

"""The one-screen summary `lightgear run` prints of a run archive (its scalars: `study.archive.summary`)."""
from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from study.archive.run_variables import largest_peaks
from study.archive.summary import summarize

NAMED_SHOWN = 0.01      # named peaks printed: those above this fraction of the largest


def print_summary(ds: xr.Dataset, path, wall_time: float) -> None:
    """The one-screen summary `lightgear run` prints for a run archive written to ``path`` after
    ``wall_time`` [s]."""
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
        for f, o, a in largest_peaks(ds):
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
      + f", total {wall_time:.2f} s\n")

"""The one-screen summary `lightgear run` prints of a run archive (its scalars: `study.archive.summary`)."""
from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from study.archive.run_variables import largest_peaks
from study.archive.summary import model_comparison, summarize

NAMED_SHOWN = 0.01      # named peaks printed: those above this fraction of the largest

# what each model is, in the words a comparison of two of them needs (docs/models.md)
MODEL_ROLES = {"paper": "the paper's MUBOCO-PR: reproduces the paper",
               "compliance": "agrees with the FE reference",
               "body-torsion": "body torsion spring, no tooth-to-tooth coupling"}


def model_label(name: str, default: bool = False) -> str:
    """'default: compliance (agrees with the FE reference)', 'paper (the paper's MUBOCO-PR: ...)'."""
    role = MODEL_ROLES.get(name)
    return f"{'default: ' if default else ''}{name}" + (f" ({role})" if role else "")


def comparison_lines(ds: xr.Dataset) -> list[str]:
    """The table of the default model's numbers beside those of the model the archive ran
    (`study.archive.summary.model_comparison`), as lines; [] when the archive has one model."""
    rows = model_comparison(ds)
    if not rows:
        return []
    dflt, ran = ds.attrs["default_coupling_model"], str(ds.attrs.get("coupling_model", "?"))
    width = max(len(f"{q} [{u}]") for q, u, _, _ in rows) + 2
    out = [f"  two models of this scene (docs/models.md): {model_label(dflt, True)}; {model_label(ran)}",
           f"    {'':{width}s}{'default: ' + dflt:>22s}{ran:>14s}"]
    for q, u, d, r in rows:
        digits = 3 if u == "um" else 0
        out.append(f"    {q + ' [' + u + ']':{width}s}{d:22.{digits}f}{r:14.{digits}f}")
    out.append(f"  below: the {ran} model's run in full; ste_default, dte_default: the default's curves")
    return out


CRITICAL_SPEED_SPAN = 2.0     # critical speeds listed: up to this many times the run's top driver speed


def critical_speed_line(ds: xr.Dataset) -> str:
    """The mesh mode's critical driver speeds [rad/s] of the excitations that matter for the
    run: those up to CRITICAL_SPEED_SPAN times its top driver speed (all of them for a run
    without one), and otherwise the lowest."""
    cs = ds["critical_speed"].sel(mode=0).values
    names = [str(e) for e in ds["excitation"].values]
    top = float(ds.attrs.get("driver_speed_max_rad_s", 0.0))
    limit = CRITICAL_SPEED_SPAN * top if top > 0 else float("inf")
    shown = [f"{e} {v:.0f}" for e, v in zip(names, cs) if v <= limit]
    linear = (" (linear estimates: the teeth lost contact in this run)"
              if ds.attrs.get("contact_lost_fraction", 0.0) > 0 else "")
    if shown:
        return "    critical driver speeds [rad/s]" + linear + ": " + ", ".join(shown) + "\n"
    low = int(np.nanargmin(cs))
    return (f"    critical driver speeds [rad/s]: none up to {limit:.0f} ({CRITICAL_SPEED_SPAN:g} x the run's "
            f"{top:g} rad/s); the lowest {names[low]} {cs[low]:.0f}\n")


def print_summary(ds: xr.Dataset, path, wall_time: float) -> None:
    """The one-screen summary `lightgear run` prints for a run archive written to ``path`` after
    ``wall_time`` [s]."""
    s = summarize(ds)
    w = sys.stdout.write
    _head(ds, s, w, path)
    _stiffness(ds, s, w)
    _dynamics(ds, s, w)
    _runup(ds, w)
    _gears(ds, s, w)
    _named_orders(ds, w)
    w("  wall time: " + ", ".join(f"{k[10:-2]} {ds.attrs[k]:.3f} s" for k in ds.attrs if k.startswith("wall_time_"))
      + f", total {wall_time:.2f} s\n")


def _head(ds: xr.Dataset, s: dict, w, path) -> None:
    """The title, the archive, the comparison, the contact ratio, the model and the STE (``w``: the
    writer, ``s``: `summarize`'s scalars)."""
    w(f"{ds.attrs.get('title', '')}\n  archive: {path}\n")
    for line in comparison_lines(ds):
        w(line + "\n")
    line = f"  contact ratio {ds.attrs['contact_ratio']:.3f} (geometric)"
    if "loaded_contact_ratio" in s:
        line += f", {s['loaded_contact_ratio']:.3f} loaded (mean loaded pairs, tip corners included)"
    w(line + f", backlash offset {ds.attrs['backlash_offset_um']:.3f} um\n")
    if "coupling_model" in ds.attrs:
        w(f"  model: {ds.attrs['coupling_model']} (coupling.model = {ds.attrs.get('coupling_model_setting', '?')})\n")
    if "ste" in s or "ste_mean" in s:
        w(f"  STE: mean {s['ste_mean']:.3f} um (elastic part {s['ste_elastic_mean']:.3f} um), "
          f"peak-to-peak {s['ste_p2p']:.3f} um over {float(ds['angle'][-1]):.4g} deg\n")


def _stiffness(ds: xr.Dataset, s: dict, w) -> None:
    """The mesh stiffness against ISO 6336-1 and the tooth stiffness at the pitch point."""
    if "mesh_stiffness_mean" in s:
        w(f"  mesh stiffness (tangent, along the line of action): pair {s['mesh_stiffness_mean']:.1f} N/um mean (both "
          f"bodies' wind-up from the bore in it), peak-to-peak {s['mesh_stiffness_p2p']:.1f} N/um")
        if "mesh_stiffness_mesh_mean" in s:
            w(f"; mesh alone {s['mesh_stiffness_mesh_mean']:.1f} N/um mean")
        w("\n    per face width [N/(mm·um)]    pair   mesh alone   ISO 6336-1 B   mesh alone / ISO\n")
        for name, what in (("c_prime", "c' single pair"), ("c_gamma_alpha", "c_gamma_alpha mesh")):
            m, alone, iso = s[name], s.get(f"{name}_mesh", float("nan")), s[f"{name}_iso6336"]
            w(f"    {what:<28s} {m:6.2f}   {alone:10.2f}   {iso:12.2f}   {alone / iso:16.3f}\n")
        a = ds["c_prime_iso6336"].attrs if "c_prime_iso6336" in ds else {}
        if "value_without_C_M_and_low_load_factor" in a:
            el = [ds[f"{n}_iso6336"].attrs["value_without_C_M_and_low_load_factor"] for n in ("c_prime", "c_gamma_alpha")]
            w(f"    ISO: Method B with the low-load factor {a['low_load_factor']:.3f} (F_t/b {a['load_per_width_N_per_mm']:.1f} "
              f"N/mm); without it and C_M 0.8 (an elastic pair of perfect involutes): c' {el[0]:.2f}, c_gamma_alpha "
              f"{el[1]:.2f}\n")
    if "tooth_stiffness_pitch" in ds:
        k = ds["tooth_stiffness_pitch"]
        line = "  tooth stiffness at the pitch point [N/um], the body rigid: " + ", ".join(
            f"gear {g} {_range(k.sel(gear=g))}" for g in (1, 2))
        if "tooth_stiffness_pitch_bore" in ds:
            kb = ds["tooth_stiffness_pitch_bore"]
            line += "; with the wind-up from the bore: " + ", ".join(f"gear {g} {_range(kb.sel(gear=g))}" for g in (1, 2))
        w(line + "\n")


def _dynamics(ds: xr.Dataset, s: dict, w) -> None:
    """The DTE, its largest peaks, the dynamic tooth force and the mesh mode with its critical speeds."""
    runup = "order_amplitude" in ds
    if "dte_rms" in s and not runup:
        short = ds.attrs.get("steady_window_note")
        spread = (f"RMS and peak-to-peak undefined ({short})" if short else
                  f"RMS {s['dte_rms']:.3f} um, peak-to-peak {s['dte_p2p']:.3f} um")
        w(f"  DTE after {ds.attrs['spectrum_start_s']:.3g} s: mean {s['dte_mean']:.3f} um, {spread}, "
          f"largest contact force {s['tooth_force_max']:.1f} N "
          f"({ds.attrs['dynamic_status']}, dt {ds.attrs['dt_s'] * 1e6:.3g} us)\n")
        if np.isfinite(s["mesh_efficiency"]):
            w(f"  mesh efficiency after the ramp {s['mesh_efficiency'] * 100:.3f} % (flank friction and dampers)\n")
        for f, o, a in largest_peaks(ds):
            w(f"    peak {a:8.4f} um at {f:8.1f} Hz = order {o:6.2f}\n")
    if "dynamic_factor" in s:
        fm = ds["dte_tooth_force_max"]
        w(f"  dynamic tooth force after {ds.attrs.get('spectrum_start_s', 0.0):.3g} s: largest "
          f"{float(fm.sel(gear=1).max()):.1f} N on the driver, {float(fm.sel(gear=2).max()):.1f} N on the driven gear; "
          + (f"dynamic factor K_v {s['dynamic_factor']:.3f} ({ds['dynamic_factor'].attrs.get('comment', '')})\n"
             if np.isfinite(s["dynamic_factor"]) else
             f"dynamic factor K_v {ds['dynamic_factor'].attrs.get('comment', 'undefined')}\n"))
    if "mesh_mode_frequency_hz" in ds.attrs:
        a = ds.attrs
        line = (f"  mesh mode: {a['mesh_mode_frequency_hz']:.0f} Hz, damping {a['mesh_mode_damping']:.4f} of critical "
                f"(modal, mean over the mesh period)")
        if "mesh_mode_damping_decay" in a:
            line += f", {a['mesh_mode_damping_decay']:.4f} from the free decay ({a['mesh_mode_damping_at_decay']:.4f} modal there)"
        w(line + "\n")
        w(critical_speed_line(ds))


def _runup(ds: xr.Dataset, w) -> None:
    """A run-up's resonance peaks, and where its teeth lost contact."""
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
        lost = ds.attrs.get("contact_lost_speed_rad_s")
        if lost is not None and "critical_speed" in ds:
            # the teeth separated: the response left the linear range the modal speeds stand for
            cs = ds["critical_speed"].sel(mode=0)
            peaks = []
            for k in (1, 2, 3):
                sel = np.abs(order - k * z) <= 0.5
                modal = float(cs.sel(excitation=f"{k}Z"))
                if sp[0] <= modal <= sp[-1]:
                    at = float(sp[np.argmax(amp[:, sel].max(axis=1))])
                    peaks.append(f"{k}Z measured {at:.0f} rad/s, modal {modal:.0f} ({100 * (at / modal - 1):+.1f} %)")
            w(f"    the teeth lost contact between {lost[0]:.0f} and {lost[1]:.0f} rad/s: the response left the linear "
              "range, and the critical speeds are linear estimates" + (": " + ", ".join(peaks) if peaks else "") + "\n")


def _gears(ds: xr.Dataset, s: dict, w) -> None:
    """Each gear's mass, inertia and root stress, and the strength lines."""
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
    if "bending_stress" in ds:
        for line in strength_lines(ds):
            w(line + "\n")


def _named_orders(ds: xr.Dataset, w) -> None:
    """The DTE and STE at the named orders."""
    for what in ("dte", "ste"):
        if f"{what}_peak_amplitude" in ds:
            named = [(str(n), float(a)) for n, a in zip(ds[f"{what}_peak"].values, ds[f"{what}_peak_amplitude"].values)
                     if np.isfinite(a) and not str(n).startswith("other")]
            top = max((a for _, a in named), default=0.0)
            shown = [(n, a) for n, a in named if a >= NAMED_SHOWN * top]
            more = f" (and {len(named) - len(shown)} below {NAMED_SHOWN:.0%} of the largest: {what}_peak_*)" \
                if len(shown) < len(named) else ""
            w(f"  {what.upper()} at named orders [um]: " + ", ".join(f"{n} {a:.3g}" for n, a in shown) + more + "\n")


def _range(k: xr.DataArray) -> str:
    """'lo-hi' of the finite values of ``k`` with one decimal (one value when they are equal)."""
    lo, hi = float(k.min()), float(k.max())
    return f"{lo:.1f}" if f"{lo:.1f}" == f"{hi:.1f}" else f"{lo:.1f}-{hi:.1f}"


def strength_lines(ds: xr.Dataset) -> list[str]:
    """The printed strength of each gear: largest tensile stress at the root, rim and web, m_B,
    Y_B, the failure mode and S_F; the FE root stress beside ISO 6336-3's at the HPSTC."""
    out = []
    kv = ds["bending_safety"].attrs.get("loads", "")
    for g in (1, 2):
        b = ds["bending_stress"].sel(gear=g).values
        if not np.isfinite(b[0]):
            continue
        sf = ds["bending_safety"].sel(gear=g).values
        site = str(ds["web_stress_site"].sel(gear=g).values)
        web = f"web {b[2]:.1f} MPa ({site})" if np.isfinite(b[2]) else "web: no openings"
        mat = f"{ds['gear_material'].sel(gear=g).values}, sigma_FG {float(ds['bending_limit_stress'].sel(gear=g)):g} MPa"
        out.append(f"  gear {g} strength: largest tensile stress root {b[0]:.1f} MPa, rim {b[1]:.1f} MPa, {web}; "
                   f"m_B {float(ds['backup_ratio'].sel(gear=g)):.2f}, Y_B {float(ds['rim_thickness_factor_iso6336'].sel(gear=g)):.3f}; "
                   f"failure mode {ds['failure_mode'].sel(gear=g).values}; S_F ({mat}, {kv}) "
                   + ", ".join(f"{loc} {v:.2f}" for loc, v in zip(ds["location"].values, sf) if np.isfinite(v)))
        fe, iso = float(ds["root_stress_hpstc"].sel(gear=g)), float(ds["root_stress_iso6336"].sel(gear=g))
        y_f, y_s = (float(ds[f"{n}_iso6336"].sel(gear=g)) for n in ("tooth_form_factor", "stress_correction_factor"))
        out.append(f"    root stress at the HPSTC (one tooth, F = T/rb): FE {fe:.1f} MPa, ISO 6336-3 sigma_F0 {iso:.1f} MPa "
                   f"(Y_F {y_f:.3f}, Y_S {y_s:.3f}): FE/ISO {fe / iso:.3f}")
    return out


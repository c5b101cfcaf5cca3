"""Solver results -> labelled xarray datasets (CF-style units and long names) and NetCDF.

The run archive of one scene holds:
  ste(angle)               static transmission error [um] over driver rotation [deg]
  ste_contacts(angle)      loaded tooth contacts [1]
  ste_tooth_force(angle, tooth)  normal force on each driver tooth [N]
  dte(time)                dynamic transmission error [um]
  contact_force_max(time)  largest contact force over each output interval [N]
  dte_contacts(time), driver_torque(time), energy_balance_error(time)
  mesh_efficiency                  work out over work in after the ramp (with flank friction) [1]
  dte_amplitude(frequency) amplitude spectrum of DTE after the ramp [um], coordinate order
  dte_peak_*(dte_peak)     named peaks of that spectrum (hole order N, mesh order Z, harmonics,
                           sidebands kZ+-N, the largest unexplained ones): order, frequency, amplitude
  ste_amplitude(ste_order) amplitude spectrum of STE over orders of the driven gear's rotation [um]
  ste_peak_*(ste_peak)     named peaks of the STE spectrum
  tooth_stiffness(gear, tooth), stiffness_ratio(gear, tooth)
Global attributes: the scene as TOML, backlash offset, mesh and hole orders, versions.
"""
from __future__ import annotations

import datetime
import functools
import hashlib
import platform
from importlib import metadata
from pathlib import Path

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.energy_guard import energy_error_limit
from study.report.spectra import WINDOW, amplitude_spectrum, named_peaks, ste_order_spectrum

INACCURATE = 6      # `solver.mbs.dynamics.INACCURATE` (not imported: the reports load no numba)


@functools.lru_cache(maxsize=1)
def versions() -> str:
    """The installed versions of the packages a result depends on; read once per process (the
    package metadata lookups took 0.09 s a call, a third of a sampled build's statics)."""
    out = []
    for pkg in ("lightgear", "numpy", "numba", "scipy", "xarray", "netCDF4", "dask", "scikit-fem", "gmsh"):
        try:
            out.append(f"{pkg} {metadata.version(pkg)}")
        except metadata.PackageNotFoundError:
            pass
    return ", ".join(out)


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """Hash of the source of the `solver` and `study` packages (file names and contents): any
    change to the code that computes results changes it. Computed once per process."""
    root = Path(__file__).resolve().parents[2]
    h = hashlib.sha256()
    for pkg in ("solver", "study"):
        for path in sorted((root / pkg).rglob("*.py")):
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


def history_line(created: str | None = None) -> str:
    """CF ``history``: UTC time, then the program and its arguments."""
    import shlex
    import sys
    created = created or datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    spec = getattr(sys.modules.get("__main__"), "__spec__", None)
    program = f"python -m {spec.name.removesuffix('.__main__')}" if spec is not None and spec.name else Path(sys.argv[0]).name
    return f"{created} {program} {shlex.join(sys.argv[1:])}".strip()


def provenance() -> dict:
    created = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    return {
        "software": versions(),
        "code_fingerprint": code_fingerprint(),
        "machine": f"{platform.node()} {platform.machine()} {platform.processor() or ''} python {platform.python_version()}".strip(),
        "created": created,
        "history": history_line(created),
        "Conventions": "CF-1.8",
    }


def scene_title(scene) -> str:
    """A title that says what the scene as run is (never its free-text title, which an
    override leaves behind): teeth and module, each body, load and speed, coupling model."""
    g1, g2 = scene.gear1, scene.gear2

    def body(name, g, n):
        b = g.body
        if not scene.is_lightened(n):
            return f"{name} solid"
        holes = f"{b.holes} holes of R_h {b.hole_radius:g} mm" if b.holes else "no holes"
        return f"{name} {holes}, web {b.web_thickness:g} mm, rim {b.rim_height:g} mm"
    parts = [f"z {g1.teeth}/{g2.teeth}, m {g1.module:g} mm", body("driver", g1, 1), body("driven", g2, 2)]
    d, qs = scene.dynamic, scene.quasi_static
    load = f"{(d.torque if d.enabled else qs.torque):g} N·m"
    if d.enabled:
        load += f", {d.speed:g} rad/s" if d.speed_end <= 0 else f", run-up 0-{d.speed_end:g} rad/s"
    parts.append(load)
    if scene.coupling.model != "none":
        parts.append(f"coupling {scene.coupling.model}")
    return "; ".join(parts)


def _var(dims, data, unit, long_name, **attrs):
    return xr.Variable(dims, data, {"units": unit, "long_name": long_name, **attrs})


def static_variables(res, offset_m: float) -> dict:
    angle_deg = np.degrees(res.angle)
    coords = {"angle": _var("angle", angle_deg, "degree", "driver rotation from the nominal position")}
    data = {
        "ste": _var("angle", res.te * units.UM_PER_M, "um", "static transmission error rb1*theta1 + rb2*theta2",
                    comment=f"zero at the zero-backlash conjugate position; rigid teeth in drive contact read +{offset_m * 1e6:.4f} um"),
        "ste_contacts": _var("angle", res.n_contacts.astype("int16"), "1", "loaded tooth contacts"),
        "ste_tooth_force": _var(("angle", "driver_tooth"), res.tooth_force, "N", "normal contact force on each driver tooth"),
        "ste_converged": _var("angle", res.converged.astype("int8"), "1", "static equilibrium reached (1) or not (0)"),
    }
    coords["driver_tooth"] = _var("driver_tooth", np.arange(res.tooth_force.shape[1]), "1", "driver tooth index")
    return coords, data


def peak_variables(prefix: str, peaks, frequency_per_order: float | None = None) -> tuple[dict, dict]:
    """A small table of named spectral peaks along dimension ``{prefix}_peak`` (names as coordinate)."""
    dim = f"{prefix}_peak"
    coords = {dim: _var(dim, np.array([p.name for p in peaks], dtype=object), "1",
                        "peak name: N hole order, Z mesh order, kZ+-N sidebands, R1 and R2 the driver's and the driven "
                        "gear's once-per-revolution orders (gears with errors), other k = k-th largest unexplained peak")}
    what = prefix.upper()
    data = {
        f"{dim}_nominal_order": _var(dim, np.array([p.nominal for p in peaks]), "1", f"nominal order of the named {what} peak (driven-gear revolutions)"),
        f"{dim}_order": _var(dim, np.array([p.order for p in peaks]), "1", f"order where the {what} peak was found (driven-gear revolutions)"),
        f"{dim}_amplitude": _var(dim, np.array([p.amplitude for p in peaks]), "um", f"{what} amplitude at the peak"),
    }
    if frequency_per_order is not None:
        data[f"{dim}_frequency"] = _var(dim, np.array([p.order for p in peaks]) * frequency_per_order, "Hz", f"frequency of the {what} peak")
    return coords, data


def ste_spectrum_variables(angle_deg, ste_um, z1: int, z2: int, hole_order: float, pad: int = 4,
                           revolutions: bool = False) -> tuple[dict, dict]:
    """STE amplitude spectrum over orders per revolution of the driven gear, and its named peaks
    (``revolutions``: also each gear's once-per-revolution order, R1 = Z2/Z1 and R2 = 1)."""
    angle_deg = np.asarray(angle_deg, float)
    if angle_deg.size < 16:
        return {}, {}
    step = float(angle_deg[1] - angle_deg[0])
    order, amp, res = ste_order_spectrum(ste_um, step, z1, z2, pad=pad)
    coords = {"ste_order": _var("ste_order", order, "1", "order of the driven gear's rotation (STE spectrum)")}
    data = {"ste_amplitude": _var("ste_order", amp, "um", "one-sided amplitude spectrum of STE over driven-gear orders",
                                  window=WINDOW, resolution_orders=res, zero_padding=pad,
                                  record_driven_revolutions=1.0 / res,
                                  comment="driven rotation = driver rotation * z1/z2; NaN samples interpolated")}
    c, d = peak_variables("ste", named_peaks(order, amp, hole_order, z2, res,
                                             revolution_orders=(z2 / z1, 1.0) if revolutions else None))
    coords.update(c); data.update(d)
    return coords, data


def dynamic_variables(res, spectrum_start: float, driven_speed: float, hole_order: float = 0.0,
                      mesh_order: float | None = None, revolution_orders: tuple | None = None) -> tuple[dict, dict, dict]:
    """DTE and its spectrum after ``spectrum_start`` [s] with the named peaks (``revolution_orders``:
    see `study.report.spectra.named_orders`)."""
    coords = {"time": _var("time", res.time, "s", "time",
                           comment="elapsed time from the start of the run, not a calendar time")}
    data = {
        "dte": _var("time", res.te * units.UM_PER_M, "um", "dynamic transmission error rb1*theta1 + rb2*theta2"),
        "contact_force_max": _var("time", res.force_max, "N", "largest tooth contact force over the output interval"),
        "dte_contacts": _var("time", res.n_contacts.astype("int16"), "1", "loaded tooth contacts"),
        "driver_torque": _var("time", res.driver_torque, "N m", "torque applied by the driver"),
        "energy_balance_error": _var("time", res.energy_error, "J", "work in - change of kinetic and potential energy "
                                     "- dissipated energy - energy taken out by the coupled set's switches"),
    }
    attrs = {}
    sel = res.time >= spectrum_start
    if sel.sum() >= 16 and res.status in (0, INACCURATE):     # an inaccurate run keeps its numbers, flagged
        dt = float(res.time[1] - res.time[0])
        f, a = amplitude_spectrum(res.te[sel] * units.UM_PER_M, dt)
        f_rot = driven_speed / (2 * np.pi)
        coords["frequency"] = _var("frequency", f, "Hz", "frequency")
        coords["order"] = _var("frequency", f / f_rot if f_rot > 0 else np.full_like(f, np.nan), "1",
                               "order of the driven gear's rotation")
        data["dte_amplitude"] = _var("frequency", a, "um", "one-sided amplitude spectrum of DTE after the ramp",
                                     window=WINDOW, resolution_Hz=1.0 / (sel.sum() * dt), start_s=float(res.time[sel][0]))
        if f_rot > 0 and mesh_order:
            peaks = named_peaks(f / f_rot, a, hole_order, mesh_order, 1.0 / (sel.sum() * dt) / f_rot,
                                revolution_orders=revolution_orders)
            c, v = peak_variables("dte", peaks, f_rot)
            coords.update(c); data.update(v)
    attrs.update(dt_s=res.dt, steps=res.steps, omega_max_rad_s=res.omega_max, dynamic_status=res.message,
                 max_active_teeth=res.max_active_teeth)
    if res.time.size > 1:
        # the energy guard's margin: largest |error| / limit over the run (flagged above 1)
        err = np.abs(res.energy_error)
        attrs.update(energy_error_max_J=float(err.max()), potential_energy_max_J=float(np.max(res.potential)),
                     energy_error_margin=float(np.max(err / np.maximum(energy_error_limit(res), 1e-300))))
    return coords, data, attrs


def efficiency_variable(res, torque: float, speed: float, start: float) -> dict:
    """``mesh_efficiency``: output over input work of the dynamic run ``res`` after ``start``
    [s], at the constant driver speed ``speed`` [rad/s] and resisting torque ``torque`` [N·m]:
    torque*|theta2 change| / (speed * integral of the driver torque). NaN without a window."""
    sel = res.time >= start
    eta = float("nan")
    if sel.sum() >= 2 and res.status in (0, INACCURATE):
        t, tq = res.time[sel], res.driver_torque[sel]
        w_in = speed * float(np.sum(0.5 * (tq[1:] + tq[:-1]) * np.diff(t)))
        eta = abs(torque) * abs(float(res.theta2[sel][-1] - res.theta2[sel][0])) / w_in if w_in > 0 else eta
    return {"mesh_efficiency": _var((), eta, "1", "mesh efficiency: work out over work in after the ramp",
                                    comment="driven torque times driven rotation over driver speed times the integral "
                                            "of the driver torque; its loss is the flank friction's plus the dampers'",
                                    start_s=float(start))}


def stiffness_variables(k_nmm: tuple, ratio: tuple) -> tuple[dict, dict]:
    zmax = max(len(k) for k in k_nmm)
    K = np.full((2, zmax), np.nan)
    R = np.full((2, zmax), np.nan)
    for g in range(2):
        K[g, : len(k_nmm[g])] = k_nmm[g]
        R[g, : len(ratio[g])] = ratio[g]
    coords = {"gear": _var("gear", np.array([1, 2]), "1", "gear (1 driver, 2 driven)"),
              "tooth": _var("tooth", np.arange(zmax), "1", "tooth index (counter-clockwise from tooth 0)")}
    data = {"tooth_stiffness": _var(("gear", "tooth"), K, "N mm", "torsion spring stiffness k_phi of each tooth",
                                    unit_symbol="N·mm/rad^n_k",
                                    comment="T = k_phi |phi|^n_k: k_phi is in N·mm/rad^n_k (n_k of each gear in its scene "
                                            "section; the radian is dimensionless, so the CF unit reads N mm); "
                                            "tooth_stiffness_pitch gives the linear stiffness in N/um"),
            "stiffness_ratio": _var(("gear", "tooth"), R, "1", "tooth stiffness relative to the solid gear (FE)")}
    return coords, data


def cf_ready(ds: xr.Dataset) -> tuple[xr.Dataset, dict]:
    """A shallow copy of ``ds`` and its NetCDF encoding in the form CF-1.8 asks for.

    Integers become int32 where the values fit (CF has no 64-bit integers), coordinate
    variables get no ``_FillValue`` (a coordinate has no missing values), floats and integers
    are compressed, and a dataset without ``history`` (one not made with `provenance`) gets
    one. Names, values and every other attribute stay as they are.
    """
    ds = ds.copy(deep=False)
    i32 = np.iinfo(np.int32)
    for name in list(ds.variables):
        v = ds[name]
        if v.dtype.kind in "iu" and v.dtype.itemsize > 4 and (v.size == 0 or i32.min <= int(v.min()) and int(v.max()) <= i32.max):
            ds[name] = v.astype(np.int32)
    enc = {v: {"zlib": True, "complevel": 4} for v in ds.data_vars if ds[v].dtype.kind in "fiu"}
    for c in ds.coords:
        enc.setdefault(c, {})["_FillValue"] = None
    if not str(ds.attrs.get("history", "")).strip():
        ds.attrs["history"] = history_line()
    return ds, enc


TMP_MARK = ".tmp"


def host_tag() -> str:
    """Short tag of this machine in temporary names: a shared folder on a cluster holds other
    hosts' temporary files, whose process ids mean nothing here."""
    return hashlib.sha256(platform.node().encode()).hexdigest()[:6]


def clean_stale_temporaries(path) -> list[Path]:
    """Remove the temporary files of ``path`` (``.NAME.tmpPID.HOST-XXXXXXXX``) left by writers
    on this machine that no longer run (a kill during a write) -> the paths removed. Files
    of live processes and of other hosts are left alone."""
    import os
    path = Path(path)
    removed = []
    for tmp in path.parent.glob(f".{path.name}{TMP_MARK}*"):
        pid_text, _, rest = tmp.name[len(path.name) + 1 + len(TMP_MARK):].partition(".")
        host = rest.partition("-")[0] if "-" in rest else host_tag()   # older names carry no host
        if not pid_text.isdigit() or host != host_tag() or int(pid_text) == os.getpid():
            continue
        try:
            os.kill(int(pid_text), 0)
            continue                       # its writer still runs
        except ProcessLookupError:
            pass
        except PermissionError:
            continue                       # alive, owned by another user
        try:
            tmp.unlink()
            removed.append(tmp)
        except OSError:
            pass
    return removed


def write_netcdf(ds: xr.Dataset, path) -> None:
    """Write compressed CF NetCDF4 (`cf_ready`) atomically (temporary file, then rename).

    The temporary name is unique per process and call, so concurrent writers of the same path
    (dask workers filling the FE spring cache) never share a half-written file; the last
    rename wins and readers only ever open complete files. Temporaries that a killed writer
    left behind are removed on the next write of the same path.
    """
    import os
    import uuid
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_stale_temporaries(path)
    tmp = path.with_name(f".{path.name}{TMP_MARK}{os.getpid()}.{host_tag()}-{uuid.uuid4().hex[:8]}")
    ds, enc = cf_ready(ds)
    try:
        ds.to_netcdf(tmp, engine="netcdf4", encoding=enc)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def largest_peaks(ds: xr.Dataset, n: int = 5, min_order: float = 0.5):
    """The n largest local maxima of dte_amplitude: list of (frequency Hz, order, amplitude um),
    from ``min_order`` and beyond the window's main lobe of DC (leakage of the mean)."""
    if "dte_amplitude" not in ds:
        return []
    from study.report.spectra import HANN_MAIN_LOBE_BINS
    a = ds["dte_amplitude"].values
    f = ds["frequency"].values
    o = ds["order"].values
    lobe = HANN_MAIN_LOBE_BINS * float(ds["dte_amplitude"].attrs.get("resolution_Hz", 0.0))
    min_order = max(min_order, float(np.nanmax(o[f <= lobe])) if np.any(f <= lobe) else 0.0)
    idx = [i for i in range(1, a.size - 1) if a[i] >= a[i - 1] and a[i] >= a[i + 1] and o[i] > min_order]
    idx.sort(key=lambda i: -a[i])
    return [(float(f[i]), float(o[i]), float(a[i])) for i in idx[:n]]

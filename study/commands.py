"""The work of the commands besides run, sweep and render, as functions of a Scene: the FE
stiffness map (`lightgear stiffness`), the contact law's Weber fit (`fit-contact`), the FE
reference STE (`reference`) and the work-precision study (`precision`). The command line
prints what these return; the Python API (`study`) exposes them.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

from study import estimate
from study.scene import Scene, SceneError


def stiffness(scene: Scene, max_time: float | None = None, progress: bool = False):
    """Per-tooth FE stiffness map of both gears -> xarray.Dataset (``tooth_stiffness`` [N mm/rad^n],
    ``stiffness_ratio`` [1] over gear and tooth). ``max_time`` [s]: refuse (BudgetError) a map
    estimated to take longer, before any work; ``progress``: a bar on stderr for a long one."""
    from study.inputs.springs import stiffness_dataset
    est = estimate.Estimate({"FE bodies": estimate.fe_seconds(scene)})
    estimate.check_time(est, max_time)
    estimate.run_fe_bodies(scene, progress)
    return stiffness_dataset(scene)


@dataclass(frozen=True)
class SpringIdentification:
    """Tooth 0's spring of one gear fitted to the FE compliance of its body along the profile."""
    pivot_radius_mm: float       # mm, on the tooth axis
    k_phi: float                 # N mm/rad^n
    n: float                     # 1, the spring's exponent (a linear FE body gives about 1)
    rms_rel_error: float         # 1, of the compliance fit
    load_radii: int              # load points along the profile


def identify_spring(scene: Scene, gear: int) -> SpringIdentification:
    """Fit (pivot radius, k_phi, n) of gear ``gear``'s tooth 0 to FE compliance at several load
    radii along its profile (`study.inputs.springs.identify_spring`)."""
    from study.inputs.springs import identify_spring as fit
    from study.scene_model import gear_setup
    if gear not in (1, 2):
        raise ValueError(f"identify_spring: gear takes 1 (driver) or 2 (driven), got {gear!r}")
    f, u, _c = fit(gear_setup(scene, gear))
    return SpringIdentification(f.pivot_radius * 1e3, f.k_phi * 1e3, f.n, f.rms_rel_error, int(u.size))


@dataclass(frozen=True)
class ContactFit:
    """Weber's contact deflection at the pitch point fitted to F = k_con * delta^m1 (plane strain)."""
    k_con: float                 # N/mm^m1
    m1: float                    # 1
    depth_mm: float              # mm, the depth of the first gear's deflection
    force_range_N: tuple         # N, the load range of the fit
    radius_mm: float             # mm, the relative curvature radius at the pitch point
    rms_log_error: float         # 1, RMS of the fit in ln F
    reference_force_N: float     # N, quasi_static.torque / base radius of gear 1


def fit_contact(scene: Scene, depth_fraction: float = 0.5) -> ContactFit:
    """Weber's contact deflection of the scene's pair and material, fitted to k_con * delta^m1 over
    half to the full reference load (quasi_static.torque / base radius); ``depth_fraction``: the
    depth as a fraction of the way to the tooth centreline (0.5, the default the paper's values
    match; 1.0: to the centreline, where the FE tooth spring is read)."""
    from solver import units
    from solver.identify.weber import fit_contact as weber_fit
    from study.scene_model import gear_setups
    if not 0 < depth_fraction <= 1:
        raise ValueError(f"fit_contact: depth_fraction takes a number in (0, 1], got {depth_fraction!r}")
    if not scene.quasi_static.torque > 0:
        raise SceneError("quasi_static.torque", f"must be positive to set the fit's load range, got {scene.quasi_static.torque}")
    g1, g2 = (setup.geometry for setup in gear_setups(scene))
    f_ref = scene.quasi_static.torque / g1.base_radius
    f = weber_fit(g1, g2, scene.material_spec(), f_ref, depth_fraction=depth_fraction)
    return ContactFit(f.k_con / units.contact_stiffness_to_si(1.0, f.m1), f.m1, f.depth[0] * 1e3,
                      tuple(float(x) for x in f.force_range), f.radius * 1e3, f.rms_log_error, f_ref)


def reference(scene: Scene, step: float | None = None, max_time: float | None = None, progress: bool = False,
              solver: str = "ltca", flank_size: float | None = None, contact_stiffness: float | None = None):
    """FE reference STE -> xarray.Dataset (``ste`` [um] over ``angle`` [degree]). ``solver``:
    "ltca" (loaded-tooth-contact analysis with FE influence coefficients of both bodies) or
    "calculix" (the independent FE contact peer, `study.verify.calculix_reference`, with
    ``flank_size`` [mm] and ``contact_stiffness`` [MPa/mm]); ``max_time`` [s]: refuse a run
    estimated to take longer (BudgetError, before any work)."""
    from study.scene_model import static_angles
    from study.verify.fe_reference import REFERENCE_MEMORY_FACTOR, reference_dataset
    if step is not None and not step > 0:
        raise SceneError("--step", f"must be positive, got {step}")
    if solver not in ("ltca", "calculix"):
        raise SceneError("--solver", f"one of ltca, calculix, got {solver!r}")
    angles = static_angles(scene, step, REFERENCE_MEMORY_FACTOR)
    if solver == "calculix":
        from study.verify.calculix_reference import calculix_dataset, peer_estimate, settings_for
        settings = settings_for(scene, flank_size, contact_stiffness)
        est = peer_estimate(angles.size, settings, scene.gear1.module * 1e-3)
        estimate.check_time(est, max_time)
        if progress:
            print(f"CalculiX contact peer: {angles.size} decks, about {estimate.duration_text(est.total_s)} "
                  f"({est.total_s / angles.size:.0f} s a deck)", file=sys.stderr, flush=True)
        return calculix_dataset(scene, angles, settings, progress=progress)
    estimate.check_time(estimate.reference_estimate(scene, angles), max_time)
    return reference_dataset(scene, angles, progress=progress)


def precision_scene(scene: Scene) -> Scene:
    """The scene a work-precision study runs: the integrators it compares (explicit, implicit
    HHT, the scipy reference) all exist for the paper's plain model only, so the default
    ``coupling.model = "auto"`` runs as ``"paper"``; a coupled model named by the scene is
    refused (SceneError naming coupling.model)."""
    from study.scene import SceneError
    if scene.coupling.model == "auto":
        return scene.replace(**{"coupling.model": "paper"})
    if scene.coupling_model != "none":
        raise SceneError("coupling.model", f"the work-precision study compares the explicit, implicit and scipy "
                                           f"integrators, which exist together for the paper's model only, not for "
                                           f"{scene.coupling.model!r}: set coupling.model = 'paper'")
    return scene


def precision(scene: Scene, output: str | Path | None = None, duration: float = 0.002, ramp_fraction: float = 0.5,
              rotation: float = 6.0, repeats: int = 3, only: str | None = None, progress=None, model=None) -> dict:
    """Work-precision studies of a scene: TE error [um] against wall time [s] for every solver
    -> {"static": Dataset, "dynamic": Dataset} (`study.verify.precision`). ``duration`` [s]: the
    dynamic window, its ramps ending at ``ramp_fraction`` of it; ``rotation`` [deg]: the
    quasi-static range; ``repeats``: timed runs per setting (the best is kept); ``only``:
    'static' or 'dynamic'. With ``output`` (BASE.nc) each study is written to BASE_static.nc and
    BASE_dynamic.nc with its plot (.png). ``progress(i, spec, errors, wall, message)`` is called
    after each run. ``model``: the model of `precision_scene` when the caller has built it
    already. The integrators compared exist for the paper's model: `precision_scene`."""
    from study.archive.netcdf import write_netcdf
    from study.scene_model import build_scene_model
    from study.verify.precision import dynamic_study, plot, static_study
    for name, value, ok, what in (("duration", duration, lambda v: v > 0, "a positive number of seconds"),
                                  ("ramp_fraction", ramp_fraction, lambda v: 0 < v < 1, "a number in (0, 1)"),
                                  ("rotation", rotation, lambda v: v > 0, "a positive number of degrees"),
                                  ("repeats", repeats, lambda v: v >= 1 and float(v).is_integer(), "an integer >= 1")):
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or not ok(value):
            raise ValueError(f"precision: {name} takes {what}, got {value!r}")
    if only not in (None, "static", "dynamic"):
        raise ValueError(f"precision: only takes 'static', 'dynamic' or None, got {only!r}")
    scene = precision_scene(scene)
    model = model if model is not None else build_scene_model(scene)
    out = {}
    for kind in ("static", "dynamic"):
        if only and only != kind:
            continue
        if kind == "dynamic":
            ds = dynamic_study(scene, model, duration, ramp_fraction, int(repeats), progress)
        else:
            ds = static_study(scene, model, rotation, int(repeats), progress)
        if output is not None:
            path = Path(output).with_name(f"{Path(output).stem}_{kind}.nc")
            write_netcdf(ds, path)
            plot(ds, path.with_suffix(".png"))
            ds.attrs["archive"] = str(path)
        out[kind] = ds
    return out

"""The work of the commands besides run and sweep: the FE stiffness map of a scene (`lightgear
stiffness`), the contact law's Weber fit (`fit-contact`), the FE reference STE (`reference`),
the work-precision study (`precision`) and the pictures of an archive (`render`). The command
line prints what these return; the Python API (`study`) offers them.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

from study import estimate
from study.errors import check_argument, check_scene_argument, is_number, is_path
from study.scene import Scene, SceneError


def stiffness(scene: Scene, max_time: float | None = None, progress: bool = False):
    """Per-tooth FE stiffness map of both gears -> xarray.Dataset (``tooth_stiffness`` [N mm/rad^n],
    ``stiffness_ratio`` [1] over gear and tooth). ``max_time`` [s]: refuse (BudgetError) a map
    estimated to take longer, before any work; ``progress``: a bar on stderr for a long one."""
    from study.inputs.gearsetup import gear_setups
    from study.inputs.springs import stiffness_dataset
    from study.stages import compute_fe_bodies
    check_scene_argument("stiffness", scene)
    setups = gear_setups(scene)
    est = estimate.Estimate({"FE bodies": estimate.fe_seconds(setups, scene.coupling_model)})
    estimate.check_time(est, max_time)
    compute_fe_bodies(setups, scene.coupling_model, progress)
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
    check_scene_argument("identify_spring", scene)
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
    check_scene_argument("fit_contact", scene)
    if not 0 < depth_fraction <= 1:
        raise ValueError(f"fit_contact: depth_fraction takes a number in (0, 1], got {depth_fraction!r}")
    if not scene.quasi_static.torque > 0:
        raise SceneError("quasi_static.torque", f"must be positive to set the fit's load range, got {scene.quasi_static.torque}")
    g1, g2 = (setup.geometry for setup in gear_setups(scene))
    f_ref = scene.quasi_static.torque / g1.base_radius
    f = weber_fit(g1, g2, scene.material_spec(), f_ref, depth_fraction=depth_fraction)
    return ContactFit(f.k_con / units.contact_stiffness_to_si(1.0, f.m1), f.m1, f.depth[0] * 1e3,
                      tuple(float(x) for x in f.force_range), f.radius * 1e3, f.rms_log_error, f_ref)


REFERENCE_OPTIONS = {"ltca": ("tip_edge_radius",), "calculix": ("flank_size", "contact_stiffness", "thin_decks")}


def reference(scene: Scene, step: float | None = None, max_time: float | None = None, progress: bool = False,
              solver: str = "ltca", **options):
    """FE reference STE -> xarray.Dataset (``ste`` [um] over ``angle`` [degree]). ``solver``:
    "ltca" (loaded-tooth-contact analysis with FE influence coefficients of both bodies; option
    ``tip_edge_radius`` [mm]: its tip corners meet the mating flanks rounded to it, see
    `study.verify.fe_reference.tip_edge`) or "calculix" (the independent FE contact peer,
    `study.verify.calculix_reference`; options ``flank_size`` [mm], ``contact_stiffness``
    [MPa/mm] and ``thin_decks``: decks as thin as the flank elements, plane stress). An option
    None (or False) or left out: its default; one of the other solver's, given: SceneError. ``max_time`` [s]: refuse a run estimated to take longer
    (BudgetError, before any work)."""
    from study.scene_model import static_angles
    from study.verify.fe_reference import REFERENCE_MEMORY_FACTOR
    check_scene_argument("reference", scene)
    check_argument(step is None or is_number(step), "reference", "step", "a number of degrees or None", step)
    if step is not None and not step > 0:
        raise SceneError("--step", f"must be positive, got {step}")
    if solver not in REFERENCE_OPTIONS:
        raise SceneError("--solver", f"one of ltca, calculix, got {solver!r}")
    for name, value in options.items():
        if value is not None and value is not False and name not in REFERENCE_OPTIONS[solver]:
            other = [s for s, names in REFERENCE_OPTIONS.items() if name in names]
            raise SceneError("--" + name.replace("_", "-"), f"applies to --solver {other[0]} only" if other else
                             f"not an option of reference; its options: {sorted(sum(REFERENCE_OPTIONS.values(), ()))}")
    edge_m = _tip_edge_m(scene, options.get("tip_edge_radius"))      # refused before any work
    angles = static_angles(scene, step, REFERENCE_MEMORY_FACTOR)
    if solver == "ltca":
        return _ltca_reference(scene, angles, max_time, progress, edge_m)
    return _calculix_reference(scene, angles, max_time, progress, options)


def _tip_edge_m(scene: Scene, tip_edge_radius) -> float | None:
    """The LTCA's tip edge radius [m] from ``tip_edge_radius`` [mm] (None: sharp corners),
    checked against the scene's teeth."""
    if tip_edge_radius is None:
        return None
    from solver import units
    from study.scene_model import geometry_model
    from study.verify.fe_reference import tip_edge
    check_argument(is_number(tip_edge_radius), "reference", "tip_edge_radius", "a radius in mm", tip_edge_radius)
    edge_m = tip_edge_radius * units.MM
    tip_edge(scene, geometry_model(scene), edge_m)
    return edge_m


def _ltca_reference(scene: Scene, angles, max_time, progress: bool, edge_m):
    """`reference` by the project's LTCA at ``angles`` [rad]."""
    from study.verify.fe_reference import check_reference_memory, reference_cost, reference_dataset
    est = reference_cost(scene, angles)
    estimate.check_time(est, max_time)
    line = check_reference_memory(scene, est)      # refused whatever --max-time
    if line:
        from study.plausibility import report_warnings
        report_warnings([line], True)
    return reference_dataset(scene, angles, progress=progress, tip_edge_radius=edge_m)


def _calculix_reference(scene: Scene, angles, max_time, progress: bool, options: dict):
    """`reference` by the CalculiX contact peer at ``angles`` [rad] (``options``: `reference`'s)."""
    from study.verify.calculix_reference import calculix_dataset, peer_estimate, settings_for
    from study.verify.fe_reference import check_reference_memory
    settings = settings_for(scene, options.get("flank_size"), options.get("contact_stiffness"),
                            bool(options.get("thin_decks", False)))
    est = peer_estimate(angles.size, settings, scene.gear1.module * 1e-3)
    estimate.check_time(est, max_time)
    line = check_reference_memory(scene, est, "--flank-size", "a CalculiX deck needs about {need} (flanks at "
                                  f"{settings.sizes.flank * 1e3:.3g} mm)", "a larger --flank-size")
    if line:
        from study.plausibility import report_warnings
        report_warnings([line], True)
    if progress:
        print(f"CalculiX contact peer: {angles.size} decks, about {estimate.duration_text(est.total_s)} "
              f"({est.total_s / angles.size:.0f} s a deck)", file=sys.stderr, flush=True)
    return calculix_dataset(scene, angles, settings, progress=progress)


def precision_scene(scene: Scene) -> Scene:
    """The scene a work-precision study runs. The default ``coupling.model = "auto"`` runs as
    ``"paper"``: every integrator the study compares (explicit, implicit HHT, the scipy peer)
    exists for the paper's plain model. A body-coupled model named by the scene (``"compliance"``,
    the default of a run, or ``"body-torsion"``) runs as named, with the explicit integrators and
    the static solver, which are all it has (`study.verify.precision_cases`)."""
    if scene.coupling.model == "auto":
        return scene.replace(**{"coupling.model": "paper"})
    return scene


def precision(scene: Scene, output: str | Path | None = None, duration: float = 0.002, ramp_fraction: float = 0.5,
              rotation: float = 6.0, repeats: int = 3, only: str | None = None, **hooks) -> dict:
    """Work-precision studies of a scene: TE error [um] against CPU and wall time [s] for every solver
    -> {"static": Dataset, "dynamic": Dataset} (`study.verify.precision`). ``duration`` [s]: the
    dynamic window, its ramps ending at ``ramp_fraction`` of it; ``rotation`` [deg]: the
    quasi-static range; ``repeats``: timed runs per setting (the best is kept); ``only``:
    'static' or 'dynamic'. With ``output`` (BASE.nc) each study is written to BASE_static.nc and
    BASE_dynamic.nc with its plot (.png). ``hooks`` (by keyword): ``progress(i, spec, errors, wall,
    message)``, called after each run; ``model``, the model of `precision_scene` when the caller
    has built it already. Which model runs and with which integrators: `precision_scene`."""
    from study.archive.netcdf import write_netcdf
    from study.scene_model import build_scene_model
    from study.verify.precision import dynamic_study, plot, static_study
    check_scene_argument("precision", scene)
    unknown = set(hooks) - {"progress", "model"}
    if unknown:
        raise TypeError(f"precision: unknown keyword {sorted(unknown)[0]!r} (hooks: progress, model)")
    progress, model = hooks.get("progress"), hooks.get("model")
    check_argument(output is None or is_path(output), "precision", "output", "an archive base name ending in .nc, or None",
                   output)
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


def precision_mesh(scene: Scene, output: str | Path | None = None, factors=(2.0, 1.0, 0.5), rotation: float = 6.0,
                   repeats: int = 2, progress=None):
    """Work-precision of the FE mesh size: the scene's STE and DTE at fe.mesh_size = each of
    ``factors`` x its default (a quarter of the smaller module), their errors [um] against the
    finest, the FE CPU time of each gear [s] from an empty FE cache and the run's CPU times [s]
    -> Dataset over ``mesh`` (`study.verify.precision_mesh`). ``rotation`` [deg]: the STE's
    range; ``repeats``: timed runs (best kept); the DTE is the scene's own dynamic run. With
    ``output`` (a .nc path) the archive is written there with its plot beside it (.png).
    ``progress(i, size_mm, row)``: called after each size."""
    from study.archive.netcdf import write_netcdf
    from study.verify.precision_mesh import mesh_plot, mesh_study
    check_scene_argument("precision_mesh", scene)
    check_argument(output is None or is_path(output), "precision_mesh", "output", "an archive path ending in .nc, or None",
                   output)
    check_argument(isinstance(factors, tuple | list) and len(factors) >= 2 and all(
        is_number(f) and math.isfinite(f) and f > 0 for f in factors), "precision_mesh", "factors",
        "two or more positive multiples of the default mesh size", factors)
    for name, value, ok, what in (("rotation", rotation, lambda v: v > 0, "a positive number of degrees"),
                                  ("repeats", repeats, lambda v: v >= 1 and float(v).is_integer(), "an integer >= 1")):
        check_argument(is_number(value) and math.isfinite(value) and ok(value), "precision_mesh", name, what, value)
    ds = mesh_study(scene, tuple(factors), rotation_deg=float(rotation), repeats=int(repeats), progress=progress)
    if output is not None:
        path = Path(output)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_netcdf(ds, path)
        mesh_plot(ds, path.with_suffix(".png"))
        ds.attrs["archive"] = str(path)
    return ds


def render(archive, out_dir=None, renders: bool = True, limits: dict | None = None, prefix: str = "",
           reuse_after: float | None = None) -> list:
    """Plots (and, unless ``renders=False``, pyvista renders) of a run or study archive as PNG
    files in ``out_dir`` (default: beside the archive file) -> their paths. ``archive``: a
    path or an xarray.Dataset; ``limits`` ({output: value}, sampled studies): the probability
    of exceeding each; ``prefix``: put before every file name (`lightgear render` gives the
    archive's stem, ``h3_ste.png``). The renders of a lightened body draw its FE fields from
    the FE cache (solved and cached once when missing). ``reuse_after`` (a file time [s]): a
    run's figures written since are kept as they are (`study.report.figures.make_figures`)."""
    from study.archive.netcdf import read_netcdf
    from study.report.figures import make_figures, renders_fresh
    check_argument(isinstance(prefix, str), "render", "prefix", "a string put before every file name", prefix)
    if not hasattr(archive, "data_vars"):
        check_argument(is_path(archive), "render", "archive", "an archive's path or an xarray.Dataset", archive)
        path = Path(archive)
        if not path.is_file():
            raise FileNotFoundError(f"no such archive: {path}")
        out_dir = path.parent if out_dir is None else out_dir
        archive = read_netcdf(path)
    elif out_dir is None:
        raise ValueError("render: out_dir is needed for a dataset")
    fields = None
    if (renders and "scene" in archive.attrs and "tooth_stiffness" in archive and "status" not in archive
            and not renders_fresh(archive, out_dir, prefix, reuse_after)):
        from study.inputs.springs import archive_body_fields
        fields = archive_body_fields(archive)      # what the renders of a lightened body draw: FE cache, else solved
    return make_figures(archive, Path(out_dir), prefix=prefix, renders=renders, limits=limits, fields=fields,
                        reuse_after=reuse_after)


def write_report(archive, out_dir=None, renders: bool = True) -> list:
    """A report to hand on of a run, study or tolerance-study archive (path): one self-contained
    HTML page (figures embedded as base64 PNG) and its Markdown twin, with the scene or study as
    run, the summary table with units, the validation status of the model used and the figures,
    written into ``out_dir`` (default: beside the archive) as ``STEM_report.html`` and
    ``STEM_report.md`` (the figures beside them, ``STEM_*.png``; a run's figures that
    `render` already wrote there since the archive was written are taken as they are) -> [html, md] paths."""
    from study.archive.netcdf import read_netcdf
    from study.report.report_page import write_report as write
    from study.sweep.outputs import report_rows
    check_argument(is_path(archive), "write_report", "archive", "an archive's path", archive)
    path = Path(archive)
    if not path.is_file():
        raise FileNotFoundError(f"no such archive: {path}")
    out_dir = Path(out_dir) if out_dir is not None else path.parent
    ds = read_netcdf(path)
    figures = [p for p in render(ds, out_dir, renders=renders, prefix=f"{path.stem}_", reuse_after=path.stat().st_mtime)
               if p.suffix == ".png"]
    summary, extra = report_rows(ds)
    return write(ds, path.stem, out_dir, figures, summary, extra)


def export(archive, outdir=None) -> list:
    """The variables of an archive (path or Dataset) as CSV files in ``outdir`` (default: beside
    the archive, ``NAME_csv``), one per dimension group, with units in the headers, and the
    summary scalars (STE peak-to-peak, DTE RMS and mean, ...) in ``scalars.csv`` -> their paths
    (`study.report.export`)."""
    import xarray as xr

    from study.report.export import export_csv
    from study.sweep.outputs import summary_rows
    if isinstance(archive, xr.Dataset):
        check_argument(outdir is not None, "export", "outdir", "a folder (needed for a Dataset)", outdir)
        return export_csv(archive, Path(outdir), summary_rows(archive))
    check_argument(is_path(archive), "export", "archive", "a NetCDF path or a Dataset", archive)
    path = Path(archive)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return export_csv(ds, Path(outdir) if outdir is not None else path.with_name(f"{path.stem}_csv"),
                          summary_rows(ds))


"""`lightgear` command line: one ``arguments``/``command`` pair of functions per subcommand.

The commands parse arguments and print; the work is done by the Python API (`study`) and
the modules behind it, which keep no argument parsing. Modules are imported only when their
command runs, so ``lightgear --help`` is quick and ``lightgear run`` never loads gmsh or VTK.
Exit codes (also in ``lightgear --help``): see `EXIT_CODES`.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from study.errors import UsageError  # noqa: F401  (raised here and by the option parsers)
from study.process import end_of_process, guarded, stop_on_sigterm

EXIT_CODES = """exit codes:
  0    done
  1    an unexpected error (one line on stderr; LIGHTGEAR_DEBUG=1 shows the traceback),
       or sweep points lost to failed workers (run the same command again)
  2    invalid input, before any work: scene or study field (named), option, output path,
       archive to render; or a run refused by its estimate (memory it would need, or a
       run time beyond --max-time)
  3    a run that diverged, whose energy balance does not close (inaccurate) or whose statics
       did not converge (archive written, cause and count on stderr); a CalculiX peer deck
       that did not converge within its CPU-time limit (no archive; the angle on stderr)
  130  interrupted by Ctrl-C or SIGTERM (a sweep keeps its finished points)"""



def writable_folder(folder: Path, option: str = "-o") -> None:
    """Create ``folder`` if needed and prove that a file can be written in it, before any work.
    Missing folders are created under the working directory (``results/...``), and elsewhere
    one new folder in an existing one: a slip such as ``/nonexistent/dir`` never makes folders
    at the root of the file system."""
    import tempfile
    if folder.exists() and not folder.is_dir():
        raise UsageError(option, f"{folder} is a file, not a directory")
    if not folder.exists() and not folder.parent.is_dir() \
            and not folder.resolve().is_relative_to(Path.cwd().resolve()):
        raise UsageError(option, f"the folder {folder.parent} does not exist: outside the working directory lightgear "
                                 f"creates only the last folder of a path; create {folder.parent} first")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".lightgear-probe"):
            pass
    except OSError as e:
        raise UsageError(option, f"cannot write in {folder}: {e.strerror or e}") from None


# bytes that names derived from an archive's add to it: the temporary file of the atomic write
# (".NAME.tmpPID.HOST-XXXXXXXX"), a sweep's ".NAME.parts", precision's NAME_dynamic.nc
NAME_MARGIN = 40


def checked_output(path, option: str = "-o") -> Path:
    """An archive path that ends in .nc, is no directory, whose folder is writable and whose
    name (with the names derived from it) the file system takes."""
    import os
    path = Path(path)
    try:
        name_max = os.pathconf(path.parent if path.parent.is_dir() else ".", "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    too_long = [part for part in path.parts if len(part.encode()) > name_max]
    if too_long or len(path.name.encode()) + NAME_MARGIN > name_max:
        raise UsageError(option, f"a name of {len((too_long or [path.name])[0].encode())} bytes is too long: this file "
                                 f"system takes {name_max} bytes a name, and the archive's temporary and parts names "
                                 f"add up to {NAME_MARGIN} to its own: give a name of at most {name_max - NAME_MARGIN} bytes")
    if path.is_dir():
        raise UsageError(option, f"{path} is a directory; give the archive's file name (e.g. {path / 'run.nc'})")
    if path.suffix != ".nc":
        raise UsageError(option, f"archives are NetCDF files ending in .nc, got {path.name[:60]!r}")
    writable_folder(path.parent, option)
    return path


def max_time_argument(p) -> None:
    from study.estimate import DEFAULT_MAX_TIME_S
    p.add_argument("--max-time", type=float, default=DEFAULT_MAX_TIME_S, metavar="SECONDS",
                   help=f"refuse (exit 2, before any work) a run estimated to take longer (default {DEFAULT_MAX_TIME_S:g} s); "
                        "a run expected to take more than a few seconds shows a progress bar")


def checked_max_time(args) -> float:
    if not args.max_time > 0:
        raise UsageError("--max-time", f"must be a positive number of seconds, got {args.max_time}")
    return args.max_time


def scene_arguments(p, output: str | None, output_help: str = "archive to write (NetCDF)") -> None:
    """The scene file, the archive (when the command writes one) and ``--set`` overrides."""
    p.add_argument("scene", nargs="?", help="scene TOML, or the name of an embedded scene (`lightgear scenes`; "
                                            "default: the embedded paper example)")
    if output is not None:
        p.add_argument("-o", "--output", default=output, help=output_help)
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene field by its dotted path, e.g. --set gear2.body.holes=3")


def args_scene(args):
    """The scene of a command's arguments; an override without '=' (``--set key value``) gets a
    hint before the value is taken for a scene file."""
    import study
    for item in args.overrides:
        if "=" not in item:
            fix = f"--set {item}={args.scene}" if args.scene else f"--set {item}=VALUE"
            raise UsageError("--set", f"{item!r} is not key=value: write {fix} (no space around '=')")
    return study.load_scene(args.scene, args.overrides)


# ---------------------------------------------------------------- run

def run_arguments(p) -> None:
    scene_arguments(p, "results/run.nc")
    p.add_argument("--no-static", action="store_true", help="skip the quasi-static STE")
    p.add_argument("--no-dynamic", action="store_true", help="skip the dynamic DTE")
    p.add_argument("--figures", action="store_true", help="also write plots and renders beside the archive")
    max_time_argument(p)


def run_command(args) -> int:
    import study
    from study.estimate import check_dynamic_memory
    from study.plausibility import check_dynamic_window
    from study.report.summary import print_summary
    scene = args_scene(args)
    if args.no_dynamic and scene.dynamic.enabled:
        # the scene without its dynamic run: the title, modes and critical speeds at the STE's
        # torque (`study.scene_model.mean_load`), not at the torque of the run left out
        scene = scene.replace(**{"dynamic.enabled": False})
    if not args.no_dynamic:
        check_dynamic_window(scene)       # the summary needs a steady part after the ramps
        check_dynamic_memory(scene)       # at once, before the solver is even loaded
    checked_output(args.output)
    max_time = checked_max_time(args)
    from study.plausibility import face_width_note
    if face_width_note(scene):
        print(face_width_note(scene))
    if not args.no_static:
        from study.estimate import error_period_note
        note = error_period_note(scene)
        if note:
            print(note)
    from solver.mbs.dynamics import DivergenceError
    t0 = time.perf_counter()
    try:
        ds = study.run_scene(scene, static=False if args.no_static else None, dynamic=False if args.no_dynamic else None,
                             max_time=max_time, progress=True)
    except DivergenceError as e:
        print(f"lightgear run: diverged: {e}", file=sys.stderr)
        return 3
    study.write(ds, args.output)
    print_summary(ds, args.output, time.perf_counter() - t0)
    if args.figures:
        for path in study.render(ds, Path(args.output).parent, prefix=f"{Path(args.output).stem}_"):
            print(f"  figure: {path}")
    problems = run_problems(ds)
    for msg in problems:
        print(f"lightgear run: {msg} (see the archive's attributes)", file=sys.stderr)
    return 3 if problems else 0


def run_problems(ds) -> list[str]:
    """Why a run archive's numbers are not to be trusted: unconverged statics, a stopped dynamic run."""
    out = []
    if "ste_converged" in ds and not ds["ste_converged"].values.all():
        conv = ds["ste_converged"].values
        out.append(ds.attrs.get("static_status", "ok") if ds.attrs.get("static_status", "ok") != "ok" else
                   f"static equilibrium not reached at {int((conv == 0).sum())} of {conv.size} angles")
    status = ds.attrs.get("dynamic_status", "ok")
    if status != "ok":
        out.append(f"dynamic run {'not to be trusted' if status.startswith('inaccurate') else 'diverged'}: {status}")
    return out


# ---------------------------------------------------------------- stiffness

def stiffness_arguments(p) -> None:
    scene_arguments(p, "results/stiffness.nc")
    p.add_argument("--identify", action="store_true",
                   help="also fit (pivot radius, k_phi, n) of each gear's tooth to FE compliance along the profile")
    max_time_argument(p)


def stiffness_command(args) -> int:
    import numpy as np

    import study
    from solver.geometry import hole_offset
    scene = args_scene(args)
    checked_output(args.output)
    ds = study.stiffness(scene, max_time=checked_max_time(args), progress=True)
    study.write(ds, args.output)
    print(f"tooth stiffness map -> {args.output} ({ds.attrs['wall_time_springs_s']:.2f} s)")
    for g in (1, 2):
        k = ds["tooth_stiffness"].sel(gear=g).values[: scene.gear(g).teeth]
        r = ds["stiffness_ratio"].sel(gear=g).values[: scene.gear(g).teeth]
        lo, hi = int(np.argmin(k)), int(np.argmax(k))
        print(f"  gear {g}: k_phi {k.min():.4g} .. {k.max():.4g} N mm/rad^n (ratio {r.min():.4f} .. {r.max():.4f})")
        if scene.gear(g).body.holes:
            off = hole_offset(scene.gear(g).teeth, scene.gear(g).body.holes, scene.gear(g).body.hole_phase)
            print(f"    stiffest tooth {hi} ({off[hi]:+.2f} pitches from a hole centre), "
                  f"softest tooth {lo} ({off[lo]:+.2f} pitches from a hole centre)")
        if args.identify:
            fit = study.identify_spring(scene, g)
            print(f"    identified spring of tooth 0: pivot radius {fit.pivot_radius_mm:.3f} mm, "
                  f"k_phi {fit.k_phi:.4g} N mm/rad^n, n {fit.n:.3f} (linear FE body), "
                  f"compliance fit RMS {fit.rms_rel_error * 100:.1f} % over {fit.load_radii} load radii")
    return 0


# ---------------------------------------------------------------- sweep

def sweep_arguments(p) -> None:
    p.add_argument("study", help="study TOML (base scene + [grid] and/or [[points]], or a [sample], + [outputs]), "
                                 "or the name of an embedded study (`lightgear scenes`)")
    p.add_argument("-o", "--output", help="archive to write (NetCDF; default results/<study name>.nc)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="address of an existing dask scheduler, e.g. tcp://host:8786")
    p.add_argument("--workers", type=int, default=None,
                   help="LocalCluster workers (default: one per core); 0 runs the points in this process")
    p.add_argument("--keep-parts", action="store_true", help="keep the per-task files after the archive is complete")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    max_time_argument(p)


def sweep_command(args) -> int:
    import study
    from study.sweep.engine import SchedulerUnreachable, parts_folder, run_sweep
    from study.sweep.outputs import STATUS
    st = study.load_study(args.study)
    output = args.output or f"results/{Path(args.study).stem}.nc"
    checked_output(output)
    if parts_folder(output).exists() and not parts_folder(output).is_dir():
        raise UsageError("-o", f"{parts_folder(output)} is a file, where the sweep keeps its finished tasks: "
                               "move it away or choose another output name")
    if args.workers is not None and args.workers < 0:
        raise UsageError("--workers", f"must be >= 0 (0 runs the points in this process), got {args.workers}")
    from study.estimate import check_study_size
    n = check_study_size(st, checked_max_time(args))      # before its points are built
    from study.plausibility import face_width_note
    if any(f.endswith(".face_width") for f in st.fields):
        try:
            note = face_width_note(st.base_scene(), swept=True)
        except study.SceneError:      # a base that only the grid's values make valid: no note
            note = None
        if note:
            print(note)
    print(f"{st.title}: {n} points ({' x '.join(map(str, st.shape))}, {st.layout} layout) -> {output}")
    try:
        res = run_sweep(st, output, workers=args.workers, scheduler=args.scheduler, progress=not args.no_progress,
                        keep_parts=args.keep_parts, max_time=checked_max_time(args))
    except SchedulerUnreachable as e:
        raise UsageError("--scheduler", str(e)) from None
    except KeyboardInterrupt:
        print(f"lightgear sweep: interrupted: {kept_parts_text(parts_folder(output))}", file=sys.stderr)
        return 130
    ds = res.dataset
    counts = {name: int((ds["status"].values == i).sum()) for i, name in enumerate(STATUS)}
    print(f"  {res.points} points; analyses computed {res.computed}, reused {res.reused} (a static analysis is shared "
          f"by the points that differ only in dynamic.*); invalid combinations {res.invalid}, "
          f"wall time {res.wall_time:.1f} s")
    print("  status: " + ", ".join(f"{k} {v}" for k, v in counts.items() if v))
    for msg in sorted({str(m) for m, s in zip(ds["message"].values.ravel(), ds["status"].values.ravel()) if s > 1})[:5]:
        print(f"    {msg}")
    partial = [str(m) for m in ds["message"].values.ravel() if "not stored" in str(m)]
    if partial:     # ok points whose curves the archive could not hold: said, not only in `message`
        print(f"  {len(partial)} points without some of their curves: {partial[0]}", file=sys.stderr)
    if res.pending:
        causes = sorted({str(m) for m in ds["message"].values.ravel() if str(m).startswith("lost: ")})
        print(f"  {res.pending} analyses lost (worker failures; {counts['pending']} points pending): "
              "run the same command again to compute them", file=sys.stderr)
        for cause in causes[:3]:
            print(f"    {cause}", file=sys.stderr)
        return 1
    return 0


def kept_parts_text(folder: Path) -> str:
    """What an interrupted sweep really kept: the finished analyses in its parts folder, or nothing."""
    kept = len(list(folder.glob("*.pkl"))) if folder.is_dir() else 0
    if not kept:
        return "no analysis had finished: nothing kept (the same command starts the study again)"
    return (f"{kept} finished {'analysis' if kept == 1 else 'analyses'} kept in {folder}; "
            "the same command resumes from them")


# ---------------------------------------------------------------- fit-contact

def fit_contact_arguments(p) -> None:
    scene_arguments(p, None)


def fit_contact_command(args) -> int:
    """Weber's contact deflection fitted to F = k_con * delta**m1, against the scene's law."""
    import study
    scene = args_scene(args)
    fits = [(study.fit_contact(scene, frac), note) for frac, note in (
        (0.5, "default: depth half-way to the tooth centreline"),
        (1.0, "depth to the tooth centreline (where the FE tooth spring is read)"))]
    f0 = fits[0][0]
    print(f"Weber contact deflection at the pitch point, plane strain, F_ref = {f0.reference_force_N:.1f} N "
          f"(quasi_static.torque / base radius), R = {f0.radius_mm:.3f} mm")
    for f, note in fits:
        print(f"  {note}:\n    k_con = {f.k_con:.4g} N/mm^m1, m1 = {f.m1:.4f} "
              f"(depth {f.depth_mm:.3f} mm, load {f.force_range_N[0]:.0f}..{f.force_range_N[1]:.0f} N, "
              f"fit RMS {f.rms_log_error:.1e} in ln F)")
    c = scene.contact
    print(f"  scene: k_con = {c.k_con:.4g} N/mm^m1, m1 = {c.m1:.4f}")
    return 0


# ---------------------------------------------------------------- render

def render_arguments(p) -> None:
    p.add_argument("archive", help="run or sweep archive (NetCDF)")
    p.add_argument("-o", "--output", default=None, help="directory for the PNGs, named ARCHIVE-STEM_*.png "
                                                        "(default: beside the archive)")
    p.add_argument("--no-renders", action="store_true", help="plots only (no pyvista renders, no FE)")
    p.add_argument("--limit", dest="limits", action="append", default=[], metavar="OUTPUT=VALUE",
                   help="sampled study: the probability of exceeding a limit, e.g. --limit dte_rms=0.5 "
                        "(in the output's units; repeatable)")


def render_command(args) -> int:
    import study
    from study.report.render_limits import checked_limits
    path = checked_archive(args.archive)
    limits = checked_limits(path, args.limits)
    writable_folder(Path(args.output) if args.output else path.parent)
    t0 = time.perf_counter()
    for p in study.render(path, args.output, renders=not args.no_renders, limits=limits, prefix=f"{path.stem}_"):
        print(f"  figure: {p}")
    print(f"  {time.perf_counter() - t0:.1f} s")
    return 0


def checked_archive(name) -> Path:
    """An existing NetCDF file written by lightgear (its provenance attributes), else UsageError."""
    import xarray as xr
    path = Path(name)
    if not path.exists():
        raise UsageError("archive", f"no such file: {path}")
    if not path.is_file():
        raise UsageError("archive", f"{path} is not a file")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            attrs = dict(ds.attrs)
    except Exception as e:  # noqa: BLE001 - netCDF4/HDF5 raise many kinds for a damaged file
        reason = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise UsageError("archive", f"{path} is not a readable NetCDF file ({reason}); empty, truncated or of another kind") from None
    if "code_fingerprint" not in attrs:
        raise UsageError("archive", f"{path} is NetCDF but not a lightgear archive (no lightgear provenance attributes)")
    return path


# ---------------------------------------------------------------- report

def report_arguments(p) -> None:
    p.add_argument("archive", help="run, study or tolerance-study archive (NetCDF)")
    p.add_argument("-o", "--output", default=None, help="directory for the report and its figures "
                                                        "(default: beside the archive)")
    p.add_argument("--no-renders", action="store_true", help="plots only (no pyvista renders, no FE)")


def report_command(args) -> int:
    import study
    path = checked_archive(args.archive)
    writable_folder(Path(args.output) if args.output else path.parent)
    for p in study.write_report(path, args.output, renders=not args.no_renders):
        print(f"  report: {p}")
    return 0


# ---------------------------------------------------------------- export

def export_arguments(p) -> None:
    p.add_argument("archive", help="run or sweep archive (NetCDF)")
    p.add_argument("-o", "--output", default=None, help="directory for the CSV files (default: ARCHIVE_csv beside it)")


def export_command(args) -> int:
    import study
    path = checked_archive(args.archive)
    outdir = Path(args.output) if args.output else path.with_name(f"{path.stem}_csv")
    writable_folder(outdir)
    for p in study.export(path, outdir):
        print(f"  csv: {p}")
    return 0


# ---------------------------------------------------------------- precision

def precision_arguments(p, output: str = "results/work_precision.nc") -> None:
    scene_arguments(p, output, "archive base name: writes BASE_dynamic.nc and BASE_static.nc with their plots (.png)")
    p.add_argument("--duration", type=float, default=0.002, help="dynamic window [s] (default 0.002)")
    p.add_argument("--ramp-fraction", type=float, default=0.5, help="ramps end at this fraction of the window")
    p.add_argument("--rotation", type=float, default=6.0, help="quasi-static driver rotation [deg] (default 6)")
    p.add_argument("--repeats", type=int, default=3, help="timed repeats per run (best is kept)")
    p.add_argument("--only", choices=("dynamic", "static"), help="run only one of the two studies")
    max_time_argument(p)


def precision_command(args) -> int:
    import math

    import study
    from study import estimate
    from study.commands import precision as run_precision
    from study.commands import precision_scene
    from study.scene_model import build_scene_model, check_static_memory
    from study.verify.precision import setting_label
    check_precision_options(args)
    scene = precision_scene(args_scene(args))
    # the memory of its runs' outputs and of its static angles, before the model is built
    if args.only != "static":
        estimate.check_dynamic_memory(scene.replace(**{"dynamic.duration": args.duration}), "--duration")
    if args.only != "dynamic":
        check_static_memory(scene.replace(**{"quasi_static.rotation": args.rotation}), field="--rotation")
    base = checked_output(args.output)
    max_time = checked_max_time(args)
    model = build_scene_model(scene)
    est = estimate.precision_estimate(scene, model, args.duration, args.rotation, args.repeats, args.only)
    estimate.check_time(est, max_time)
    print(f"estimated {estimate.duration_text(est.total_s)} ({est.describe()})", flush=True)

    def progress(i, s, e, w, msg):
        setting = setting_label(s.method, s.step if math.isfinite(s.step) else s.rtol)
        print(f"  [{i + 1}] {s.method}, {setting}: linf {e[2]:.3g} um, {w:.3g} s  {'' if msg == 'ok' else msg}",
              flush=True)
    for kind in ("static", "dynamic"):
        if args.only and args.only != kind:
            continue
        part_s = sum(v for k, v in est.seconds.items() if k.startswith(kind))
        print(f"{kind} study ... (about {estimate.duration_text(part_s)}; its reference runs first, then each run "
              "is listed as it ends)", flush=True)
        ds = run_precision(scene, base, args.duration, args.ramp_fraction, args.rotation, args.repeats, kind,
                           progress, model=model)[kind]
        path = ds.attrs["archive"]
        print(study.precision_table(ds))
        print(f"  archive: {path}\n  plot: {path[:-3]}.png", flush=True)
    return 0


def check_precision_options(args) -> None:
    """The work-precision options, before any work (UsageError naming the option)."""
    import math
    for option, value in (("--duration", args.duration), ("--rotation", args.rotation)):
        if not (math.isfinite(value) and value > 0):
            raise UsageError(option, f"must be a positive number, got {value}")
    if not 0 < args.ramp_fraction <= 1:
        raise UsageError("--ramp-fraction", f"the ramps end at this fraction of the window: must lie in (0, 1], "
                                            f"got {args.ramp_fraction}")
    if args.repeats < 1:
        raise UsageError("--repeats", f"must be at least 1, got {args.repeats}")


# ---------------------------------------------------------------- reference

def reference_arguments(p) -> None:
    scene_arguments(p, "results/reference.nc")
    p.add_argument("--step", type=float, default=None, metavar="DEG",
                   help="driver angle step [deg] (default: quasi_static.angle_step)")
    p.add_argument("--solver", choices=("ltca", "calculix"), default="ltca",
                   help="ltca (default): the loaded-tooth-contact analysis on FE influence coefficients; calculix: "
                        "the independent FE contact peer (both gears meshed in full in CalculiX; needs ccx)")
    p.add_argument("--flank-size", type=float, default=None, metavar="MM",
                   help="calculix: element size at the flanks around the mesh [mm] (default: module/30)")
    p.add_argument("--contact-stiffness", type=float, default=None, metavar="MPA_PER_MM",
                   help="calculix: slope of the penalty contact's pressure-overclosure law [MPa/mm] (default 2e7)")
    max_time_argument(p)


def reference_command(args) -> int:
    import numpy as np

    import study
    if args.solver == "ltca" and (args.flank_size is not None or args.contact_stiffness is not None):
        raise UsageError("--flank-size" if args.flank_size is not None else "--contact-stiffness",
                         "applies to --solver calculix only")
    if args.solver == "calculix":
        from solver.peers.calculix import CalculixMissing, ccx_path
        try:
            ccx_path()
        except CalculixMissing as e:
            raise UsageError("--solver calculix", str(e)) from None
    scene = args_scene(args)
    if args.step is not None and not args.step > 0:
        raise study.SceneError("--step", f"must be positive, got {args.step}")
    checked_output(args.output)
    from solver.peers.calculix import CalculixFailed
    try:
        ds = study.reference(scene, args.step, max_time=checked_max_time(args), progress=True, solver=args.solver,
                             flank_size=args.flank_size, contact_stiffness=args.contact_stiffness)
    except CalculixFailed as e:
        print(f"lightgear reference: the CalculiX peer stopped, no archive written: {e}", file=sys.stderr)
        return 3
    study.write(ds, args.output)
    ste = ds["ste"].values
    name = "FE contact peer (CalculiX)" if args.solver == "calculix" else "FE reference"
    print(f"{name} STE -> {args.output}")
    print(f"  mean {ste.mean():.3f} um (elastic part {ste.mean() - np.sign(scene.quasi_static.torque or 1.0) * ds.attrs['backlash_offset_um']:.3f} um), "
          f"peak-to-peak {np.ptp(ste):.3f} um over {float(ds['angle'][-1]):.4g} deg, {ste.size} angles")
    if args.solver == "calculix":
        print(f"  {ds.attrs['nodes']} nodes, flanks {ds.attrs['flank_mesh_size_mm']:.3g} mm; ccx CPU {ds.attrs['cpu_time_ccx_s']:.1f} s, "
              f"total wall {ds.attrs['wall_time_reference_s']:.1f} s")
    else:
        print(f"  wall time: compliance {ds.attrs['wall_time_compliance_s']:.2f} s, contact {ds.attrs['wall_time_contact_s']:.2f} s, "
              f"total {ds.attrs['wall_time_reference_s']:.2f} s")
    return 0


# ---------------------------------------------------------------- scenes, fields, outputs

def scenes_arguments(p) -> None:
    pass


def scenes_command(args) -> int:
    import study
    rows = study.scenes()
    width = max(len(n) for n in rows)
    for name, (_path, kind, title) in rows.items():
        print(f"{name:{width}s}  {kind:5s}  {title}")
    from study.scene import SCENES_DIR
    print(f"\n`lightgear run NAME` runs a scene, `lightgear sweep NAME` a study; their files are in {SCENES_DIR}")
    return 0


def fields_arguments(p) -> None:
    p.add_argument("prefix", nargs="?", default="", help="only the fields under this dotted path, e.g. gear2.body")
    p.add_argument("--markdown", action="store_true", help="as the Markdown tables of docs/scenes.md")


def fields_command(args) -> int:
    from study.docs import fields_markdown, fields_text
    if args.markdown and args.prefix:
        raise UsageError("--markdown", "writes the whole reference; give no prefix")
    sys.stdout.write(fields_markdown() if args.markdown else fields_text(args.prefix))
    return 0


def outputs_arguments(p) -> None:
    p.add_argument("--markdown", action="store_true", help="as the Markdown table of docs/numbers.md")


def outputs_command(args) -> int:
    from study.docs import outputs_markdown, outputs_text
    sys.stdout.write(outputs_markdown() if args.markdown else outputs_text())
    return 0


# ---------------------------------------------------------------- the parser

# name -> (one-line help, arguments, command)
COMMANDS = {
    "run": ("run a scene (default: the paper example) and write its archive", run_arguments, run_command),
    "stiffness": ("per-tooth FE stiffness map of a scene's gears (no solve)", stiffness_arguments, stiffness_command),
    "sweep": ("run a parametric study (scene + grid) with dask into one NetCDF archive", sweep_arguments, sweep_command),
    "fit-contact": ("fit the contact law k_con*delta^m1 to Weber's contact deflection", fit_contact_arguments,
                    fit_contact_command),
    "render": ("plots and renders (PNG) of a run or sweep archive", render_arguments, render_command),
    "report": ("a report to hand on: one self-contained HTML page and its Markdown twin (scene, summary table "
               "with units, the model's validation, figures)", report_arguments, report_command),
    "export": ("an archive's variables as CSV (one file per dimension group, units in the header)", export_arguments,
               export_command),
    "precision": ("work-precision study: TE error against wall time for every solver of a scene", precision_arguments,
                  precision_command),
    "reference": ("FE reference STE and load sharing (loaded-tooth-contact analysis)", reference_arguments,
                  reference_command),
    "scenes": ("list the embedded scenes and studies (run them by name)", scenes_arguments, scenes_command),
    "fields": ("list the scene fields with unit, default, range and meaning", fields_arguments, fields_command),
    "outputs": ("list the sweep outputs (scalars and curves) with their units", outputs_arguments, outputs_command),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lightgear", description="Transmission error of lightened spur gears (MUBOCO-PR).",
                                     epilog=EXIT_CODES, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (help_, arguments, command) in COMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        p.set_defaults(_command=command)
        arguments(p)
    return parser


def main(argv=None) -> int:
    """Run the command of ``argv`` (None: the command line) and return its exit code."""
    args = build_parser().parse_args(argv)
    with stop_on_sigterm():
        code = guarded(f"lightgear {args.command}", lambda: args._command(args))
    if argv is None:
        end_of_process()
    return code


if __name__ == "__main__":
    sys.exit(main())

"""`lightgear` command line: one ``arguments``/``command`` pair of functions per subcommand
(those of the FE and the solver checks in `study.cli_fe`, the options they share in
`study.cli_options`).

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

from study.cli_fe import (
    fit_contact_arguments,
    fit_contact_command,
    precision_arguments,
    precision_command,
    reference_arguments,
    reference_command,
    stiffness_arguments,
    stiffness_command,
)
from study.cli_options import (  # noqa: F401 - the shared options, importable from here
    NAME_MARGIN,
    args_scene,
    checked_archive,
    checked_max_time,
    checked_output,
    max_time_argument,
    scene_arguments,
    writable_folder,
)
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
                             max_time=max_time, progress=True, compile_ahead=True)
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
    from study.sweep.cost import check_study_size
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
    "precision": ("work-precision study: TE error against CPU and wall time for every solver of a scene", precision_arguments,
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

"""The `lightgear` commands of the FE and the checks of the solvers: ``stiffness`` (the
per-tooth FE stiffness map), ``fit-contact`` (Weber's contact deflection), ``precision`` (the
work-precision study), ``reference`` (the FE reference STE). One ``arguments``/``command``
pair of functions each, as in `study.cli`.
"""
from __future__ import annotations

import sys

from study.cli_options import args_scene, checked_max_time, checked_output, max_time_argument, scene_arguments
from study.errors import UsageError


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
                           progress=progress, model=model)[kind]
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
    p.add_argument("--thin-decks", action="store_true",
                   help="calculix: write each deck as thin as its flank elements, loads scaled alike (plane stress; "
                        "a deck at the full face width reads 2-6 %% stiffer, docs/models.md)")
    p.add_argument("--tip-edge-radius", type=float, default=None, metavar="MM",
                   help="ltca: both gears' tip-corner contacts carry the compliance of an edge of this radius [mm] (its "
                        "narrower Hertz patch), on the corners as the scene shapes them (sharp, or rounded by "
                        "gearN.modification.tip_edge_radius, whose compliance it replaces); 0.035 reads as the CalculiX "
                        "peer's sharp corner at its 0.1 mm flank mesh")
    max_time_argument(p)


def reference_command(args) -> int:
    import numpy as np

    import study
    if args.solver == "ltca" and (args.flank_size is not None or args.contact_stiffness is not None or args.thin_decks):
        raise UsageError("--flank-size" if args.flank_size is not None else
                         "--contact-stiffness" if args.contact_stiffness is not None else "--thin-decks",
                         "applies to --solver calculix only")
    if args.solver == "calculix" and args.tip_edge_radius is not None:
        raise UsageError("--tip-edge-radius", "applies to --solver ltca only (the CalculiX peer meshes the scene's tip "
                         "edges: gearN.modification.tip_edge_radius)")
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
                             flank_size=args.flank_size, contact_stiffness=args.contact_stiffness,
                             tip_edge_radius=args.tip_edge_radius, thin_decks=args.thin_decks)
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

"""Lightening shapes at equal mass: round holes against arc slots against spoked windows.

    python -m workflows.shapes [STUDY] [-o results/shapes] [--workers N] [--reference [--step 0.1]]
        [--no-progress]

Runs a study whose points are bodies of one gear with differently shaped openings (default: the
embedded ``shapes`` study, the paper's pair with six round holes, six slots and six windows that
each take out the same mass), and writes

* ``shapes.nc``: the study archive (`lightgear sweep` of the same study gives the same);
* ``shapes.txt``: one table, also printed: per body its openings, the driven gear's mass [kg],
  STE peak-to-peak [um], STE amplitude at the openings' order N [nm] (fitted with the mesh
  harmonics and their sidebands, `study.verify.model_validation.order_amplitude`), DTE RMS and
  DTE amplitude at order N [um], largest root stress [MPa] and its ratio to the solid gear's;
* ``shapes.png``: one figure: the openings drawn on the web (one of each, to scale) and the STE of
  each body over the driver angle;
* with ``--reference``, ``reference.txt``: the default model against the FE reference for each
  body (`study.validate_bodies`: elastic mean STE, p2p, opening order over two opening periods).

Exit codes: 0 done; 1 a point did not run (its message printed); 2 invalid input (one line).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

import study
from study import SceneError

DEFAULT_OUT = "results/shapes"
COLUMNS = (("mass_gear2", "mass kg", "{:.4f}"), ("ste_p2p", "STE p2p um", "{:.3f}"),
           ("ste_hole_order", "STE order N nm", "{:.1f}"), ("dte_rms", "DTE RMS um", "{:.3f}"),
           ("amp_hole_order", "DTE order N um", "{:.3f}"), ("root_stress_max_gear2", "root stress MPa", "{:.1f}"),
           ("root_stress_ratio_gear2", "x solid", "{:.3f}"))


def table_rows(ds, points: list) -> list[dict]:
    """One dict per point of a shapes study archive (point layout): 'openings' in words and the
    `COLUMNS` values (NaN where the archive lacks one)."""
    rows = []
    for i, p in enumerate(points):
        sel = ds.isel(point=i)
        row = {"openings": study.describe_openings(p.scene) if p.scene is not None else p.error}
        for name, _, _ in COLUMNS:
            row[name] = float(sel[name]) if name in sel else math.nan
        if "ste" in sel and p.scene is not None:
            row["ste_hole_order"] = 1e3 * study.opening_order_amplitude(p.scene, sel["angle"].values, sel["ste"].values)
        rows.append(row)
    return rows


def format_table(rows: list[dict]) -> str:
    width = max(len(r["openings"]) for r in rows)
    head = f"{'driven gear openings':<{width}}  " + "  ".join(f"{label:>15}" for _, label, _ in COLUMNS)
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r['openings']:<{width}}  " + "  ".join(f"{fmt.format(r[k]):>15}" for k, _, fmt in COLUMNS))
    return "\n".join(lines)


def figure(ds, points: list, rows: list[dict], path, title: str) -> Path:
    """Left: one opening of each body on the driven gear's web (rim and hub circles), to scale [mm];
    right: the STE of each body over the driver angle [um]."""
    import matplotlib.pyplot as plt
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(13, 5.2), gridspec_kw={"width_ratios": [1, 1.6]})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    first = next(p.scene for p in points if p.scene is not None)
    g2 = first.gear2
    r_root = g2.module * (g2.teeth / 2 - g2.dedendum)                              # mm
    r_rim = r_root - g2.body.rim_height
    r_hub = r_rim - g2.body.web_height
    a = np.linspace(math.radians(45), math.radians(135), 200)
    for r, what in ((r_root, "root circle"), (r_rim, "rim"), (r_hub, "hub")):
        ax0.plot(r * np.cos(a), r * np.sin(a), color="0.6", lw=1, ls=":" if what == "root circle" else "-")
    for i, (p, row) in enumerate(zip(points, rows)):
        if p.scene is None:
            continue
        c = colours[i % len(colours)]
        x, y = study.opening_outline(p.scene, 2, angle=90.0)
        x, y = np.append(x, x[0]), np.append(y, y[0])
        ax0.fill(x, y, color=c, alpha=0.25, lw=0)
        ax0.plot(x, y, color=c, lw=1.6, label=row["openings"])
        if "ste" in ds:
            sel = ds.isel(point=i)
            ax1.plot(sel["angle"].values, sel["ste"].values, color=c, lw=1.2,
                     label=f"{p.scene.gear2.body.opening}: p2p {row['ste_p2p']:.3f} um, order N {row['ste_hole_order']:.1f} nm")
    ax0.set_aspect("equal")
    ax0.set_xlabel("x [mm]")
    ax0.set_ylabel("y [mm]")
    ax0.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18))
    ax0.set_title(f"one opening of each body, to scale (gear of {rows[0]['mass_gear2']:.4f} kg);\n"
                  "grey: root circle (dotted), rim and hub", fontsize=9)
    ax1.set_xlabel("driver angle [deg]")
    ax1.set_ylabel("static transmission error STE [um]")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax1.set_title("STE of each body", fontsize=10)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return Path(path)


def run(args) -> int:
    st = study.load_study(args.study)
    points = st.points()
    out = Path(args.output)
    if out.is_file():
        raise SceneError("--output", f"{args.output} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    print(f"{st.title}: {len(points)} bodies -> {out}", flush=True)
    with study.local_cluster(args.workers) as address:
        res = study.run_sweep(st, out / "shapes.nc", workers=0 if address is None else None, scheduler=address,
                              progress=not args.no_progress)
    ds = res.dataset
    rows = table_rows(ds, points)
    text = format_table(rows)
    (out / "shapes.txt").write_text(text + "\n")
    fig = figure(ds, points, rows, out / "shapes.png", st.title)
    print(f"\n{text}\n  figure: {fig}")
    bad = [f"point {i}: {m}" for i, (s, m) in enumerate(zip(ds["status"].values, ds["message"].values))
           if s != study.STATUS.index("ok")]
    for b in bad:
        print(f"  {b}", file=sys.stderr)
    if args.reference:
        ref = reference_table(points, args.step)
        (out / "reference.txt").write_text(ref + "\n")
        print(f"\n{ref}")
    return 1 if bad else 0


def reference_table(points: list, step: float) -> str:
    """The default model against the FE reference (`study.validate_bodies`) for every body of the
    study: the FE figures and the errors, in %, of elastic mean STE / p2p / opening order."""
    scenes = {study.describe_openings(p.scene): p.scene for p in points if p.scene is not None}
    ds = study.validate_bodies(scenes, step=step, log=lambda line: print(f"  {line}", flush=True))
    err = study.validation_errors(ds).sel(model="compliance")
    ref = ds.sel(model="fe-reference")
    width = max(len(n) for n in scenes)
    lines = [f"{'driven gear openings':<{width}}  FE elastic mean um  FE p2p um  FE order N nm  default model error %",
             "-" * (width + 75)]
    for name in scenes:
        e = err.sel(body=name)
        lines.append(f"{name:<{width}}  {float(ref['ste_elastic_mean'].sel(body=name)):>18.3f}  "
                     f"{float(ref['ste_p2p'].sel(body=name)):>9.3f}  {1e3 * float(ref['hole_amplitude'].sel(body=name)):>13.1f}  "
                     f"{100 * float(e['elastic_mean']):+.2f} / {100 * float(e['p2p']):+.2f} / {100 * float(e['hole']):+.2f}")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("study", nargs="?", default="shapes", help="study TOML or embedded study (default: shapes)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT, help="output folder (archive, table, figure)")
    p.add_argument("--workers", type=int, default=0, help="LocalCluster workers (0, the default: in this process)")
    p.add_argument("--reference", action="store_true",
                   help="also the default model against the FE reference for every body (reference.txt)")
    p.add_argument("--step", type=float, default=0.1, help="driver angle step of the --reference STE [deg]")
    p.add_argument("--no-progress", action="store_true")
    args = p.parse_args(argv)
    try:
        return run(args)
    except SceneError as e:
        print(f"error: {e.field}: {e.reason}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.shapes", main))

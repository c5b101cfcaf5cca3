"""Validation of the pseudo-rigid models against the FE reference (LTCA): STE, load sharing and
the error figures of the solid and the lightened pair.

The comparison is `study.validation` (`study.verify.validation`, whose docstring lists the
models and the figures); this script runs it and prints, archives and draws the result.

    python -m workflows.validation [SCENE] [-o results/validation/validation.nc] [--step DEG]

Over the design space (`study.verify.model_validation`; the tables of docs/models.md):

    python -m workflows.validation --design-space [-o results/validation/design_space.nc]
    python -m workflows.validation --relief [-o results/validation/relief.nc]

``--design-space``: gear 2's body over holes {0, 3, 6, 9, 12} x web {6, 10} mm x rim {5, 7} mm
at 50 N m; ``--relief``: the solid and the paper pair with a linear tip relief {0, 1, 2, 3, 4, 6}
um on both gears at 25, 50 and 100 N m. Both print the table and the points where the default
model misses its targets; ``--quick`` runs a reduced grid.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import xarray as xr

import study

DEFAULT_OUT = "results/validation/validation.nc"


def print_table(ds: xr.Dataset) -> None:
    off = ds.attrs["backlash_offset_um"]
    print(f"STE against the FE reference ({ds.attrs['static_torque_N_m']:g} N m; backlash offset {off:.3f} um; um unless stated)")
    head = f"{'pair':10s} {'model':13s} {'mean':>8s} {'elastic':>8s} {'p2p':>7s} {'hole N':>7s} {'err':>7s} {'err 1':>7s} {'err 2':>7s} {'rms 1':>6s} {'rms 2':>6s} {'share':>6s} {'time s':>7s}"
    print(head)
    for p in ds["pair"].values:
        for m in ds["model"].values:
            r = ds.sel(pair=p, model=m)
            print(f"{p:10s} {m:13s} {float(r['mean']):8.3f} {float(r['mean']) - off:8.3f} {float(r['p2p']):7.3f} "
                  f"{float(r['hole_amplitude']):7.4f} {float(r['error_mean']):+7.3f} {float(r['error_mean_single']):+7.3f} "
                  f"{float(r['error_mean_double']):+7.3f} {float(r['error_rms_single']):6.3f} {float(r['error_rms_double']):6.3f} "
                  f"{float(r['load_share_error_max']):6.3f} {float(r['wall_time']):7.2f}")
    if "compliance_k_body" in ds:
        for p in ds["pair"].values:
            r = ds.sel(pair=p)
            print(f"  compliance fit, {p:9s}: k_body {r['compliance_k_body'].values.round(-3)} N m/rad, pivot "
                  f"{r['compliance_pivot_radius'].values.round(3)} mm, RMS residual {r['compliance_fit_rms'].values.round(4)}")
    if "comment" in ds["hole_amplitude"].attrs:
        print(f"  hole order N: {ds['hole_amplitude'].attrs['comment']}")
    for p in ds["pair"].values:
        ref = ds.sel(pair=p, model="fe-reference")
        for m in ds["model"].values[1:]:
            r = ds.sel(pair=p, model=m)
            el = float(ref["mean"]) - off
            hole = (f", hole order {100 * (float(r['hole_amplitude']) / float(ref['hole_amplitude']) - 1):+.1f} %"
                    if np.isfinite(float(ref["hole_amplitude"])) and float(ref["hole_amplitude"]) > 0 else "")
            print(f"  {p:9s} {m:10s}: mean {100 * float(r['error_mean']) / float(ref['mean']):+.2f} % "
                  f"(elastic part {100 * float(r['error_mean']) / el:+.1f} %), "
                  f"p2p {100 * (float(r['p2p']) / float(ref['p2p']) - 1):+.1f} %{hole}")


def make_figures(ds: xr.Dataset, outdir: Path) -> list[Path]:
    import matplotlib.pyplot as plt
    outdir.mkdir(parents=True, exist_ok=True)
    paths = []
    style = {"fe-reference": dict(color="k", lw=2.0), "plain": dict(color="tab:red", lw=1.0),
             "plain-fe": dict(color="tab:orange", lw=1.0, ls="--"), "coupled": dict(color="tab:blue", lw=1.2),
             "compliance": dict(color="tab:green", lw=1.2)}
    a = ds["angle"].values
    pitch = 360.0 / ds.attrs["mesh_order"]
    for p in ds["pair"].values:
        fig, axs = plt.subplots(2, 1, figsize=(9, 7))
        for m in ds["model"].values:
            for ax in axs:
                ax.plot(a, ds["ste"].sel(pair=p, model=m), label=m, **style[m])
        axs[1].set_xlim(a[0], a[0] + 3 * pitch)
        for ax in axs:
            ax.set_xlabel("driver rotation [deg]")
            ax.set_ylabel("STE [um]")
            ax.grid(alpha=0.3)
        axs[0].legend(ncol=4, fontsize=8)
        axs[0].set_title(f"STE, {p} pair, {ds.attrs['static_torque_N_m']:g} N m (bottom: three mesh pitches)")
        fig.tight_layout()
        path = outdir / f"ste_{p}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
        fig, ax = plt.subplots(figsize=(9, 4))
        for m in ds["model"].values:
            ax.plot(a, ds["load_share"].sel(pair=p, model=m), label=m, **style[m])
        sh = ds["load_share"].sel(pair=p, model="fe-reference").values
        on = np.flatnonzero(sh > 0)
        if on.size:
            ax.set_xlim(a[max(on[0] - 5, 0)], a[min(on[-1] + 5, a.size - 1)])
        ax.set_xlabel("driver rotation [deg]")
        ax.set_ylabel("load share of one driver tooth [1]")
        ax.set_title(f"Load sharing, {p} pair")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = outdir / f"load_sharing_{p}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    models = [m for m in ds["model"].values if m != "fe-reference"]
    x = np.arange(len(models))
    for ax, p in zip(axs, ds["pair"].values):
        for i, (k, lab) in enumerate((("error_mean_single", "single contact"), ("error_mean_double", "double contact"))):
            ax.bar(x + (i - 0.5) * 0.35, [float(ds[k].sel(pair=p, model=m)) for m in models], 0.35, label=lab)
        ax.set_xticks(x, models)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_ylabel("mean STE error against the FE reference [um]")
        ax.set_title(f"{p} pair")
        ax.legend(fontsize=8)
    fig.tight_layout()
    path = outdir / "errors.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    paths.append(path)
    return paths


def print_design_space(ds: xr.Dataset, default: str = "compliance") -> None:
    err = study.validation_errors(ds)
    models = [str(m) for m in ds["model"].values if m != "fe-reference"]
    print(f"STE against the FE reference over gear 2's body, {ds.attrs['static_torque_N_m']:g} N m "
          "(FE: elastic mean and p2p in um, hole-order amplitude in nm; models: error in %, mean / p2p / hole order)")
    print(f"{'holes':>5s} {'web':>5s} {'rim':>5s} {'FE mean':>8s} {'p2p':>6s} {'hole':>6s}  " + "  ".join(f"{m:>20s}" for m in models))
    for n in ds["holes"].values:
        for w in ds["web_thickness"].values:
            for r in ds["rim_height"].values:
                ref = ds.sel(holes=n, web_thickness=w, rim_height=r, model="fe-reference")
                e = err.sel(holes=n, web_thickness=w, rim_height=r)
                cells = []
                for m in models:
                    em = e.sel(model=m)
                    h = f"{100 * float(em['hole']):+5.1f}" if np.isfinite(float(em["hole"])) else "    -"
                    cells.append(f"{100 * float(em['elastic_mean']):+5.1f} {100 * float(em['p2p']):+5.1f} {h}")
                hole = float(ref["hole_amplitude"]) * 1e3
                print(f"{int(n):5d} {w:5.1f} {r:5.1f} {float(ref['ste_elastic_mean']):8.3f} {float(ref['ste_p2p']):6.3f} "
                      f"{hole if np.isfinite(hole) else float('nan'):6.1f}  " + "  ".join(f"{c:>20s}" for c in cells))
    for m in models:
        em = err.sel(model=m)
        print(f"  {m:12s} largest |error|: elastic mean {100 * float(np.abs(em['elastic_mean']).max()):.1f} %, "
              f"p2p {100 * float(np.abs(em['p2p']).max()):.1f} %, hole order {100 * float(np.abs(em['hole']).max()):.1f} %")
    miss = study.validation_misses(ds, default)
    print(f"  default model ({default}): " + ("every point within the targets" if not miss else
                                              f"{len(miss)} misses: " + "; ".join(miss)))


def print_relief(ds: xr.Dataset, default: str = "compliance") -> None:
    models = [str(m) for m in ds["model"].values]
    print("STE peak-to-peak [um] against a linear tip relief on both gears")
    for p in ds["pair"].values:
        for t in ds["torque"].values:
            print(f"  {p} pair, {t:g} N m: relief [um] " + " ".join(f"{r:6.2f}" for r in ds["relief"].values) + "   optimum")
            for m in models:
                r = ds.sel(pair=p, torque=t, model=m)
                print(f"    {m:14s}" + " " * 13 + " ".join(f"{x:6.3f}" for x in r["ste_p2p"].values)
                      + f"   {float(r['optimum_relief']):5.2f}")
    miss = study.validation_misses(ds, default)
    print(f"  default model ({default}): " + ("every point within the targets" if not miss else
                                              f"{len(miss)} misses: " + "; ".join(miss)))


def campaign(args) -> int:
    """The design-space or relief campaign (`study.validate_design_space`, `study.validate_relief`)."""
    base = study.load_scene(args.scene, args.overrides)
    step = args.step or 0.1
    t0 = time.perf_counter()
    if args.design_space:
        grid = dict(holes=(0, 6, 12), webs=(6.0,), rims=(5.0,)) if args.quick else {}
        ds = study.validate_design_space(base.replace(**{"quasi_static.torque": 50.0}), step=step, log=print, **grid)
        out = args.output if args.output != DEFAULT_OUT else "results/validation/design_space.nc"
    else:
        kw = dict(reliefs=(0.0, 2.0, 4.0), torques=(50.0,)) if args.quick else {}
        ds = study.validate_relief(base, step=step, log=print, **kw)
        out = args.output if args.output != DEFAULT_OUT else "results/validation/relief.nc"
    ds.attrs["wall_time_s"] = time.perf_counter() - t0
    study.write(ds, out)
    print(f"archive -> {out} ({ds.attrs['wall_time_s']:.0f} s)")
    (print_design_space if args.design_space else print_relief)(ds)
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", help="scene TOML (default: the paper example; its driven gear is the lightened one)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT)
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--step", type=float, default=None, metavar="DEG", help="driver angle step (default: quasi_static.angle_step)")
    p.add_argument("--no-figures", action="store_true", help="write only the archive")
    p.add_argument("--design-space", action="store_true", help="all models against the FE reference over gear 2's body")
    p.add_argument("--relief", action="store_true", help="all models against the FE reference over tip relief and torque")
    p.add_argument("--quick", action="store_true", help="a reduced grid (with --design-space or --relief)")
    args = p.parse_args(argv)
    if args.design_space or args.relief:
        return campaign(args)
    scene = study.load_scene(args.scene, args.overrides)
    ds = study.validation(scene, args.step)
    study.write(ds, args.output)
    print(f"validation archive -> {args.output} ({ds.attrs['wall_time_s']:.1f} s)")
    print_table(ds)
    if not args.no_figures:
        for path in make_figures(ds, Path(args.output).parent):
            print(f"  figure: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.validation", main))

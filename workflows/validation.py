"""Validation of the pseudo-rigid models against the FE reference (LTCA) for the solid and the
lightened pair: STE, load sharing, and the error figures.

Models (all at the scene's quasi-static torque, static equilibrium at every angle):
  fe-reference  loaded-tooth-contact analysis with FE influence coefficients (`study.verify.fe_reference`)
  plain         MUBOCO-PR as the scene defines it (the paper's calibrated springs)
  plain-fe      MUBOCO-PR with each tooth's spring from the same FE body (linear, k = k_fe):
                the paper's structure with our FE, so the difference to the reference is
                the missing foundation coupling alone
  coupled       body-torsion coupling (`coupling.model = "body-torsion"`), same FE body
                (body spring, tooth springs without the body wind-up, tooth pivot refitted)
  compliance    the full coupling (`coupling.model = "compliance"`): body spring plus tooth
                springs coupled through the FE compliance between every pair of teeth

Figures per model against the reference: mean STE, peak-to-peak, the hole-order amplitude
(order N of the driven gear, least-squares fit together with the mesh harmonics and their
hole sidebands), mean and RMS error where the rigid geometry has one and two pairs in the
path of contact, and the worst load-sharing error of one driver tooth through the mesh.

    python -m workflows.validation [SCENE] [-o results/validation/validation.nc] [--step DEG]
"""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import xarray as xr

from solver import units
from solver.fe.ltca import mesh_points
from solver.mbs.statics import solve_static
from study.report import results
from study.scene import load_scene
from study.setup import build_scene_model, coupling_fit, gear_setup, solid_scene
from study.verify.fe_reference import reference, static_angles

DEFAULT_OUT = "results/validation/validation.nc"
MODELS = ("fe-reference", "plain", "plain-fe", "coupled", "compliance")
PAIRS = ("solid", "lightened")


def model_scene(scene, name: str):
    """(scene, springs) of a pseudo-rigid model variant; springs None = the scene's own."""
    if name == "plain":
        return scene, None
    if name == "coupled":
        return scene.replace(**{"coupling.model": "body-torsion"}), None
    if name == "compliance":
        return scene.replace(**{"coupling.model": "compliance"}), None
    if name == "plain-fe":
        from study.inputs.coupling import plain_fe_springs
        lin = scene.replace(**{"gear1.spring.n_k": 1.0, "gear2.spring.n_k": 1.0, "coupling.model": "none"})
        springs = []
        for g in (1, 2):
            k = plain_fe_springs(gear_setup(scene, g)) / units.spring_stiffness_to_si(1.0)
            springs.append((k, k / k.max()))
        return lin, tuple(springs)
    raise ValueError(f"model: unknown {name!r}")


def order_amplitude(angle_rad: np.ndarray, te: np.ndarray, order: float, mesh_order: float) -> float:
    """Amplitude [units of te] at ``order`` of the driven gear's rotation (equal to the driver's
    for a 1:1 pair scaled by z1/z2), fitted jointly with the mesh harmonics and their sidebands."""
    x = np.asarray(angle_rad)
    cols = [np.ones_like(x)]
    freqs = [order] + [h * mesh_order + s * order for h in (1, 2, 3) for s in (-1, 0, 1)]
    for f in freqs:
        cols += [np.cos(f * x), np.sin(f * x)]
    c, *_ = np.linalg.lstsq(np.column_stack(cols), te, rcond=None)
    return float(math.hypot(c[1], c[2]))


def nominal_contacts(model, angles) -> np.ndarray:
    """Tooth pairs in the path of contact of the rigid geometry at each driver angle [rad]."""
    return np.array([int(np.count_nonzero(mesh_points(model, float(a)).kind == 1)) for a in angles])


def evaluate_pair(scene, angles):
    """STE [um] and driver-tooth forces [N] of every model, the nominal contact count and times."""
    ste, force, wall = {}, {}, {}
    t0 = time.perf_counter()
    ref, model, info = reference(scene, angles)
    wall["fe-reference"] = time.perf_counter() - t0
    ste["fe-reference"] = ref.te * units.UM_PER_M
    force["fe-reference"] = ref.tooth_force
    for name in MODELS[1:]:
        sc, springs = model_scene(scene, name)
        t0 = time.perf_counter()
        m = build_scene_model(sc, springs)
        st = solve_static(m, angles, sc.quasi_static.torque)
        wall[name] = time.perf_counter() - t0
        ste[name] = st.te * units.UM_PER_M
        force[name] = st.tooth_force
    return ste, force, nominal_contacts(model, angles), wall, model


def metrics(angles, ste: dict, force: dict, nominal, scene, model) -> dict:
    """Error figures of every model against the reference (units in the keys' docs below)."""
    z1, z2 = model.teeth
    ratio = z1 / z2                                   # driven rotation per driver rotation
    n_holes = scene.gear2.body.holes or scene.gear1.body.holes
    ref = ste["fe-reference"]
    # the driver tooth that passes the mesh in the middle of the range
    mid = angles.size // 2
    tooth = int(np.argmax(force["fe-reference"][mid]))
    out = {}
    for name in MODELS:
        t = ste[name]
        d = t - ref
        f = force[name]
        share = f[:, tooth] / np.maximum(f.sum(axis=1), 1e-30)
        share_ref = force["fe-reference"][:, tooth] / np.maximum(force["fe-reference"].sum(axis=1), 1e-30)
        single, double = nominal == 1, nominal == 2
        out[name] = dict(
            mean=float(t.mean()), p2p=float(np.ptp(t)),
            hole_amplitude=order_amplitude(angles * ratio, t, n_holes, z2) if n_holes else float("nan"),
            error_mean=float(d.mean()),
            error_mean_single=float(d[single].mean()) if single.any() else float("nan"),
            error_mean_double=float(d[double].mean()) if double.any() else float("nan"),
            error_rms_single=float(np.sqrt(np.mean(d[single] ** 2))) if single.any() else float("nan"),
            error_rms_double=float(np.sqrt(np.mean(d[double] ** 2))) if double.any() else float("nan"),
            load_share_error_max=float(np.max(np.abs(share - share_ref))),
            load_share=share, tooth=tooth)
    return out


METRIC_DOC = {
    "mean": ("um", "mean STE"),
    "p2p": ("um", "peak-to-peak STE"),
    "hole_amplitude": ("um", "STE amplitude at the hole order N of the driven gear"),
    "error_mean": ("um", "mean STE error against the FE reference"),
    "error_mean_single": ("um", "mean STE error where the rigid geometry has one pair in the path of contact"),
    "error_mean_double": ("um", "mean STE error where the rigid geometry has two pairs in the path of contact"),
    "error_rms_single": ("um", "RMS STE error in single contact"),
    "error_rms_double": ("um", "RMS STE error in double contact"),
    "load_share_error_max": ("1", "largest error in the load share of one driver tooth through the mesh"),
}


def validation_dataset(scene, angles) -> xr.Dataset:
    pairs = {"solid": solid_scene(scene, gears=(2,)), "lightened": scene}     # the driven gear made solid
    na = angles.size
    ste = np.full((len(PAIRS), len(MODELS), na), np.nan)
    share = np.full_like(ste, np.nan)
    nominal = np.zeros((len(PAIRS), na), dtype="int16")
    tab = {k: np.full((len(PAIRS), len(MODELS)), np.nan) for k in METRIC_DOC}
    wall = np.full((len(PAIRS), len(MODELS)), np.nan)
    fit = {k: np.full((len(PAIRS), 2), np.nan) for k in ("k_body", "pivot", "rms")}
    offsets = []
    for p, name in enumerate(PAIRS):
        sc = pairs[name]
        s, f, nom, w, model = evaluate_pair(sc, angles)
        if "compliance" in MODELS:
            for g in (1, 2):
                tc = coupling_fit(sc, g, "compliance")
                fit["k_body"][p, g - 1], fit["pivot"][p, g - 1], fit["rms"][p, g - 1] = (
                    tc.k_body, tc.pivot_radius * units.MM_PER_M, tc.rms_rel_error)
        offsets.append(model.backlash_offset * units.UM_PER_M)
        m = metrics(angles, s, f, nom, sc, model)
        nominal[p] = nom
        for i, mod in enumerate(MODELS):
            ste[p, i] = s[mod]
            share[p, i] = m[mod]["load_share"]
            wall[p, i] = w[mod]
            for k in METRIC_DOC:
                tab[k][p, i] = m[mod][k]
    v = results._var
    coords = {"pair": v("pair", np.array(PAIRS), "", "gear pair (driven gear solid or lightened)"),
              "model": v("model", np.array(MODELS), "", "model (fe-reference: LTCA with FE influence coefficients)"),
              "angle": v("angle", np.degrees(angles), "degree", "driver rotation from the nominal position")}
    data = {"ste": v(("pair", "model", "angle"), ste, "um", "static transmission error rb1*theta1 + rb2*theta2"),
            "load_share": v(("pair", "model", "angle"), share, "1", "share of the mesh force carried by one driver tooth"),
            "nominal_contacts": v(("pair", "angle"), nominal, "1", "tooth pairs in the path of contact of the rigid geometry"),
            "wall_time": v(("pair", "model"), wall, "s", "wall time of the STE (FE compliance included for the reference)")}
    for k, (unit, doc) in METRIC_DOC.items():
        data[k] = v(("pair", "model"), tab[k], unit, doc)
    coords["gear"] = v("gear", np.array([1, 2]), "1", "gear (1 driver, 2 driven)")
    data["compliance_k_body"] = v(("pair", "gear"), fit["k_body"], "N m rad-1", "body torsion stiffness of the compliance model")
    data["compliance_pivot_radius"] = v(("pair", "gear"), fit["pivot"], "mm", "tooth pivot radius of the compliance model")
    data["compliance_fit_rms"] = v(("pair", "gear"), fit["rms"], "1",
                                   "RMS relative residual of the compliance model's fit to the FE influence coefficients")
    attrs = {"title": "STE of the pseudo-rigid models against the FE reference", "scene": scene.to_toml(),
             "backlash_offset_um": offsets[0], "static_torque_N_m": scene.quasi_static.torque,
             "hole_order": float(scene.gear2.body.holes), "mesh_order": float(scene.gear2.teeth),
             **results.provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)


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
    for p in ds["pair"].values:
        ref = ds.sel(pair=p, model="fe-reference")
        for m in MODELS[1:]:
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


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", help="scene TOML (default: the paper example; its driven gear is the lightened one)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT)
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--step", type=float, default=None, metavar="DEG", help="driver angle step (default: quasi_static.angle_step)")
    p.add_argument("--no-figures", action="store_true", help="write only the archive")
    args = p.parse_args(argv)
    scene = load_scene(args.scene, args.overrides)
    if scene.coupling.model != "none":
        scene = scene.replace(**{"coupling.model": "none"})
    angles = static_angles(scene, args.step)
    t0 = time.perf_counter()
    ds = validation_dataset(scene, angles)
    ds.attrs["wall_time_s"] = time.perf_counter() - t0
    results.write_netcdf(ds, args.output)
    print(f"validation archive -> {args.output} ({ds.attrs['wall_time_s']:.1f} s)")
    print_table(ds)
    if not args.no_figures:
        for path in make_figures(ds, Path(args.output).parent):
            print(f"  figure: {path}")
    return 0


if __name__ == "__main__":
    from study.cli import script_main
    raise SystemExit(script_main("python -m workflows.validation", main))

"""Which model agrees with the FE reference, over the design space a lightening study sweeps.

Two campaigns, each against the FE reference (`study.verify.fe_reference`: loaded-tooth-contact
analysis with the bodies' FE influence coefficients and the same contact law):

* `design_space_dataset`: the driven gear's body over holes x web thickness x rim thickness
  (bore and hub kept: the web grows as the rim thins) at one torque; STE mean, elastic mean
  (less the backlash offset jn/2), peak-to-peak and the hole-order amplitude of every model.
* `relief_dataset`: pairs with a linear tip relief of the same amount on both gears (the
  scene's relief length) over a list of reliefs and torques; STE peak-to-peak and elastic
  mean, and the relief that minimises the STE peak-to-peak of each model (the grid's best,
  refined by a bounded scalar search to 0.05 um).

Models: 'fe-reference', 'paper' (plain MUBOCO-PR, ``coupling.model = "paper"``),
'body-torsion', 'compliance'. `TARGETS` are the agreement a default model must reach;
`check_targets` lists the points outside them. Units: um, N·m, mm as the variables say.
"""
from __future__ import annotations

import math
import time

import numpy as np
import xarray as xr

from solver import units
from solver.mbs.statics import solve_static
from study.archive.netcdf import cf_variable, provenance
from study.errors import check_scene_argument
from study.scene import Scene
from study.scene_model import build_scene_model
from study.verify.fe_reference import reference

MODELS = ("fe-reference", "paper", "body-torsion", "compliance")
# agreement with the FE reference a default model must reach: relative errors of the elastic
# mean STE, of the STE peak-to-peak and of the hole-order amplitude [1], and the distance of
# the relief that minimises the STE peak-to-peak [um]
TARGETS = {"elastic_mean": 0.02, "p2p": 0.10, "hole": 0.15, "relief_um": 0.5}
COUPLING = {"paper": "paper", "body-torsion": "body-torsion", "compliance": "compliance"}


# the fit's columns: a constant, cos and sin of the order and of the three mesh harmonics with
# their sidebands at +-order
ORDER_FIT_COLUMNS = 1 + 2 * (1 + 3 * 3)


def order_unresolved(angle_rad: np.ndarray, order: float) -> str | None:
    """Why the record over ``angle_rad`` (the driven gear's rotation [rad], evenly spaced)
    cannot give the amplitude at ``order`` (`order_amplitude`), or None: fewer angles than
    the fit has columns, or a rotation shorter than one period of the order (the fit then
    trades the order against the constant and reports thousands of times the STE)."""
    x = np.asarray(angle_rad, float)
    if x.size < ORDER_FIT_COLUMNS:
        return f"{x.size} angles, fewer than the {ORDER_FIT_COLUMNS} columns of the fit"
    span = float(x[-1] - x[0]) + float(x[1] - x[0])
    if order * span < 2 * math.pi * (1 - 1e-9):
        return (f"the driven gear turns {math.degrees(span):.4g} deg, less than one period of order {order:g} "
                f"({360 / order:.4g} deg): a longer rotation resolves it")
    return None


def order_amplitude(angle_rad: np.ndarray, te: np.ndarray, order: float, mesh_order: float) -> float:
    """Amplitude [units of te] at ``order`` of the driven gear's rotation (angle_rad: the driven
    gear's rotation [rad]), fitted jointly with the first three mesh harmonics and their
    sidebands at +-order (least squares), so the mesh ripple does not leak into it. NaN where
    the record cannot resolve the order (`order_unresolved`)."""
    x = np.asarray(angle_rad)
    if order_unresolved(x, order):
        return float("nan")
    cols = [np.ones_like(x)]
    freqs = [order] + [h * mesh_order + s * order for h in (1, 2, 3) for s in (-1, 0, 1)]
    for f in freqs:
        cols += [np.cos(f * x), np.sin(f * x)]
    c, *_ = np.linalg.lstsq(np.column_stack(cols), te, rcond=None)
    return float(math.hypot(c[1], c[2]))


def model_ste(scene: Scene, model: str, angles: np.ndarray) -> tuple[np.ndarray, float]:
    """(STE [m] at the driver ``angles`` [rad], backlash offset jn/2 [m]) of one model at the
    scene's quasi-static torque. The FE part of a model (FE springs, coupling fit, influence
    coefficients) comes from the FE cache."""
    torque = scene.quasi_static.torque
    if model == "fe-reference":
        ref, m, _ = reference(scene, angles)
        return ref.te, m.backlash_offset
    m = build_scene_model(scene.replace(**{"coupling.model": COUPLING[model]}))
    return solve_static(m, angles, torque).te, m.backlash_offset


def ste_figures(scene: Scene, angles: np.ndarray, models=MODELS) -> dict:
    """{model: dict(mean, elastic_mean, p2p, hole [um], wall [s])} of the STE over ``angles``."""
    z1, z2 = scene.gear1.teeth, scene.gear2.teeth
    holes = scene.gear2.body.holes
    out = {}
    for name in models:
        t0 = time.perf_counter()
        te, off = model_ste(scene, name, angles)
        wall = time.perf_counter() - t0
        te = te * units.UM_PER_M
        out[name] = dict(mean=float(te.mean()), elastic_mean=float(te.mean() - off * units.UM_PER_M),
                         p2p=float(np.ptp(te)), wall=wall,
                         hole=order_amplitude(angles * z1 / z2, te, holes, z2) if holes else float("nan"))
    return out


def body_scene(base: Scene, holes: int, web: float, rim: float) -> Scene:
    """The base scene with gear 2's body at ``holes``, web thickness ``web`` [mm] and rim
    height ``rim`` [mm]; the bore and the hub stay, the web takes up the rim's change."""
    b = base.gear2.body
    return base.replace(**{"gear2.body.holes": holes, "gear2.body.web_thickness": web,
                           "gear2.body.rim_height": rim, "gear2.body.web_height": b.web_height + b.rim_height - rim})


def _angles(rotation_deg: float, step_deg: float) -> np.ndarray:
    return np.radians(np.arange(int(math.floor(rotation_deg / step_deg + 1e-9)) + 1) * step_deg)


def design_space_dataset(scene: Scene, holes=(0, 3, 6, 9, 12), webs=(6.0, 10.0), rims=(5.0, 7.0),
                         rotation: float = 120.0, step: float = 0.1, log=None, models=MODELS) -> xr.Dataset:
    """STE of every model (paper, body-torsion, compliance) and the FE reference over gear 2's
    body: hole counts x web thickness [mm] x rim height [mm], at the scene's quasi-static torque,
    over ``rotation`` [deg] of the driver at ``step`` [deg] (a whole number of hole periods for
    every hole count: 120 deg for 3, 6, 9 and 12 holes) -> Dataset (mean, elastic mean and p2p
    [um], hole-order amplitude [um], wall time [s]). ``log``: called with a line per body."""
    check_scene_argument("validate_design_space", scene)
    shape = (len(holes), len(webs), len(rims), len(models))
    figs = {k: np.full(shape, np.nan) for k in ("mean", "elastic_mean", "p2p", "hole", "wall")}
    angles = _angles(rotation, step)
    for i, n in enumerate(holes):
        for j, web in enumerate(webs):
            for k, rim in enumerate(rims):
                f = ste_figures(body_scene(scene, n, web, rim), angles, models)
                for m, name in enumerate(models):
                    for key in figs:
                        figs[key][i, j, k, m] = f[name][key]
                if log:
                    log(f"holes {n:2d}, web {web:4.1f} mm, rim {rim:4.1f} mm: " + ", ".join(
                        f"{name} p2p {f[name]['p2p']:.3f} um" for name in models))
    dims, coords = _model_grid(models, holes=(np.asarray(holes), "1", "holes in gear 2's web"),
                               web_thickness=(np.asarray(webs, float), "mm", "gear 2's web thickness"),
                               rim_height=(np.asarray(rims, float), "mm", "gear 2's rim under the root circle"))
    v = cf_variable
    data = {"ste_mean": v(dims, figs["mean"], "um", "mean static transmission error"),
            "ste_elastic_mean": v(dims, figs["elastic_mean"], "um", "mean STE less the backlash offset jn/2"),
            "ste_p2p": v(dims, figs["p2p"], "um", "peak-to-peak static transmission error"),
            "hole_amplitude": v(dims, figs["hole"], "um", "STE amplitude at the hole order of gear 2"),
            "wall_time": v(dims, figs["wall"], "s", "wall time of the model's STE (its FE included unless cached)")}
    attrs = {"title": "STE of the models against the FE reference over gear 2's body",
             "static_torque_N_m": scene.quasi_static.torque, "rotation_deg": rotation, "angle_step_deg": step,
             "base_scene": scene.to_toml(), **_target_attrs(), **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def validate_bodies(scenes: dict, step: float = 0.1, models=("fe-reference", "compliance"), log=None) -> xr.Dataset:
    """STE of ``models`` and the FE reference for named scenes ({name: Scene}, bodies of any
    opening shape), each over two periods of its driven gear's openings at ``step`` [deg] ->
    Dataset over (body, model): mean, elastic mean and p2p [um], opening-order amplitude [um]
    (`bodies_dataset`); errors with `relative_errors`."""
    from study.errors import check_argument, check_scene_argument
    check_argument(isinstance(scenes, dict), "validate_bodies", "scenes", "a dict {name: Scene}", scenes)
    for sc in scenes.values():
        check_scene_argument("validate_bodies", sc)
    return bodies_dataset(dict(scenes), step=step, models=tuple(models), log=log)


def bodies_dataset(scenes: dict, step: float = 0.1, models=MODELS, log=None) -> xr.Dataset:
    """STE figures of every model for named scenes (``{name: Scene}``: bodies of any opening
    shape), each at its quasi-static torque over two periods of its driven gear's openings
    (360/N deg of the driven gear each; 120 deg without openings) at ``step`` [deg] of the driver.
    ``log``: called with a line per body."""
    names = list(scenes)
    shape = (len(names), len(models))
    figs = {k: np.full(shape, np.nan) for k in ("mean", "elastic_mean", "p2p", "hole", "wall")}
    rotations = []
    for i, name in enumerate(names):
        sc = scenes[name]
        n = sc.gear2.body.holes
        rotation = 2 * 360.0 / n * sc.gear2.teeth / sc.gear1.teeth if n else 120.0
        rotations.append(rotation)
        f = ste_figures(sc, _angles(rotation, step), models)
        for m, model in enumerate(models):
            for key in figs:
                figs[key][i, m] = f[model][key]
        if log:
            log(f"{name}: " + ", ".join(f"{model} p2p {f[model]['p2p']:.3f} um" for model in models))
    dims, coords = _model_grid(models, body=(np.array(names), "", "body of gear 2"))
    v = cf_variable
    data = {"ste_mean": v(dims, figs["mean"], "um", "mean static transmission error"),
            "ste_elastic_mean": v(dims, figs["elastic_mean"], "um", "mean STE less the backlash offset jn/2"),
            "ste_p2p": v(dims, figs["p2p"], "um", "peak-to-peak static transmission error"),
            "hole_amplitude": v(dims, figs["hole"], "um", "STE amplitude at the opening order of gear 2"),
            "wall_time": v(dims, figs["wall"], "s", "wall time of the model's STE (its FE included unless cached)"),
            "rotation": v("body", np.array(rotations), "degree", "driver rotation of the STE (two opening periods)")}
    attrs = {"title": "STE of the models against the FE reference for bodies of gear 2", "angle_step_deg": step,
             "scenes": "\n\n".join(f"# {n}\n{scenes[n].to_toml()}" for n in names), **_target_attrs(), **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _model_grid(models, **axes) -> tuple[tuple, dict]:
    """Dimensions and coordinates of a grid of figures over ``axes`` (name: (values, unit, long
    name), in order) and the models compared, last."""
    v = cf_variable
    coords = {name: v(name, values, unit, long_name) for name, (values, unit, long_name) in axes.items()}
    coords["model"] = v("model", np.array(models), "", "model (fe-reference: LTCA with FE influence coefficients)")
    return tuple(coords), coords


def relief_scene(scene: Scene, relief: float, torque: float) -> Scene:
    """``scene`` with a linear tip relief of ``relief`` [um] on both gears (the scene's tip
    length, else the paper pair's 3.55 mm) and quasi-static ``torque`` [N·m]."""
    over = {"quasi_static.torque": torque}
    for g in (1, 2):
        length = scene.gear(g).modification.tip_length or 3.55
        over.update({f"gear{g}.modification.tip_relief": float(relief), f"gear{g}.modification.tip_shape": "linear",
                     f"gear{g}.modification.tip_length": length})
    return scene.replace(**over)


def optimum_relief(scene: Scene, model: str, torque: float, angles, reliefs, p2p) -> float:
    """The relief [um] that minimises the STE peak-to-peak of ``model``: each local minimum of
    the grid ``reliefs`` (with its ``p2p`` [um]; the curve can have two, e.g. where the tip
    corners stop carrying load) refined by a bounded scalar search between its neighbours (to
    0.05 um), the best of them."""
    from scipy.optimize import minimize_scalar
    reliefs, p2p = np.asarray(reliefs, float), np.asarray(p2p, float)
    n = reliefs.size

    def f(r):
        te, _ = model_ste(relief_scene(scene, r, torque), model, angles)
        return float(np.ptp(te)) * units.UM_PER_M
    best = (float(np.nanmin(p2p)), float(reliefs[int(np.nanargmin(p2p))]))
    for i in range(n):
        if (i > 0 and p2p[i] > p2p[i - 1]) or (i < n - 1 and p2p[i] > p2p[i + 1]):
            continue                       # not a local minimum of the grid
        res = minimize_scalar(f, bounds=(reliefs[max(i - 1, 0)], reliefs[min(i + 1, n - 1)]), method="bounded",
                              options=dict(xatol=0.05))
        if res.fun < best[0]:
            best = (float(res.fun), float(res.x))
    return best[1]


def relief_dataset(pairs: dict, reliefs=(0.0, 1.0, 2.0, 3.0, 4.0, 6.0), torques=(25.0, 50.0, 100.0),
                   rotations: dict | None = None, step: float = 0.1, models=MODELS, refine: bool = True,
                   log=None) -> xr.Dataset:
    """STE peak-to-peak and elastic mean of every model for each pair (name -> Scene) with the
    tip ``reliefs`` [um] on both gears at the ``torques`` [N·m], over ``rotations[name]`` [deg]
    of the driver (default 30 deg), and each model's optimum relief (`optimum_relief`; the
    grid's best when ``refine`` is False)."""
    names = list(pairs)
    shape = (len(names), len(torques), len(reliefs), len(models))
    p2p, mean, hole = np.full(shape, np.nan), np.full(shape, np.nan), np.full(shape, np.nan)
    opt = np.full((len(names), len(torques), len(models)), np.nan)
    for a, name in enumerate(names):
        angles = _angles((rotations or {}).get(name, 30.0), step)
        for b, torque in enumerate(torques):
            for c, r in enumerate(reliefs):
                f = ste_figures(relief_scene(pairs[name], r, torque), angles, models)
                for m, mod in enumerate(models):
                    p2p[a, b, c, m], mean[a, b, c, m], hole[a, b, c, m] = f[mod]["p2p"], f[mod]["elastic_mean"], f[mod]["hole"]
            for m, mod in enumerate(models):
                opt[a, b, m] = (optimum_relief(pairs[name], mod, torque, angles, reliefs, p2p[a, b, :, m]) if refine
                                else reliefs[int(np.nanargmin(p2p[a, b, :, m]))])
            if log:
                log(f"{name} pair, {torque:g} N m: optimum relief " + ", ".join(
                    f"{mod} {opt[a, b, m]:.2f} um" for m, mod in enumerate(models)))
    dims, coords = _model_grid(models, pair=(np.array(names), "", "gear pair"),
                               torque=(np.asarray(torques, float), "N m", "quasi-static torque on gear 2"),
                               relief=(np.asarray(reliefs, float), "um", "linear tip relief at the tip, both gears"))
    v = cf_variable
    data = {"ste_p2p": v(dims, p2p, "um", "peak-to-peak static transmission error"),
            "ste_elastic_mean": v(dims, mean, "um", "mean STE less the backlash offset jn/2"),
            "hole_amplitude": v(dims, hole, "um", "STE amplitude at the hole order of gear 2 (NaN: no holes)"),
            "optimum_relief": v(("pair", "torque", "model"), opt, "um", "tip relief that minimises the STE peak-to-peak",
                                comment="best of the relief grid, refined by a bounded scalar search to 0.05 um" if refine
                                else "best of the relief grid")}
    attrs = {"title": "STE against tip relief: the models against the FE reference",
             "angle_step_deg": step, "rotation_deg": str({n: (rotations or {}).get(n, 30.0) for n in names}),
             "scenes": "\n\n".join(f"# {n}\n{pairs[n].to_toml()}" for n in names), **_target_attrs(),
             **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)


def validate_relief(scene: Scene, reliefs=(0.0, 1.0, 2.0, 3.0, 4.0, 6.0), torques=(25.0, 50.0, 100.0),
                    step: float = 0.1, log=None) -> xr.Dataset:
    """STE peak-to-peak of every model and the FE reference for the scene's pair with its driven
    gear solid and as given, with a linear tip relief [um] of each amount on both gears at each
    torque [N·m], and the relief that minimises it -> Dataset (`relief_dataset`)."""
    check_scene_argument("validate_relief", scene)
    return relief_dataset({"solid": scene.solid(), "paper": scene}, reliefs=reliefs, torques=torques,
                          rotations={"solid": 30.0, "paper": 60.0}, step=step, log=log)


def _target_attrs() -> dict:
    return {f"target_{k}": v for k, v in TARGETS.items()}


def relative_errors(ds: xr.Dataset) -> xr.Dataset:
    """Relative errors [1] of every model against the FE reference: elastic mean, p2p, hole order."""
    ref = ds.sel(model="fe-reference")
    out = {"elastic_mean": ds["ste_elastic_mean"] / ref["ste_elastic_mean"] - 1,
           "p2p": ds["ste_p2p"] / ref["ste_p2p"] - 1}
    if "hole_amplitude" in ds:
        out["hole"] = ds["hole_amplitude"] / ref["hole_amplitude"] - 1
    return xr.Dataset(out).drop_sel(model="fe-reference")


def check_targets(ds: xr.Dataset, model: str = "compliance") -> list[str]:
    """The points of a validation dataset where ``model`` misses a target of `TARGETS`, as text
    (empty: all met)."""
    miss = []
    err = relative_errors(ds).sel(model=model)
    for key in ("elastic_mean", "p2p", "hole"):
        if key not in err:
            continue
        e = err[key]
        bad = np.abs(e) > TARGETS[key]
        for idx in zip(*np.nonzero(bad.values)):
            where = ", ".join(f"{d} {e[d].values[i]}" for d, i in zip(e.dims, idx))
            miss.append(f"{key} {100 * float(e.values[idx]):+.1f} % at {where}")
    if "optimum_relief" in ds:
        d = ds["optimum_relief"].sel(model=model) - ds["optimum_relief"].sel(model="fe-reference")
        for idx in zip(*np.nonzero(np.abs(d.values) > TARGETS["relief_um"])):
            where = ", ".join(f"{dim} {d[dim].values[i]}" for dim, i in zip(d.dims, idx))
            miss.append(f"optimum relief {float(d.values[idx]):+.2f} um at {where}")
    return miss

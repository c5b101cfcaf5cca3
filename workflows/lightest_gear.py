"""The lightest driven-gear body whose transmission error and strength stay within limits.

Among driven-gear bodies (hole count, hole radius, rim and web thickness), the one that saves
the most mass while its STE peak-to-peak and its DTE RMS at the given speed stay within given
factors of the solid gear's (no holes, web as thick as the face), its largest root stress
within a limit (relative to the solid gear's, and optionally in MPa) and its bending safety
factor S_F at the root, in the rim and in the web (under the STE's contact forces, against the
scene's gear2.material) at least ``--safety-min``:

    python -m workflows.lightest_gear [SCENE.toml] [--ste-factor 2.0] [--dte-factor 4.0]
        [--stress-ratio 1.15] [--stress-max MPA] [--safety-min 1.4] [--speed 100]
        [--grid gear2.body.holes=3,6,9 ...] [--shapes round,slot,window] [--refine 2] [-o results/lightest_gear]
        [--workers N]

1. the solid gear, at the same speed: the reference of the factors;
2. a coarse grid over the four body fields (full factorial, `study.make_study` + `study.run_sweep`
   on a dask LocalCluster), archived as ``coarse.nc``;
3. refinement: around each of the ``--refine`` lightest feasible bodies of the grid, the
   continuous fields (hole radius, rim, web) are moved half a grid step towards the lighter side
   (larger holes, thinner rim and web; never beyond the grid's range), every combination, the
   hole count kept: the lightest feasible body of the grid has an infeasible (or no) lighter
   neighbour, so the limit lies within that half step. Archived as ``refine.nc`` (point layout).
   With ``--shapes`` each opening shape runs its own coarse grid (``coarse_slot.nc``,
   ``coarse_window.nc``), sized by its own field in place of the hole radius (a slot's width,
   wider is lighter; a window's spokes, narrower is lighter), and all compete for the answer;
4. ``tradeoff.png``: mass saved against STE p2p and DTE RMS over every body run, coloured by root
   stress, the Pareto set, the TE limits and the chosen body; ``lightest.txt``: the answer, also
   printed; ``candidates.csv``: every body run, its S_F, the location that limits it (root, rim or
   web: the smallest S_F), its failure mode and whether it meets the limits.

The default factors are wide because the solid paper gear's STE is small (0.33 um peak-to-peak):
every body of the default grid raises it by at least 45 % (its web, 10 mm or less of the 17 mm
face, softens every tooth), most by more than 80 %. The DTE factor is wider still: damped at 5 %
of critical on its mesh mode (the scene default), the solid gear's DTE RMS at 100 rad/s is only
0.084 um, and the holes add their own orders: every body of the grid raises it 2.5 to 10 times.

Exit codes: 0 an answer; 1 no body of the grid meets the limits (the nearest miss is printed)
or points lost to failed workers; 2 invalid options or scene fields (one line naming them).

Budget (paper pair, 2 cores): the FE maps of the bodies dominate, about 15-20 s of one core
each with the body's two runs (cached on disk in the FE cache: a second run reuses them). The
default grid is 3 x 2 x 2 x 2 = 24 bodies and the refinement at most 2 x 7 = 14: measured from an
empty cache, 460 s of CPU for the grid and 120 s for the 6 refined bodies the defaults give,
about 5 minutes on 2 quiet cores and at most some 7 with 14 refined bodies. Each body is run once for its statics (120 deg at
0.2 deg) and once for its dynamics over a short window: the ramp twice (the steady window starts
at twice the ramp time, `study.check_dynamic_window`) and then one revolution of the
driven gear, so the DTE RMS covers every tooth and hole once (0.083 s at 100 rad/s for the paper
pair, instead of the paper's 0.2 s).
"""
from __future__ import annotations

import argparse
import itertools
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

import study
from study import SceneError

DEFAULT_OUT = "results/lightest_gear"
FIELDS = {"gear2.body.holes": "n_holes", "gear2.body.hole_radius": "hole_radius",
          "gear2.body.rim_height": "rim_thickness", "gear2.body.web_thickness": "web_thickness"}
COARSE = {"gear2.body.holes": [3, 6, 9], "gear2.body.hole_radius": [5.0, 7.0],
          "gear2.body.rim_height": [5.0, 7.0], "gear2.body.web_thickness": [6.0, 10.0]}
# the other opening shapes (--shapes): the field that sizes each (in place of the hole radius)
# and its coarse values [mm]; the slot's span, the window's height and corners as the scene gives
SHAPE_SIZE = {"round": "gear2.body.hole_radius", "slot": "gear2.body.slot_width", "window": "gear2.body.spoke_width"}
SHAPE_COARSE = {"gear2.body.slot_width": [5.0, 7.0], "gear2.body.spoke_width": [16.0, 10.0]}
SIZE_NAMES = {"gear2.body.hole_radius": "hole_radius", "gear2.body.slot_width": "slot_width",
              "gear2.body.spoke_width": "spoke_width"}
OPENING = "gear2.body.opening"
# direction in which the body loses mass
LIGHTER = {"hole_radius": +1, "slot_width": +1, "spoke_width": -1, "rim_thickness": -1, "web_thickness": -1}


def fields_of(opening: str) -> dict:
    """{dotted field: table column} of a body with openings of shape ``opening``: the four of
    `FIELDS`, the hole radius replaced by the shape's size field (`SHAPE_SIZE`)."""
    size = SHAPE_SIZE[opening]
    return {(size if path == "gear2.body.hole_radius" else path): (SIZE_NAMES[size] if path == "gear2.body.hole_radius"
                                                                  else name) for path, name in FIELDS.items()}
SCALARS = ["ste_p2p", "dte_rms", "mass_gear2", "mass_saving_gear2", "inertia_gear2",
           "root_stress_max_gear2", "root_stress_ratio_gear2", "bending_safety_gear2", "bending_safety_root_gear2",
           "bending_safety_rim_gear2", "bending_safety_web_gear2", "failure_mode_gear2"]
LOCATIONS = ("root", "rim", "web")
MODES = ("tooth", "rim", "web")        # failure_mode_gear2's codes (solver.strength.FAILURE_MODES)


@dataclass(frozen=True)
class Limits:
    ste_factor: float = 2.0           # STE p2p over the solid gear's [1]
    dte_factor: float = 4.0           # DTE RMS over the solid gear's [1]
    stress_ratio: float = 1.15        # largest root stress over the solid gear's [1]
    stress_max: float = math.inf      # largest root stress [MPa]
    safety_min: float = 1.4           # smallest bending safety factor S_F at the root, rim and web [1]


# ---------------------------------------------------------------- selection (any candidate table)

def candidates(ds: xr.Dataset, base: dict | None = None) -> xr.Dataset:
    """A study archive (grid or point layout) as a table over ``candidate``: the body fields
    (variables n_holes, hole_radius, slot_width, spoke_width, rim_thickness, web_thickness and
    opening; from ``base``, {dotted field: value}, where the study does not sweep them; an
    opening 'round' and NaN sizes where neither gives them), status and the scalars (each
    broadcast over the study's points)."""
    keep = [v for v in ["status", *SCALARS] if v in ds]
    status = ds["status"]
    data = {}
    for v in keep:
        data[v] = ("candidate", ds[v].broadcast_like(status).transpose(*status.dims).values.ravel())
    columns = {**FIELDS, **SIZE_NAMES, OPENING: "opening"}
    for path, name in columns.items():
        if name in ds.coords:
            data[name] = ("candidate", ds[name].broadcast_like(status).transpose(*status.dims).values.ravel())
        else:
            default = "round" if name == "opening" else math.nan
            data[name] = ("candidate", np.full(status.size, (base or {}).get(path, default),
                                               dtype=object if name == "opening" else float))
    data["opening"] = ("candidate", data["opening"][1].astype(str))
    return xr.Dataset(data)


def feasible(table: xr.Dataset, solid: dict, limits: Limits) -> xr.DataArray:
    """True where a candidate is ok and within every limit (NaN, as a root stress no FE gave, fails)."""
    ok = table["status"] == study.STATUS.index("ok")
    ok &= table["ste_p2p"] <= limits.ste_factor * solid["ste_p2p"]
    ok &= table["dte_rms"] <= limits.dte_factor * solid["dte_rms"]
    ok &= table["root_stress_ratio_gear2"] <= limits.stress_ratio
    if math.isfinite(limits.stress_max):
        ok &= table["root_stress_max_gear2"] <= limits.stress_max
    if limits.safety_min > 0:
        ok &= table["bending_safety_gear2"] >= limits.safety_min
    return ok


def limiting_location(table: xr.Dataset) -> np.ndarray:
    """The location (root, rim, web) with the smallest S_F of each candidate ('' where none is known)."""
    sf = np.stack([table[f"bending_safety_{loc}_gear2"].values for loc in LOCATIONS], axis=1)
    known = np.isfinite(sf).any(axis=1)
    idx = np.argmin(np.where(np.isfinite(sf), sf, np.inf), axis=1)
    return np.where(known, np.array(LOCATIONS)[idx], "")


def candidate_rows(table: xr.Dataset, mask: xr.DataArray) -> str:
    """Every candidate as CSV: body, mass saved, TE, S_F and the location that limits it, failure mode, feasible."""
    where = limiting_location(table)
    lines = ["n_holes,opening,hole_radius_mm,slot_width_mm,spoke_width_mm,rim_thickness_mm,web_thickness_mm,"
             "mass_saving_pct,ste_p2p_um,dte_rms_um,"
             "root_stress_ratio,bending_safety,limiting_location,failure_mode,feasible"]
    for i in range(table.sizes["candidate"]):
        v = {k: table[k].values[i] for k in table.data_vars}
        mode = v["failure_mode_gear2"]
        lines.append(f"{int(v['n_holes'])},{v['opening']},{v['hole_radius']:g},{v['slot_width']:g},{v['spoke_width']:g},"
                     f"{v['rim_thickness']:g},{v['web_thickness']:g},"
                     f"{v['mass_saving_gear2']:.2f},{v['ste_p2p']:.4f},{v['dte_rms']:.4f},{v['root_stress_ratio_gear2']:.4f},"
                     f"{v['bending_safety_gear2']:.3f},{where[i]},{MODES[int(mode)] if np.isfinite(mode) else ''},"
                     f"{int(bool(mask.values[i]))}")
    return "\n".join(lines) + "\n"


def ranked(table: xr.Dataset, mask: xr.DataArray) -> list[int]:
    """Candidates where ``mask``, most mass saved first."""
    idx = np.flatnonzero(mask.values)
    return [int(i) for i in idx[np.argsort(-table["mass_saving_gear2"].values[idx], kind="stable")]]


def body_of(table: xr.Dataset, i: int) -> dict:
    """{dotted field: value} of candidate ``i``: the fields of its shape (`fields_of`), and its
    opening when not round."""
    opening = str(table["opening"].values[i]) if "opening" in table else "round"
    body = {path: table[name].values[i].item() for path, name in fields_of(opening).items()}
    return body if opening == "round" else {**body, OPENING: opening}


def refine_points(seeds: list[dict], grid: dict) -> list[dict]:
    """Bodies around the seeds (each {dotted field: value}): every combination of each continuous
    field at its value and half a step of ``grid`` towards the lighter side (none past the grid's
    range), the hole count kept; the seeds themselves and repeats left out."""
    out, seen = [], {tuple(sorted(s.items())) for s in seeds}
    for seed in seeds:
        levels = []
        opening = seed.get(OPENING, "round")
        fields = fields_of(opening)
        for path, name in fields.items():
            x = seed[path]
            if name not in LIGHTER:
                levels.append([x])
                continue
            vals = sorted(grid[path])
            side = [v for v in vals if (v - x) * LIGHTER[name] > 0]
            nxt = min(side, key=lambda v: abs(v - x)) if side else None
            levels.append([x] if nxt is None else [x, float(round((x + nxt) / 2, 6))])
        for combo in itertools.product(*levels):
            body = dict(zip(fields, combo))
            if opening != "round":
                body[OPENING] = opening
            key = tuple(sorted(body.items()))
            if key not in seen:
                seen.add(key)
                out.append(body)
    return out


# ---------------------------------------------------------------- the run

def base_scene(path, overrides, speed: float, duration: float | None, angle_step: float):
    scene = study.load_scene(path, overrides)
    scene = scene.replace(**{"dynamic.speed": speed, "quasi_static.angle_step": angle_step})
    if duration is None:     # two ramps, then one revolution of the driven gear
        d = scene.dynamic
        driven = speed * scene.gear1.teeth / scene.gear2.teeth            # rad/s
        duration = math.ceil(1e3 * (2 * d.ramp_time + 2 * math.pi / driven) * 1.02) / 1e3
        scene = scene.replace(**{"dynamic.duration": duration})
    else:
        scene = scene.replace(**{"dynamic.duration": duration})
    study.check_dynamic_window(scene)
    return scene


def solid_of(scene):
    """The reference: the driven gear solid, run by the model the lightened bodies run, named
    (whatever 'auto' makes of a solid pair, a factor between two models' STE would measure the
    models, not the lightening)."""
    lightened = scene.replace(**{"gear2.body.holes": max(scene.gear2.body.holes, 1)})
    return study.solid_scene(scene, gears=(2,)).replace(**{"coupling.model": lightened.coupling_model_name})


def _openings(best: dict) -> str:
    """The openings of a table row in words."""
    n, opening = int(best["n_holes"]), str(best.get("opening", "round"))
    if opening == "slot":
        return f"{n} slots {best['slot_width']:g} mm wide"
    if opening == "window":
        return f"{n} windows between spokes of {best['spoke_width']:g} mm"
    return f"{n} holes of {best['hole_radius']:g} mm radius"


def answer(best: dict, solid: dict, speed: float) -> str:
    """The one-paragraph answer for the chosen candidate ``best`` (a row of the table as a dict)."""
    ste = 100 * (best["ste_p2p"] / solid["ste_p2p"] - 1)
    dte = 100 * (best["dte_rms"] / solid["dte_rms"] - 1)
    return (f"{_openings(best)}, a {best['rim_thickness']:g} mm rim and a "
            f"{best['web_thickness']:g} mm web save {best['mass_saving_gear2']:.1f} % mass "
            f"({best['mass_gear2']:.3f} kg against {solid['mass_gear2']:.3f} kg solid; inertia "
            f"{best['inertia_gear2']:.0f} against {solid['inertia_gear2']:.0f} kg mm2) for {ste:+.1f} % STE p2p "
            f"({best['ste_p2p']:.3f} against {solid['ste_p2p']:.3f} um) and {dte:+.1f} % DTE RMS at {speed:g} rad/s "
            f"({best['dte_rms']:.3f} against {solid['dte_rms']:.3f} um), root stress {best['root_stress_max_gear2']:.1f} MPa "
            f"(x {best['root_stress_ratio_gear2']:.2f} of solid); bending safety S_F {best['bending_safety_gear2']:.2f}, "
            f"limited by the {_limit(best)}, failure mode {_mode(best)}.")


def _limit(row: dict) -> str:
    sf = [row.get(f"bending_safety_{loc}_gear2", math.nan) for loc in LOCATIONS]
    known = [(v, loc) for v, loc in zip(sf, LOCATIONS) if np.isfinite(v)]
    return min(known)[1] if known else "(unknown)"


def _mode(row: dict) -> str:
    m = row.get("failure_mode_gear2", math.nan)
    return MODES[int(m)] if np.isfinite(m) else "unknown"


def _row(table, i) -> dict:
    return {k: table[k].values[i].item() for k in table.data_vars}


def parse_grid(items: list[str]) -> dict:
    """The coarse grid: `COARSE` and the other shapes' size axes (`SHAPE_COARSE`), each axis
    replaced by a ``field=v1,v2,...`` of ``items``."""
    grid = {k: list(v) for k, v in {**COARSE, **SHAPE_COARSE}.items()}
    for item in items:
        field, _, values = item.partition("=")
        field = field.strip()
        if field not in grid:
            raise SceneError(field or "--grid", f"the grid is over {', '.join(grid)}; got {item!r}")
        if not values:
            raise SceneError(field, "a grid axis must look like field=v1,v2,...")
        grid[field] = [study.parse_overrides([f"x={v}"])["x"] for v in values.split(",")]
    return grid


def run(args) -> int:
    """The workflow for the parsed command line ``args`` (its options checked first) -> exit code."""
    check_options(args)
    limits = Limits(args.ste_factor, args.dte_factor, args.stress_ratio, args.stress_max, args.safety_min)
    scene = base_scene(args.scene, args.set, args.speed, args.duration, args.angle_step)
    grid = parse_grid(args.grid)
    shapes = parse_shapes(args.shapes)
    outputs = {"scalars": SCALARS}
    coarse = {}          # shape -> (its coarse study, archive name)
    for shape in shapes:
        fields = fields_of(shape)
        base = scene if shape == "round" else scene.replace(**{OPENING: shape})
        coarse[shape] = (study.make_study(base, grid={p: grid[p] for p in fields}, outputs=outputs,
                                          title=f"lightest driven gear: coarse grid{'' if shape == 'round' else ', ' + shape + 's'}"),
                         "coarse.nc" if shape == "round" else f"coarse_{shape}.nc")
    solid_study = study.make_study(solid_of(scene), grid={"dynamic.speed": [args.speed]}, outputs=outputs,
                                   title="lightest driven gear: the solid reference")
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    n = sum(int(np.prod(st.shape)) for st, _ in coarse.values())
    print(f"lightest driven gear at {args.speed:g} rad/s: STE p2p <= {limits.ste_factor:g} x solid, DTE RMS <= "
          f"{limits.dte_factor:g} x solid, root stress <= {limits.stress_ratio:g} x solid"
          + (f" and <= {limits.stress_max:g} MPa" if math.isfinite(limits.stress_max) else "")
          + (f", S_F >= {limits.safety_min:g} at the root, rim and web" if limits.safety_min > 0 else "")
          + f"; DTE over {scene.dynamic.duration:g} s; coarse grid {n} bodies"
          + (f" ({', '.join(shapes)})" if shapes != ["round"] else "") + f" -> {out}", flush=True)
    lost = 0
    with study.local_cluster(args.workers) as address:
        kw = {"workers": 0 if address is None else None, "scheduler": address, "progress": not args.no_progress}
        res = study.run_sweep(solid_study, out / "solid.nc", **kw)
        solid_table = candidates(res.dataset, {path: solid_study.base_value(path) for path in FIELDS})
        solid = _row(solid_table, 0)
        if res.dataset["status"].values.ravel()[0] != 1:
            raise RuntimeError(f"the solid reference did not run: {res.dataset['message'].values.ravel()[0]}")
        tables, wall = [], 0.0
        for st, name in coarse.values():
            res = study.run_sweep(st, out / name, **kw)
            lost += res.pending
            wall += res.wall_time
            tables.append(candidates(res.dataset, {p: st.base_value(p) for p in (*FIELDS, *SIZE_NAMES, OPENING)}))
        first = xr.concat(tables, "candidate")
        order = ranked(first, feasible(first, solid, limits))
        print(f"  coarse grid: {len(order)} of {n} bodies feasible ({wall:.0f} s)", flush=True)
        seeds = [body_of(first, i) for i in order[: args.refine]]
        tables = [first]
        points = refine_points(seeds, grid)
        if points:
            fine = study.make_study(scene, points=points, outputs=outputs, title="lightest driven gear: refinement")
            res = study.run_sweep(fine, out / "refine.nc", **kw)
            lost += res.pending
            tables.append(candidates(res.dataset))
            print(f"  refinement: {len(points)} bodies around {len(seeds)} ({res.wall_time:.0f} s)", flush=True)
    table = xr.concat(tables, "candidate")
    mask = feasible(table, solid, limits)
    order = ranked(table, mask)
    figure = tradeoff(table, solid_table, limits, order[0] if order else None, out / "tradeoff.png",
                      f"lightest driven-gear body at {args.speed:g} rad/s (bodies varied from the scene: {scene.title})")
    if order:
        text = answer(_row(table, order[0]), solid, args.speed)
    else:
        ok = np.flatnonzero(table["status"].values == study.STATUS.index("ok"))
        worst = np.fmax(table["ste_p2p"].values[ok] / solid["ste_p2p"] / limits.ste_factor,
                        table["dte_rms"].values[ok] / solid["dte_rms"] / limits.dte_factor)
        near = ok[int(np.nanargmin(worst))] if ok.size else None
        text = "No body of the grid meets the limits." + (
            f" The nearest miss: {answer(_row(table, near), solid, args.speed)}" if near is not None else "")
    (out / "lightest.txt").write_text(text + "\n")
    (out / "candidates.csv").write_text(candidate_rows(table, mask))
    where = limiting_location(table)
    print("  S_F limited by: " + ", ".join(f"{loc} {int((where == loc).sum())}" for loc in LOCATIONS)
          + f" of {table.sizes['candidate']} bodies (each in candidates.csv)")
    print(f"\n{text}\n  figure: {figure}")
    if lost:
        print(f"  {lost} analyses lost (worker failures): run the same command again", file=sys.stderr)
    return 0 if order and not lost else 1


def tradeoff(table: xr.Dataset, solid_table: xr.Dataset, limits: Limits, chosen: int | None, path, title: str):
    """Mass saving against STE p2p and DTE RMS of every body run and of the solid gear
    (`study_views.tradeoff_figure`), with the TE limits and the chosen body marked."""
    meta = {name: (unit, doc) for name, _kind, unit, _analysis, doc in study.outputs()}
    ds = xr.concat([table, solid_table], "candidate")
    ds = ds.assign_coords(candidate=np.arange(ds.sizes["candidate"])).assign_attrs(title=title)
    for k in SCALARS:
        ds[k].attrs.update(units=meta[k][0], long_name=meta[k][1])
    solid = _row(solid_table, 0)
    pareto = study.pareto(ds, limits.stress_ratio)
    te_limits = {"ste_p2p": limits.ste_factor * solid["ste_p2p"], "dte_rms": limits.dte_factor * solid["dte_rms"]}
    return study.tradeoff_figure(ds, pareto, path, te_limits=te_limits, chosen=chosen)


def parse_shapes(text: str) -> list[str]:
    """``'round,slot'`` -> ['round', 'slot']; SceneError naming --shapes for an unknown shape."""
    shapes = [x.strip() for x in text.split(",") if x.strip()]
    bad = [x for x in shapes if x not in SHAPE_SIZE]
    if not shapes or bad:
        raise SceneError("--shapes", f"a comma-separated list of {', '.join(SHAPE_SIZE)}; got {text!r}")
    return list(dict.fromkeys(shapes))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", default=None, help="scene TOML (default: the paper example)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a scene field")
    p.add_argument("--ste-factor", type=float, default=Limits.ste_factor, help="STE p2p limit over the solid gear's [1]")
    p.add_argument("--dte-factor", type=float, default=Limits.dte_factor, help="DTE RMS limit over the solid gear's [1]")
    p.add_argument("--stress-ratio", type=float, default=Limits.stress_ratio,
                   help="root stress limit over the solid gear's [1]")
    p.add_argument("--stress-max", type=float, default=math.inf, help="root stress limit [MPa] (default: none)")
    p.add_argument("--safety-min", type=float, default=Limits.safety_min,
                   help="smallest bending safety factor S_F at the root, rim and web [1] (0: no limit)")
    p.add_argument("--speed", type=float, default=100.0, help="driver speed of the DTE [rad/s]")
    p.add_argument("--duration", type=float, default=None,
                   help="DTE run [s] (default: twice the ramp, then one revolution of the driven gear)")
    p.add_argument("--angle-step", type=float, default=0.2, help="STE driver angle step [deg]")
    p.add_argument("--grid", action="append", default=[], metavar="FIELD=V1,V2",
                   help="replace a coarse grid axis (gear2.body.holes, hole_radius, rim_height, web_thickness; "
                        "slot_width, spoke_width with --shapes)")
    p.add_argument("--shapes", default="round", help="opening shapes searched, comma-separated: round, slot, "
                   "window (each its own coarse grid, its size field in place of the hole radius)")
    p.add_argument("--refine", type=int, default=2, help="lightest feasible bodies refined around (0: none)")
    p.add_argument("-o", "--output", default=DEFAULT_OUT, help="output folder (archives, figure, answer)")
    p.add_argument("--workers", type=int, default=None, help="LocalCluster workers (default: one per core; 0: in process)")
    p.add_argument("--no-progress", action="store_true")
    args = p.parse_args(argv)
    try:
        return run(args)
    except SceneError as e:
        print(f"error: {e.field}: {e.reason}", file=sys.stderr)    # one line, no traceback
        return 2


def check_options(args) -> None:
    """SceneError naming the option whose value cannot be used, before any work."""
    for name in ("ste_factor", "dte_factor", "stress_ratio", "stress_max", "speed", "angle_step"):
        v = getattr(args, name)
        if not v > 0:
            raise SceneError(f"--{name.replace('_', '-')}", f"must be positive, got {v:g}")
    if args.duration is not None and not args.duration > 0:
        raise SceneError("--duration", f"must be positive, got {args.duration:g}")
    if not args.safety_min >= 0:
        raise SceneError("--safety-min", f"must be >= 0 (0: no limit), got {args.safety_min:g}")
    if args.refine < 0:
        raise SceneError("--refine", f"must be >= 0, got {args.refine}")
    if args.workers is not None and args.workers < 0:
        raise SceneError("--workers", f"must be >= 0 (0 runs in this process), got {args.workers}")
    if Path(args.output).is_file():
        raise SceneError("--output", f"{args.output} is a file, not a folder")


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.lightest_gear", main))

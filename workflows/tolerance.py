"""What a driver's tolerance class does to the transmission error, in one paragraph.

    python -m workflows.tolerance [STUDY.toml] [--size N] [--set key=value ...] [--answer dte_rms ...]
        [--limit dte_rms=0.5] [-o results/tolerance] [--workers N]

Runs a sampled study (default `study/scenes/tolerance.toml`: the lightened paper pair with tip
reliefs, driver of ISO 1328-1 class 5 against class 7, a new pitch set, a runout and both
reliefs drawn in every build, the Saltelli design) with `study.run_sweep` on dask, renders it
(`lightgear render`: distributions, convergence, Sobol indices; ``study_tables.nc``) and prints
the answer, also written to ``tolerance.txt``: per grid point the P95 of the output with its
95 % interval and which drawn field explains how much of its variance ("class 7 raises P95 DTE
RMS from X to Y um; runout explains Z % of its variance").

``--size`` replaces the number of draws a grid point (the Saltelli design runs size x (d + 2)
builds), ``--set`` overrides a field of the study's base scene (a shorter DTE, say:
``--set dynamic.duration=0.1``): a reduced variant for a first look. A second run of the same
study reuses its archive; an interrupted one computes only the missing builds.

Exit codes: 0 an answer; 1 builds lost to failed workers (run again); 2 invalid options or
study fields (one line naming them).
"""
from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import numpy as np
import xarray as xr

import study

DEFAULT_STUDY = Path(__file__).resolve().parents[1] / "study" / "scenes" / "tolerance.toml"
DEFAULT_OUT = "results/tolerance"
DEFAULT_LIMIT = "dte_rms=0.5"           # um
DEFAULT_ANSWER = ("dte_rms", "amp_mesh_order")
# the drawn fields in a gear engineer's words
WORDS = {
    "gear1.errors.seed": "the driver's pitch deviations",
    "gear2.errors.seed": "the driven gear's pitch deviations",
    "gear1.errors.eccentricity": "the driver's runout",
    "gear2.errors.eccentricity": "the driven gear's runout",
    "gear1.errors.eccentricity_phase": "the driver's runout direction",
    "gear2.errors.eccentricity_phase": "the driven gear's runout direction",
    "gear1.modification.tip_relief": "the driver's tip relief",
    "gear2.modification.tip_relief": "the driven gear's tip relief",
}


GRID_WORDS = {"gear1.errors.grade": "driver class {}", "gear2.errors.grade": "driven gear class {}"}


def grid_label(ds: xr.Dataset, at: dict) -> str:
    """'driver class 5' for a grid point of the grade, else 'field = value'."""
    words = []
    for d, i in at.items():
        field = ds[d].attrs.get("scene_field", d) if d in ds.coords else d
        value = ds[d].values[i] if d in ds.coords else i
        words.append(GRID_WORDS[field].format(value) if field in GRID_WORDS else study.sample_point_label(ds, {d: i}))
    return ", ".join(words) or "all builds"


def reduced_study(path: Path, size: int | None, overrides: list[str]) -> study.Study:
    """The study at ``path`` with ``size`` draws (when given) and scene overrides."""
    text = path.read_text()
    if size is None and not overrides:
        return study.load_study(path)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise study.SceneError("study", f"{path} is not valid TOML: {e}") from None
    if size is not None:
        if "sample" not in raw:
            raise study.SceneError("--size", f"{path} has no [sample] table")
        raw["sample"]["size"] = size
    if overrides:
        scene = raw.get("scene")
        table = dict(scene) if isinstance(scene, dict) else ({"file": scene} if scene else {})
        if isinstance(table.get("file"), str) and not Path(table["file"]).is_absolute():
            table["file"] = str(path.parent / table["file"])
        table.update(study.parse_overrides(overrides))
        raw["scene"] = table
    return study.study_from_dict(raw, path.parent)


def _pct(tab: xr.Dataset, out: str, at: dict, q: float = 0.95) -> tuple[float, float, float]:
    v = tab["sample_percentile"].isel(at).sel(output=out, quantile=q)
    return tuple(float(v.sel(bound=b)) for b in ("estimate", "low", "high"))


def _bounded(p: tuple[float, float, float]) -> str:
    """'7.31 [6.51, 7.55]', or the estimate alone where the sample cannot bound it."""
    return f"{p[0]:.3g} [{p[1]:.3g}, {p[2]:.3g}]" if np.isfinite(p[1:]).all() else f"{p[0]:.3g}"


def answer(ds: xr.Dataset, tab: xr.Dataset, out: str, limits: dict) -> str:
    """The one-paragraph answer from a sampled study's archive and tables."""
    unit = ds[out].attrs.get("units", "")
    points = study.sample_points(ds)
    labels = [grid_label(ds, at) for at in points]
    p95 = [_pct(tab, out, at) for at in points]
    p50 = [_pct(tab, out, at, 0.5) for at in points]
    parts = []
    if len(points) >= 2:
        change = "raises" if p95[-1][0] > p95[0][0] else "lowers"
        parts.append(f"Going from {labels[0]} to {labels[-1]} {change} the P95 of {out} from "
                     f"{_bounded(p95[0])} to {_bounded(p95[-1])} {unit} (median {p50[0][0]:.3g} -> {p50[-1][0]:.3g} {unit})")
        for lab, p in zip(labels[1:-1], p95[1:-1]):
            parts.append(f"{lab}: P95 {_bounded(p)} {unit}")
    else:
        parts.append(f"The P95 of {out} is {_bounded(p95[0])} {unit} (median {p50[0][0]:.3g} {unit})")
    if not all(np.isfinite(p[1:]).all() for p in p95):
        need = int(tab["sample_percentile"].attrs["min_independent_builds"][list(tab["quantile"].values).index(0.95)])
        parts.append(f"No 95 % interval bounds these P95s: {tab.attrs['independent_builds']} independent builds a "
                     f"grid point are fewer than the {need} it takes (a larger --size gives one)")
    if out in limits and "exceedance_probability" in tab:
        probs = [[tab["exceedance_probability"].isel(at).sel(limit=out, bound=b).item() for b in ("estimate", "low", "high")]
                 for at in points]
        parts.append(f"the share of builds whose {out} exceeds {limits[out]:g} {unit} is " + ", ".join(
            f"{100 * p:.1f} % [{100 * lo:.1f}, {100 * hi:.1f}] at {lab}"
            for (p, lo, hi), lab in zip(probs, labels)))
    if "sobol_total" in tab:
        for at, lab in zip(points, labels):
            s1 = tab["sobol_first"].isel(at).sel(output=out)
            st = tab["sobol_total"].isel(at).sel(output=out)
            order = np.argsort(-np.nan_to_num(st.sel(bound="estimate").values, nan=-1))
            if not np.isfinite(st.sel(bound="estimate").values).any():
                parts.append(f"no Sobol indices of {out} at {lab}: fewer than 4 rows of the design have every build ok")
                continue
            words = []
            for i in order[:3]:
                f = str(tab["field"].values[i])
                # shares in words: the estimators can stray below 0 or above 1 by their sampling
                # error; the tables keep the raw values
                e1, e1l, e1h = (min(max(float(s1.isel(field=i).sel(bound=b)), 0.0), 1.0)
                                for b in ("estimate", "low", "high"))
                et = min(max(float(st.isel(field=i).sel(bound="estimate")), 0.0), 1.0)
                words.append(f"{WORDS.get(f, f)} {100 * e1:.0f} % alone ({100 * e1l:.0f} to {100 * e1h:.0f} %), "
                             f"{100 * et:.0f} % with its interactions")
            parts.append(f"of the variance of {out} at {lab}: " + "; ".join(words))
    return ". ".join(p[0].upper() + p[1:] for p in parts) + "."


def cost(ds: xr.Dataset) -> str:
    """'N of M builds ok, T s of compute (t s a build)'."""
    n = int(ds["status"].size)
    ok = int((ds["status"] == study.STATUS.index("ok")).sum())
    compute = float(ds["wall_time"].sum())
    return f"{ok} of {n} builds ok, {compute:.0f} s of compute ({compute / n:.2f} s a build)."


def run(args) -> int:
    """The workflow for the parsed command line ``args`` (its options checked first) -> exit code."""
    check_options(args)
    st = reduced_study(Path(args.study), args.size, args.set)
    limits = {}
    for item in args.limit or [DEFAULT_LIMIT]:
        key, _, value = item.partition("=")
        try:
            limits[key] = float(value)
        except ValueError:
            raise study.SceneError("--limit", f"expected OUTPUT=VALUE, got {item!r}") from None
    outdir = Path(args.output_dir)
    outdir.mkdir(parents=True, exist_ok=True)
    archive = outdir / "tolerance.nc"
    print(f"{st.title}: {int(np.prod(st.shape))} builds ({st.sample.describe()}) -> {archive}", flush=True)
    res = study.run_sweep(st, archive, workers=args.workers, progress=not args.no_progress)
    print(f"  {res.computed} analyses computed, {res.reused} reused (a build's statics and its dynamics are two), "
          f"{res.wall_time:.0f} s wall", flush=True)
    ds = res.dataset
    outputs = study.sample_outputs(ds)
    answers = [o for o in (args.answer or DEFAULT_ANSWER) if o in outputs] or outputs[:1]
    if not args.limit and DEFAULT_LIMIT.split("=")[0] not in outputs:
        limits = {}             # the default limit, on an output this study does not have
    for k in limits:
        if k not in outputs:
            raise study.SceneError("--limit", f"{k!r} is not an output of the study ({', '.join(outputs)})")
    study.render(ds, outdir, limits=limits)
    tab = study.sample_tables(ds, outputs, limits)
    text = "\n\n".join([*(answer(ds, tab, out, limits) for out in answers), cost(ds)])
    (outdir / "tolerance.txt").write_text(text + "\n")
    print("\n" + text)
    return 1 if res.pending else 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("study", nargs="?", default=str(DEFAULT_STUDY), help="sampled study TOML (default: tolerance.toml)")
    p.add_argument("--size", type=int, default=None, help="draws a grid point (replaces [sample] size)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a base-scene field")
    p.add_argument("--answer", action="append", default=[], metavar="OUTPUT",
                   help=f"an output the answer is about, repeatable (default {', '.join(DEFAULT_ANSWER)}; "
                        "else the study's first)")
    p.add_argument("--limit", action="append", default=[], metavar="OUTPUT=VALUE",
                   help=f"probability of exceeding a limit, repeatable (default {DEFAULT_LIMIT} um)")
    p.add_argument("-o", "--output-dir", default=DEFAULT_OUT, help="output folder (archive, figures, answer)")
    p.add_argument("--workers", type=int, default=None, help="LocalCluster workers (default: one per core; 0: in process)")
    p.add_argument("--no-progress", action="store_true")
    args = p.parse_args(argv)
    try:
        return run(args)
    except study.SceneError as e:
        print(f"error: {e.field}: {e.reason}", file=sys.stderr)    # one line, no traceback
        return 2


def check_options(args) -> None:
    """SceneError naming the option whose value cannot be used, before any work."""
    if args.size is not None and args.size < 2:
        raise study.SceneError("--size", f"must be at least 2, got {args.size}")
    if args.workers is not None and args.workers < 0:
        raise study.SceneError("--workers", f"must be >= 0 (0 runs in this process), got {args.workers}")
    if Path(args.output_dir).is_file():
        raise study.SceneError("-o", f"{args.output_dir} is a file, not a folder")
    if not Path(args.study).is_file():
        raise study.SceneError("study", f"no such file: {args.study}")


if __name__ == "__main__":
    raise SystemExit(study.script_main("python -m workflows.tolerance", main))

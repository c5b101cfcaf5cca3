"""Validation table against the independent FE contact peer (CalculiX): the default (compliance)
model, the paper model and the project's own reference (LTCA, with its tip corners under the
flanks' law and, 'fe-reference-edge', rounded to the peer's equivalent edge radius) against the
peer's elastic STE.

Cases (gear 2's body; gear 1 as the scene gives it):
  solid      study/scenes/paper_solid.toml
  paper      the paper pair: 6 holes of 6 mm in a 10 mm web (study/scenes/paper.toml)
  holes3     3 holes of 9 mm on the paper's hole circle, 10 mm web
  holes12    12 holes of 3.5 mm, 10 mm web
  thin_rim   the paper pair with a 2.5 mm rim (the web takes up the rest)
  relief     the paper pair with its 2 um linear long tip relief (study/scenes/paper_relief.toml)
at 25, 50 and 100 N·m, at driver angles over one mesh period (5.373 deg for the 67-tooth
driver). Each case writes its peer archive (`lightgear reference --solver calculix`) under
results/benchmarks/calculix/ and is reused when it is there, so the table grows run by run;
figures: elastic mean STE and STE peak-to-peak of each model against the peer [%].

With --tip-edge-radius MM both gears' tip corners are rounded to that radius
(``gearN.modification.tip_edge_radius``): the peer meshes the round, the default model and the
LTCA take its compliance on their tip-corner contacts (the paper model refuses the key: its
column is left empty), and the LTCA at the peer's equivalent sharp-corner radius is left out.

Run:  .venv/bin/python benchmarks/bench_calculix.py [--cases solid,paper] [--torques 50]
      [--angles 0,1.34,4.0] [--flank-size MM] [--tip-edge-radius MM] [--quick]
Prints the table and writes results/benchmarks/calculix.csv. A deck of the paper pair at the
default mesh (0.05 mm at the flanks, ~140k nodes) takes 200-250 s of one core.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.common import OUT, machine_line, write_table  # noqa: E402

CASES = {
    "solid": ("paper_solid", {}),
    "paper": ("paper", {}),
    "holes3": ("paper", {"gear2.body.holes": 3, "gear2.body.hole_radius": 9.0}),
    "holes12": ("paper", {"gear2.body.holes": 12, "gear2.body.hole_radius": 3.5}),
    "thin_rim": ("paper", {"gear2.body.rim_height": 2.5, "gear2.body.web_height": 23.25 + 6.075 - 2.5}),
    "relief": ("paper_relief", {}),
}
MODELS = ("compliance", "paper", "fe-reference", "fe-reference-edge")
# one mesh period of the 67-tooth driver, the single-pair peak (~4.0 deg) and the double-pair
# minimum (~1.3 deg) included
DEFAULT_ANGLES = (0.0, 0.67, 1.34, 2.01, 2.69, 3.36, 3.8, 4.0, 4.1, 4.7)


def case_scene(name: str, torque: float, edge: float = 0.0):
    """The case's scene under ``torque`` [N·m], both gears' tip edges rounded to ``edge`` [mm]."""
    import study
    base, over = CASES[name]
    if edge:
        over = {**over, "gear1.modification.tip_edge_radius": edge, "gear2.modification.tip_edge_radius": edge}
    return study.load_scene(base).replace(**{**over, "quasi_static.torque": torque})


def peer(name: str, torque: float, angles_deg, flank_size: float | None, log, thin: bool = False,
         edge: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(angles [deg], elastic STE [um]) of the peer, from its archive when it is there; ``thin``:
    decks as thin as the flank elements (plane stress, a separate archive); ``edge``: the tip
    edge radius [mm] (a separate archive)."""
    import xarray as xr

    import study
    from study.verify.calculix_reference import calculix_dataset, settings_for
    tag = (f"{name}_{torque:g}Nm_{'default' if flank_size is None else f'{flank_size:g}mm'}{'_thin' if thin else ''}"
           f"{f'_edge{edge:g}mm' if edge else ''}")
    path = OUT / "calculix" / f"{tag}.nc"
    done = {}
    if path.exists():
        with xr.open_dataset(path) as old:
            done = dict(zip(np.round(old["angle"].values, 6), old["ste"].values - old.attrs["backlash_offset_um"]))
    todo = [a for a in angles_deg if round(a, 6) not in done]
    if todo:
        scene = case_scene(name, torque, edge)
        # each deck starts from the default model's approach: fewer Newton iterations, same result
        from study.verify.model_validation import model_ste
        te, off = model_ste(scene, "compliance", np.radians(todo))
        ds = calculix_dataset(scene, np.radians(todo), settings_for(scene, flank_size, thin_decks=thin), progress=True, starts=te - off)
        for a, s in zip(ds["angle"].values, ds["ste"].values - ds.attrs["backlash_offset_um"]):
            done[round(float(a), 6)] = float(s)
        merged = ds
        if path.exists():           # the archive as it is now (another process may have added decks)
            with xr.open_dataset(path) as old:
                old = old.load()
            for a, s in zip(np.round(old["angle"].values, 6), old["ste"].values - old.attrs["backlash_offset_um"]):
                done.setdefault(a, float(s))
            # the new decks, and the archive's others with their own deck times
            merged = ds.combine_first(old)
        path.parent.mkdir(parents=True, exist_ok=True)
        study.write(merged, path)
        log(f"{tag}: {len(todo)} decks, ccx CPU {ds.attrs['cpu_time_ccx_s']:.0f} s")
    a = np.array([x for x in sorted(done) if any(abs(x - y) < 1e-6 for y in angles_deg)])
    return a, np.array([done[x] for x in a])


def models(name: str, torque: float, angles_deg, edge: float = 0.0) -> dict:
    """{model: elastic STE [um]} at the angles (NaN where a model refuses the scene: the paper
    model and a tip edge)."""
    from solver import units
    from study import SceneError
    from study.verify.model_validation import model_ste
    scene = case_scene(name, torque, edge)
    out = {}
    for m in MODELS:
        if m == "fe-reference-edge" and edge:
            continue            # the scene's own edge is in the LTCA's column
        if m == "fe-reference-edge":
            # the LTCA with its tip corners rounded to the radius at which they read like the
            # peer's sharp corners (study.verify.calculix_reference.PEER_TIP_EDGE_RADIUS_MM)
            from study.verify.calculix_reference import PEER_TIP_EDGE_RADIUS_MM
            from study.verify.fe_reference import reference
            res, _, _ = reference(scene, np.radians(angles_deg), tip_edge_radius=PEER_TIP_EDGE_RADIUS_MM * units.MM)
            te, off = res.te, res.backlash_offset
        else:
            try:
                te, off = model_ste(scene, m, np.radians(angles_deg))
            except SceneError:
                if m != "paper" or not edge:
                    raise
                te, off = np.full(len(angles_deg), np.nan), 0.0
        out[m] = (te - off) * units.UM_PER_M
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", default="solid,paper", help=f"comma-separated, of {', '.join(CASES)}")
    p.add_argument("--torques", default="50", help="N·m, comma-separated (the table: 25,50,100)")
    p.add_argument("--angles", default=",".join(f"{a:g}" for a in DEFAULT_ANGLES), help="driver angles [deg]")
    p.add_argument("--flank-size", type=float, default=None, metavar="MM", help="peer mesh at the flanks (default module/30)")
    p.add_argument("--thin-decks", action="store_true", help="peer decks as thin as their flank elements (plane stress)")
    p.add_argument("--tip-edge-radius", type=float, default=0.0, metavar="MM",
                   help="both gears' tip edges rounded to this radius (scene key gearN.modification.tip_edge_radius)")
    p.add_argument("--quick", action="store_true", help="the solid pair at 50 N·m, 0 and 4 deg, 0.1 mm at the flanks")
    args = p.parse_args(argv)
    if args.quick:
        args.cases, args.torques, args.angles, args.flank_size = "solid", "50", "0,4.0", args.flank_size or 0.1
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    for c in cases:
        if c not in CASES:
            p.error(f"--cases: unknown case {c!r} (one of {', '.join(CASES)})")
    torques = [float(t) for t in args.torques.split(",")]
    angles = [float(a) for a in args.angles.split(",")]

    def log(line):
        print(line, file=sys.stderr, flush=True)
    rows = []
    t0 = time.perf_counter()
    for c in cases:
        for t in torques:
            a, ste_peer = peer(c, t, angles, args.flank_size, log, args.thin_decks, args.tip_edge_radius)
            ms = models(c, t, a, args.tip_edge_radius)
            row = {"case": c, "torque_Nm": t, "tip_edge_radius_mm": args.tip_edge_radius, "angles": len(a),
                   "peer_mean_um": ste_peer.mean(), "peer_p2p_um": np.ptp(ste_peer)}
            for m, ste in ms.items():
                row[f"{m}_mean_err_pct"] = 100 * (ste.mean() / ste_peer.mean() - 1)
                row[f"{m}_p2p_err_pct"] = 100 * (np.ptp(ste) / np.ptp(ste_peer) - 1) if np.ptp(ste_peer) > 0 else np.nan
            rows.append(row)
            log(f"{c} {t:g} N m: peer mean {row['peer_mean_um']:.3f} um, p2p {row['peer_p2p_um']:.3f} um; " + ", ".join(
                f"{m} {row[f'{m}_mean_err_pct']:+.1f} % / {row[f'{m}_p2p_err_pct']:+.1f} %" for m in ms))
            for i, x in enumerate(a):
                log(f"  {x:g} deg: peer {ste_peer[i]:.4f} um; " + ", ".join(f"{m} {ste[i]:.4f}" for m, ste in ms.items()))
    path = write_table("calculix", f"Models against the CalculiX peer (elastic STE; {machine_line()})", rows,
                       columns=list(rows[0]))
    print(f"{time.perf_counter() - t0:.0f} s; table -> {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""What a study point can compute and archive, declared once: scalar and curve outputs, the
selection a study makes (`Outputs`), and the status flags of a point.

A scalar is one number per point (the names of `study.archive.summary.summarize`), with its
units and long name; a curve is a run-archive variable over its own axis, archived with the
units and long name the run archive gives it (`study.archive.schema`). Each output needs one
analysis: 'static' (quasi-static STE), 'dynamic' (DTE run), 'modes' (the pair linearised at the mean
load: a few static solves, no time integration), 'geometry' (mass properties, no solve) or 'fe' (the
FE body of the springs: root stress, NaN for a gear whose springs need no FE).

The per-gear outputs of the run archive (`study.archive.lightening`) are scalars named
``{variable}_gear{g}``: ``mass_gear2`` is ``mass.sel(gear=2)``.

`ANALYSIS_FIELDS` says which scene fields (dotted paths) each analysis reads; it is the one
place that rule lives. A sweep runs an analysis once per combination of the swept fields it
reads and archives its outputs over those dimensions only (an STE is not stored over the speed).
"""
from __future__ import annotations

import difflib
from dataclasses import dataclass

from solver.mbs.kernels.status import POINT_STATUS
from study.scene import SceneError


@dataclass(frozen=True)
class Scalar:
    units: str
    long_name: str
    analysis: str        # 'static', 'dynamic', 'modes', 'geometry' or 'fe'


@dataclass(frozen=True)
class Curve:
    axis: str            # dimension of the curve in the run archive
    analysis: str        # 'static' or 'dynamic'
    comment: str = ""    # added to the archived variable's attributes when given


SCALARS = {
    "ste_mean": Scalar("um", "mean static transmission error", "static"),
    "ste_elastic_mean": Scalar("um", "mean static transmission error less the rigid backlash offset", "static"),
    "ste_p2p": Scalar("um", "peak-to-peak static transmission error", "static"),
    "mesh_stiffness_mean": Scalar("N um-1", "mean tangent mesh stiffness of the pair along the line of action over the "
                                            "STE, the bodies' wind-up from the bore included", "static"),
    "mesh_stiffness_p2p": Scalar("N um-1", "peak-to-peak of the tangent mesh stiffness of the pair over the STE", "static"),
    "c_prime": Scalar("N mm-1 um-1", "single stiffness c' of a tooth pair per face width (largest over the STE), the "
                                     "bodies' wind-up from the bore included", "static"),
    "c_gamma_alpha": Scalar("N mm-1 um-1", "mesh stiffness c_gamma_alpha per face width (mean over the STE), the bodies' "
                                           "wind-up from the bore included", "static"),
    "mesh_stiffness_mesh_mean": Scalar("N um-1", "mean tangent stiffness of the mesh alone (the bodies' wind-up from the "
                                                 "bore taken out) over the STE", "static"),
    "c_prime_mesh": Scalar("N mm-1 um-1", "single stiffness c' of a tooth pair per face width of the mesh alone (the "
                                          "bodies' wind-up from the bore taken out)", "static"),
    "c_gamma_alpha_mesh": Scalar("N mm-1 um-1", "mesh stiffness c_gamma_alpha per face width of the mesh alone (the "
                                                "bodies' wind-up from the bore taken out)", "static"),
    "c_prime_iso6336": Scalar("N mm-1 um-1", "single stiffness c' by ISO 6336-1 Method B with its low-load factor", "static"),
    "c_gamma_alpha_iso6336": Scalar("N mm-1 um-1", "mesh stiffness c_gamma_alpha by ISO 6336-1 Method B with its "
                                                   "low-load factor", "static"),
    "loaded_contact_ratio": Scalar("1", "loaded contact ratio: mean number of loaded tooth pairs in the STE", "static"),
    "dte_mean": Scalar("um", "mean dynamic transmission error after the ramp", "dynamic"),
    "dte_rms": Scalar("um", "RMS of the dynamic transmission error about its mean after the ramp (NaN when that "
                            "covers less than a mesh period)", "dynamic"),
    "dte_p2p": Scalar("um", "peak-to-peak dynamic transmission error after the ramp (NaN when that covers less "
                            "than a mesh period)", "dynamic"),
    "amp_mesh_order": Scalar("um", "DTE amplitude at the mesh order Z2", "dynamic"),
    "amp_mesh2_order": Scalar("um", "DTE amplitude at twice the mesh order", "dynamic"),
    "amp_mesh3_order": Scalar("um", "DTE amplitude at three times the mesh order", "dynamic"),
    "amp_hole_order": Scalar("um", "DTE amplitude at the hole order N (NaN for a gear without holes)", "dynamic"),
    "tooth_force_max": Scalar("N", "largest tooth contact force of the dynamic run after the ramp", "dynamic"),
    "dynamic_factor": Scalar("1", "dynamic factor K_v: largest dynamic tooth force after the ramp over the largest "
                                  "static one at the same torque (NaN, its reason in the run archive, without a load, "
                                  "at standstill or over less than a mesh period before any load change)", "dynamic"),
    "mesh_efficiency": Scalar("1", "work out over work in of the dynamic run after the ramp (NaN without flank "
                                   "friction, a run-up or a load change)", "dynamic"),
    "mesh_mode_frequency": Scalar("Hz", "natural frequency of the mesh mode at the mean load (mean over the mesh period)", "modes"),
    "mesh_mode_damping": Scalar("1", "damping ratio of the mesh mode (modal, mean over the mesh period)", "modes"),
    "mesh_mode_damping_decay": Scalar("1", "damping ratio of the mesh mode from its simulated free decay", "dynamic"),
    "critical_speed_z": Scalar("rad/s", "driver speed at which the mesh order Z meets the mesh mode", "modes"),
    "critical_speed_2z": Scalar("rad/s", "driver speed at which twice the mesh order meets the mesh mode", "modes"),
    "critical_speed_3z": Scalar("rad/s", "driver speed at which three times the mesh order meets the mesh mode", "modes"),
}
for _g, _which in ((1, "driver"), (2, "driven gear")):
    SCALARS.update({
        f"mass_gear{_g}": Scalar("kg", f"mass of the {_which} (body and teeth)", "geometry"),
        f"mass_saving_gear{_g}": Scalar("%", f"mass of the {_which} saved against the same gear solid", "geometry"),
        f"inertia_gear{_g}": Scalar("kg mm2", f"polar moment of inertia of the {_which} about its axis", "geometry"),
        f"root_stress_max_gear{_g}": Scalar("MPa", f"largest fillet stress of the {_which}'s teeth (FE; NaN when its "
                                                   "springs need no FE)", "fe"),
        f"root_stress_ratio_gear{_g}": Scalar("1", f"largest fillet stress of the {_which} relative to the same gear solid "
                                                   "(FE; NaN when its springs need no FE)", "fe"),
    })
# the strength of each gear under the STE's contact forces (`study.archive.strength`; static: no K_v in a
# study): asked for by name, not among the default outputs (each body's strength costs its FE solves)
STRENGTH_SCALARS = ()
for _g, _which in ((1, "driver"), (2, "driven gear")):
    _s = {
        f"web_stress_max_gear{_g}": Scalar("MPa", f"largest tensile stress at the {_which}'s web openings and ligaments "
                                                  "under the STE's contact forces (FE; NaN without openings)", "static"),
        f"rim_stress_max_gear{_g}": Scalar("MPa", f"largest tensile stress in the inner half of the {_which}'s rim under "
                                                  "the STE's contact forces (FE)", "static"),
        f"bending_stress_root_gear{_g}": Scalar("MPa", f"largest tensile stress at the {_which}'s tooth roots under the "
                                                       "STE's contact forces (FE)", "static"),
        f"backup_ratio_gear{_g}": Scalar("1", f"backup ratio m_B = s_R/h_t of the {_which}", "static"),
        f"rim_thickness_factor_iso6336_gear{_g}": Scalar("1", f"rim thickness factor Y_B (ISO 6336-3; AGMA K_B) of the "
                                                              f"{_which}", "static"),
        f"root_stress_hpstc_gear{_g}": Scalar("MPa", f"FE root stress of the {_which}, one tooth loaded by T/rb at the "
                                                     "HPSTC", "static"),
        f"root_stress_iso6336_gear{_g}": Scalar("MPa", f"ISO 6336-3 nominal root stress sigma_F0 of the {_which} at the "
                                                       "HPSTC, Y_B included", "static"),
        f"failure_mode_gear{_g}": Scalar("1", f"where the {_which}'s first crack is expected: 0 tooth, 1 rim, 2 web", "static"),
        f"bending_safety_gear{_g}": Scalar("1", f"smallest bending safety factor S_F of the {_which} (root, rim, web; "
                                                "static loads)", "static"),
        **{f"bending_safety_{_loc}_gear{_g}": Scalar("1", f"bending safety factor S_F of the {_which} at the {_loc} "
                                                          "(static loads)", "static") for _loc in ("root", "rim", "web")},
    }
    SCALARS.update(_s)
    STRENGTH_SCALARS += tuple(_s)
# the outputs of the linearised mesh and the tooth loads (the run's 'mesh' stage, `stages_of`):
# a study that asks for none of them skips that part
MESH_SCALARS = ("mesh_stiffness", "mesh_stiffness_mean", "mesh_stiffness_p2p", "c_prime", "c_gamma_alpha",
                "mesh_stiffness_mesh_mean", "c_prime_mesh", "c_gamma_alpha_mesh", "c_prime_iso6336",
                "c_gamma_alpha_iso6336", "loaded_contact_ratio", "dynamic_factor")
# GEAR_VARIABLES (`study.archive.schema`): the per-gear archive variables a study archives as *_gear{g}

CURVES = {
    "ste": Curve("angle", "static"),
    "mesh_stiffness": Curve("angle", "static"),
    "dte": Curve("time", "dynamic"),
    "dte_amplitude": Curve("frequency", "dynamic",
                           "order of the driven gear's rotation = frequency / (speed * Z1 / Z2 / (2 pi)); "
                           "spectrum of DTE after the ramp"),
}

# Scene fields each analysis reads: (prefixes read, prefixes not read); a prefix is a dotted path
# that covers itself and every field under it, '' covers every field; the longest prefix that
# covers a field decides. The sets nest: geometry < fe < static < modes < dynamic.
#   geometry  mass and inertia: the gears' teeth and bodies, the backlash that thins the teeth, the
#             density (solver.inertia.gear_mass via study.inputs.gearsetup); not the gears' errors
#   fe        root stress: the gears (springs included: 'uniform' runs no FE), the material, the
#             backlash, the FE mesh and the torque that sets the FE load (gearsetup.reference_torque)
#   static    STE: every field but the dynamic run's (study.stages.run_static reads no 'dynamic.*')
#   modes     the pair linearised at the mean load (its dampers given as ratios converted there):
#             the static fields (damping included) and the mean load, the dynamic run's torque
#             when it runs (study.scene_model.mean_load reads dynamic.enabled and dynamic.torque)
#   dynamic   DTE: every field
ERRORS = ("gear1.errors", "gear2.errors")    # pitch errors and runout: no part of a gear's mass or FE body
RATING = ("gear1.material", "gear2.material")  # the bending rating's steel: read by the strength outputs (static) only
ANALYSIS_FIELDS = {
    "geometry": (("gear1", "gear2", "pair", "material.density"), ("gear1.spring", "gear2.spring", *ERRORS, *RATING)),
    "fe": (("gear1", "gear2", "pair", "material", "fe", "quasi_static.torque"), (*ERRORS, *RATING)),
    "static": (("",), ("dynamic", "title")),
    "modes": (("", "dynamic.enabled", "dynamic.torque"), ("dynamic", "title")),
    "dynamic": (("",), ("title",)),
}
ANALYSES = tuple(ANALYSIS_FIELDS)        # narrowest first


def _under(path: str, prefix: str) -> bool:
    return prefix == "" or path == prefix or path.startswith(prefix + ".")


def reads(analysis: str, path: str) -> bool:
    """True when ``analysis`` ('geometry', 'fe', 'static', 'modes', 'dynamic') reads the scene
    field ``path``: the longest prefix of `ANALYSIS_FIELDS` that covers it is one it reads."""
    read, not_read = ANALYSIS_FIELDS[analysis]
    longest = max((len(p) for p in read if _under(path, p)), default=-1)
    return longest > max((len(p) for p in not_read if _under(path, p)), default=-1)


def reads_dynamic(analysis: str) -> bool:
    """True when ``analysis`` reads a field of the dynamic run (``dynamic.*``): modes, dynamic."""
    return reads(analysis, "dynamic.torque")


# CF flag meanings, values 0..5 (`solver.mbs.kernels.status.POINT_STATUS`); inaccurate: the
# dynamic run completed but its energy balance does not close: its scalars are kept, flagged
STATUS = POINT_STATUS


def analysis_of(output: str) -> str:
    """'static', 'dynamic', 'modes', 'geometry' or 'fe': the analysis an output (scalar or curve) needs."""
    return (SCALARS.get(output) or CURVES[output]).analysis


def _needs(analysis: str, what: str) -> property:
    """A read-only flag of `Outputs`: True when an output needs ``analysis`` (`Outputs.needs`)."""
    return property(lambda self: self.needs(analysis), doc=f"True when an output needs {what}.")


@dataclass(frozen=True)
class Outputs:
    """What each point of a study computes and archives: scalar names and full curves."""
    scalars: tuple[str, ...]
    curves: tuple[str, ...] = ()

    def needs(self, analysis: str) -> bool:
        """True when an output needs ``analysis`` ('static', 'dynamic', 'modes', 'fe', 'geometry')."""
        return any(analysis_of(x) == analysis for x in self.scalars + self.curves)

    static = _needs("static", "a quasi-static (STE) analysis")
    dynamic = _needs("dynamic", "a dynamic (DTE) analysis")
    modes = _needs("modes", "the modal analysis of the loaded pair")
    fe = _needs("fe", "the FE body of the springs (root stress)")

    @property
    def widest(self) -> str:
        """The analysis among the outputs' that reads the most scene fields (`ANALYSIS_FIELDS`)."""
        return max((analysis_of(x) for x in self.scalars + self.curves), key=ANALYSES.index)

    def parts(self) -> tuple[Outputs, ...]:
        """The outputs split by what they read: the ones that read no ``dynamic.*`` field (static,
        FE, geometry: one run per combination of the fields they read), then the ones that do
        (dynamic; modes, which read the dynamic run's torque as the mean load); empty parts left out."""
        out = []
        for dyn in (False, True):
            sc = tuple(x for x in self.scalars if reads_dynamic(analysis_of(x)) == dyn)
            cu = tuple(x for x in self.curves if reads_dynamic(analysis_of(x)) == dyn)
            if sc or cu:
                out.append(Outputs(sc, cu))
        return tuple(out)


def stages_of(outputs: Outputs) -> frozenset:
    """The stages of a run (`study.plan.STAGES`) the outputs need, each only when an output
    asks for it: 'static' and 'dynamic' by the outputs' analyses, 'mesh' for `MESH_SCALARS`
    (the linearised mesh over the STE; K_v with a dynamic run), 'gear' for the geometry and FE
    outputs (mass, inertia, root stress), 'modes' for the modal outputs and the free decay
    (``mesh_mode_damping_decay``, with the dynamic run), 'strength' for `STRENGTH_SCALARS`."""
    names = set(outputs.scalars + outputs.curves)
    wanted = {"static": outputs.static, "dynamic": outputs.dynamic, "mesh": bool(names & set(MESH_SCALARS)),
              "gear": outputs.needs("geometry") or outputs.fe,
              "modes": outputs.modes or "mesh_mode_damping_decay" in names,
              "strength": bool(names & set(STRENGTH_SCALARS))}
    return frozenset(k for k, v in wanted.items() if v)


def outputs_from_table(table) -> Outputs:
    """The [outputs] table of a study ({scalars = [...], curves = [...]}) checked: unknown names
    and an empty selection are SceneErrors. Scalars default to all of `SCALARS` but the strength
    outputs (`STRENGTH_SCALARS`), curves to none.
    A plain list of names (``["ste_p2p", "dte"]``) is split into its scalars and curves."""
    if isinstance(table, Outputs):
        table = {"scalars": list(table.scalars), "curves": list(table.curves)}
    if isinstance(table, str):
        table = [table]
    if isinstance(table, (list, tuple)):
        unknown = [x for x in table if x not in SCALARS and x not in CURVES]
        if unknown:
            raise SceneError("outputs", f"unknown output {unknown[0]!r} (scalars: {', '.join(SCALARS)}; curves: "
                             f"{', '.join(CURVES)}; `lightgear outputs` lists them with their units)")
        table = {"scalars": [x for x in table if x in SCALARS], "curves": [x for x in table if x in CURVES]}
    if not isinstance(table, dict):
        raise SceneError("outputs", f"must be a table, got {table!r}")
    for k in table:
        if k not in ("scalars", "curves"):
            raise SceneError(f"outputs.{k}", "unknown key (expected scalars, curves)")
    scalars = table.get("scalars", [x for x in SCALARS if x not in STRENGTH_SCALARS])
    curves = table.get("curves", [])
    for name, items, known in (("scalars", scalars, tuple(SCALARS)), ("curves", curves, tuple(CURVES))):
        if not isinstance(items, (list, tuple)):
            raise SceneError(f"outputs.{name}", f"must be a list, got {items!r}")
        for it in items:
            if it not in known:
                close = difflib.get_close_matches(str(it), known, n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise SceneError(f"outputs.{name}", f"unknown output {it!r} (expected one of: {', '.join(known)}){hint}")
    if not scalars and not curves:
        raise SceneError("outputs", "asks for nothing")
    return Outputs(tuple(dict.fromkeys(scalars)), tuple(dict.fromkeys(curves)))


def summary_rows(ds) -> list[tuple[str, float, str, str]]:
    """A run archive's summary scalars (`study.archive.summary.summarize`: STE peak-to-peak,
    DTE mean and RMS, ...) with their declared units and long names: [(name, value, units,
    long name)]; [] for a sweep archive (its scalars are variables already)."""
    if "status" in ds.data_vars:
        return []
    from study.archive.summary import summarize
    return [(k, v, SCALARS[k].units, SCALARS[k].long_name) for k, v in summarize(ds).items() if k in SCALARS]


def report_rows(ds) -> tuple[list[tuple], list[str]]:
    """What a report (`study.report`) tables of an archive: rows (name, value or text, units,
    long name) of its summary scalars, and Markdown blocks to add (the default model's numbers
    beside the archive's; a sampled study's statistics over the builds)."""
    import numpy as np
    extra = []
    if "status" not in ds.data_vars:        # a run
        from study.archive.summary import model_comparison
        rows = model_comparison(ds)
        if rows:
            dflt, ran = ds.attrs["default_coupling_model"], ds.attrs.get("coupling_model", "?")
            extra.append("## Two models of this scene\n\n| quantity | unit | default: " + dflt + " | " + ran + " |\n"
                         "|---|---|---|---|\n" + "\n".join(f"| {q} | {u} | {d:.4g} | {r:.4g} |" for q, u, d, r in rows))
        return summary_rows(ds), extra
    ok = ds["status"].values == STATUS.index("ok")
    rows = []
    for name, s in SCALARS.items():
        if name not in ds.data_vars:
            continue
        v = ds[name].broadcast_like(ds["status"]).values[ok]
        v = v[np.isfinite(v)]
        text = (f"{v.min():.4g} to {v.max():.4g}, mean {v.mean():.4g} over {v.size} points" if v.size else
                "no point ok")
        rows.append((name, text, s.units, s.long_name))
    if "sample" in ds.dims:
        from study.report.distributions import sample_outputs, sample_tables
        from study.report.sample_views import sample_table_text
        outputs = [v for v in sample_outputs(ds) if v in SCALARS]
        extra.append("## Statistics over the builds\n\n```text\n"
                     + sample_table_text(ds, sample_tables(ds, outputs), outputs) + "\n```")
    return rows, extra


def summarize_sweep(ds) -> dict:
    """The scalars of a sweep archive: {name: DataArray over the swept dimensions}, NaN where
    the point's status is not ok (an output not over every swept dimension is broadcast)."""
    ok = ds["status"] == STATUS.index("ok")
    return {k: ds[k].where(ok) for k in SCALARS if k in ds.data_vars}


def archive_summary(ds) -> dict:
    """The summary scalars of an archive. A run archive: {name: float} (STE mean and
    peak-to-peak [um], DTE RMS [um], amplitudes at the mesh and hole orders [um], largest tooth
    force [N], ...; `study.archive.summary.summarize`). A sweep archive: {name:
    xarray.DataArray} of its scalars over the swept dimensions, NaN where a point is not ok
    (`summarize_sweep`)."""
    from study.archive.summary import summarize
    from study.errors import check_argument
    check_argument(hasattr(ds, "data_vars"), "summarize", "ds", "a run or sweep archive (xarray.Dataset; study.read(path))", ds)
    if "status" in ds.data_vars and "study_key" in ds.attrs:
        return summarize_sweep(ds)
    return summarize(ds)


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

`study.validation` runs it; `python -m workflows.validation` prints its table and draws its figures.
"""
from __future__ import annotations

import time

import numpy as np
import xarray as xr

from solver import units
from solver.fe.ltca import mesh_points
from solver.mbs.statics import solve_static
from study.archive.netcdf import cf_variable, provenance
from study.errors import check_argument, check_scene_argument, is_number
from study.scene_model import build_scene_model, coupling_fit, gear_setup, static_angles
from study.verify.fe_reference import REFERENCE_MEMORY_FACTOR, reference
from study.verify.model_validation import order_amplitude, order_unresolved

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


def validation(scene, step: float | None = None) -> xr.Dataset:
    """STE of the pseudo-rigid models (plain, plain-fe, coupled, compliance) against the FE
    reference for the scene's pair with its driven gear solid and lightened -> Dataset over
    (pair, model, angle [degree]) with the error figures [um]; ``step`` [deg]: the driver angle
    step (None: quasi_static.angle_step)."""
    check_scene_argument("validation", scene)
    check_argument(step is None or is_number(step), "validation", "step", "a number of degrees or None", step)
    if scene.coupling.model != "none":       # the plain model is the scene's own; the coupled ones are built from it
        scene = scene.replace(**{"coupling.model": "none"})
    t0 = time.perf_counter()
    ds = validation_dataset(scene, static_angles(scene, step, REFERENCE_MEMORY_FACTOR))
    ds.attrs["wall_time_s"] = time.perf_counter() - t0
    return ds


def validation_dataset(scene, angles) -> xr.Dataset:
    pairs = {"solid": scene.solid(gears=(2,)), "lightened": scene}     # the driven gear made solid
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
    v = cf_variable
    coords = {"pair": v("pair", np.array(PAIRS), "", "gear pair (driven gear solid or lightened)"),
              "model": v("model", np.array(MODELS), "", "model (fe-reference: LTCA with FE influence coefficients)"),
              "angle": v("angle", np.degrees(angles), "degree", "driver rotation from the nominal position")}
    data = {"ste": v(("pair", "model", "angle"), ste, "um", "static transmission error rb1*theta1 + rb2*theta2"),
            "load_share": v(("pair", "model", "angle"), share, "1", "share of the mesh force carried by one driver tooth"),
            "nominal_contacts": v(("pair", "angle"), nominal, "1", "tooth pairs in the path of contact of the rigid geometry"),
            "wall_time": v(("pair", "model"), wall, "s", "wall time of the STE (FE compliance included for the reference)")}
    for k, (unit, doc) in METRIC_DOC.items():
        data[k] = v(("pair", "model"), tab[k], unit, doc)
    n_holes = scene.gear2.body.holes or scene.gear1.body.holes
    unresolved = order_unresolved(angles * scene.gear1.teeth / scene.gear2.teeth, n_holes) if n_holes else None
    if unresolved:
        data["hole_amplitude"].attrs["comment"] = f"undefined (NaN): {unresolved}"
    coords["gear"] = v("gear", np.array([1, 2]), "1", "gear (1 driver, 2 driven)")
    data["compliance_k_body"] = v(("pair", "gear"), fit["k_body"], "N m rad-1", "body torsion stiffness of the compliance model")
    data["compliance_pivot_radius"] = v(("pair", "gear"), fit["pivot"], "mm", "tooth pivot radius of the compliance model")
    data["compliance_fit_rms"] = v(("pair", "gear"), fit["rms"], "1",
                                   "RMS relative residual of the compliance model's fit to the FE influence coefficients")
    attrs = {"title": "STE of the pseudo-rigid models against the FE reference", "scene": scene.to_toml(),
             "backlash_offset_um": offsets[0], "static_torque_N_m": scene.quasi_static.torque,
             "hole_order": float(scene.gear2.body.holes), "mesh_order": float(scene.gear2.teeth),
             **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)

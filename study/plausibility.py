"""Cross-field checks of a scene that need a little physics: what the FE mesh can represent,
whether the loads are plausible (both called by `study.scene.check_scene`), and whether the
dynamic window leaves a steady part (called by `lightgear run`). Each raises `SceneError`
naming the field, before any work.
"""
from __future__ import annotations

import math

from solver import units
from study.errors import SceneError

# Elements of the outline size across the rim: fewer and the FE body has no element layer
# between the tooth roots and the web or the holes (the spring map reads points outside the mesh).
RIM_ELEMENTS = 2
# Longest an element across a web ligament (between two openings, an opening and the rim or
# the hub) may be against its width: the mesh puts the size of the opening's edge along the
# ligament and one element across it, and beyond this aspect ratio the (quadratic) elements
# spoil the ligament's bending stiffness. A thinner ligament takes a finer mesh.
LIGAMENT_ASPECT = 4.0
# Samples of the stored DTE after the ramp that a spectrum and the summary need.
STEADY_SAMPLES = 16
# Largest plausible elastic approach of the teeth along the line of action, as a fraction of
# the module: beyond it the pseudo-rigid teeth leave the range where the model means anything
# (teeth bent by a sizeable part of their height), and the statics find no equilibrium.
DEFLECTION_FRACTION = 0.2
# Smallest elastic approach a nonzero load must give [mm]. Far below it (the small 24-tooth pair
# at 1e-6 N·m: 2e-9 mm) the statics lose convergence, the dynamic run's energy guard trips and the
# damping conversion fails after the FE work blaming the damping ratio. Around it what resolves
# depends on more than the approach: the small pair lost convergence at 1e-3 N·m (3.6 nm) where a
# pair 1e4 times stiffer resolves 3.5 nm at 50 N·m (tests/solver/mbs/test_statics.py, the
# rigid-tooth limit); the bound sits below both, and loads between fail with the solver's message.
MIN_APPROACH_MM = 2e-6


def mesh_size_mm(scene, g: int) -> float:
    """FE element size at gear g's outline [mm]: fe.mesh_size, else a quarter of the module
    (`solver.fe.mesh.default_mesh_size`)."""
    return scene.fe.mesh_size or scene.gear(g).module / 4.0


def check_fe_mesh(scene) -> None:
    """fe.mesh_size at most the smaller module; a rim at least RIM_ELEMENTS elements thick; the
    web's ligaments at least 1/LIGAMENT_ASPECT of an element (`check_ligaments`)."""
    h = scene.fe.mesh_size
    m_min = min(scene.gear1.module, scene.gear2.module)
    if h > m_min:
        raise SceneError("fe.mesh_size", f"must lie in (0, module = {m_min:.4g} mm] (0: module/4), got {h:.4g} mm")
    for g in (1, 2):
        b, hg = scene.gear(g).body, mesh_size_mm(scene, g)
        if b.rim_height < RIM_ELEMENTS * hg:
            raise SceneError(f"gear{g}.body.rim_height",
                             f"rim thinner than the FE mesh can represent: it needs {RIM_ELEMENTS} elements of the "
                             f"outline size ({'fe.mesh_size' if scene.fe.mesh_size else 'module/4'} = {hg:.4g} mm), "
                             f"i.e. >= {RIM_ELEMENTS * hg:.4g} mm, got {b.rim_height:.4g} mm "
                             "(a finer fe.mesh_size allows a thinner rim)")
        check_ligaments(scene, g)


def check_ligaments(scene, g: int) -> None:
    """Gear g's web ligaments (between neighbouring openings, from the openings to the rim and to
    the hub) at least 1/LIGAMENT_ASPECT of the element size the body mesh uses on the opening's
    edge (`solver.fe.mesh.opening_edge_sizes`); SceneError naming
    the field that sets the ligament. Checked on a body that fits its gear
    (`solver.geometry.validate_body` first)."""
    from solver.fe.mesh import opening_edge_sizes
    from solver.openings import between_openings, radial_extent, shape_of
    gs = scene.gear(g)
    b = gs.body
    if b.holes == 0 or b.web_height == 0:
        return
    body, geo = scene.body_spec(g), scene.geometry(g)
    h = mesh_size_mm(scene, g) * units.MM
    edge, _corner = opening_edge_sizes(body, h)
    r_rim = geo.root_radius - body.rim_height
    r_hub = r_rim - body.web_height
    shape = shape_of(body)
    r_in, r_out = radial_extent(shape)
    size_field = {"round": "hole_radius", "slot": "slot_width", "window": "window_height"}[b.opening]
    gap_field = {"round": "holes", "slot": "slot_angle", "window": "spoke_width"}[b.opening]
    for field, where, width in ((gap_field, "between neighbouring openings", between_openings(shape)),
                                (size_field, "between the openings and the rim", r_rim - r_out),
                                (size_field, "between the openings and the hub", r_in - r_hub)):
        if width < edge / LIGAMENT_ASPECT:
            raise SceneError(f"gear{g}.body.{field}",
                             f"the web {where} is {width / units.MM:.4g} mm wide, thinner than the FE mesh can hold: "
                             f"the body mesh puts elements of {edge / units.MM:.4g} mm along the opening's edge (from "
                             f"{'fe.mesh_size' if scene.fe.mesh_size else 'module/4'} = {h / units.MM:.4g} mm and the "
                             f"opening's size), at most {LIGAMENT_ASPECT:g} times the ligament's width, so it needs "
                             f">= {edge / LIGAMENT_ASPECT / units.MM:.4g} mm (a finer fe.mesh_size allows a thinner ligament)")


RUNUP_REVOLUTIONS = 2.0       # driven revolutions a run-up must give its order tracking


def check_dynamic_window(scene) -> None:
    """SceneError when the scene's dynamic run leaves no steady part after its ramps for the DTE
    summary and spectrum (`lightgear run` checks it; integrator studies end with the ramps on purpose)."""
    from study.errors import check_scene_argument
    check_scene_argument("check_dynamic_window", scene)
    d = scene.dynamic
    if not d.enabled:
        return
    start = d.spectrum_start or 2 * d.ramp_time
    need = STEADY_SAMPLES * d.output_step
    if d.speed_end > 0:
        # a run-up's order tracking takes blocks of one driven revolution, one every 1/8
        # revolution (`order_tracking`): two revolutions give a map of nine blocks over speed
        turns = 0.5 * d.speed_end * d.duration * scene.gear1.teeth / scene.gear2.teeth / (2 * math.pi)
        if turns < RUNUP_REVOLUTIONS:
            need_end = RUNUP_REVOLUTIONS * 4 * math.pi * scene.gear2.teeth / scene.gear1.teeth / d.duration
            raise SceneError("dynamic.speed_end",
                             f"the driven gear turns {turns:.3g} revolutions over the run-up (0 -> {d.speed_end:.4g} rad/s "
                             f"in dynamic.duration = {d.duration:.4g} s), and its order tracking over speed needs at least "
                             f"{RUNUP_REVOLUTIONS:g} (blocks of one revolution): give speed_end >= {need_end:.4g} rad/s "
                             "or a longer duration")
    if d.duration - start < need:
        what = "dynamic.spectrum_start" if d.spectrum_start else "twice dynamic.ramp_time"
        raise SceneError("dynamic.duration",
                         f"leaves no steady part: the DTE summary and spectrum start at {what} ({start:.4g} s) and need "
                         f"{STEADY_SAMPLES} samples of dynamic.output_step ({d.output_step:.4g} s) after it, so the "
                         f"duration must be >= {start + need:.4g} s, got {d.duration:.4g} s")


def approach_estimate_mm(scene, torque_nm: float) -> float:
    """Elastic approach of one tooth pair carrying the whole load [mm], from the scene's laws:
    the contact (F = k_con delta^m1) plus each tooth's torsion spring (T = k_phi phi^n_k) with the
    normal force acting at the pitch circle, lever = pitch radius - pivot radius. A rough upper
    estimate (load sharing halves it); for the coupled body models, whose tooth springs come
    from the FE body, the springs of the paper's solid tooth stand in."""
    g1, g2 = (scene.geometry(g) for g in (1, 2))
    force = abs(torque_nm) / g2.base_radius                      # N, along the line of action
    c = scene.contact
    k_con = units.contact_stiffness_to_si(c.k_con, c.m1)         # N/m^m1
    delta = (force / k_con) ** (1.0 / c.m1)                      # m
    for g, geo in ((1, g1), (2, g2)):
        spring = scene.gear(g).spring
        if scene.coupling_model != "none":    # the coupled models' springs: the paper's solid tooth stands in
            spring = type(spring)()
        lever = max(geo.pitch_radius - scene.pivot_radius(g), 0.25 * scene.gear(g).module * units.MM)   # m
        k_phi = spring.k_phi * units.NMM                         # N·m/rad^n_k
        phi = (force * lever / k_phi) ** (1.0 / spring.n_k)       # rad
        delta += phi * lever
    return delta / units.MM


def check_loads(scene) -> None:
    """Each torque of the scene against the deflection bound (DEFLECTION_FRACTION of the module)."""
    loads = [("quasi_static.torque", scene.quasi_static.torque), ("dynamic.torque", scene.dynamic.torque)]
    if scene.dynamic.torque_change_time > 0:
        loads.append(("dynamic.torque_after", scene.dynamic.torque_after))
    bound = DEFLECTION_FRACTION * min(scene.gear1.module, scene.gear2.module)
    for name, torque in loads:
        if torque == 0:
            continue
        d = approach_estimate_mm(scene, torque)
        if d < MIN_APPROACH_MM:
            raise SceneError(name, f"a load too small to resolve: {torque:.4g} N*m presses one tooth pair together by about "
                             f"{d:.3g} mm (contact law and tooth springs), less than the {MIN_APPROACH_MM:g} mm the "
                             f"solvers resolve; give at least {smallest_torque(scene):.2g} N*m in magnitude, or 0 for no load")
        if not d <= bound:
            raise SceneError(name, f"implausible load: {torque:.4g} N*m bends one tooth pair by about {d:.3g} mm "
                             f"(contact law and tooth springs), more than {DEFLECTION_FRACTION:g} x module = {bound:.4g} mm; "
                             "the pseudo-rigid tooth model does not hold there")


def smallest_torque(scene) -> float:
    """The torque [N·m] whose `approach_estimate_mm` is MIN_APPROACH_MM (bisection in log scale)."""
    lo, hi = 1e-12, 1e6
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if approach_estimate_mm(scene, mid) < MIN_APPROACH_MM else (lo, mid)
    return hi


def check_plausibility(scene) -> None:
    """The checks every scene passes (mesh, loads). `check_dynamic_window` is for the commands
    that summarise a run: integrator studies run windows that end with the ramps on purpose."""
    check_fe_mesh(scene)
    check_loads(scene)


def carrying_equilibria(scene, model, torque: float, positions: int = 12):
    """`solver.mbs.equilibria.loaded_equilibria` of the scene's model under ``torque`` [N·m];
    SceneError naming the load when the teeth cannot carry it: no equilibrium within the
    deflection bound (DEFLECTION_FRACTION of the module) at any position. The torque check of
    `check_loads` estimates from the scene's laws alone; this is what the springs actually
    built (FE springs of a soft material or a thin face, a modification that opens the mesh)
    make of the load."""
    from solver.mbs.equilibria import loaded_equilibria
    try:
        return loaded_equilibria(model, torque, positions)
    except ValueError:
        d = scene.dynamic
        field = "dynamic.torque" if d.enabled and d.torque == torque else "quasi_static.torque"
        bound = DEFLECTION_FRACTION * min(scene.gear1.module, scene.gear2.module)
        raise SceneError(field, f"implausible load: under {torque:.4g} N*m the pair finds no equilibrium with the "
                                f"flanks approaching less than {DEFLECTION_FRACTION:g} x module = {bound:.4g} mm: the teeth "
                                "are too soft for it or the flanks do not meet (the tooth springs of "
                                "material.youngs_modulus, gearN.face_width and gearN.spring, the flank deviations of "
                                "gearN.modification): lower the torque or check those fields") from None



FACE_WIDTH_REF_MM = 17.0      # face width the paper's per-tooth laws were calibrated at [mm]


def face_width_note(scene, swept: bool = False) -> str | None:
    """A line for the user when the face width cannot act on the STE: the contact law (k_con)
    and, unless a gear's springs come from the FE directly (spring.stiffness = 'fe'), the tooth
    springs are given per tooth, so a face width other than the calibration's (or a swept
    one) changes only masses and inertias. None when it does act or stays at 17 mm: with 'fe'
    springs, and under the coupled models ('compliance', the default, and 'body-torsion'),
    whose tooth springs come from the FE body at its face width (the small 24-tooth pair's mesh
    stiffness rises 1.8 times from 20 to 40 mm of face) and read no k_phi."""
    if scene.coupling_model != "none":
        return None
    gears = [g for g in (1, 2) if scene.gear(g).spring.stiffness != "fe"]
    widths = {scene.gear(g).face_width for g in (1, 2)}
    if not gears or (not swept and widths == {FACE_WIDTH_REF_MM}):
        return None
    return ("note: the face width acts on masses and inertias only: contact.k_con and the tooth springs of "
            + " and ".join(f"gear {g} (spring.stiffness = {scene.gear(g).spring.stiffness!r})" for g in gears)
            + " are per tooth, calibrated at 17 mm; for stiffness that follows the face width use "
              "gearN.spring.stiffness = 'fe' and refit k_con (lightgear fit-contact)")


# ---------------------------------------------------------------- warnings (valid, but almost certainly a slip)

# Pitch-line velocity above which a spur gear pair is almost certainly not meant (precision
# spur gears rarely run above 40-60 m/s; rad/s given as rpm gives some ten times the speed).
PITCH_LINE_VELOCITY_MAX = 100.0       # m/s
# A driver speed this many times the mesh mode's 1Z critical speed (the highest critical speed
# of the mesh orders) is far beyond the range the dynamic model is built for.
CRITICAL_SPEED_FACTOR = 3.0


def scene_warnings(scene) -> list[str]:
    """Values that pass the checks but are almost certainly a unit slip, each as one line naming
    the field: a lightening hole smaller than the FE mesh size (metres typed for millimetres), a
    pitch-line velocity above PITCH_LINE_VELOCITY_MAX (rpm typed for rad/s), a spring field the
    coupled model does not read (`unread_spring_warnings`). `run_scene` prints them on stderr and
    keeps them in the archive's ``plausibility_warnings`` attribute."""
    from study.errors import check_scene_argument
    check_scene_argument("plausibility_warnings", scene)
    out = []
    for g in (1, 2):
        b, h = scene.gear(g).body, mesh_size_mm(scene, g)
        field = {"round": "hole_radius", "slot": "slot_width", "window": "window_height"}[b.opening]
        size = getattr(b, field)          # a round hole's radius; a slot's width, a window's height
        if b.holes and size < h:
            out.append(f"gear{g}.body.{field}: {size:.4g} mm is smaller than the FE mesh size "
                       f"({h:.4g} mm): the {'hole' if b.opening == 'round' else b.opening} is no lightening the model "
                       "can see (millimetres meant?)")
    out += unread_spring_warnings(scene)
    d = scene.dynamic
    if d.enabled:
        field, speed = ("dynamic.speed_end", d.speed_end) if d.speed_end > 0 else ("dynamic.speed", d.speed)
        v = speed * scene.geometry(1).pitch_radius        # m/s
        if v > PITCH_LINE_VELOCITY_MAX:
            out.append(f"{field}: {speed:.4g} rad/s turns the pitch line at {v:.3g} m/s, above "
                       f"{PITCH_LINE_VELOCITY_MAX:g} m/s (rpm meant? {speed:.4g} rpm = {speed * 0.10471975511965977:.4g} rad/s)")
    return out


def unread_spring_warnings(scene) -> list[str]:
    """A line for each tooth-spring field a scene sets that its model does not read: a coupled
    model ('body-torsion', 'compliance', and 'auto' unless both gears' springs are 'uniform')
    takes its tooth springs, their linear law and the tooth pivot from the FE body, so
    gearN.spring.k_phi, gearN.spring.n_k and gearN.pivot_radius away from their defaults have
    no effect, nor does gearN.spring.stiffness = 'uniform' on a lightened body."""
    if scene.coupling_model == "none":
        return []
    how = (f"coupling.model = 'auto' runs {scene.coupling_model!r} here" if scene.coupling.model == "auto"
           else f"coupling.model = {scene.coupling.model!r}")
    out = []
    for g in (1, 2):
        gs = scene.gear(g)
        sp, sp0, gs0 = gs.spring, type(gs.spring)(), type(gs)()
        for field, value, default, unit in (("spring.k_phi", sp.k_phi, sp0.k_phi, " N*mm/rad^n_k"),
                                            ("spring.n_k", sp.n_k, sp0.n_k, ""),
                                            ("pivot_radius", gs.pivot_radius, gs0.pivot_radius, " mm")):
            if value != default:
                out.append(f"gear{g}.{field}: {value:.4g}{unit} has no effect: {how}, whose tooth springs and pivots "
                           f"come from the FE body (the paper's per-tooth law is read by coupling.model = 'paper' only)")
        if sp.stiffness == "uniform" and scene.is_lightened(g):
            out.append(f"gear{g}.spring.stiffness: 'uniform' has no effect: {how}, which takes gear {g}'s lightened "
                       "body from its FE (springs that ignore the lightening: coupling.model = 'paper')")
    return out


def critical_speed_warning(scene, critical_speed_1z: float) -> str | None:
    """A line when the driver speed lies far above the mesh mode's 1Z critical speed [rad/s]
    (the highest of the mesh orders' critical speeds), else None."""
    d = scene.dynamic
    if not d.enabled:
        return None
    field, speed = ("dynamic.speed_end", d.speed_end) if d.speed_end > 0 else ("dynamic.speed", d.speed)
    if critical_speed_1z > 0 and speed > CRITICAL_SPEED_FACTOR * critical_speed_1z:
        return (f"{field}: {speed:.4g} rad/s is {speed / critical_speed_1z:.3g} x the highest critical speed of the mesh "
                f"orders (1Z on the mesh mode: {critical_speed_1z:.4g} rad/s), far beyond the resonances the model is "
                "built to study (rpm meant?)")
    return None


def report_warnings(messages, show: bool = True) -> str:
    """Print each warning on stderr (``show``) -> the text for an archive attribute ('' for none)."""
    import sys
    for m in messages:
        if show:
            print(f"lightgear: warning: {m}", file=sys.stderr)
    return "\n".join(messages)

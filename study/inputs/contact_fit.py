"""`lightgear fit-contact [SCENE]`: Weber's contact deflection fitted to F = k_con * delta**m1."""
from __future__ import annotations

from solver import units
from solver.identify.weber import fit_contact
from study.inputs.gearsetup import gear_setups
from study.scene import load_scene


def add_arguments(p):
    p.add_argument("scene", nargs="?", help="scene TOML (default: the embedded paper example)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene field by its dotted path")


def main(args) -> int:
    scene = load_scene(args.scene, args.overrides)
    g1, g2 = (setup.geometry for setup in gear_setups(scene))
    f_ref = scene.quasi_static.torque / g1.base_radius
    print(f"Weber contact deflection at the pitch point, plane strain, F_ref = {f_ref:.1f} N "
          f"(quasi_static.torque / base radius), R = {fit_contact(g1, g2, scene.material_spec(), f_ref).radius * 1e3:.3f} mm")
    for frac, note in ((0.5, "default: depth half-way to the tooth centreline"),
                       (1.0, "depth to the tooth centreline (where the FE tooth spring is read)")):
        f = fit_contact(g1, g2, scene.material_spec(), f_ref, depth_fraction=frac)
        k = f.k_con / units.contact_stiffness_to_si(1.0, f.m1)
        print(f"  {note}:\n    k_con = {k:.4g} N/mm^m1, m1 = {f.m1:.4f} "
              f"(depth {f.depth[0] * 1e3:.3f} mm, load {f.force_range[0]:.0f}..{f.force_range[1]:.0f} N, "
              f"fit RMS {f.rms_log_error:.1e} in ln F)")
    c = scene.contact
    print(f"  scene: k_con = {c.k_con:.4g} N/mm^m1, m1 = {c.m1:.4f}")
    return 0

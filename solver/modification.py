"""Profile modifications of a gear's flanks (SI): tip and root relief and a deviation table.

A modification is a deviation of the flank along its normal, positive where material is
removed, as a function of the involute roll parameter u (the roll angle [rad]: the flank point
at roll u lies at radius rb*sqrt(1 + u**2), and rb*u is its distance along the line of action
from the base circle's tangent point). Both flanks of every tooth of the gear carry it.

* Tip relief: ``amount * ((u - u_start)/(u_tip - u_start))**exponent`` for u > u_start
  (exponent 1 linear, 2 parabolic); the amount is the deviation at the tip.
* Root relief: ``amount * ((u_start - u)/(u_start - u_form))**exponent`` for u < u_start; the
  amount is the deviation at the form circle (the lowest flank point of the model).
* Table: deviation [m] against roll [rad], linear between its points, constant beyond its ends;
  added to the reliefs.
* Tip edge radius [m]: the tip corner rounded by a circular arc of that radius, tangent to the
  flank and to the tip circle (0: a sharp corner). The contact search ends the flank at the
  round's tangent point and meets the mating flank with the round's circle beyond it, with the
  compliance of its narrower Hertz patch in series with the contact law (gear_par EDGE_*, the
  compliance model's series law; `solver.tip_edge`); the CalculiX peer meshes the round.

The contact search reads it as a table sampled on a fixed roll grid from the form circle to the
tip (`sample`), through which it passes a cubic with a continuous slope
(`solver.mbs.kernels.gearmesh.flank_deviation`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Relief:
    """A tip or root relief: deviation [m] at the flank end, start roll [rad], exponent [-]."""

    amount: float = 0.0
    start: float = 0.0
    exponent: float = 1.0


@dataclass(frozen=True)
class ProfileModification:
    """Tip and root relief, a deviation table and the tip edge radius of one gear's flanks (SI,
    rolls in rad)."""

    tip: Relief = Relief()
    root: Relief = Relief()
    table_roll: tuple = ()      # rad, increasing
    table_deviation: tuple = () # m
    tip_edge_radius: float = 0.0  # m; 0: a sharp tip corner

    def deviation(self, u, u_form: float, u_tip: float) -> np.ndarray:
        """Deviation [m] along the flank normal at roll parameters u [rad] (positive: material removed)."""
        u = np.asarray(u, float)
        dev = np.zeros_like(u)
        t = self.tip
        if t.amount != 0.0:
            x = np.clip((u - t.start) / (u_tip - t.start), 0.0, None)
            dev += t.amount * x ** t.exponent
        r = self.root
        if r.amount != 0.0:
            x = np.clip((r.start - u) / (r.start - u_form), 0.0, None)
            dev += r.amount * x ** r.exponent
        if len(self.table_roll):
            dev += np.interp(u, np.asarray(self.table_roll, float), np.asarray(self.table_deviation, float))
        return dev

    def check(self, u_form: float, u_tip: float, name: str = "gear") -> None:
        """ValueError naming the field when a relief starts outside the flank or the table is malformed."""
        for which, rel in (("tip", self.tip), ("root", self.root)):
            if rel.amount != 0.0 and not u_form < rel.start < u_tip:
                raise ValueError(f"{name}.modification.{which}_relief: starts at roll {np.degrees(rel.start):.4g} deg, "
                                 f"outside the flank ({np.degrees(u_form):.4g} to {np.degrees(u_tip):.4g} deg)")
        if self.tip.amount != 0.0 and self.root.amount != 0.0 and self.root.start > self.tip.start:
            raise ValueError(f"{name}.modification.root_relief: starts above the tip relief's start")
        r = np.asarray(self.table_roll, float)
        if r.size != len(self.table_deviation):
            raise ValueError(f"{name}.modification.profile_deviation: {len(self.table_deviation)} values for {r.size} positions")
        if r.size == 1 or np.any(np.diff(r) <= 0):
            raise ValueError(f"{name}.modification.profile_deviation: needs at least two positions, strictly increasing")

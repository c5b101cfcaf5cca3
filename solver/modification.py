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

The contact search reads it as a table sampled on a fixed roll grid from the form circle to the
tip (`sample`), through which it passes a cubic with a continuous slope
(`solver.mbs.kernels.gearmesh.flank_deviation`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.mbs.kernels import layout as L


@dataclass(frozen=True)
class Relief:
    """A tip or root relief: deviation [m] at the flank end, start roll [rad], exponent [-]."""

    amount: float = 0.0
    start: float = 0.0
    exponent: float = 1.0


@dataclass(frozen=True)
class ProfileModification:
    """Tip and root relief and a deviation table of one gear's flanks (SI, rolls in rad)."""

    tip: Relief = Relief()
    root: Relief = Relief()
    table_roll: tuple = ()      # rad, increasing
    table_deviation: tuple = () # m

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


def sample(mod: ProfileModification | None, u_form: float, u_tip: float, row: np.ndarray) -> None:
    """Write the model columns DEV_* of one gear into ``row`` (a gear_par row): the deviation
    [m] on N_DEV rolls from u_form to u_tip, the flag DEV_ON, the grid and DEV_NEG (a bound on
    the material addition [m], which widens the rigid gap bound of the pre-search)."""
    u = np.linspace(u_form, u_tip, L.N_DEV)
    dev = np.zeros(L.N_DEV) if mod is None else mod.deviation(u, u_form, u_tip)
    row[L.DEV_U0] = u_form
    row[L.DEV_DU] = u[1] - u[0]
    row[L.DEV0:L.DEV0 + L.N_DEV] = dev
    row[L.DEV_ON] = 1.0 if np.any(dev != 0.0) else 0.0
    # the cubic through the samples may undershoot them by a fraction of a step near a kink
    row[L.DEV_NEG] = max(0.0, -float(dev.min())) + 0.25 * float(np.abs(np.diff(dev)).max())

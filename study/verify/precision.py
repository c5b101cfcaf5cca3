"""Work-precision study: TE error against CPU and wall time for every solver of a scene.

Dynamic scene (DTE): every method integrates the same equations, those of the scipy peer
(`solver.peers.scipy_dynamics`: every tooth free, none frozen), over a shortened window (the paper's
0.2 s is out of reach of the scipy solvers) with the speed and torque ramps scaled to it:
  explicit   velocity Verlet at fractions of its stability step,
  implicit   HHT-alpha at multiples of that step, alpha = 0 and alpha < 0,
  Radau, LSODA  scipy stiff solvers at several relative tolerances,
plus ``explicit, active set``: the production path (idle teeth frozen rigid to their hub),
whose error also holds that model reduction.
Reference: DOP853 at rtol 1e-10; cross-check: Verlet at 1/32 of its stability step. Their
mutual difference is in the dataset attrs and on the plot; it must lie far below the errors.

Quasi-static scene (STE over a rotation of the driver): the static Newton solver at several
tolerances, and the paper's slow-ramp transient with the explicit and the implicit
integrators. Reference: static Newton at tol 1e-13; cross-check: `scipy.optimize.root` on the
plain-Python forces. The transient's error also holds its physical ringing (not a solver
error): it is measured on the angles after the ramp.

A body-coupled model (the default compliance model) has the explicit ladders and the static
solver only, each against the same model's own converged answer (`study.verify.precision_cases`).
The FE mesh size's share: `study.verify.precision_mesh`.

Errors: TE minus reference TE [um] on the common output grid, as norms ``final`` (last
sample), ``l2`` (root mean square over the samples) and ``linf`` (largest magnitude).
Wall and CPU time [s]: best of ``repeats`` runs after a warm-up run of each numba method
(compile time and the first call are timed apart, in ``first_call_time``); a run over 10 s is
timed once; runs are compared by CPU time. A failed run keeps NaN errors and its message.

`lightgear precision [SCENE] [-o OUT.nc]` runs both for a scene (default: the paper example).

The study in three modules: `study.verify.precision_cases` (the cases, solver ladders and
references), `study.verify.precision_study` (timed runs, errors -> Dataset) and
`study.verify.precision_report` (cheapest run, text table, plot).
"""
from __future__ import annotations

from study.verify.precision_cases import Spec
from study.verify.precision_report import cheapest, plot, setting_label, table
from study.verify.precision_study import NORMS, dynamic_study, machine, run_study, static_study, te_error_norms

__all__ = ["NORMS", "Spec", "cheapest", "dynamic_study", "machine", "plot", "run_study", "setting_label",
           "static_study", "table", "te_error_norms"]

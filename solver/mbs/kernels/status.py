"""Status codes of a run and of a study's point, as plain constants: importing this module
loads no numba (`solver.mbs.kernels` imports numba only when a kernel is decorated), so the
kernels, the solver, the sweep and the pictures all take them from here.

A run's status (``DynamicResult.status``, the stepping loops' return value):
  0 OK, 1 NONFINITE state, 2 PENETRATION beyond the bound, 3 ENERGY growth, 4 NEWTON failure
  (implicit), 5 INTERRUPTED (``par[ABORT]`` set from another thread: `solver.mbs.interrupt`;
  the scipy peer's wall-time limit), 6 INACCURATE: completed, but the energy balance does not
  close (`solver.mbs.dynamics.accuracy_check`): its numbers are kept, flagged.

A study point's status (the sweep archive's ``status`` flag, CF ``flag_values`` 0..5 with
these ``flag_meanings``): `POINT_STATUS`; ``POINT_STATUS.index(name)`` is its value.
"""
OK = 0
NONFINITE = 1
PENETRATION = 2
ENERGY = 3
NEWTON = 4
INTERRUPTED = 5
INACCURATE = 6
COMPLETED = (OK, INACCURATE)      # runs whose numbers are kept (an inaccurate one with its flag)
STATUS_TEXT = {OK: "ok", NONFINITE: "non-finite state", PENETRATION: "penetration beyond the bound",
               ENERGY: "energy growth", NEWTON: "Newton failure", INTERRUPTED: "wall-time limit",
               INACCURATE: "inaccurate"}     # INTERRUPTED: the scipy peer's wall-time limit

POINT_STATUS = ("pending", "ok", "diverged", "invalid", "failed", "inaccurate")
POINT_OK = POINT_STATUS.index("ok")

"""The energy guard of a completed run: how large its energy-balance error may be before the
run is flagged inaccurate (`solver.mbs.dynamics.accuracy_check`). numpy only, so that the
reports can quote the margin without loading the kernels."""
from __future__ import annotations

import numpy as np

# Largest energy-balance error of a completed run [J]: ENERGY_ERROR_RATIO times the largest
# potential energy of the mesh plus ENERGY_FLOW_RATIO times the energy dissipated so far. The
# residual of a converged run has two parts. One is bounded: the energy Verlet reads at the step
# instants oscillates about its conserved (shadow) energy, by up to a/(1 - a) (a = (w dt/2)²) of
# the stiff modes' share, a fraction of the mesh's potential energy (paper pair at 0.9 of the
# bound: 0.16 of it, at any run length). The other accumulates: the trapezoidal quadrature of
# the input and damper powers errs by O(dt²) of the power that cycles through the vibration,
# which the dampers take out, so it grows with the dissipated energy, not with the potential
# energy: the 1 s run-up 0 -> 400 rad/s of the paper pair reads 0.23 % of its dissipated
# energy at 0.588 us and 0.11 % at 0.4 us (O(dt²); its DTE agrees to three digits), 0.65 and
# 0.31 x the potential energy, so a bound on the potential energy alone flagged it. The runs
# whose step misses the contact events read 0.66 x the potential energy within 20 ms while
# dissipating as much as the error (contact stiffness x1000, explicit), and 9 x it (150/150
# teeth rattling, HHT at 2.5 us, 3 x the DTE of a converged run): the flow term, 20 x the
# converged runs' rate, leaves them flagged.
ENERGY_ERROR_RATIO = 0.5
ENERGY_FLOW_RATIO = 0.05


def energy_error_limit(res) -> np.ndarray:
    """The energy-balance error [J] a converged run stays under at each output instant:
    ENERGY_ERROR_RATIO x the largest potential energy of the mesh + ENERGY_FLOW_RATIO x the
    energy dissipated so far (see there); ``res``: a `solver.mbs.dynamics.DynamicResult`."""
    return ENERGY_ERROR_RATIO * float(np.max(res.potential)) + ENERGY_FLOW_RATIO * np.abs(res.dissipated)

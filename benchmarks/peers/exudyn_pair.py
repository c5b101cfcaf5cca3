"""The pseudo-rigid-tooth gear pair built in Exudyn (C++ multibody code, Python front end).

One `NodeGenericODE2` carries the free coordinates q = [theta2, phi_0 .. phi_{N-1}] [rad]
(every tooth of both gears free, as in `solver.peers.pair_equations.PairEquations`); an
`ObjectGenericODE2` holds the constant arrowhead mass matrix of hubs and teeth (driver hub
prescribed, so it is not a coordinate) and a force user function that returns the
generalised forces: the torsion springs of eq. (1.2), the involute contact of eq. (1.3)
computed by the same closed forms (`PairEquations.contacts`), the load torque on gear 2 and
the inertial push -I_cpl*theta1'' of the prescribed driver on its teeth.
Exudyn's own integrators (e.g. its velocity Verlet or RK44 at a fixed step, DOPRI5 adaptive)
advance it; a node sensor records theta2, from which TE = rb1*theta1 + rb2*theta2 [m].
"""
from __future__ import annotations

import time

import numpy as np

from solver.peers.pair_equations import PairEquations, driver_motion


def mass_matrix(eq: PairEquations) -> np.ndarray:
    """Arrowhead mass matrix [kg m^2] over [theta2, phi_0 .. phi_{N-1}]."""
    n, z1 = eq.n, eq.z1
    m = np.zeros((n, n))
    m[0, 0] = eq.itot[1]
    idx = np.arange(1, n)
    m[idx[:z1], idx[:z1]] = eq.ip[0]
    m[idx[z1:], idx[z1:]] = eq.ip[1]
    m[0, 1 + z1:] = m[1 + z1:, 0] = eq.icpl[1]
    return m


def generalized_force(eq: PairEquations, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Right-hand side f(t, q, q_t) of M q'' = f [N m] (contacts, springs, load, driver push)."""
    f, _q1, _cons, a1 = eq.forces(t, q, v)
    f[1:1 + eq.z1] -= eq.icpl[0] * a1
    return f


def simulate_exudyn(model, drive, dt: float, output_step: float = 1e-5, solver: str = "VelocityVerlet"):
    """Integrate the pair from rest under ``drive`` (`solver.mbs.dynamics.Drive`: its speed and
    torque ramps, no load profile) in Exudyn at the fixed step dt [s] with `solver` (an
    `exudyn.DynamicSolverType` name). Returns (time [s], TE [m], wall time of the solve [s]).
    dt is rounded down to divide output_step [s] (as `solver.mbs.dynamics.simulate` does), so
    the sensor samples fall on steps.
    """
    import math

    import exudyn as exu
    from exudyn.itemInterface import NodeGenericODE2, ObjectGenericODE2, SensorNode

    speed, speed_ramp, torque, torque_ramp, duration = (drive.speed, drive.speed_ramp, drive.torque, drive.torque_ramp,
                                                        drive.duration)
    dt = output_step / max(1, int(math.ceil(output_step / dt - 1e-9)))
    eq = PairEquations(model, speed, speed_ramp, torque, torque_ramp)
    n = eq.n
    q0 = np.zeros(n)
    q0[0] = model.theta2_for_te(0.0, (1.0 if torque >= 0 else -1.0) * model.backlash_offset)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n, initialCoordinates=q0.tolist(),
                                       initialCoordinates_t=[0.0] * n, numberOfODE2Coordinates=n))

    def force(mbs_, t, item, q, q_t):
        return generalized_force(eq, t, np.asarray(q), np.asarray(q_t))

    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=mass_matrix(eq), forceUserFunction=force))
    sens = mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=exu.OutputVariableType.Coordinates,
                                    storeInternal=True, writeToFile=False))
    mbs.Assemble()
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.numberOfSteps = int(round(duration / dt))
    ti.endTime = duration
    ti.verboseMode = 0
    ti.explicitIntegration.dynamicSolverType = getattr(exu.DynamicSolverType, solver)
    s.solutionSettings.writeSolutionToFile = False
    s.solutionSettings.sensorsWritePeriod = output_step
    s.displayStatistics = False
    s.displayComputationTime = False
    t0 = time.perf_counter()
    exu.SolveDynamic(mbs, s, solverType=getattr(exu.DynamicSolverType, solver))
    wall = time.perf_counter() - t0
    data = np.asarray(mbs.GetSensorStoredData(sens))
    t = data[:, 0]
    th1 = np.array([driver_motion(tt, speed, speed_ramp)[0] for tt in t])
    rb1, rb2 = model.base_radii
    return t, rb1 * th1 + rb2 * data[:, 1], wall

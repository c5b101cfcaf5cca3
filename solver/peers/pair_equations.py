"""Equations of motion of the pair in plain numpy + ``math``, every tooth free: the peers'
model (`scipy_dynamics`, `scipy_statics`), independent of the numba kernels.

Written the way a Python user would write them: every tooth of both gears is a degree of
freedom (no active set), the contact search is a direct numpy/``math`` transcription of the
closed forms of `kernels/contact.py` and `kernels/gearmesh.py`, and the arrowhead mass matrix
is inverted in closed form. The driver hub follows the prescribed speed ramp (theta1 is not a
DOF); the load torque ramps on gear 2 (or follows a profile).

The dynamic Jacobian and the static root loop share the tangents (`PairEquations.tangents`):
K = sum_c k_t G G^T + spring tangents and the damping tangent C = sum_c dF/d(ddelta) G G^T
+ spring damping tangents (the geometric term F dG/dq is left out: it changes only Newton's
convergence rate, not the solution). SI units throughout.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.mbs.kernels import layout as L
from solver.mbs.model import Model

# ------------------------------------------------------------------ loads (plain Python)

def driver_motion(t: float, speed: float, ramp: float) -> tuple[float, float, float]:
    """Driver angle [rad], speed [rad/s] and acceleration [rad/s²] of the linear speed ramp."""
    if t < ramp:
        acc = speed / ramp
        return 0.5 * acc * t * t, acc * t, acc
    return speed * (t - 0.5 * ramp), speed, 0.0


def load_torque(t: float, torque: float, ramp: float) -> float:
    """Resisting torque on gear 2 [N·m], ramped linearly from zero."""
    return torque * t / ramp if t < ramp else torque


# ------------------------------------------------------------------ contact geometry

def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def _flank_flank(a: tuple, b: tuple, s: float):
    """Overlap of two flanks of sense s along the internal tangent of their base circles; each
    flank ``a``, ``b`` as (centre x [m], centre y [m], base radius [m], flank angle [rad])."""
    cax, cay, rba, ba = a
    cbx, cby, rbb, bb = b
    dx, dy = cbx - cax, cby - cay
    c = (rba + rbb) / math.hypot(dx, dy)
    if c >= 1.0:
        return -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ta = math.atan2(dy, dx) - s * math.acos(c)
    ct, st = math.cos(ta), math.sin(ta)
    nx, ny = -s * st, s * ct
    ua = s * _wrap(ba - ta)
    ub = s * _wrap(bb - ta - math.pi)
    delta = nx * cax + ny * cay + rba * ua - (nx * cbx + ny * cby) + rbb * ub
    return delta, ua, ub, nx, ny, cax + rba * ct + rba * ua * nx, cay + rba * st + rba * ua * ny


def _point_flank(qx, qy, cx, cy, rb, beta, s):
    """Penetration of point Q into an involute flank along the flank normal through Q."""
    wx, wy = qx - cx, qy - cy
    r2 = wx * wx + wy * wy
    if r2 <= rb * rb:
        return -1.0, -1.0, 0.0, 0.0
    uq = math.sqrt(r2 / (rb * rb) - 1.0)
    t = math.atan2(wy, wx) - s * math.atan(uq)
    uf = s * _wrap(beta - t)
    return rb * (uf - uq), uf, -s * math.sin(t), s * math.cos(t)


def _tip_corner(cx, cy, rb, beta, s, u_tip):
    t = beta - s * u_tip
    return cx + rb * math.cos(t) - s * rb * u_tip * math.sin(t), cy + rb * math.sin(t) + s * rb * u_tip * math.cos(t)


def _cross(ax, ay, bx, by):
    return ax * by - ay * bx


@dataclass
class Contact:
    """One active contact: penetration [m], its rate [m/s], force [N], tangents and gradient.

    ``g`` = d delta / d(theta1, phi_A, theta2, phi_B) [m]; ``ia``/``ib`` global tooth indices.
    """
    delta: float
    ddelta: float
    force: float
    kt: float            # dF/d delta [N/m]
    ct: float            # dF/d ddelta [N s/m]
    g: tuple
    ia: int
    ib: int
    kind: int            # 1 flank-flank, 2 gear-1 tip corner, 3 gear-2 tip corner; sign = side


class PairEquations:
    """Equations of motion of the pair with every tooth free (numpy, SI).

    DOFs x = [theta2, phi_0 .. phi_{N-1}] (gear-1 teeth first), velocities v likewise.
    """

    def __init__(self, model: Model, speed: float, speed_ramp: float, torque: float, torque_ramp: float,
                 load_table: np.ndarray | None = None):
        if model.coupled:
            raise ValueError("coupling.model: the scipy peer has no body-torsion coupling; use the explicit integrator")
        if np.any(model.gear_par[:, L.DEV_ON] > 0):
            raise ValueError("gearN.modification: the scipy peer has perfect involutes; use the explicit integrator")
        if model.pair_par.size > L.N_PAIR_PAR:
            raise ValueError("gearN.errors: the scipy peer has perfect gears; use the explicit integrator")
        if model.law_par[L.MU] > 0:
            raise ValueError("contact.friction: the scipy peer has frictionless flanks; use the explicit integrator")
        gp = model.gear_par
        self.model = model
        self.speed, self.speed_ramp = float(speed), float(speed_ramp)
        self.torque, self.torque_ramp = float(torque), float(torque_ramp)
        self.load_table = np.zeros((0, 2)) if load_table is None else np.asarray(load_table, float)
        self.z1, self.z2 = model.teeth
        self.nt = self.z1 + self.z2
        self.n = 1 + self.nt
        self.gp = gp
        self.pp = model.pair_par
        k, m1, c, m2, m3 = model.law_par[[L.K_CON, L.M1, L.C_CON, L.M2, L.M3]]
        self.law = (float(k), float(m1), float(c), float(m2), float(m3))
        self.kphi = np.asarray(model.k_phi, float)
        g_of = np.r_[np.zeros(self.z1, int), np.ones(self.z2, int)]
        self.nk = gp[g_of, L.N_K]
        self.cphi = gp[g_of, L.C_PHI]
        self.nc = gp[g_of, L.N_C]
        self.ip = gp[:, L.I_P]
        self.icpl = gp[:, L.I_CPL]
        self.itot = gp[:, L.I_TOT]
        # Schur complement of the driven gear's arrowhead mass matrix (all teeth free)
        self.s2 = self.itot[1] - self.z2 * self.icpl[1] ** 2 / self.ip[1]

    # -------------------------------------------------- contact search (pre-search + closed forms)
    def candidates(self, theta1: float, theta2: float):
        """(k, j, side) tooth pairs whose rigid roll parameters lie on the flanks (+ margin)."""
        gp, pp = self.gp, self.pp
        p1, p2 = gp[0, L.PITCH], gp[1, L.PITCH]
        ratio = gp[0, L.RB] / gp[1, L.RB]
        alpha, margin = pp[L.ALPHA], pp[L.MARGIN]
        out = []
        for s in (1, -1):
            lo = gp[0, L.U_LO] - margin - gp[0, L.PSI_B] - alpha
            hi = gp[0, L.U_HI] + margin - gp[0, L.PSI_B] - alpha
            if s < 0:
                lo, hi = -hi, -lo
            base = theta1 + gp[0, L.GAMMA0]
            for kk in range(math.ceil((lo - base) / p1), math.floor((hi - base) / p1) + 1):
                psi1 = base + kk * p1
                j_space = math.floor((math.pi - psi1 * ratio - theta2 - gp[1, L.GAMMA0]) / p2)
                j = (j_space if s > 0 else j_space + 1) % self.z2
                psi2 = theta2 + gp[1, L.GAMMA0] + j * p2
                ub = s * _wrap(psi2 - math.pi) + gp[1, L.PSI_B] + alpha
                if gp[1, L.U_LO] - margin <= ub <= gp[1, L.U_HI] + margin:
                    out.append((kk % self.z1, j, s))
        return out

    def contacts(self, theta1, theta2, phi, w1, w2, dphi) -> list[Contact]:
        """All contacts of the mesh in this state."""
        gp = self.gp
        jn_half = self.pp[L.JN_HALF]
        rba, rbb = gp[0, L.RB], gp[1, L.RB]
        o1x, o1y, o2x, o2y = gp[0, L.CX], gp[0, L.CY], gp[1, L.CX], gp[1, L.CY]
        te = rba * theta1 + rbb * theta2
        out = []
        for k, j, s in self.candidates(theta1, theta2):
            ia, ib = k, self.z1 + j
            pa, pb = phi[ia], phi[ib]
            if s * te - jn_half + abs(pa) * gp[0, L.R_BND] + abs(pb) * gp[1, L.R_BND] <= 0.0:
                continue                      # rigid gap bound: cannot touch
            axa = theta1 + gp[0, L.GAMMA0] + k * gp[0, L.PITCH]
            axb = theta2 + gp[1, L.GAMMA0] + j * gp[1, L.PITCH]
            ra, rb_ = gp[0, L.R_PV], gp[1, L.R_PV]
            # a tooth rotated about its pivot is an involute of a moved base circle
            cax = o1x + ra * (math.cos(axa) - math.cos(axa + pa))
            cay = o1y + ra * (math.sin(axa) - math.sin(axa + pa))
            cbx = o2x + rb_ * (math.cos(axb) - math.cos(axb + pb))
            cby = o2y + rb_ * (math.sin(axb) - math.sin(axb + pb))
            ba = axa + pa + s * gp[0, L.PSI_B]
            bb = axb + pb + s * gp[1, L.PSI_B]
            pvax, pvay = o1x + ra * math.cos(axa), o1y + ra * math.sin(axa)
            pvbx, pvby = o2x + rb_ * math.cos(axb), o2y + rb_ * math.sin(axb)
            vel = (w1, dphi[ia], w2, dphi[ib])
            delta, ua, ub, nx, ny, px, py = _flank_flank((cax, cay, rba, ba), (cbx, cby, rbb, bb), s)
            a_in = gp[0, L.U_LO] <= ua <= gp[0, L.U_HI]
            b_in = gp[1, L.U_LO] <= ub <= gp[1, L.U_HI]
            if a_in and b_in:
                if delta > 0.0:
                    g = (_cross(px - o1x, py - o1y, nx, ny), _cross(px - pvax, py - pvay, nx, ny),
                         -_cross(px - o2x, py - o2y, nx, ny), -_cross(px - pvbx, py - pvby, nx, ny))
                    out.append(self._contact(delta, g, vel, ia, ib, s))
                continue
            if ua > gp[0, L.U_HI]:            # tip corner of the gear-1 tooth on the gear-2 flank
                qx, qy = _tip_corner(cax, cay, rba, ba, s, gp[0, L.U_HI])
                d, uf, mx, my = _point_flank(qx, qy, cbx, cby, rbb, bb, s)
                if d > 0.0 and gp[1, L.U_LO] <= uf <= gp[1, L.U_HI]:
                    g = (-_cross(qx - o1x, qy - o1y, mx, my), -_cross(qx - pvax, qy - pvay, mx, my),
                         _cross(qx - o2x, qy - o2y, mx, my), _cross(qx - pvbx, qy - pvby, mx, my))
                    out.append(self._contact(d, g, vel, ia, ib, 2 * s))
            if ub > gp[1, L.U_HI]:            # tip corner of the gear-2 tooth on the gear-1 flank
                qx, qy = _tip_corner(cbx, cby, rbb, bb, s, gp[1, L.U_HI])
                d, uf, mx, my = _point_flank(qx, qy, cax, cay, rba, ba, s)
                if d > 0.0 and gp[0, L.U_LO] <= uf <= gp[0, L.U_HI]:
                    g = (_cross(qx - o1x, qy - o1y, mx, my), _cross(qx - pvax, qy - pvay, mx, my),
                         -_cross(qx - o2x, qy - o2y, mx, my), -_cross(qx - pvbx, qy - pvby, mx, my))
                    out.append(self._contact(d, g, vel, ia, ib, 3 * s))
        return out

    def _contact(self, delta, g, vel, ia, ib, kind) -> Contact:
        """Eq. (1.3) force, clipped at zero, and its tangents for one contact."""
        k, m1, c, m2, m3 = self.law
        dd = g[0] * vel[0] + g[1] * vel[1] + g[2] * vel[2] + g[3] * vel[3]
        f = k * delta ** m1
        kt = m1 * k * delta ** (m1 - 1.0)
        ct = 0.0
        if c != 0.0:
            sp = math.copysign(abs(dd) ** m2, dd)
            f += c * sp * delta ** m3
            kt += m3 * c * sp * delta ** (m3 - 1.0)
            ct = c * m2 * abs(dd) ** (m2 - 1.0) * delta ** m3 if (dd != 0.0 or m2 == 1.0) else 0.0
        if f <= 0.0:
            f, kt, ct = 0.0, 0.0, 0.0
        return Contact(delta, dd, f, kt, ct, g, ia, ib, kind)

    # -------------------------------------------------- forces, accelerations, energies
    def spring_torques(self, phi, dphi):
        """Eq. (1.2) torques on every tooth [N·m]."""
        el = self.kphi * np.sign(phi) * np.abs(phi) ** self.nk
        dm = self.cphi * np.sign(dphi) * np.abs(dphi) ** self.nc
        return -el - dm

    def state(self, t, x, v):
        th1, w1, a1 = driver_motion(t, self.speed, self.speed_ramp)
        if self.load_table.shape[0]:       # piecewise linear, held at the ends
            return th1, w1, a1, float(np.interp(t, self.load_table[:, 0], self.load_table[:, 1]))
        return th1, w1, a1, load_torque(t, self.torque, self.torque_ramp)

    def forces(self, t, x, v):
        """Generalised forces Q on the free DOFs, Q on theta1, and the contacts at time t."""
        th1, w1, a1, tl = self.state(t, x, v)
        phi, dphi = x[1:], v[1:]
        cons = self.contacts(th1, x[0], phi, w1, v[0], dphi)
        q = np.empty(self.n)
        q[0] = tl
        q[1:] = self.spring_torques(phi, dphi)
        q1 = 0.0
        for c in cons:
            q1 -= c.force * c.g[0]
            q[1 + c.ia] -= c.force * c.g[1]
            q[0] -= c.force * c.g[2]
            q[1 + c.ib] -= c.force * c.g[3]
        return q, q1, cons, a1

    def solve_mass(self, q, a1):
        """Accelerations from the arrowhead mass matrix; gear-1 teeth feel -I_cpl*theta1''."""
        z1 = self.z1
        a = np.empty(self.n)
        q2 = q[1 + z1:]
        a[0] = (q[0] - self.icpl[1] / self.ip[1] * q2.sum()) / self.s2
        a[1 + z1:] = (q2 - self.icpl[1] * a[0]) / self.ip[1]
        a[1:1 + z1] = (q[1:1 + z1] - self.icpl[0] * a1) / self.ip[0]
        return a

    def driver_torque(self, q1, a, a1):
        """Torque the driver applies [N·m]: I_tot1*theta1'' + I_cpl1*sum(phi'') - Q_theta1."""
        return self.itot[0] * a1 + self.icpl[0] * a[1:1 + self.z1].sum() - q1

    def dissipation_power(self, dphi, cons):
        """Power dissipated by the spring and contact dampers [W]."""
        p = float(np.sum(self.cphi * np.abs(dphi) ** self.nc * np.abs(dphi)))
        k, m1 = self.law[0], self.law[1]
        for c in cons:
            p += (c.force - k * c.delta ** m1) * c.ddelta
        return p

    def energies(self, t, x, v, cons):
        """(kinetic, potential) energy [J]."""
        _th1, w1, _a1, _tl = self.state(t, x, v)
        z1 = self.z1
        dphi, phi = v[1:], x[1:]
        ke = 0.5 * self.itot[0] * w1 ** 2 + 0.5 * self.itot[1] * v[0] ** 2
        ke += self.icpl[0] * w1 * dphi[:z1].sum() + 0.5 * self.ip[0] * np.dot(dphi[:z1], dphi[:z1])
        ke += self.icpl[1] * v[0] * dphi[z1:].sum() + 0.5 * self.ip[1] * np.dot(dphi[z1:], dphi[z1:])
        pe = float(np.sum(self.kphi * np.abs(phi) ** (self.nk + 1.0) / (self.nk + 1.0)))
        k, m1 = self.law[0], self.law[1]
        pe += sum(k * c.delta ** (m1 + 1.0) / (m1 + 1.0) for c in cons)
        return float(ke), pe

    # -------------------------------------------------- first-order system for solve_ivp
    def rhs(self, t, y):
        n = self.n
        x, v = y[:n], y[n:2 * n]
        q, q1, cons, a1 = self.forces(t, x, v)
        a = self.solve_mass(q, a1)
        _th1, w1, _a1, tl = self.state(t, x, v)
        dy = np.empty_like(y)
        dy[:n] = v
        dy[n:2 * n] = a
        dy[2 * n] = self.driver_torque(q1, a, a1) * w1 + tl * v[0]
        dy[2 * n + 1] = self.dissipation_power(v[1:], cons)
        return dy

    def tangents(self, phi, dphi, cons, spring_floor: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(dQ/dx [N·m/rad], dQ/dv [N·m·s/rad]) over x = [theta2, phi]: the springs' tangents
        and k_t G G^T, c_t G G^T of each contact (without the geometric stiffness F dG/dq).
        ``spring_floor`` [-]: that fraction of k_phi added to every spring tangent (a static
        solve regularises unloaded teeth with it: the tangent of n_k > 1 vanishes at 0)."""
        n = self.n
        dqdx = np.zeros((n, n))
        dqdv = np.zeros((n, n))
        a = np.abs(phi)
        kt = np.where(self.nk == 1.0, self.kphi, self.nk * self.kphi * np.where(a > 0, a, 0.0) ** (self.nk - 1.0))
        ad = np.abs(dphi)
        ct = np.where(self.nc == 1.0, self.cphi, self.nc * self.cphi * np.where(ad > 0, ad, 0.0) ** (self.nc - 1.0))
        idx = np.arange(1, n)
        dqdx[idx, idx] = -(kt + spring_floor * self.kphi)
        dqdv[idx, idx] = -ct
        for c in cons:
            dofs = (1 + c.ia, 0, 1 + c.ib)
            g = (c.g[1], c.g[2], c.g[3])
            for r in range(3):
                for s in range(3):
                    dqdx[dofs[r], dofs[s]] -= c.kt * g[r] * g[s]
                    dqdv[dofs[r], dofs[s]] -= c.ct * g[r] * g[s]
        return dqdx, dqdv

    def jac(self, t, y):
        """Analytic Jacobian of `rhs` (without the geometric stiffness F dG/dq)."""
        n = self.n
        x, v = y[:n], y[n:2 * n]
        th1, w1, a1, _tl = self.state(t, x, v)
        phi, dphi = x[1:], v[1:]
        cons = self.contacts(th1, x[0], phi, w1, v[0], dphi)
        dqdx, dqdv = self.tangents(phi, dphi, cons)
        J = np.zeros((2 * n + 2, 2 * n + 2))
        J[:n, n:2 * n] = np.eye(n)
        J[n:2 * n, :n] = self._minv_columns(dqdx)
        J[n:2 * n, n:2 * n] = self._minv_columns(dqdv)
        return J

    def _minv_columns(self, b):
        """M^-1 b for a matrix b (columns solved together; no driver term)."""
        z1 = self.z1
        out = np.empty_like(b)
        b2 = b[1 + z1:]
        out[0] = (b[0] - self.icpl[1] / self.ip[1] * b2.sum(axis=0)) / self.s2
        out[1 + z1:] = (b2 - self.icpl[1] * out[0]) / self.ip[1]
        out[1:1 + z1] = b[1:1 + z1] / self.ip[0]
        return out

"""Force laws of the paper, as numba kernels (SI units).

Torsion spring (eq. 1.2, T0 = 0, phi0 = 0):
    T = -k*sgn(phi)|phi|^n_k - c*sgn(dphi)|dphi|^n_c          [N m]
Contact (eq. 1.3), for delta > 0, clipped at zero (the damping term can pull otherwise):
    F = k*delta^m1 + c*sgn(ddelta)|ddelta|^m2 * delta^m3      [N]
"""
from solver.mbs.kernels import njit


@njit(cache=True, no_cfunc_wrapper=True)
def signed_pow(x, n):
    """sgn(x)|x|^n."""
    if n == 1.0:
        return x
    if x > 0.0:
        return x ** n
    if x < 0.0:
        return -((-x) ** n)
    return 0.0


@njit(cache=True, no_cfunc_wrapper=True)
def spring_torque(phi, dphi, k, n_k, c, n_c):
    """Torque on the tooth from its joint spring [N m]."""
    return -k * signed_pow(phi, n_k) - c * signed_pow(dphi, n_c)


@njit(cache=True, no_cfunc_wrapper=True)
def spring_tangent(phi, k, n_k):
    """d|T|/d phi of the elastic part [N m/rad]; 0 at phi = 0 when n_k > 1."""
    a = abs(phi)
    if n_k == 1.0:
        return k
    if a == 0.0:
        return 0.0
    return n_k * k * a ** (n_k - 1.0)


@njit(cache=True, no_cfunc_wrapper=True)
def spring_energy(phi, k, n_k):
    """Elastic energy of the spring [J]."""
    return k * abs(phi) ** (n_k + 1.0) / (n_k + 1.0)


@njit(cache=True, no_cfunc_wrapper=True)
def contact_force(delta, ddelta, k, m1, c, m2, m3):
    """Normal force [N] (>= 0) for penetration delta [m] and its rate [m/s]."""
    if delta <= 0.0:
        return 0.0
    f = k * delta ** m1
    if c != 0.0:
        f += c * signed_pow(ddelta, m2) * delta ** m3
    return f if f > 0.0 else 0.0


@njit(cache=True, no_cfunc_wrapper=True)
def contact_tangent(delta, k, m1):
    """dF/d delta of the elastic part [N/m]."""
    if delta <= 0.0:
        return 0.0
    if m1 == 1.0:
        return k
    return m1 * k * delta ** (m1 - 1.0)


@njit(cache=True, no_cfunc_wrapper=True)
def contact_energy(delta, k, m1):
    """Elastic energy stored in a contact [J]."""
    if delta <= 0.0:
        return 0.0
    return k * delta ** (m1 + 1.0) / (m1 + 1.0)


@njit(cache=True, no_cfunc_wrapper=True)
def spring_damping_tangent(dphi, c, n_c):
    """d|T_damping|/d dphi [N m s/rad]: c*n_c*|dphi|^(n_c-1).

    At rest it is 0 for n_c != 1 (infinite for n_c < 1: Newton then runs on the inertia and
    stiffness terms alone, the residual stays exact)."""
    if c == 0.0:
        return 0.0
    if n_c == 1.0:
        return c
    a = abs(dphi)
    if a == 0.0:
        return 0.0
    return c * n_c * a ** (n_c - 1.0)


@njit(cache=True, no_cfunc_wrapper=True)
def contact_damping_tangents(delta, ddelta, force, c, m2, m3):
    """Tangents of the damping term c*sgn(dd)|dd|^m2*delta^m3 of eq. (1.3).

    Returns (dF/d delta [N/m], dF/d ddelta [N s/m]); both 0 where the force is clipped at zero
    or the contact is open.
    """
    if delta <= 0.0 or force <= 0.0 or c == 0.0:
        return 0.0, 0.0
    sp = signed_pow(ddelta, m2)
    kd = m3 * c * sp * delta ** (m3 - 1.0) if m3 != 0.0 else 0.0
    a = abs(ddelta)
    if m2 == 1.0:
        cd = c * delta ** m3
    elif a == 0.0:
        cd = 0.0
    else:
        cd = c * m2 * a ** (m2 - 1.0) * delta ** m3
    return kd, cd

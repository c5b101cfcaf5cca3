"""Force laws of the paper, as numba kernels (SI units).

Torsion spring (eq. 1.2, T0 = 0, phi0 = 0):
    T = -k*sgn(phi)|phi|^n_k - c*sgn(dphi)|dphi|^n_c          [N m]
Contact (eq. 1.3), for delta > 0, clipped at zero (the damping term can pull otherwise):
    F = k*delta^m1 + c*sgn(ddelta)|ddelta|^m2 * delta^m3      [N]
"""
from numba import njit


@njit(cache=True)
def signed_pow(x, n):
    """sgn(x)|x|^n."""
    if n == 1.0:
        return x
    if x > 0.0:
        return x ** n
    if x < 0.0:
        return -((-x) ** n)
    return 0.0


@njit(cache=True)
def spring_torque(phi, dphi, k, n_k, c, n_c):
    """Torque on the tooth from its joint spring [N m]."""
    return -k * signed_pow(phi, n_k) - c * signed_pow(dphi, n_c)


@njit(cache=True)
def spring_tangent(phi, k, n_k):
    """d|T|/d phi of the elastic part [N m/rad]; 0 at phi = 0 when n_k > 1."""
    a = abs(phi)
    if n_k == 1.0:
        return k
    if a == 0.0:
        return 0.0
    return n_k * k * a ** (n_k - 1.0)


@njit(cache=True)
def spring_energy(phi, k, n_k):
    """Elastic energy of the spring [J]."""
    return k * abs(phi) ** (n_k + 1.0) / (n_k + 1.0)


@njit(cache=True)
def contact_force(delta, ddelta, k, m1, c, m2, m3):
    """Normal force [N] (>= 0) for penetration delta [m] and its rate [m/s]."""
    if delta <= 0.0:
        return 0.0
    f = k * delta ** m1
    if c != 0.0:
        f += c * signed_pow(ddelta, m2) * delta ** m3
    return f if f > 0.0 else 0.0


@njit(cache=True)
def contact_tangent(delta, k, m1):
    """dF/d delta of the elastic part [N/m]."""
    if delta <= 0.0:
        return 0.0
    if m1 == 1.0:
        return k
    return m1 * k * delta ** (m1 - 1.0)


@njit(cache=True)
def contact_energy(delta, k, m1):
    """Elastic energy stored in a contact [J]."""
    if delta <= 0.0:
        return 0.0
    return k * delta ** (m1 + 1.0) / (m1 + 1.0)

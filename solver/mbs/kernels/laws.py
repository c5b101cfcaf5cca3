"""Force laws of the paper, as numba kernels (SI units).

Torsion spring (eq. 1.2, T0 = 0, phi0 = 0):
    T = -k*sgn(phi)|phi|^n_k - c*sgn(dphi)|dphi|^n_c          [N m]
Contact (eq. 1.3), for delta > 0, clipped at zero (the damping term can pull otherwise):
    F = k*delta^m1 + c*sgn(ddelta)|ddelta|^m2 * delta^m3      [N]
Series contact (compliance model): the elastic part of eq. (1.3) in series with a linear local
compliance c_loc [m/N] (the tooth's own compliance that its rigid pivot misses), so that the
elastic force F_e solves
    delta = (F_e/k)^(1/m1) + c_loc*F_e,
tangent dF_e/d delta = 1/(1/(m1*k*delta_c^(m1-1)) + c_loc), energy k*delta_c^(m1+1)/(m1+1) +
c_loc*F_e^2/2 (delta_c = (F_e/k)^(1/m1), the contact law's own share). The damping term stays
on the whole penetration.
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


# a negative c_loc (the rigid tooth too soft there) is kept above this fraction of the contact
# law's own tangent compliance, so that F_e(delta) stays single-valued (never active for FE
# tooth data: |c_loc| is a tenth of the contact compliance at the rated load)
SERIES_NEG_LIMIT = 0.5


@njit(cache=True, no_cfunc_wrapper=True)
def series_contact(delta, c_loc, k, m1):
    """(delta_c [m], F_e [N], dF_e/d delta [N/m]) of the contact law in series with the local
    compliance c_loc [m/N] at the penetration delta [m] of both; c_loc = 0: the plain law,
    bit for bit. A scalar Newton on h(x) = x + c_loc*k*x^m1 - delta from x = delta: h is
    monotone and convex (c_loc > 0) or concave (c_loc < 0), so the iterates approach the root
    from one side; 3-4 steps for FE tooth data."""
    if delta <= 0.0:
        return delta, 0.0, 0.0
    if c_loc == 0.0:
        return delta, k * delta ** m1, contact_tangent(delta, k, m1)
    if m1 == 1.0:
        kt = 1.0 / (1.0 / k + c_loc)
        f = kt * delta
        return f / k, f, kt
    if c_loc < 0.0:
        # guard: c_loc above -SERIES_NEG_LIMIT times the law's compliance at delta
        c_loc = max(c_loc, -SERIES_NEG_LIMIT / (m1 * k * delta ** (m1 - 1.0)))
    x = delta
    for _ in range(60):
        f = k * x ** m1
        kx = m1 * f / x
        h = x + c_loc * f - delta
        dx = h / (1.0 + c_loc * kx)
        x -= dx
        if x <= 0.0:
            x = 1e-3 * delta
        # quadratic convergence: the step after one of 1e-8*delta would be below rounding
        if abs(dx) <= 1e-8 * delta:
            break
    f = k * x ** m1
    kx = m1 * f / x
    return x, f, 1.0 / (1.0 / kx + c_loc)


@njit(cache=True, no_cfunc_wrapper=True)
def series_energy(delta_c, c_loc, k, m1):
    """Elastic energy [J] of the series contact whose law's own penetration is delta_c [m]."""
    if delta_c <= 0.0:
        return 0.0
    f = k * delta_c ** m1
    return k * delta_c ** (m1 + 1.0) / (m1 + 1.0) + 0.5 * c_loc * f * f

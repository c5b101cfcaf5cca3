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
import math

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


# a negative c_loc (the rigid tooth too soft there) is kept so small that the series spring stays
# at most 1/(1 - SERIES_NEG_LIMIT) times as stiff as the contact law alone at its own penetration
# delta_c: 1 + c_loc*m1*k*delta_c^(m1-1) >= 1 - SERIES_NEG_LIMIT, so that F_e(delta) is single-valued
# and its tangent finite for every m1 (never active for FE tooth data: |c_loc| is a tenth of the
# contact compliance at the rated load)
SERIES_NEG_LIMIT = 0.5
# c_loc*k*delta^(m1-1)*m1 at that limit lies below this for every m1 > 1 (there y^(m1-1) <
# exp(SERIES_NEG_LIMIT), y = delta_c/delta): above it the limit needs no power to check
SERIES_NEG_CHECK = -SERIES_NEG_LIMIT * math.exp(-SERIES_NEG_LIMIT)
# the Halley iteration of `series_contact` stops where the error its last step leaves,
# C*(dy/y)^3 with C its error constant, is below 2^-56 (a sixteenth of a unit in the last place)
SERIES_TOL3 = 2.0 ** -56


@njit(cache=True, no_cfunc_wrapper=True)
def series_contact(delta, c_loc, k, m1):
    """(delta_c [m], F_e [N], dF_e/d delta [N/m]) of the contact law in series with the local
    compliance c_loc [m/N] at the penetration delta [m] of both; c_loc = 0: the plain law,
    bit for bit.

    Solved for the share y = delta_c/delta of the law: with a = c_loc*k*delta^(m1-1) (c_loc
    over the law's secant compliance at delta), h(y) = y - 1 + a*y^m1 = 0, h monotone and
    convex (a > 0) or concave (a < 0). Halley's iteration from y = 1, where y^(m1-1) = 1 is
    known, so that the first step costs no power; each further step one power y^(m1-1), whose
    h' and h'' come with it. It stops where the step's cubic convergence leaves an error below
    rounding (2-3 powers in all for FE tooth data, against 4-6 for Newton's iteration on
    delta_c with a final power), and F_e and the tangent at the last iterate follow from the
    power of the one before by their Taylor series in the last, small step. Within a few
    units in the last place of the exact root (`tests/solver/mbs/test_series_law.py`)."""
    if delta <= 0.0:
        return delta, 0.0, 0.0
    if c_loc == 0.0:
        return delta, k * delta ** m1, contact_tangent(delta, k, m1)
    if m1 == 1.0:
        kt = 1.0 / (1.0 / k + c_loc)
        f = kt * delta
        return f / k, f, kt
    b = m1 - 1.0
    kd = k * delta ** b              # the law's secant stiffness at delta [N/m]
    a = c_loc * kd
    am = a * m1
    if am < SERIES_NEG_CHECK:
        # the limit (SERIES_NEG_LIMIT): at its bound the root is known, y = m1/(m1 - limit)
        y = m1 / (m1 - SERIES_NEG_LIMIT)
        w = y ** b
        if am * w < -SERIES_NEG_LIMIT:
            c_loc = -SERIES_NEG_LIMIT / (m1 * kd * w)
            kx = m1 * kd * w
            return y * delta, kd * delta * y * w, kx / (1.0 + c_loc * kx)
    amb = am * b
    # Halley's error constant over |dy/y|^3, bounded for any a the guard lets pass
    c3 = 0.25 * b * b + abs(b * (b - 1.0)) / 6.0
    y = 1.0
    w = 1.0                          # y^b
    for _ in range(60):
        h = (y - 1.0) + a * y * w    # (y - 1) exact near the root: no rounding of 1 + a - 1
        hp = 1.0 + am * w
        hp2y = hp * hp * y
        den = 2.0 * hp2y - h * amb * w
        if den >= hp2y:
            dy = 2.0 * h * hp * y / den     # Halley: (h/h')/(1 - h h''/(2 h'^2)), h'' = a m1 b w/y
        else:
            dy = h / hp                     # Newton where Halley's factor would exceed 2
        if c3 * dy * dy * abs(dy) <= SERIES_TOL3 * y * y * y:
            # the last step, and the powers at its end by their Taylor series in r = -dy/y to
            # r^3 (the next terms, r^4 times coefficients of the order of c3, below 1e-19)
            r = -dy / y
            fm = 1.0 + r * (m1 + r * (0.5 * m1 * b * (1.0 + r * (b - 1.0) / 3.0)))
            fb = 1.0 + r * (b + r * (0.5 * b * (b - 1.0) * (1.0 + r * (b - 2.0) / 3.0)))
            kx = m1 * kd * w * fb
            return (y - dy) * delta, kd * delta * y * w * fm, kx / (1.0 + c_loc * kx)
        yn = y - dy
        y = yn if yn > 0.0 else 1e-3 * y
        w = y ** b
    kx = m1 * kd * w
    return y * delta, kd * delta * y * w, kx / (1.0 + c_loc * kx)


@njit(cache=True, no_cfunc_wrapper=True)
def series_energy(delta_c, c_loc, k, m1):
    """Elastic energy [J] of the series contact whose law's own penetration is delta_c [m]."""
    if delta_c <= 0.0:
        return 0.0
    f = k * delta_c ** m1
    return k * delta_c ** (m1 + 1.0) / (m1 + 1.0) + 0.5 * c_loc * f * f

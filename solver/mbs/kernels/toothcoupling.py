"""Teeth coupled through the body: tooth springs from a compliance matrix (numba).

The compliance model (`solver.identify.coupling.tooth_compliance_fit`) gives the tooth rotations
[rad] under moments on the tooth springs [N m]: phi = C M, C (teeth x teeth) symmetric
positive definite [rad/(N m)], block-diagonal by gear. The teeth outside a set S (the teeth
near the mesh) carry no load, so the moments of the teeth in S follow from their rotations
alone:

    M_S = K_S phi_S,   K_S = (C[S, S])^-1

exactly, whatever the rotations of the unloaded teeth. The kernels keep S small (the
candidates of the contact pre-search), so K_S is a few teeth square and is rebuilt only when
S changes. ``lst[:n]`` holds the tooth indices of S; ``ks[:n, :n]`` its stiffness.
"""
from numba import njit


@njit(cache=True)
def set_stiffness(ctooth, lst, n, ks):
    """ks[:n, :n] = inverse of ctooth[lst[:n], lst[:n]] (Gauss-Jordan; C is SPD, no pivoting
    needed). Uses ks[:n, n:2n] as scratch, so ks needs at least 2n columns."""
    for a in range(n):
        for b in range(n):
            ks[a, b] = ctooth[lst[a], lst[b]]
            ks[a, n + b] = 1.0 if a == b else 0.0
    for k in range(n):
        piv = ks[k, k]
        for j in range(2 * n):
            ks[k, j] /= piv
        for i in range(n):
            if i != k:
                f = ks[i, k]
                if f != 0.0:
                    for j in range(2 * n):
                        ks[i, j] -= f * ks[k, j]
    for a in range(n):
        for b in range(n):
            ks[a, b] = ks[a, n + b]


@njit(cache=True)
def set_moment(ks, lst, n, phi, a):
    """Elastic moment [N m] on the a-th tooth of the set: (K_S phi_S)[a] (its spring pushes
    back with minus this)."""
    s = 0.0
    for b in range(n):
        s += ks[a, b] * phi[lst[b]]
    return s


@njit(cache=True)
def set_energy(ks, lst, n, phi):
    """Strain energy [J] of the set's springs: phi_S^T K_S phi_S / 2."""
    e = 0.0
    for a in range(n):
        e += 0.5 * phi[lst[a]] * set_moment(ks, lst, n, phi, a)
    return e

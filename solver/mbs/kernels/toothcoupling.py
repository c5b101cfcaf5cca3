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

The stepping loop keeps S in ``cset`` (`layout.CoupledSet`, from `coupled_set`, in the loop's
work arrays): C the compliance, ``ks`` and ``lst`` as above, ``newl`` the next set's teeth,
``inset``/``innew`` per-tooth 0/1 flags of the current and the next set, ``mo``/``dmo``
scratch moments.
"""
import numpy as np

from solver.mbs.kernels import njit
from solver.mbs.kernels.layout import MAX_CONTACTS, CoupledSet


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
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


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True, inline="always")
def set_moment(ks, lst, n, phi, a):
    """Elastic moment [N m] on the a-th tooth of the set: (K_S phi_S)[a] (its spring pushes
    back with minus this)."""
    s = 0.0
    for b in range(n):
        s += ks[a, b] * phi[lst[b]]
    return s


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def set_energy(ks, lst, n, phi):
    """Strain energy [J] of the set's springs: phi_S^T K_S phi_S / 2."""
    e = 0.0
    for a in range(n):
        e += 0.5 * phi[lst[a]] * set_moment(ks, lst, n, phi, a)
    return e


def coupled_set(ctooth):
    """Work arrays ``cset`` of the coupled set for the compliance ctooth (teeth x teeth, or
    0 x 0: no coupled teeth, empty arrays). The set holds at most both teeth of every
    candidate pair. Plain Python (`stepping.work_arrays` allocates it for the loop)."""
    ntooth = ctooth.shape[0]
    ms = 2 * MAX_CONTACTS if ntooth > 0 else 0
    return CoupledSet(ctooth, np.zeros((ms, 2 * ms)), np.zeros(ms, dtype=np.int64), np.zeros(ms, dtype=np.int64),
                      np.zeros(ntooth, dtype=np.int64), np.zeros(ntooth, dtype=np.int64), np.zeros(ms), np.zeros(ms))


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def set_differs(cset, ns, nn):
    """Whether newl[:nn] differs from the current set (ns teeth)."""
    newl, inset = cset.newl, cset.inset
    if nn != ns:
        return True
    for a in range(nn):
        if not inset[newl[a]]:
            return True
    return False


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def update_set(cset, ns, nn, phi, dphi, vpred):
    """Make newl[:nn] the coupled set (``inset`` flags the old members, ns of them): teeth that
    join take their neighbours' share of rotation phi [rad] and of the rates dphi, vpred
    [rad/s]; teeth that leave give it back (see the module docstring of `explicit_coupled`
    for what stays continuous). Returns the new size."""
    ctooth, ks, slst, newl, inset, innew, mo, dmo = cset
    for a in range(nn):
        innew[newl[a]] = True
    same = nn == ns
    if same:
        for a in range(ns):
            if not innew[slst[a]]:
                same = False
                break
    if not same:
        for a in range(ns):
            mo[a] = set_moment(ks, slst, ns, phi, a)
            dmo[a] = set_moment(ks, slst, ns, vpred, a)
        for a in range(ns):                     # leaving
            i = slst[a]
            if not innew[i]:
                for b in range(ns):
                    j = slst[b]
                    if j != i:
                        phi[i] -= ctooth[i, j] * mo[b]
                        dphi[i] -= ctooth[i, j] * dmo[b]
                        vpred[i] -= ctooth[i, j] * dmo[b]
                inset[i] = False
        for a in range(nn):                     # joining
            i = newl[a]
            if not inset[i]:
                for b in range(ns):
                    j = slst[b]
                    phi[i] += ctooth[i, j] * mo[b]
                    dphi[i] += ctooth[i, j] * dmo[b]
                    vpred[i] += ctooth[i, j] * dmo[b]
        for a in range(nn):
            slst[a] = newl[a]
            inset[newl[a]] = True
        set_stiffness(ctooth, slst, nn, ks)
        ns = nn
    for a in range(nn):
        innew[newl[a]] = False
    return ns


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def set_springs(cset, ns, kphi, phi, q):
    """Replace the own elastic spring torque of the set's teeth in q[2 + i] by the coupled one."""
    ks, slst = cset.ks, cset.lst
    for a in range(ns):
        i = slst[a]
        q[2 + i] += kphi[i] * phi[i] - set_moment(ks, slst, ns, phi, a)

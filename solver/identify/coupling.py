"""Foundation coupling of the pseudo-rigid model: a body-torsion spring per gear, and the
full version with the tooth springs coupled through the body's compliance.

The per-tooth spring fitted to a bore-clamped FE body holds the wind-up of the whole body,
which all loaded teeth share. Put into every tooth spring, it is counted once per tooth, so
in double contact the body is effectively twice as stiff as it is. The body-torsion model
splits it off: hub -> body torsion spring k_body -> rigid rim -> tooth springs k_tooth.

Identification from the FE influence coefficients at the pitch point (`solver.fe.ltca`,
displacement along the line of action read at the tooth centreline, [m/N]):

* c_total[a]: a tooth's own compliance (the plain model's spring: k_fe = lever**2 / c_total);
* c_adjacent[a]: the mean compliance of tooth a under a load on its two neighbours. In
  double contact the two loaded teeth are neighbours, so this is the compliance they share;
  c_body = mean over the teeth of c_adjacent, k_body = rb**2 / c_body [N·m/rad];
* k_tooth[a] = lever**2 / (c_total[a] - c_body) [N·m/rad]: the tooth spring without the
  body wind-up.

The body wind-up is a rotation about the gear centre (lever rb whatever the contact point),
the tooth's own deflection a rotation about a point low in the tooth. So once the body part is
split off, the tooth's pivot is refitted to the remaining compliance along the profile
(`solver.identify.pivot.fit_pivot`; about 1 mm below the root circle for Table 1): the fit's
stiffness is tooth 0's spring, the other teeth scale it by their pitch-point tooth compliance.
Against the FE reference (Table 1, 50 N·m) this halves the STE error of a root-circle pivot.

With k_body -> infinity and k_tooth = k_fe the coupled model is the plain one.

The full version (`tooth_compliance_fit`): a load on one tooth also turns its neighbours
through rim and web, and by how much depends on where the holes are. The body spring stays;
the tooth springs become one compliance matrix C over the teeth (tooth rotation per tooth
moment), fitted with c_body and the pivot to the FE influence coefficients at the points where
the mesh loads the teeth together (a tooth's own contact point; neighbours at their
simultaneous contact points). Where a local compliance in series with the contact completes
each tooth's own compliance along the profile (`local_compliance`), the pivot and c_body come
from the samples between different teeth alone (``own_completed``). The kernels use it through
`kernels.toothcoupling`.
Units: SI.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BodyTorsionFit:
    k_body: float            # body torsion stiffness hub -> rim [N·m/rad]
    c_body: float            # the same as a compliance along the line of action [m/N]
    k_tooth: np.ndarray      # (Z,) tooth springs without the body wind-up [N·m/rad]
    k_total: np.ndarray      # (Z,) tooth springs with it (the plain model's FE springs) [N·m/rad]
    c_total: np.ndarray      # (Z,) own compliance at the pitch point [m/N]
    c_adjacent: np.ndarray   # (Z,) compliance under the neighbours' loads [m/N]
    pivot_radius: float      # tooth pivot the levers are taken about [m]


def body_torsion_fit(c_total, c_adjacent, lever: float, base_radius: float,
                     pivot_radius: float = float("nan"), k_profile: float | None = None) -> BodyTorsionFit:
    """Body and tooth springs from the own and adjacent pitch-point compliances [m/N] of every
    tooth, the pitch-point load lever about the tooth pivot [m] (at ``pivot_radius`` [m]) and the
    base radius [m]. ``k_profile`` [N·m/rad]: tooth 0's spring from the fit along its profile;
    the other teeth then scale it by their pitch-point tooth compliance (else each tooth's
    spring matches its pitch-point compliance exactly)."""
    c_total = np.asarray(c_total, float)
    c_adjacent = np.asarray(c_adjacent, float)
    if c_total.shape != c_adjacent.shape or c_total.ndim != 1:
        raise ValueError("c_total and c_adjacent: need one value per tooth")
    if not np.all(c_total > 0):
        raise ValueError("c_total: tooth compliance must be positive")
    c_body = float(np.mean(c_adjacent))
    if not 0 < c_body < c_total.min():
        raise ValueError(f"body compliance {c_body:.4g} m/N is not between 0 and the smallest tooth compliance {c_total.min():.4g} m/N")
    c_tooth = c_total - c_body
    k_tooth = lever**2 / c_tooth if k_profile is None else k_profile * c_tooth[0] / c_tooth
    return BodyTorsionFit(base_radius**2 / c_body, c_body, k_tooth, lever**2 / c_total,
                          c_total, c_adjacent, pivot_radius)


def body_windup(torque: float, base_radii, k_body) -> float:
    """Static TE added by the body springs [m] under ``torque`` [N·m] on gear 2 (flank contact:
    the driver carries torque*rb1/rb2): rb1*M1/k_body1 + rb2*T/k_body2."""
    rb1, rb2 = base_radii
    return rb1 * (torque * rb1 / rb2) / k_body[0] + rb2 * torque / k_body[1]


@dataclass(frozen=True)
class ToothComplianceFit:
    """The compliance model of one gear body (`tooth_compliance_fit`)."""

    k_body: float            # body torsion stiffness hub -> rim [N·m/rad]
    c_body: float            # the same as a compliance along the line of action [m/N]
    compliance: np.ndarray   # (Z, Z) tooth rotation per tooth moment, C[a, b] [rad/(N·m)]
    pivot_radius: float      # tooth pivot [m]
    reach: int               # teeth up to this many pitches apart are coupled [-]
    rms_rel_error: float     # RMS relative residual of the fitted influence coefficients [-]
    # local compliance in series with the contact (`local_compliance`): rolls [-] and c_loc [m/N]
    local_u: np.ndarray | None = None
    local_compliance: np.ndarray | None = None

    @property
    def k_own(self) -> np.ndarray:
        """(Z,) each tooth's spring when it alone is loaded, 1/C[a, a] [N·m/rad]."""
        return 1.0 / np.diag(self.compliance)


def _linear_fit(sample_pair, n_pairs, LL, value, weight, shared):
    """For levers fixed (LL = lever_read*lever_load [m^2]): the weighted least-squares c_body
    [m/N] and C of every pair [rad/(N·m)] (the model is linear in them), and the weighted sum
    of squared relative residuals. C_p = A_p - c_body*B_p eliminates the pairs (each pair's C
    from its own samples); c_body is then one linear fit to the ``shared`` samples (bool mask,
    which also make the returned residual), held at or below the smallest coefficient (the
    objective is convex in it, so the bound is the constrained optimum): the body part is what
    every loaded pair shares, and the local part never pulls a neighbour back."""
    w = weight / value**2
    den = np.bincount(sample_pair, w * LL * LL, n_pairs)
    A = np.bincount(sample_pair, w * value * LL, n_pairs) / den
    B = np.bincount(sample_pair, w * LL, n_pairs) / den
    e = 1.0 - B[sample_pair] * LL                  # d residual / d c_body
    f = A[sample_pair] * LL - value                # residual at c_body = 0
    ws = np.where(shared, w, 0.0)
    c_body = min(-np.sum(ws * e * f) / np.sum(ws * e * e), float(value.min()))
    r = c_body * e + f
    return c_body, A - c_body * B, float(np.sum(ws * r * r))


@dataclass(frozen=True)
class InfluenceSamples:
    """FE influence coefficients to fit, k = 0..N-1: ``value[k]`` [m/N], the displacement along
    the line of action at roll parameter ``u_read[k]`` of tooth ``pairs[sample_pair[k], 0]``
    under a unit load at ``u_load[k]`` of tooth ``pairs[sample_pair[k], 1]``, at the points the
    mesh loads together (a tooth's own block at its contact point, neighbours at their
    simultaneous contact points); ``weight[k]`` [1] (default 1): how much load the mesh puts
    there."""
    pairs: np.ndarray
    sample_pair: np.ndarray
    u_read: np.ndarray
    u_load: np.ndarray
    value: np.ndarray
    weight: np.ndarray | None = None

    def checked(self) -> tuple:
        """(pairs, sample_pair, u_read, u_load, value, weight) as arrays; ValueError naming what
        is wrong."""
        pairs = np.asarray(self.pairs, int)
        sample_pair = np.asarray(self.sample_pair, int)
        u_read, u_load, value = (np.asarray(x, float) for x in (self.u_read, self.u_load, self.value))
        n = value.size
        if pairs.ndim != 2 or pairs.shape[1] != 2:
            raise ValueError(f"pairs: need (pairs, 2) tooth indices, got shape {pairs.shape}")
        if not (sample_pair.shape == u_read.shape == u_load.shape == (n,)) or n == 0:
            raise ValueError("samples: sample_pair, u_read, u_load and value need the same length, at least 1")
        if sample_pair.min() < 0 or sample_pair.max() >= len(pairs) or np.bincount(sample_pair, minlength=len(pairs)).min() == 0:
            raise ValueError("sample_pair: every pair needs at least one sample, and only listed pairs")
        if not np.all(value > 0):
            raise ValueError("value: influence coefficients along the load must be positive")
        weight = np.ones(n) if self.weight is None else np.asarray(self.weight, float)
        if weight.shape != (n,) or not np.all(weight >= 0) or np.bincount(sample_pair, weight, len(pairs)).min() <= 0:
            raise ValueError("weight: need one non-negative weight per sample, and a positive one in every pair")
        return pairs, sample_pair, u_read, u_load, value, weight


def tooth_compliance_fit(samples: InfluenceSamples, teeth: int, base_radius: float, psi_base: float,
                         pivot_bounds: tuple, own_completed: bool = False) -> ToothComplianceFit:
    """The full foundation coupling, identified from FE influence coefficients.

    ``samples``: the influence coefficients (`InfluenceSamples`) of a gear of ``teeth`` teeth,
    base radius ``base_radius`` [m] and half base tooth angle ``psi_base`` [rad]. The model of a
    sample is

        c_body + lever(u_read) * lever(u_load) * C[a, b],

    the body wind-up (a rotation about the gear centre, lever rb: the same along the line of
    action wherever the contact) plus the teeth's rotations about the pivot (levers about the
    pivot at radius r_Q). For a given r_Q the model is linear in c_body and the C of every
    pair (one least-squares solve on the relative residuals, each sample's squared residual
    times its weight); r_Q minimises
    that residual within ``pivot_bounds`` [m] (the rim under the tooth; a bounded scalar
    search). ``rms_rel_error`` is the weighted RMS relative residual. Pairs not
    listed are not coupled (C = 0): the mesh never loads them together.

    ``own_completed``: each tooth's own compliance along the profile is completed by a local
    compliance in series with the contact (`local_compliance`), which makes the own samples
    (read tooth = load tooth) exact whatever the fit. They then set only their C[a, a], and the
    shared pivot and c_body are fitted to the samples between different teeth, the coupling
    through rim and web that nothing else corrects (with no such samples, to all). Fitted to
    all samples instead, the pivot follows the own compliance's bending shape (near the root
    circle), and the coupling's levers grow towards the tip where the FE's neighbour
    coupling stays nearly flat: the model is too stiff in double contact. Raises ValueError
    when the fit is not a valid stiffness (a window of reach + 2 neighbouring teeth not
    positive definite).
    """
    from scipy.optimize import minimize_scalar

    pairs, sample_pair, u_read, u_load, value, weight = samples.checked()
    n = value.size
    lo, hi = pivot_bounds
    if not 0 < lo < hi:
        raise ValueError(f"pivot_bounds: need 0 < lower < upper, got {pivot_bounds}")
    P = len(pairs)
    cos_r, cos_l = np.cos(psi_base - u_read), np.cos(psi_base - u_load)
    own = (pairs[:, 0] - pairs[:, 1]) % teeth == 0
    shared = ~own[sample_pair] if own_completed else np.ones(n, bool)
    if not np.any(shared & (weight > 0)):
        shared = np.ones(n, bool)

    def fit(r_q):       # levers about the pivot (identify.lever), r_q [m]
        LL = np.abs(base_radius - r_q * cos_r) * np.abs(base_radius - r_q * cos_l)
        return _linear_fit(sample_pair, P, LL, value, weight, shared)

    res = minimize_scalar(lambda x: fit(x * 1e-3)[2], bounds=(lo * 1e3, hi * 1e3), method="bounded",
                          options=dict(xatol=1e-6))
    r_q = float(res.x) * 1e-3
    c_body, c, j = fit(r_q)
    if not c_body > 0:
        raise ValueError(f"value: fitted body compliance {c_body:.4g} m/N is not positive")
    C, reach = _compliance_matrix(pairs, c, teeth)
    return ToothComplianceFit(base_radius**2 / c_body, c_body, C, r_q, reach, float(np.sqrt(j / weight[shared].sum())))


def _compliance_matrix(pairs: np.ndarray, c: np.ndarray, teeth: int) -> tuple[np.ndarray, int]:
    """(the symmetric tooth compliance matrix [m/N] of the fitted ``c`` of each pair, the
    farthest pair's reach in teeth); ValueError where it is no valid stiffness (a window of
    reach + 2 neighbouring teeth not positive definite)."""
    d = pairs[:, 1] - pairs[:, 0]
    reach = int(np.minimum(d % teeth, (-d) % teeth).max())
    C = np.zeros((teeth, teeth))
    C[pairs[:, 0] % teeth, pairs[:, 1] % teeth] = c
    C = 0.5 * (C + C.T)
    if np.any(np.diag(C) <= 0):
        raise ValueError("value: a tooth's fitted compliance is not positive")
    w = min(reach + 2, teeth)
    for a in range(teeth):
        idx = (a + np.arange(w)) % teeth
        try:
            np.linalg.cholesky(C[np.ix_(idx, idx)])
        except np.linalg.LinAlgError:
            raise ValueError(f"value: the fitted compliance of teeth {a}..{a + w - 1} is not positive "
                             "definite (not a valid stiffness)") from None
    return C, reach


def local_compliance(fit: ToothComplianceFit, u, own, base_radius: float, psi_base: float) -> np.ndarray:
    """The tooth compliance [m/N] along the profile that the rigid tooth on its pivot misses:
    c_loc(u) = own(u) - c_body - lever(u)**2 * C[a, a], averaged over the teeth a (one table
    per gear). ``u``: rolls [-] of the profile grid, ``own``: (teeth, n_u) or (n_u,) FE
    compliance [m/N] of each tooth at u under its own load there. In series with the contact
    law (`solver.mbs.kernels.laws.series_contact`) a single loaded tooth then has the FE
    compliance at every profile point. Signed: the best single pivot is too soft at
    mid-profile (c_loc < 0 there, a few 1e-11 m/N, a tenth of the contact law's own
    compliance at the rated load, so the series spring stays monotone) and too stiff towards
    the tip."""
    u = np.asarray(u, float)
    own = np.atleast_2d(np.asarray(own, float))
    if own.shape[1] != u.size:
        raise ValueError(f"own: need {u.size} values per tooth (one per roll), got shape {own.shape}")
    lev = np.abs(base_radius - fit.pivot_radius * np.cos(psi_base - u))
    caa = np.diag(fit.compliance)[: own.shape[0]]
    return np.mean(own - fit.c_body - lev[None, :] ** 2 * caa[:, None], axis=0)

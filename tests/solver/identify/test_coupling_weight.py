"""The compliance fit's sample weights: where the mesh carries no load, the FE data do not
pull the fitted body and tooth compliance."""
import numpy as np
import pytest

from solver.identify.coupling import InfluenceSamples, tooth_compliance_fit
from solver.identify.pivot import lever

RB, PSI_B, Z = 0.047, 0.05, 6
C_BODY, R_Q = 1.3e-9, 0.0465


def samples(corrupt: float):
    """Samples of the body-tooth model itself (three teeth coupled), the own compliance at the
    two highest profile points made ``corrupt`` times larger (a shape the rigid tooth cannot
    follow), and a mask of those samples."""
    C = np.zeros((Z, Z))
    for a in range(Z):
        C[a, a] = 1 / 4000.0
        for d, c in ((1, 0.1), (2, 0.02)):
            C[a, (a + d) % Z] = C[(a + d) % Z, a] = c / 4000.0
    u = np.linspace(0.25, 0.45, 7)
    pairs, sp, ur, ul, val, bad = [], [], [], [], [], []
    for a in range(Z):
        for d in (-2, -1, 0, 1, 2):
            uu = np.column_stack([u, u]) if d == 0 else np.array([(x, y) for x in u for y in u])
            sp.append(np.full(len(uu), len(pairs)))
            pairs.append((a, (a + d) % Z))
            ur.append(uu[:, 0])
            ul.append(uu[:, 1])
            L = lever(RB, PSI_B - uu[:, 0], R_Q) * lever(RB, PSI_B - uu[:, 1], R_Q)
            b = (d == 0) & (uu[:, 0] > 0.41)
            val.append((C_BODY + L * C[a, (a + d) % Z]) * np.where(b, corrupt, 1.0))
            bad.append(b)
    cat = np.concatenate
    return np.array(pairs), cat(sp), cat(ur), cat(ul), cat(val), C, cat(bad)


def test_samples_without_weight_do_not_pull_the_fit():
    pairs, sp, ur, ul, val, C, bad = samples(1.2)
    fit = lambda w: tooth_compliance_fit(InfluenceSamples(pairs, sp, ur, ul, val, w), Z, RB, PSI_B, (0.044, 0.048))  # noqa: E731
    free = fit(np.where(bad, 0.0, 1.0))
    assert free.c_body == pytest.approx(C_BODY, rel=1e-6)
    assert free.pivot_radius == pytest.approx(R_Q, rel=1e-5)
    assert free.compliance == pytest.approx(C, rel=1e-5, abs=1e-12)
    assert free.rms_rel_error < 1e-6
    # weighted equally, the corrupted tip samples move the pivot and leave a residual
    equal = fit(None)
    assert abs(equal.pivot_radius - R_Q) > 1e-5 and equal.rms_rel_error > 1e-3


def test_bad_weights_are_refused():
    pairs, sp, ur, ul, val, _, _ = samples(1.0)
    for w in (np.ones(val.size - 1), -np.ones(val.size), np.where(sp == 0, 0.0, 1.0)):
        with pytest.raises(ValueError, match="weight"):
            tooth_compliance_fit(InfluenceSamples(pairs, sp, ur, ul, val, w), Z, RB, PSI_B, (0.044, 0.048))


def test_own_samples_completed_in_series_leave_the_pivot_to_the_coupling():
    """Own compliance of a bending shape no rigid tooth follows (every own sample reshaped
    along the profile): with ``own_completed`` (a local compliance in series makes the own
    samples exact) the pivot, c_body and the neighbour coupling are recovered exactly from the
    samples between different teeth, and the own samples set only C[a, a]; fitted to all
    samples, the own shape drags the pivot and spoils the coupling."""
    pairs, sp, ur, ul, val, C, _ = samples(1.0)
    own = (pairs[sp, 0] == pairs[sp, 1])
    bent = val * np.where(own, 1.0 + 2.0 * (ur - 0.25) ** 2, 1.0)       # softer towards the tip
    fit = lambda **k: tooth_compliance_fit(InfluenceSamples(pairs, sp, ur, ul, bent), Z, RB, PSI_B, (0.044, 0.048), **k)  # noqa: E731
    done = fit(own_completed=True)
    assert done.pivot_radius == pytest.approx(R_Q, rel=1e-5)
    assert done.c_body == pytest.approx(C_BODY, rel=1e-6)
    off = ~np.eye(Z, dtype=bool)
    assert done.compliance[off] == pytest.approx(C[off], rel=1e-5, abs=1e-12)
    assert done.rms_rel_error < 1e-6                     # the residual is the coupling's: none
    # each C[a, a]: the least-squares fit of its own (bent) samples at that pivot
    L = lever(RB, PSI_B - ur, R_Q) ** 2
    s0 = sp == next(i for i, (a, b) in enumerate(pairs) if a == b == 0)
    w = 1.0 / bent[s0] ** 2
    c00 = np.sum(w * L[s0] * (bent[s0] - C_BODY)) / np.sum(w * L[s0] ** 2)
    assert done.compliance[0, 0] == pytest.approx(c00, rel=1e-6)
    plain = fit()
    assert abs(plain.pivot_radius - R_Q) > 1e-5
    assert np.max(np.abs(plain.compliance[off] - C[off])) > 1e-3 * C[0, 1]

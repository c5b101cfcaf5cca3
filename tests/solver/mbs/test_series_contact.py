"""The contact law in series with a local tooth compliance (compliance model): the scalar law
against its closed form, and the mesh forces it gives against the energy they derive from."""
import dataclasses

import numpy as np
import pytest
from helpers import assert_forces_are_minus_the_energy_gradient, loaded_mesh_state
from scipy.integrate import quad

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.laws import contact_energy, contact_tangent, series_contact, series_energy
from solver.mbs.model import sample_local_compliance

K, M1 = 2.96e10, 1.24     # N/m^1.24: the paper's 5.64e6 N/mm^1.24


@pytest.mark.parametrize("c_loc", [4e-10, 1e-9, -6e-11])
def test_series_law_against_its_closed_form(c_loc):
    """Pick the force, build the penetration delta = (F/k)^(1/m1) + c_loc*F in closed form: the
    law gives back the force, the tangent 1/(1/(m1 k dc^(m1-1)) + c_loc) equals dF/d delta
    by differences, and the energy is the integral of F d delta."""
    series, energy = series_contact.py_func, series_energy.py_func
    for f_ref in (10.0, 500.0, 3000.0):
        dc_ref = (f_ref / K) ** (1 / M1)
        delta = dc_ref + c_loc * f_ref
        dc, f, kt = series(delta, c_loc, K, M1)
        assert f == pytest.approx(f_ref, rel=1e-12)
        assert dc == pytest.approx(dc_ref, rel=1e-12)
        assert kt == pytest.approx(1 / (1 / (M1 * K * dc_ref ** (M1 - 1)) + c_loc), rel=1e-12)
        h = 1e-6 * delta
        fd = (series(delta + h, c_loc, K, M1)[1] - series(delta - h, c_loc, K, M1)[1]) / (2 * h)
        assert kt == pytest.approx(fd, rel=1e-6)
        e, _ = quad(lambda d: series(d, c_loc, K, M1)[1], 0.0, delta, epsabs=0, epsrel=1e-11, limit=200)
        assert energy(dc, c_loc, K, M1) == pytest.approx(e, rel=1e-8)
        # in series with a positive compliance the contact is softer, with a negative one stiffer
        assert (f < K * delta**M1) == (c_loc > 0)
    # the compiled law is the same
    assert series_contact(2e-6, c_loc, K, M1) == pytest.approx(series(2e-6, c_loc, K, M1), rel=1e-14)


def test_series_law_without_compliance_is_the_plain_law_and_linear_law_closed_form():
    for d in (1e-9, 2e-6, 7e-6):
        dc, f, kt = series_contact(d, 0.0, K, M1)
        assert (dc, f, kt) == (d, K * d**M1, contact_tangent(d, K, M1))
        assert series_energy(d, 0.0, K, M1) == contact_energy(d, K, M1)
    assert series_contact(-1e-7, 1e-9, K, M1)[1:] == (0.0, 0.0)
    # m1 = 1: two linear springs in series
    k = 1e9
    dc, f, kt = series_contact(3e-6, 1e-9, k, 1.0)
    assert kt == pytest.approx(0.5e9) and f == pytest.approx(1500.0) and dc == pytest.approx(1.5e-6)


def _with_local_compliance(m, scale=1.0):
    """The model with a local compliance on both gears that grows from -5e-11 to 1e-9 m/N
    (times ``scale``) along the profile, steeply near the tip as a tooth's bending does."""
    gp = m.gear_par.copy()
    for g in range(2):
        u = np.linspace(gp[g, L.U_LO], gp[g, L.U_HI], 8)
        x = (u - u[0]) / (u[-1] - u[0])
        sample_local_compliance((u, scale * (-5e-11 + 1.05e-9 * x**3)), gp[g, L.U_LO], gp[g, L.U_HI], gp[g], "gear")
    return dataclasses.replace(m, gear_par=gp)


@pytest.mark.parametrize("angle_deg", [1.0, 2.0, 5.1])
def test_series_mesh_forces_are_minus_the_energy_gradient(paper_solid_model, angle_deg):
    """With c_loc changing along the profile, the generalised forces of the contacts are still
    -dE/dq of the series springs' energy: the force term of c_loc's change is in the records."""
    m = _with_local_compliance(paper_solid_model)
    th1, th2, phi, teeth, rec, nc = loaded_mesh_state(m, angle_deg, 2e-4)
    assert nc > 0 and np.all(rec[:nc, L.C_CLOC] != 0.0)
    assert np.all(np.abs(rec[:nc, L.C_KIND]) == 1)       # flank contacts: the exact case
    assert_forces_are_minus_the_energy_gradient(m, th1, th2, phi, teeth, rec, nc)


def test_series_compliance_softens_the_static_mesh(paper_solid_model):
    """A positive local compliance c on both gears adds to the static TE between c_total*F/n
    (n contacts sharing the mesh force F evenly) and c_total*F (one contact carrying it all),
    and the sweep still converges everywhere."""
    from solver.mbs.statics import solve_static
    m0 = paper_solid_model
    gp = m0.gear_par.copy()
    for g in range(2):
        u = np.array([gp[g, L.U_LO], gp[g, L.U_HI]])
        sample_local_compliance((u, np.full(2, 2e-10)), gp[g, L.U_LO], gp[g, L.U_HI], gp[g], "gear")
    m1 = dataclasses.replace(m0, gear_par=gp)
    angles = np.radians(np.linspace(0.0, 360.0 / m0.teeth[0], 12, endpoint=False))
    s0, s1 = solve_static(m0, angles, 50.0), solve_static(m1, angles, 50.0)
    assert s0.converged.all() and s1.converged.all()
    force = 50.0 / m0.gear_par[1, L.RB]
    extra = s1.te - s0.te
    assert np.all(extra > 4e-10 * force / s1.n_contacts * 0.999)
    assert np.all(extra < 4e-10 * force)


def test_dissipated_power_of_damped_series_contacts_is_their_dampers_alone(paper_solid_model):
    """With a contact damper (c_con) on contacts in series with a local compliance, the power
    the energy balance counts as dissipated is the dampers' c_con |d'|^m2 d^m3 d' alone: the
    elastic part taken out is the series law's force, not the plain law's."""
    from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer
    from solver.mbs.kernels.laws import signed_pow
    from solver.mbs.kernels.mechanics import dissipation_power
    m = _with_local_compliance(paper_solid_model)
    lp = m.law_par.copy()
    lp[L.C_CON] = 5.0e4
    m = dataclasses.replace(m, law_par=lp)
    th1, th2, phi, teeth, rec, nc = loaded_mesh_state(m, 2.0, 2e-4)
    dphi = np.zeros_like(phi)
    dphi[teeth] = np.random.default_rng(5).normal(scale=0.5, size=len(teeth))      # rad/s
    rec, pairs = new_contact_buffer()
    nc, _ = mesh_contacts((th1, th2, 1.0, -1.0), phi, dphi, contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
    assert nc > 0 and np.all(rec[:nc, L.C_CLOC] != 0.0) and np.any(rec[:nc, L.C_DDELTA] != 0.0)
    d, dd = rec[:nc, L.C_DELTA], rec[:nc, L.C_DDELTA]
    dampers = sum(lp[L.C_CON] * signed_pow(dd[i], lp[L.M2]) * d[i] ** lp[L.M3] * dd[i] for i in range(nc) if d[i] > 0)
    act = np.zeros(1, dtype=np.int64)
    series = contact_geo(m.gear_par, m.pair_par, lp)[3].series
    p = dissipation_power(dphi, act, 0, (m.gear_par, m.pair_par, lp), rec, nc, series)
    assert dampers > 0.0 and p == pytest.approx(dampers, rel=1e-9)

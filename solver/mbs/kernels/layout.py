"""What the kernels' arrays and tuples hold: column indices of the flat parameter arrays (see
`solver.mbs.model`), the state, output and work arrays, the named work tuples, and the short
names the kernels use for them.

``gear_par[g, :]`` holds per-gear scalars (g = 0 driver, 1 driven), SI units.
``law_par`` holds the contact law; ``pair_par`` the pair data.

Glossary of the kernels' short names (SI units throughout):

    gp, pp, lp    gear_par (2 x N_GEAR_PAR), pair_par, law_par: the columns below
    kphi          tooth spring stiffness k_phi of each tooth [N m/rad^n_k]
    ctooth        tooth compliance matrix of teeth coupled through the body [rad/(N m)] (0 x 0 or
                  None: plain springs)
    parts         which optional parts of the contact search a model has (`ContactParts`)
    geo           (gp, pp, lp, parts): what the contact search reads (`gearmesh.contact_geo`)
    mdl           (gp, pp, lp, kphi, parts) or (gp, pp, lp, kphi, ctooth, parts): the model
    ctl           (par, ipar[, load table]): the control scalars and integers (columns below)
    g             gear: 0 driver, 1 driven; s, side: flank side, +1 drive, -1 coast
    i, tz2        tooth index over both gears (gear 1 first); tz2 = gp[1, TOOTH0], the index of
                  the first gear-2 tooth (i >= tz2: a gear-2 tooth)
    k, j          tooth number within gear 1 (k) and gear 2 (j); ia, ib: their indices i
    phi, dphi     tooth rotations relative to their hub (or rim) [rad] and rates [rad/s]
    acc           tooth angular accelerations [rad/s^2]
    theta1, th1   driver hub angle [rad]; w1 its rate [rad/s], acc1 its acceleration [rad/s^2]
    theta2, w2    driven angle (hub, or rim in the coupled model) [rad] and rate [rad/s]; a2 its
                  acceleration [rad/s^2]
    w2h, w2p      theta2' at the half step of the Verlet kick [rad/s], and predicted at the step's
                  end for the damping terms (w2h + dt/2*a2)
    vpred         predicted tooth rates for the damping terms [rad/s]
    x, v, ha      body angles [rad], rates [rad/s], accelerations [rad/s^2] (hub rows POS, RATE,
                  ACC, columns H_*); vh, vp: their half-step and predicted rates
    tl            resisting (load) torque on gear 2 [N m]
    te            transmission error rb1*theta1 + rb2*theta2 [m]
    ke, pe        kinetic and potential energy [J]
    react         torque the driver applies [N m]
    s1, r1        driver torque = s1*theta1'' + r1 from the arrowhead solve [kg m^2], [N m]
    cr1           I_CPL/I_P of gear 1 (of gpk): a gear-1 tooth's rate relative to its hub drops by
                  cr1 times each driver speed increment (the inertial coupling) [-]
    gpk           gear_par of the kicks' arrowhead solve (I_P + dt/4*c_phi with implicit dampers)
    imex          the tooth-root dampers taken implicitly in the Verlet kicks (par[IMEX])
    q             generalised forces: q[0] on theta1, q[1] on theta2, q[2 + i] on tooth i [N m]
    rec           contact records, one row per contact (C_* columns), nc of them
    nc            number of contacts in rec (loaded or not); nload: those with a force > 0
    pairs, npair  candidate tooth pairs of the pre-search (gear-1 tooth, gear-2 tooth, side)
    tset          active-tooth set (T_* rows); act = tset[T_ACT], the first nact valid
    act, nact     active tooth indices and their number
    book          running sums of a run (B_* columns)
    out, o        output records (O_* or S_* columns) and the record index
    cset, ns, nn  the coupled set of teeth (`CoupledSet`), its size, the size of the next one
    ks            stiffness K_S = C[S, S]^-1 of the coupled set [N m/rad]
    nt, lst, pos  the statics' unknown teeth: their number, their indices, and each tooth's
                  unknown number (0: theta2, -1: not an unknown)
    r, rn         Newton residual [N m] and its max-norm
    nw            the HHT Newton's work arrays (`NewtonWork`); coef its scheme coefficients
    kt            tangent stiffness dF/d delta of a contact [N/m]
    drv           the driver and the load at an instant: (theta1, theta1', [theta1'',] load
                  torque, ...) as each kernel's docstring lists
    A, B          the gear-1 and the gear-2 tooth of a candidate pair (the contact search)
    ua, ub        roll parameters of the contact point on the flanks of tooth A and B [-]
    pose, frame   where a pair's teeth stand: base-circle centres, axis sines and cosines,
                  eccentric offsets; the bearing axes and tooth pivots (`gearmesh.pair_contacts`)
    dg, ser       a contact's gradient share of the flank deviations [m]; its series local
                  compliance and that compliance's gradient [m/N]
"""
from collections import namedtuple

import numpy as np

# gear_par columns
RB = 0          # base radius [m]
PSI_B = 1       # half tooth angle on the base circle [rad]
U_LO = 2        # roll parameter at the form radius [-]
U_HI = 3        # roll parameter at the tip [-]
R_PV = 4        # pivot radius [m]
PITCH = 5       # angular pitch [rad]
GAMMA0 = 6      # axis angle of tooth 0 in the gear frame [rad]
CX = 7          # centre x [m]
CY = 8          # centre y [m]
I_P = 9         # tooth inertia about its pivot [kg m^2]
I_CPL = 10      # hub-tooth inertia coupling I_P + m*r_pv*l_g [kg m^2]
I_TOT = 11      # hub + all teeth rigid, about the centre [kg m^2]
R_BND = 12      # largest distance from the pivot to a flank point [m]
N_K = 13        # spring stiffness exponent [-]
C_PHI = 14      # spring damping [N m s^n_c / rad^n_c]
N_C = 15        # spring damping exponent [-]
TOOTH0 = 16     # index of the gear's first tooth in the per-tooth arrays
NZ = 17         # number of teeth (stored as float)
K_BODY = 18     # body torsion stiffness hub -> rim [N m/rad]; 0 = rigid body (plain model)
I_HUB = 19      # inertia on the hub side of the body spring [kg m^2] (the rim side: I_TOT - I_HUB)
C_BODY = 20     # body spring damping [N m s/rad] (linear)
# profile modification (`solver.modification`): deviation of the flanks along their normal
# [m] (positive: material removed) on N_DEV roll parameters from the form circle to the tip
DEV_ON = 21     # 1: the gear has a nonzero deviation (0: the search skips it)
DEV_U0 = 22     # roll parameter of the first grid point [-]
DEV_DU = 23     # grid step [-]
DEV_NEG = 24    # bound on the material addition (-min deviation, >= 0, plus the cubic's undershoot) [m]
DEV0 = 25       # first of the N_DEV deviations [m]
N_DEV = 257
# local tooth compliance in series with the contact law (compliance model; `laws.series_contact`):
# the FE tooth's own compliance less the rigid tooth's on its pivot, [m/N] on N_CLOC roll
# parameters from the form circle to the tip, read piecewise linearly at the contact's roll
CLOC_ON = DEV0 + N_DEV  # 1: the gear has a local compliance table (0: c_loc = 0, the plain law)
CLOC_U0 = CLOC_ON + 1   # roll parameter of the first grid point [-]
CLOC_DU = CLOC_ON + 2   # grid step [-]
CLOC0 = CLOC_ON + 3     # first of the N_CLOC compliances [m/N]
N_CLOC = 33
# a rounded tip edge (`solver.tip_edge`; compliance model: the series law): the flank ends at the
# round's tangent roll EDGE_U, beyond it the tooth meets the mating flank with the round, a circle
# of radius r whose centre lies EDGE_R + EDGE_DEV inside the flank point at EDGE_U (along its
# normal), and that contact carries, in series with the contact law (rho_f the mating flank's
# radius of curvature)
#   c_edge = EDGE_A * ln(EDGE_R_LAW * (EDGE_INV_R + 1/rho_f)),  0 where that is negative
# (`solver.identify.weber.edge_compliance`, `gearmesh.edge_compliance`)
EDGE_INV_R = CLOC0 + N_CLOC  # 1 / tip edge radius [1/m]; 0: a sharp corner (the flanks' law alone)
EDGE_A = EDGE_INV_R + 1      # 2 / (pi E b) [m/N]
EDGE_R_LAW = EDGE_INV_R + 2  # equivalent radius of curvature the contact law was fitted to [m]
EDGE_R = EDGE_INV_R + 3      # tip edge radius r [m]
EDGE_U = EDGE_INV_R + 4      # roll parameter of the round's tangent point on the flank [-] (< U_HI)
EDGE_DEV = EDGE_INV_R + 5    # the flank's deviation (profile modification) at EDGE_U [m]
N_GEAR_PAR = EDGE_INV_R + 6

# law_par (contact law, eq. 1.3)
K_CON = 0       # [N/m^m1]
M1 = 1
C_CON = 2       # [N s^m2 / m^(m2+m3)]
M2 = 3
M3 = 4
# sliding friction on the flanks (Coulomb, regularised): mu_eff = MU*tanh(v_s/V_REG); MU = 0: off
MU = 5          # Coulomb coefficient [-]
V_REG = 6       # sliding speed of the regularisation [m/s]
N_LAW_PAR = 7

# pair_par
JN_HALF = 0     # half the normal backlash [m]
ALPHA = 1       # pressure angle [rad]
MARGIN = 2      # pre-search margin on the roll parameter [rad]
N_PAIR_PAR = 3
# pitch errors and eccentricity (`solver.pitch_errors`): a block after N_PAIR_PAR, present only when
# either gear has errors (the kernels test the length of pair_par)
E_BOUND = 3     # bound on the penetration the errors can add [m]
E_ECC = 4       # gear g: eccentricity [m] at E_ECC + 2g, its phase from tooth 0's axis [rad] at E_ECC + 2g + 1
E_EPS = 8       # first of the Z1 + Z2 tooth angular offsets about the teeth's centre [rad], gear 1 first

# contact record columns (one row per active contact)
C_DELTA = 0     # penetration [m]
C_DDELTA = 1    # penetration rate [m/s]
C_FORCE = 2     # normal force [N]
C_G1 = 3        # d delta / d theta1 [m]
C_GA = 4        # d delta / d phi of the gear-1 tooth [m]
C_G2 = 5        # d delta / d theta2 [m]
C_GB = 6        # d delta / d phi of the gear-2 tooth [m]
C_PX = 7        # contact point x [m]
C_PY = 8        # contact point y [m]
C_NX = 9        # normal x (outward normal of the flank owner)
C_NY = 10
C_KT = 11       # tangent stiffness dF/d delta [N/m]
C_TOOTH1 = 12   # gear-1 tooth index (float)
C_TOOTH2 = 13   # gear-2 tooth index (float)
C_KIND = 14     # 1 flank-flank, 2 gear-1 tip corner, 3 gear-2 tip corner; sign = side (+drive, -coast)
# a modified tip corner's blend into its flank (`gearmesh.TIP_BLEND`): the penetration's
# curvature F * d2 delta/dq2 = C_KGEO * V V^T that its sharp blend adds to the tangent
C_KGEO = 15     # [N/m]; 0 for other contacts
C_DG1 = 16      # V: d(roll parameter of the blend)/d(theta1, phi_A, theta2, phi_B) [-], up to sign
C_DGA = 17
C_DG2 = 18
C_DGB = 19
# friction (written only when law_par[MU] > 0, else left at zero): tangent t = n turned +90 deg
C_VS = 20       # sliding speed v_s = (v_A - v_B).t of the gear-1 over the gear-2 tooth at the point [m/s]
C_FT = 21       # friction force mu*F*tanh(v_s/v_reg) [N], acting along -t on gear 1, +t on gear 2
C_DFT = 22      # d C_FT / d v_s [N s/m]
C_H1 = 23       # d v_s / d theta1' [m]: lever arm of t about O1
C_HA = 24       # d v_s / d phi' of the gear-1 tooth [m]
C_H2 = 25       # d v_s / d theta2' [m]
C_HB = 26       # d v_s / d phi' of the gear-2 tooth [m]
# series compliance (`laws.series_contact`): C_DELTA is the penetration of the whole series
# spring, C_DCON the contact law's own share of it; equal where c_loc = 0
C_DCON = 27     # penetration of the contact law [m]
C_CLOC = 28     # local compliance c_loc1(u1) + c_loc2(u2) in series with the contact law [m/N]
N_C_COLS = 29
MAX_CONTACTS = 64

# ---- the time-stepping kernels (`stepping`, `explicit`, `explicit_coupled`, `implicit`)
# control scalars: float array ``par``
SPEED = 0           # driver speed [rad/s]
SPEED_RAMP = 1      # driver speed ramp [s]
TORQUE = 2          # resisting torque after its ramp [N m]
TORQUE_RAMP = 3     # [s]
DT = 4              # time step [s]
PHI_QUIET = 5       # a tooth outside the mesh freezes below this rotation [rad] ...
DPHI_QUIET = 6      # ... and this rate [rad/s]
DELTA_MAX = 7       # penetration bound [m]
ENERGY_TOL = 8      # relative energy growth that stops a run [-]
HHT_ALPHA = 9       # HHT-alpha parameter [-]
NEWTON_TOL = 10     # Newton stops when no flank point moves more than this [m]
IMEX = 11           # 1: the linear tooth-root dampers taken implicitly in the Verlet kicks (`explicit`)
ABORT = 12          # nonzero: stop at the end of the step (set from another thread: `solver.mbs.interrupt`)
N_PAR = 13
# control integers: int array ``ipar``
N_STEPS = 0
OUT_EVERY = 1       # steps per output record
MAX_ITER = 2        # Newton iterations per step
N_IPAR = 3

# state: ``hub[row, H_*]`` the bodies, ``teeth[row, i]`` the tooth rotations relative to their
# hub (or rim); rows: angle [rad], rate [rad/s], acceleration [rad/s^2]
POS = 0
RATE = 1
ACC = 2
H_R1 = 0            # driver rim (body-torsion coupling; the driver hub itself is prescribed)
H_TH2 = 1           # theta2: the driven gear's rim (its hub in the plain model), as the mesh sees it
H_H2 = 2            # driven hub (body-torsion coupling)
N_HUB = 3

# output records: ``out[o, :]`` at the o-th output instant
O_TIME = 0          # [s]
O_TE = 1            # transmission error at the hubs [m]
O_FMAX = 2          # largest contact force over the interval [N]
O_NC = 3            # loaded contacts [-]
O_REACT = 4         # torque the driver applies [N m]
O_KE = 5            # kinetic energy [J]
O_PE = 6            # potential energy [J]
O_WORK = 7          # work of the driver and the load since t = 0 [J]
O_DISS = 8          # dissipated energy [J]
O_THETA2 = 9        # driven hub angle [rad]
O_NEWTON = 10       # most Newton iterations in a step of the interval (implicit) [-]
O_SWITCH = 11       # energy the coupled set's switches took out since t = 0 (compliance model) [J]
N_OUT = 12
# after the N_OUT columns, when ``out`` is wider: the loaded contacts at the output instant,
# O_CONTACT_COLS columns each (as many as fit; unused slots hold tooth -1 and force 0)
OC_TOOTH1 = 0       # gear-1 tooth index
OC_TOOTH2 = 1       # gear-2 tooth index
OC_FORCE = 2        # normal contact force [N]
OC_MOMENT = 3       # its moment on the driven gear, force * d(penetration)/d(theta2) [N m]
O_CONTACT_COLS = 4
CONTACT_SLOTS = 6   # contact slots the dynamic runs record (a loaded pair has at most 4 at once)

# running sums of a run: float array ``book``
B_WORK = 0          # work in [J]
B_DISS = 1          # dissipated [J]
B_P_IN = 2          # input power at the last step [W]
B_P_D = 3           # dissipation power at the last step [W]
B_FMAX = 4          # largest contact force since the last output [N]
B_E0 = 5            # kinetic + potential energy at t = 0 [J]
B_SWITCH = 6        # energy the coupled set's switches took out [J] (`explicit_coupled`)
N_BOOK = 7

# active-tooth set: int array ``tset[row, :]``
T_ACT = 0           # active tooth indices (the first nact valid)
T_ACTIVE = 1        # 0/1 per tooth: in the active set
T_INCAND = 2        # 0/1 per tooth: named by this step's pre-search
N_TSET = 3

# ---- the static sweep (`statics`)
# control scalars: float array ``par``
S_TORQUE = 0        # resisting torque on gear 2 [N m]
S_THETA2 = 1        # driven angle at the first driver angle, the start guess [rad]
S_TOL = 2           # residual tolerance relative to the torque [-]
S_W1 = 3            # driver speed [rad/s] that sets the kinematic sliding speed of the friction (0: none)
S_ABORT = 4         # nonzero: stop before the next driver angle (`solver.mbs.interrupt`)
N_S_PAR = 5
# control integers: int array ``ipar``
S_MAX_ITER = 0      # Newton iterations per angle
N_S_IPAR = 1
# results: ``out[a, S_*]`` at the a-th driver angle
S_TE = 0            # transmission error [m]
S_TH2 = 1           # driven angle [rad]
S_NC = 2            # loaded contacts [-]
S_ITER = 3          # Newton iterations (negative: not converged) [-]
S_T1 = 4            # torque the contacts take from the driver (its rim) [N m]
N_S_OUT = 5

# ---- named work tuples: the scratch arrays a kernel carries (numba types them like tuples, and
# ``ws.rec`` compiles to the same code as ``ws[0]``)
StepWork = namedtuple("StepWork", "rec pairs q vpred tset book cset")
StepWork.__doc__ = """Work arrays of a time-stepping loop (`stepping.work_arrays`): contact records
(C_* columns), candidate pairs, generalised forces q [N m], predicted tooth rates [rad/s], the
active-tooth set (T_* rows), the running sums (B_* columns), the coupled set of teeth
(`CoupledSet`; empty arrays without a tooth compliance)."""
StaticWork = namedtuple("StaticWork", "rec pairs q zero_rates pos lst r ks")
StaticWork.__doc__ = """Work arrays of the static Newton (`statics`): contact records, candidate
pairs, generalised forces q [N m], tooth rates held at zero [rad/s], each tooth's unknown number
(0: theta2, -1: none), the unknown teeth's indices, the residual [N m] over theta2 and them,
the coupled set's stiffness [N m/rad] (teeth coupled through the body; None otherwise)."""
NewtonWork = namedtuple("NewtonWork", "coef q_old pred hpred A r dx loc cl")
NewtonWork.__doc__ = """Work arrays of the HHT-alpha Newton (`implicit.newton_arrays`): the scheme's
coefficients (`implicit` K_* columns), the forces of the last step [N m], the Newmark predictors
of the teeth and of theta2 (rows POS, RATE), the Newton matrix, residual and correction, and the
condensation's index maps (each tooth's row in A, 0: condensed; the teeth of the rows)."""
CoupledSet = namedtuple("CoupledSet", "C ks lst newl inset innew mo dmo")
CoupledSet.__doc__ = """The coupled set S of teeth (`toothcoupling.coupled_set`): the compliance C
[rad/(N m)], the set's stiffness K_S [N m/rad] (with as many scratch columns), its teeth, the
next set's teeth, per-tooth 0/1 flags of the current and the next set, scratch moments [N m]."""
ContactParts = namedtuple("ContactParts", "deviations series errors friction edges")
ContactParts.__doc__ = """The optional parts of the contact search a model has, each the array
that holds its data or None where the model lacks it (`gearmesh.contact_parts`): flank
deviations (gear_par DEV_*), local compliances in series with the contact (gear_par CLOC_*),
pitch errors and eccentricity (the pair_par block E_*), sliding friction (law_par MU > 0),
rounded tip edges (gear_par EDGE_*; only with the series compliances, whose law they join).
numba types a None apart from an array and prunes the branches under ``x is None`` (for an
argument of the compiled function), so each combination compiles its own contact search with
only the code it runs."""


# ---------------------------------------------------------------- what the contact search is given (plain Python)

def contact_parts(gp, pp, lp):
    """The `ContactParts` of the model arrays gear_par, pair_par, law_par: each part's array
    where the model has the part (a gear with a flank deviation, a gear with a local
    compliance table, the pitch-error block, a friction coefficient above zero, a rounded tip
    edge on a gear of a model with local compliances), else None.
    Plain Python: what it returns picks the compiled variant of the contact search."""
    series = gp if gp[0, CLOC_ON] + gp[1, CLOC_ON] > 0.0 else None
    return ContactParts(gp if gp[0, DEV_ON] + gp[1, DEV_ON] > 0.0 else None,
                        series,
                        pp if pp.shape[0] > N_PAIR_PAR else None,
                        lp if lp[MU] > 0.0 else None,
                        gp if series is not None and gp[0, EDGE_INV_R] + gp[1, EDGE_INV_R] > 0.0 else None)


def contact_geo(gp, pp, lp):
    """The contact search's ``geo`` = (gear_par, pair_par, law_par, `contact_parts`)."""
    return gp, pp, lp, contact_parts(gp, pp, lp)


def new_contact_buffer():
    """Preallocated contact records and candidate-pair table."""
    return np.zeros((MAX_CONTACTS, N_C_COLS)), np.zeros((MAX_CONTACTS, 3), dtype=np.int64)

"""Indices into the flat parameter arrays that the kernels take (see `solver.mbs.model`).

``gear_par[g, :]`` holds per-gear scalars (g = 0 driver, 1 driven), SI units.
``law_par`` holds the contact law; ``pair_par`` the pair data.
"""
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
N_GEAR_PAR = 21

# law_par (contact law, eq. 1.3)
K_CON = 0       # [N/m^m1]
M1 = 1
C_CON = 2       # [N s^m2 / m^(m2+m3)]
M2 = 3
M3 = 4
N_LAW_PAR = 5

# pair_par
JN_HALF = 0     # half the normal backlash [m]
ALPHA = 1       # pressure angle [rad]
MARGIN = 2      # pre-search margin on the roll parameter [rad]
N_PAIR_PAR = 3

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
N_C_COLS = 15
MAX_CONTACTS = 64

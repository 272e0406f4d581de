"""Layout of the arrays level 3's kernels share (the multibody model, seed 003): the float64
parameter vector ``P`` (:data:`PARAM_FIELDS`, positions ``I_*``, and the seat-direction tables
that :func:`pack_tables` appends), the rows of the scratch vector ``scr`` (``R_*``), the step
rule vector ``cfg`` (``CF_*``, as ``chainmodel.integrate.FixedStepper.cfg``) and the
:class:`Workspace` of preallocated arrays each model hands to the kernels.

Coordinates (lead's XY frame of seed 000/004): q = [phi1, phi2, x_0, y_0, x_1, y_1, ...],
v = dq/dt, with phi1 (driver) and phi2 (driven) forward-positive, i.e. clockwise in XY. A seat
j of sprocket s sits at angle ``phase0_s - phi_s + (2 pi / z_s) j`` about the sprocket centre.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PARAM_FIELDS", "N_PARAMS", "pack_tables", "SCR_ROWS", "Workspace"]

# layout of the float64 parameter vector handed to the kernels
PARAM_FIELDS = (
    "m", "k", "c", "l0", "kc", "cc", "clearance", "gx", "gy", "I1", "I2", "kr", "cr", "c2",
    "cx", "cy", "R1", "R2", "phase1", "phase2", "pitch_angle1", "pitch_angle2",
    "sin_gamma1", "cos_gamma1", "sin_gamma2", "cos_gamma2", "tip1", "tip2", "paper_contact",
    "paper_damping", "q_forces", "rigid_shaft", "l_min", "l_max", "z1", "z2", "reach1",
    "reach2", "cj", "gap", "onset", "roller_radius", "pitch",
    "cut1", "cut_sl1", "cut_u1", "corner_sl1", "corner_u1",
    "cut2", "cut_sl2", "cut_u2", "corner_sl2", "corner_u2",
    "role_hold",
)
(I_M, I_K, I_C, I_L0, I_KC, I_CC, I_DR, I_GX, I_GY, I_I1, I_I2, I_KR, I_CR, I_C2,
 I_CX, I_CY, I_R1, I_R2, I_PH1, I_PH2, I_TA1, I_TA2, I_SG1, I_CG1, I_SG2, I_CG2, I_TIP1, I_TIP2,
 I_PAPER_CONTACT, I_PAPER_DAMP, I_QF, I_RIGID, I_LMIN, I_LMAX, I_Z1, I_Z2, I_REACH1,
 I_REACH2, I_CJ, I_GAP, I_ONSET, I_RR, I_PITCH,
 I_CUT1, I_ASL1, I_AU1, I_KSL1, I_KU1,
 I_CUT2, I_ASL2, I_AU2, I_KSL2, I_KU2,
 I_ROLE) = range(len(PARAM_FIELDS))
# cut_s: 1 where sprocket s's flank reaches into the path of a roller articulating about its
# seated neighbour (models.multibody.articulation_cut); cut_sl, cut_u: that neighbour's seat
# centre and corner_sl, corner_u: the tooth's corner where the flank meets the path, both in
# the seat frame (outward radial, tangential towards the neighbour); role_hold: the span
# roles' hold (span_roles.lower_tight: +1 upper tight, -1 lower, 0 from the inputs)
#: P holds these scalars, then the tables cos(2 pi j / z1), sin(...) (j < z1), then the same
#: for z2 (see :func:`pack_tables`): seat directions without trigonometry in the hot loop
N_PARAMS = len(PARAM_FIELDS)


def pack_tables(P: np.ndarray) -> np.ndarray:
    """P with the seat-direction tables appended (z1, z2 taken from P)."""
    z1, z2 = int(P[I_Z1]), int(P[I_Z2])
    j1, j2 = np.arange(z1), np.arange(z2)
    return np.concatenate([P[:N_PARAMS], np.cos(2 * np.pi * j1 / z1), np.sin(2 * np.pi * j1 / z1),
                           np.cos(2 * np.pi * j2 / z2), np.sin(2 * np.pi * j2 / z2)])


#: rows of the scratch vector ``scr`` (each M long): the links' angular speed, then what the
#: positions give and the velocities reuse (multibody_forces.geometry_pass): per link its direction,
#: chord, length, spring force, damping coefficient and branch (1 stretched, -1 bearing, 0 in
#: the play); per roller and sprocket the seat penetration (<= 0: no contact), contact normal,
#: position relative to the sprocket centre and seat direction
(R_OMEGA, R_EX, R_EY, R_DX, R_DY, R_L, R_TS, R_CL, R_BRANCH) = range(9)
R_CONTACT = 9           # + 7 s + (0 pen, 1 nx, 2 ny, 3 rx, 4 ry, 5 st, 6 ct), s = 0 driver, 1 driven
SCR_ROWS = R_CONTACT + 14


#: step rule vector (chainmodel.integrate.FixedStepper.cfg): explicit step, the tolerance's
#: h omega (not used at level 3), safety times the stability limit, the limit, an outer bound
CF_STEP, CF_THETA, CF_STAB, CF_LIMIT, CF_MAX = range(5)


class Workspace:
    """Preallocated arrays for the kernels (one per model)."""

    def __init__(self, n_rollers: int):
        M = n_rollers
        n = 2 + 2 * M
        self.acc = np.zeros(n)
        self.k = [np.zeros(2 * n) for _ in range(4)]
        self.xt = np.zeros(2 * n)
        self.tension = np.zeros(M)
        self.fcon = np.zeros(M)
        self.side = np.zeros(M, np.int64)
        self.dist = np.zeros((2, M))
        self.seat_angle = np.zeros((2, M))
        self.scr = np.zeros(SCR_ROWS * M)

    def diagnostics(self):
        return self.tension, self.fcon, self.side, self.dist, self.seat_angle

"""The articulation path and the straight-flank tooth, written independently of the model, and
a probe of the kernel's penetration (kernels.multibody_forces.geometry_pass) in a seat's frame:
used by tests/test_articulation.py and docs/scripts/articulation_figure.py.

* :func:`articulation_path`: a roller centre leaving a seat turns about the seated neighbour,
  on the circle of radius p about the neighbour's centre;
* :func:`straight_flank_penetration`: the straight flank of docs/multibody.md ("Contact (eqs
  5-10) and the tooth flanks"): the seat circle (clearance dR = R_t - R_r for the roller centre)
  continued by flanks tangent to it at gamma = A/2 - 45 deg / z from the inward radial, up to a
  roller-centre height p (0.5625 - 0.4 / z) above the seat centre;
* :func:`kernel_penetration`: the kernel's penetration and normal at given roller centres.
"""

from __future__ import annotations

import math

import numpy as np

from chainmodel.chains import chain
from chainmodel.kernels import multibody_layout as K
from chainmodel.kernels.multibody_forces import geometry_pass
from chainmodel.models.multibody import MultibodyModel
from chainmodel.scene import load_scene

SEATING_ANGLE = 2 * math.pi / 3          # ISO 606's smallest roller seating angle, the default
# ISO 606 largest seating-curve radius r_i,max = 0.505 d1 + 0.069 d1^(1/3) (mm), 08A d1 = 7.92
D1_08A = 7.92
SEAT_CLEARANCE_MAX_08A = (0.505 * D1_08A + 0.069 * D1_08A ** (1 / 3) - D1_08A / 2) * 1e-3


def straight_flank_penetration(sl, u, z, p, clearance):
    """Penetration [m] of a roller centre at (sl outward along the seat's radial, u along the
    pitch circle) into the straight-flank seat (module docstring); -inf above the tip."""
    g = SEATING_ANGLE / 2 - math.pi / (4 * z)
    tip = p * (0.5625 - 0.4 / z)
    d = np.hypot(sl, u)
    seat = -sl >= d * math.cos(g)
    pen = np.where(seat, d - clearance, np.abs(u) * math.sin(g) - sl * math.cos(g) - clearance)
    return np.where(sl <= tip, pen, -np.inf)


def articulation_path(z, p, count=4000):
    """The roller centre's path (sl, u) leaving a seat about the seated neighbour at angle
    +2 pi / z: the circle of radius p about the neighbour's centre, from the seat outward."""
    R = p / (2 * math.sin(math.pi / z))
    ta = 2 * math.pi / z
    a = np.array([-R * (1 - math.cos(ta)), R * math.sin(ta)])
    start = -a                                 # the seat centre (0, 0) seen from the neighbour
    psi = np.linspace(0.0, 1.2, count)         # rad of turn about the neighbour
    # turning towards the outward radial (+sl): anticlockwise in (sl, u)
    rot = np.stack([np.cos(psi) * start[0] - np.sin(psi) * start[1],
                    np.sin(psi) * start[0] + np.cos(psi) * start[1]], axis=1)
    pts = a + rot
    # while the seat is the nearest by angle about the sprocket centre (as the contact search
    # takes it; past the bisector the neighbour's own seat takes over) and up to well past
    # the tooth tip's radius
    tip = p * (0.5625 - 0.4 / z)
    keep = ((np.abs(np.arctan2(pts[:, 1], pts[:, 0] + R)) < ta / 2)
            & (np.hypot(pts[:, 0] + R, pts[:, 1]) <= R + tip + 0.5 * p))
    return pts[keep]


def model_of(chain_name, z):
    """A level-3 model of a z / 2z drive on the chain ``chain_name`` (its own values)."""
    sc = load_scene("xu2010", fidelity=3, chain=chain_name,
                    drive_pitch=chain(chain_name).size.pitch, drive_driver_teeth=z,
                    drive_driven_teeth=2 * z, drive_links=4 * z + 20, drive_centre_distance=0.0,
                    static_tension=None, chain_pretension=0.0)
    return MultibodyModel(sc.drive, sc.parameters)


def kernel_penetration(model, pts, neighbour=+1):
    """The kernel's penetration [m] of roller centres at ``pts`` (sl, u) in the frame of the
    driver's seat 0 (u towards its seat ``neighbour``), with the normal it returns, in the
    same frame. Each point is one roller; the others are parked far away."""
    P = model.P
    M = model.M
    z = model.drive.n_driver
    R = model.drive.driver.pitch_radius
    centre = model._centres[0]
    th = P[K.I_PH1]                                  # seat 0's angle at phi1 = 0
    e_s = np.array([math.cos(th), math.sin(th)])
    ta = 2 * math.pi / z
    towards = np.array([math.cos(th + neighbour * ta), math.sin(th + neighbour * ta)]) - e_s
    e_u = towards - (towards @ e_s) * e_s
    e_u /= np.linalg.norm(e_u)
    seat = centre + R * e_s
    pens, normals = [], []
    fn = geometry_pass.py_func if hasattr(geometry_pass, "py_func") else geometry_pass
    for k in range(0, len(pts), M):
        chunk = pts[k:k + M]
        q = np.zeros(2 + 2 * M)
        far = 1e3 + np.arange(M)
        q[2::2], q[3::2] = far, far
        xy = seat + chunk[:, :1] * e_s + chunk[:, 1:] * e_u
        q[2:2 + 2 * len(chunk):2], q[3:3 + 2 * len(chunk):2] = xy[:, 0], xy[:, 1]
        fn(q, 0.0, P, model.ws.dist, model.ws.seat_angle, model.ws.scr)
        row = K.R_CONTACT * M
        pen = model.ws.scr[row:row + len(chunk)].copy()
        nx = model.ws.scr[row + M:row + M + len(chunk)]
        ny = model.ws.scr[row + 2 * M:row + 2 * M + len(chunk)]
        pens.append(pen)
        normals.append(np.stack([nx * e_s[0] + ny * e_s[1], nx * e_u[0] + ny * e_u[1]], axis=1))
    return np.concatenate(pens), np.concatenate(normals)

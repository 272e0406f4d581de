"""Level 3 linearised about its static equilibrium (shared by tests/test_top_rung_modes.py and
tests/test_level1_vs_level3.py), written here independently of the models' own analyses:
central differences of ``MultibodyModel.rhs`` in the positions at the static equilibrium of
chainmodel.models.multibody_statics (the input shaft held at a driver angle, 0 by default; no
load, velocities zero), no damping; a mode's driven-sprocket share is its kinetic energy in the driven sprocket
over its total (masses: the sprocket inertias and the link masses)."""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sl

from chainmodel.models import Inputs
from chainmodel.models.multibody_statics import static_state
from chainmodel.scene import load_scene


class Linearised:
    """Level 3 linearised about its static equilibrium at ``driver_angle`` [rad], no load."""

    def __init__(self, name, driver_angle: float = 0.0):
        sc = load_scene(name, fidelity=3)
        self.scene = sc
        model = sc.model()
        x0 = static_state(model, driver_angle).state
        n = 2 + 2 * model.M
        held = Inputs(float(x0[0]) if model.params["input_shaft.rigid"] else driver_angle,
                      0.0, 0.0)
        A = np.empty((n, n))
        h = 1e-9
        for j in range(n):
            xp, xm = x0.copy(), x0.copy()
            xp[j] += h
            xm[j] -= h
            A[:, j] = (model.rhs(0.0, xp, held)[n:] - model.rhs(0.0, xm, held)[n:]) / (2 * h)
        p = model.params
        self.mass = np.array([p["driver.inertia"], p["driven.inertia"]]
                             + [p["chain.link_mass"]] * (n - 2))
        k = -self.mass[:, None] * A
        self.K = 0.5 * (k + k.T)
        self.n = n
        self.rollers = x0[2:n].reshape(-1, 2)
        d = sc.drive
        # the driven sprocket's centre is the origin, the driver's at (x_c, y_c) (geometry.Drive)
        self.on_driven = np.abs(np.hypot(*self.rollers.T) - d.driven.pitch_radius) < 0.02 * d.pitch
        self.on_driver = (np.abs(np.hypot(*(self.rollers - [d.x_c, d.y_c]).T)
                                 - d.driver.pitch_radius) < 0.02 * d.pitch)

    def driven_mode(self, dynamic=None) -> float:
        """Frequency [Hz] of the mode with the largest kinetic-energy share in the driven
        sprocket, of the model condensed statically onto the sprocket rotations and the roller
        coordinates ``dynamic`` (indices into the state; None: every coordinate kept)."""
        master = np.arange(self.n) if dynamic is None else np.r_[0, 1, dynamic].astype(int)
        slave = np.setdiff1d(np.arange(self.n), master)
        T = np.zeros((self.n, master.size))
        T[master, np.arange(master.size)] = 1.0
        if slave.size:
            T[slave] = -np.linalg.solve(self.K[np.ix_(slave, slave)],
                                        self.K[np.ix_(slave, master)])
        lam, V = sl.eig(T.T @ self.K @ T, T.T @ np.diag(self.mass) @ T)
        best, share = None, -1.0
        for i in range(lam.size):
            v = T @ np.real(V[:, i])
            ke = self.mass * v * v
            s = ke[1] / ke.sum()
            if lam[i].real > 0 and s > share:
                best, share = math.sqrt(lam[i].real) / (2 * math.pi), s
        return best

    def rollers_dof(self, mask) -> list[int]:
        return [2 + 2 * i + c for i in np.nonzero(mask)[0] for c in (0, 1)]

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """(frequencies [Hz], driven-sprocket kinetic-energy shares) of every mode."""
        lam, V = sl.eigh(self.K, np.diag(self.mass))
        keep = lam > 0.0
        v = V[:, keep]
        energy = self.mass[:, None] * v * v
        return np.sqrt(lam[keep]) / (2 * math.pi), energy[1] / energy.sum(axis=0)

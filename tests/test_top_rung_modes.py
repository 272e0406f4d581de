"""Level 3's torsional mode from its own linearisation (issue 21 items 3 and 6), computed here
independently of the ring-down and of chainmodel.models.wrap_statics:

* the Jacobian of level 3's accelerations with respect to its positions at its static
  equilibrium (central differences of ``MultibodyModel.rhs``, velocities zero, the input shaft
  held), whose eigenvalues are -omega^2 of the undamped small-amplitude modes; the driven
  sprocket's mode is the one with the largest share of kinetic energy (masses: the sprocket
  inertias and the link masses) in the driven sprocket;
* the static (Guyan) condensation of that linearisation onto the two sprocket rotations, and
  the partial ones that keep some rollers' inertia.

They show that the ring-down measures level 3's linear mode, that levels 1-2's condensed wrap
(``torsional.wrap_statics``: K_3 from level 3's statics) is the Guyan condensation, and what
Guyan leaves out on xu2010: its spans' inertia, which at 600 Hz (ten times their first string
mode) does not follow the static span shapes (docs/reduced_models.md, "Item 3, the torsional
mode").
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sl

from chainmodel.models import Inputs
from chainmodel.models.multibody_statics import static_state
from chainmodel.models.wrap_statics import wrap_fit
from chainmodel.scene import load_scene
from ringdown_check import ring


class Linearised:
    """Level 3 linearised about its static equilibrium at driver angle 0, no load."""

    def __init__(self, name):
        sc = load_scene(name, fidelity=3)
        self.scene = sc
        model = sc.model()
        x0 = static_state(model).state
        n = 2 + 2 * model.M
        held = Inputs(float(x0[0]) if model.params["input_shaft.rigid"] else 0.0, 0.0, 0.0)
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


@pytest.fixture(scope="module")
def xu():
    return Linearised("xu2010")


def test_xu2010_ring_down_is_level3s_linear_mode(xu):
    """The ring-down after a start to 5 rpm (spectral peak) is the linear mode within 1 %: the
    reference frequency item 3 compares with is level 3's, not an artefact of the measurement."""
    f_lin = xu.driven_mode()
    assert f_lin == pytest.approx(ring("xu2010", 3, (0.8 * f_lin, 1.2 * f_lin)), rel=0.01)


def test_xu2010_static_condensation_is_the_wrap_levels_1_2_take(xu):
    """The Guyan condensation's driven-sprocket stiffness (driver held) is wrap_fit's K_3 within
    1 %: levels 1-2 with torsional.wrap_statics hold level 3's statics onto the sprockets."""
    sc = xu.scene
    fit = wrap_fit(sc.drive, sc.parameters)
    slave = np.arange(2, xu.n)
    k11 = xu.K[1, 1] - xu.K[1, slave] @ np.linalg.solve(xu.K[np.ix_(slave, slave)],
                                                         xu.K[slave, 1])
    assert k11 == pytest.approx(fit.stiffness, rel=0.01)


def test_xu2010_what_the_static_wrap_leaves_out_is_the_spans_inertia(xu):
    """Condensed statically onto the sprockets (every roller following its static shape) the
    driven mode sits more than 3 % below the linear mode; keeping the span rollers' inertia
    brings it within 1 %, keeping only the wrapped rollers' does not move it up: on xu2010 the
    gap between levels 1-2's static wrap and level 3 is the spans' own dynamics at 600 Hz."""
    full = xu.driven_mode()
    guyan = xu.driven_mode(dynamic=[])
    spans = ~(xu.on_driven | xu.on_driver)
    assert 10 < spans.sum() < xu.rollers.shape[0] - 10     # both spans found, both wraps too
    assert guyan < 0.97 * full
    assert xu.driven_mode(dynamic=xu.rollers_dof(spans)) == pytest.approx(full, rel=0.01)
    assert xu.driven_mode(dynamic=xu.rollers_dof(~spans)) < guyan

"""Static equilibrium of level 3's chain (issue 21 items 3-4; docs/multibody.md, "Statics").

Every roller position and the driven sprocket's rotation with the driver held at an angle, the
driven sprocket loaded by a torque M (0: free, its torque balance), gravity included, under the
SAME force law as the dynamic level 3 at zero velocity: the residual is the compiled
accelerations of :class:`~chainmodel.models.multibody.MultibodyModel` times the masses
(m a of each roller, I_2 a_2 of the driven sprocket), so an equilibrium found here is an
equilibrium of the dynamic model (tests/test_multibody_statics.py starts it there and watches it
stay).

The forces are conservative at rest (links, roller-seat penalty contacts, gravity, a constant
load torque: seed 003 eq A2's U plus the load's work), so the residual is minus the gradient of
a potential V and its Jacobian is minus V's Hessian, symmetric. Newton on it:

* the Jacobian by finite differences with a colouring of the columns: a roller's position moves
  the forces on itself and its two link neighbours (the joint dampers act only on velocities),
  so rollers three apart share no row and 2 x 3 (+ up to 2 for the ring's closure) perturbed
  evaluations give every roller column; the driven sprocket's column is one more evaluation,
  and its row is that column transposed (symmetry);
* the step solves (H + mu D) du = F, H = -J, with mu raised (Levenberg) until H + mu D
  factorises and the step descends; D is H's diagonal (floored), which regularises the zero
  stiffness of a roller lying loose in its seat with its links inside the pin-bushing play;
* a backtracking line search, the step taken when it lowers V (Armijo) or the residual's
  norm, each roller's move (and the driven sprocket's at its pitch radius) capped at a tenth
  of a pitch;
* the start (:func:`sagged_layout`): the wrapped rollers at the bottom of their seats and each
  span longer than its chord hung as the parabola of its length (from the straight-span layout
  a slack chain touches no seat and floats with no stiffness at all).

Converged when the largest roller force is below ``tol`` (a thousandth) of a roller's weight
(m g; without gravity 1e-2 tol of the largest link tension at the start) and the driven sprocket's torque
below the same times its pitch radius.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix, csc_matrix
from scipy.sparse.linalg import splu

from ..kernels import multibody_layout as K
from ..kernels.multibody_forces import accel, link_potential
from ..kernels.multibody_outputs import span_ends
from . import modal_assurance
from .base import Inputs

__all__ = ["StaticSolution", "solve_statics", "static_state", "linear_driven_modes",
           "linearised_modes", "mode_measures", "MODE_GATE"]

#: linear_driven_modes takes the driven-sprocket mode among the modes whose response
#: (mode_measures: the square of the driven sprocket's speed in the mode when the drive is set
#: moving in the static wrap's shape) is at least this times the largest (C3: the string mode
#: at 7.67 Hz has 0.10 of the 16.31 Hz mode's response; B3's 9.8 and 13.3 Hz modes 0.89 of
#: each other's, both kept; a 16A 13/13 drive's 93.6 Hz mode 0.25 of a 1.82 kHz
#: roller mode's share, but 7e5 times its response)
MODE_GATE = 0.5
#: where the driver turns on its input shaft's spring, linearised_modes takes the wrap's static
#: mode (the pitch circles moving against each other, less of its strain energy in the shaft
#: than the other mode) where its share of the driven sprocket and its seated rollers in its
#: kinetic energy is at least this. A span's sag mode, the sprockets nearly at rest, holds
#: 0.002-0.02 on the unseen drives without pretension and sometimes moves them against each
#: other by rounding (08B 13/39, 10A 19/38, 10B 11/33, 12B 15/45); xu2010's wrap with twice its
#: seat clearance holds 0.10 or more. Any value in 0.02-0.1 gives the same 190 fits of
#: docs/scripts/mode_picker_fits.py; 0 took the sag mode on those four drives
WRAP_SHARE = 0.05
#: modes whose frequencies differ by at most this fraction count as one (_clusters): xu2010 at
#: its tight centre distance splits its two spans' string modes by 0.06-0.35 % near 170 Hz, and
#: their shapes (and with them each one's share) turn within their plane from one pretension or
#: driver position to the next
DEGENERATE = 0.01

#: relative force tolerance (of the weight per roller) of a converged solution
TOLERANCE = 1e-3
#: finite-difference step [m] (and rad times the pitch radius) of the Jacobian: the penalty
#: contacts are piecewise quadratic, so the step only needs to be well above rounding
FD_STEP = 1e-9
DEBUG = False


@dataclass
class StaticSolution:
    """A static equilibrium of level 3's chain.

    state: the full state of :class:`MultibodyModel` (velocities zero), the driver at
    ``driver_angle``; tension_upper / tension_lower: the axial force of each span's middle link
    (measured as level 3's outputs are) [N]; residual: largest roller force [N] at the solution;
    torque_residual: driven sprocket's torque [N m]; iterations: Newton steps; wall: seconds."""
    state: np.ndarray
    driver_angle: float
    load: float
    tension_upper: float
    tension_lower: float
    residual: float
    torque_residual: float
    iterations: int
    wall: float
    converged: bool

    @property
    def driven_angle(self) -> float:
        return float(self.state[1])

    @property
    def mean_tension(self) -> float:
        return 0.5 * (self.tension_upper + self.tension_lower)


class _Problem:
    """Residual, potential and coloured Jacobian of the static problem of one model."""

    def __init__(self, model, driver_angle: float, load: float):
        self.model = model
        self.M = M = model.M
        self.n = 2 + 2 * M
        P = model.P.copy()
        P[K.I_RIGID] = 1.0          # the driver held at its angle (tau): a[0] = tau''
        self.P = P
        self.ws = K.Workspace(M)
        self.tau = float(driver_angle)
        self.load = float(load)
        self.m = P[K.I_M]
        self.I2 = P[K.I_I2]
        self.v0 = np.zeros(self.n)
        self.q = np.zeros(self.n)
        self.q[0] = self.tau
        self.acc = np.zeros(self.n)
        self.fn = accel     # level 3's own force law
        self.evaluations = 0
        # column colouring of the rollers: roller i moves rows i-1, i, i+1 (cyclic)
        base = M - M % 3
        colour = np.empty(M, np.int64)
        colour[:base] = np.arange(base) % 3
        colour[base:] = 3 + np.arange(M - base)
        self.groups = [np.flatnonzero(colour == c) for c in range(int(colour.max()) + 1)]
        # sparse pattern: unknowns u = [phi2, x0, y0, x1, ...] (index 0 the driven sprocket)
        rows, cols = [], []
        for i in range(M):
            for j in (i - 1, i, i + 1):
                jj = j % M
                for a in range(2):
                    for b in range(2):
                        rows.append(1 + 2 * i + a)
                        cols.append(1 + 2 * jj + b)
        self._rows_rr = np.array(rows)
        self._cols_rr = np.array(cols)

    def set(self, u):
        self.q[1] = u[0]
        self.q[2:] = u[1:]

    def _evaluate(self, u):
        """The force kernel at u (zero velocity); a layout with two rollers on one point has
        no link direction: ValueError, which the callers take as "no equilibrium found"."""
        self.set(u)
        try:
            return self.fn(self.q, self.v0, self.tau, 0.0, 0.0, self.load, self.P, self.ws,
                           self.acc)
        except ZeroDivisionError:
            raise ValueError("level 3's statics reached a layout with two rollers on one point "
                             "(a link of zero length): no equilibrium from there") from None

    def forces(self, u) -> np.ndarray:
        """F(u) = [driven torque balance, m a of every roller] at zero velocity."""
        a, status, _ = self._evaluate(u)
        self.evaluations += 1
        f = np.empty(self.n - 1)
        f[0] = self.I2 * a[1]
        f[1:] = self.m * a[2:]
        return f

    def potential(self, u) -> float:
        """V(u): links, contacts, gravity and the load's potential load * phi2 [J]."""
        self._evaluate(u)
        z = u[1:].reshape(self.M, 2)
        L = np.hypot(*(np.roll(z, -1, axis=0) - z).T)
        links = float(np.sum(link_potential(L - self.P[K.I_L0], self.P[K.I_K], self.P[K.I_GAP])))
        pen = np.where(self.ws.side > 0, self.ws.fcon / self.P[K.I_KC], 0.0)
        contact = 0.5 * self.P[K.I_KC] * float(pen @ pen)
        grav = -self.m * float(np.sum(z[:, 0] * self.P[K.I_GX] + z[:, 1] * self.P[K.I_GY]))
        return links + contact + grav + self.load * float(u[0])

    def jacobian(self, u, f0) -> csc_matrix:
        """dF/du (symmetric: -V's Hessian) by coloured forward differences."""
        M, h = self.M, FD_STEP
        vals = np.empty(self._rows_rr.shape[0])
        # roller columns
        blk = np.zeros((M, 3, 2, 2))          # [roller i, neighbour slot j-i+1, row a, col b]
        for b in range(2):
            for g in self.groups:
                up = u.copy()
                up[1 + 2 * g + b] += h
                df = (self.forces(up) - f0) / h
                dfr = df[1:].reshape(M, 2)
                for slot, off in enumerate((-1, 0, 1)):
                    rows = (g + off) % M            # rows moved by perturbed roller g
                    # row i = g + off sees column g at neighbour slot (g - i) + 1 = 1 - off
                    blk[rows, 1 - off, :, b] = dfr[rows]
        vals[:] = blk.reshape(-1)
        # driven sprocket column (and row, by symmetry)
        hp = h / max(self.P[K.I_R2], 1e-3)
        up = u.copy()
        up[0] += hp
        col = (self.forces(up) - f0) / hp
        nz = np.flatnonzero(col[1:]) + 1
        rows = np.concatenate([self._rows_rr, nz, np.zeros_like(nz), [0]])
        cols = np.concatenate([self._cols_rr, np.zeros_like(nz), nz, [0]])
        data = np.concatenate([vals, col[nz], col[nz], [col[0]]])
        J = coo_matrix((data, (rows, cols)), shape=(self.n - 1, self.n - 1)).tocsc()
        return 0.5 * (J + J.T)    # symmetric up to the differences' rounding


def solve_statics(model, driver_angle: float = 0.0, load: float = 0.0, start=None,
                  tol: float = TOLERANCE, max_iter: int = 200) -> StaticSolution:
    """Static equilibrium of ``model`` (a MultibodyModel) with the driver held at
    ``driver_angle`` and the load torque ``load`` on the driven sprocket (module docstring).
    ``start``: a full state to start from (default: the straight-span layout,
    ``model.straight_layout``). Raises ValueError if Newton does not converge."""
    t0 = time.perf_counter()
    pr = _Problem(model, driver_angle, load)
    x0 = (model.straight_layout(Inputs(float(driver_angle), 0.0, 0.0)) if start is None
          else start)
    u = np.concatenate([[x0[1]], x0[2:pr.n]]).astype(float)
    g = abs(model.params["gravity"])
    f = pr.forces(u)
    if g > 0:
        f_tol = tol * pr.m * g
    else:   # no weight to compare with: a hundredth of tol of the largest link tension
        f_tol = 1e-2 * tol * max(float(np.max(np.abs(pr.ws.tension))), 1e-3)
    t_tol = f_tol * model.drive.driven.pitch_radius
    f = pr.forces(u)
    V = pr.potential(u)
    # the driven sprocket's arc at its tooth tips counts like a roller's move: a free turn by
    # a whole tooth would let the seats change rollers (and a loaded sprocket's V fall for ever)
    r_turn = model.drive.driven.pitch_radius
    it = 0
    mu = 0.0
    converged = False
    for it in range(1, max_iter + 1):
        if np.max(np.abs(f[1:])) <= f_tol and abs(f[0]) <= t_tol:
            converged = True
            it -= 1
            break
        H = -pr.jacobian(u, f)
        d = np.maximum(np.abs(H.diagonal()), 1e-12 * np.max(np.abs(H.diagonal())))
        D = csc_matrix((d, (np.arange(d.size), np.arange(d.size))), shape=H.shape)
        norm = np.linalg.norm(f)
        mu = 0.0 if mu < 1e-6 else 0.1 * mu
        taken = False
        for _ in range(40):
            step = None
            try:
                du = splu((H + mu * D).tocsc()).solve(f)
                if np.all(np.isfinite(du)) and f @ du > 0.0:
                    step = du      # descends V (H + mu D positive definite along it)
            except RuntimeError:   # singular: a roller with no stiffness at all
                pass
            if step is not None:
                # backtracking, the step capped at a tenth of a pitch per roller: taken when
                # it lowers V (Armijo) or the residual's norm - either merit alone stalls, V on
                # a compressed straight span that must buckle into its sag, the residual
                # across the kinks of the contacts and the links' play
                alpha = min(1.0, 0.1 * model.drive.pitch / max(np.max(np.abs(step[1:])),
                                                               abs(step[0]) * r_turn, 1e-300))
                slope = -(f @ step)
                for _ in range(30):
                    un = u + alpha * step
                    Vn = pr.potential(un)
                    fn = pr.forces(un)
                    if Vn <= V + 1e-4 * alpha * slope or (
                            np.linalg.norm(fn) <= (1 - 1e-4 * alpha) * norm):
                        taken = True
                        break
                    alpha *= 0.5
            if taken:
                break
            mu = max(1e-6, 10.0 * mu)   # Levenberg: towards a scaled gradient step
        if not taken:
            break
        u, V, f = un, Vn, fn
        if DEBUG:
            print(it, alpha, mu, np.max(np.abs(f[1:])), np.argmax(np.abs(f[1:]))//2, f[0], V)
    x = np.zeros(2 * pr.n)
    x[0] = driver_angle
    x[1] = u[0]
    x[2:pr.n] = u[1:]
    tu, tl = _span_tensions(model, x)
    res = float(np.max(np.abs(f[1:])))
    sol = StaticSolution(x, float(driver_angle), float(load), tu, tl, res, float(f[0]), it,
                         time.perf_counter() - t0, converged)
    if not converged:
        raise ValueError(
            f"level 3 statics did not converge in {it} Newton steps (largest roller force "
            f"{res:.3g} N, driven torque {f[0]:.3g} N m; tolerance {f_tol:.3g} N)")
    return sol


def _span_tensions(model, x) -> tuple[float, float]:
    """(upper, lower) span tension at rest as level 3's outputs measure it (middle link)."""
    n = 2 + 2 * model.M
    model._accel(x, float(x[0]), 0.0, 0.0, 0.0)
    spans = model._spans_out
    _spans(model, x[:n], spans)
    return float(model.ws.tension[spans[0][0]]), float(model.ws.tension[spans[1][0]])


def _spans(model, q, spans):
    span_ends(q, model.ws.dist, model.ws.side, model.ws.seat_angle, model._engaged_tol, model.P,
       model._mids, spans)


def sagged_layout(model, driver_angle: float = 0.0) -> np.ndarray:
    """The straight-span layout (``model.straight_layout``) with each span that is longer than
    its chord (links at their free length l0) sagged into the parabola of that length along
    gravity's component across the span: a chord l with n links of free length l0 > l / n
    takes the midspan sag s = sqrt(3 l (n l0 - l) / 8) (arc length of a shallow parabola,
    l + 8 s^2 / (3 l)). The start of a slack chain's Newton solve: from a straight, compressed
    span Newton would first have to buckle it."""
    x = model.straight_layout(Inputs(float(driver_angle), 0.0, 0.0))
    M = model.M
    z = x[2:2 + 2 * M].reshape(M, 2)
    model._accel(x, float(driver_angle), 0.0, 0.0, 0.0)   # the seat search _engaged reads
    engaged = model._engaged(x)
    free = ~engaged.any(axis=0)
    if free.all() or not free.any():
        return x
    # the wrapped rollers at the bottom of their seats (towards the sprocket's centre by the
    # clearance), where a chain's tension holds them: laid on the pitch circle they touch
    # nothing, and a chain without pretension would float with no stiffness at all
    clearance = model.P[K.I_DR]
    for s in range(2):
        centre = model._centres[s]
        R = model.P[K.I_R1 + s]
        for i in np.flatnonzero(engaged[s]):
            th = model.ws.seat_angle[s, i]
            seat = centre + R * np.array([math.cos(th), math.sin(th)])
            z[i] = seat + (clearance + 1e-9) * (centre - seat) / R
    g = np.array([model.P[K.I_GX], model.P[K.I_GY]])
    l0 = model.P[K.I_L0]
    start = int(np.flatnonzero(~free)[0])
    i = 0
    while i < M:
        r = (start + i) % M
        if not free[r]:
            i += 1
            continue
        run = []
        while i < M and free[(start + i) % M]:
            run.append((start + i) % M)
            i += 1
        a, b = (run[0] - 1) % M, (run[-1] + 1) % M
        chord = z[b] - z[a]
        l = float(np.hypot(*chord))
        n = len(run) + 1
        if l <= 0 or n * l0 <= l:
            continue
        e = chord / l
        across = g - (g @ e) * e
        na = float(np.hypot(*across))
        if na == 0.0:
            across, na = np.array([-e[1], e[0]]), 1.0
        # the parabola y = 4 s xi (1 - xi) of arc length n l0 (Newton on s, from the shallow
        # approximation), the rollers at equal arc lengths along it (links at l0)
        xi = np.linspace(0.0, 1.0, 2001)
        sag = math.sqrt(3.0 * l * (n * l0 - l) / 8.0)
        for _ in range(20):
            slope = 4.0 * sag * (1.0 - 2.0 * xi) / l
            ds = np.sqrt(1.0 + slope * slope)
            arc = l * float(np.trapezoid(ds, xi))
            darc = l * float(np.trapezoid(slope * 4.0 * (1.0 - 2.0 * xi) / l / ds, xi))
            sag -= (arc - n * l0) / darc
        slope = 4.0 * sag * (1.0 - 2.0 * xi) / l
        ds = np.sqrt(1.0 + slope * slope)
        s_xi = np.concatenate([[0.0], np.cumsum(0.5 * (ds[1:] + ds[:-1]) * np.diff(xi))])
        for k, rr in enumerate(run, start=1):
            t = float(np.interp(k / n * s_xi[-1], s_xi, xi))
            z[rr] = z[a] + t * chord + 4.0 * sag * t * (1.0 - t) * across / na
    x[2:2 + 2 * M] = z.ravel()
    return x


#: Newton steps of :func:`static_state`'s last try
LONG_SOLVE = 800


def static_state(model, driver_angle: float = 0.0, load: float = 0.0,
                 long_solve: bool = False) -> StaticSolution:
    """:func:`solve_statics` from :func:`sagged_layout` (the straight-span layout where the
    spans are not longer than their chords), or, if that fails, from the straight-span
    layout; if that fails too and ``long_solve``, from the sagged layout again with
    ``LONG_SOLVE`` Newton steps (a deep sag can take a few more than the default 200: a 12B
    17/34 chain two links too long converged in 202, so level 3 had started it from straight
    spans in compression). Level 3's own start and static tension take the long solve
    (MultibodyModel); levels 0-2's fits do not (a chain that hangs that deep is beyond their
    straight spans, and they keep the seat ladder there)."""
    sagged = sagged_layout(model, driver_angle)
    try:
        return solve_statics(model, driver_angle, load, start=sagged)
    except ValueError:
        pass
    try:
        return solve_statics(model, driver_angle, load)
    except ValueError:
        if not long_solve:
            raise
        return solve_statics(model, driver_angle, load, start=sagged, max_iter=LONG_SOLVE)


def _condensed_modes(k, mass, keep):
    """(omega^2 [n], shapes [full x n]) of the model with the coordinates not in ``keep``
    condensed statically (Guyan: they follow their static shapes, T = [I; -K_ss^-1 K_sk], and
    carry their mass through them); the shapes expanded to every coordinate."""
    import scipy.linalg as sl
    drop = np.setdiff1d(np.arange(k.shape[0]), keep)
    T = np.zeros((k.shape[0], keep.size))
    T[keep, np.arange(keep.size)] = 1.0
    if drop.size:
        try:
            with warnings.catch_warnings():
                # ill-conditioned (a slack chain without gravity: rcond ~1e-25) is no stiffness
                warnings.simplefilter("error", sl.LinAlgWarning)
                T[drop] = -sl.solve(k[np.ix_(drop, drop)], k[np.ix_(drop, keep)],
                                    assume_a="sym")
        except (sl.LinAlgError, sl.LinAlgWarning, ValueError) as exc:
            raise ValueError(f"level 3's rollers have no static stiffness to condense ({exc})")
        if not np.all(np.isfinite(T)):
            raise ValueError("level 3's rollers have no static stiffness to condense")
    lam, vec = sl.eigh(T.T @ k @ T, T.T @ (mass[:, None] * T))
    return lam, T @ vec


def mode_measures(lam, phi, mass, driven: int, ref
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(share, mac, response) per mode; all -1 (response 0) where ``lam`` <= 0.

    share: J_2 phi_2^2 / (phi^T M phi), the driven sprocket's rotation's (coordinate
    ``driven``) part of the mode's kinetic energy (phi_2^2 of the mass-normalised shape is its
    driving-point residue). mac: the mass-weighted modal assurance criterion against ``ref``
    (Allemang & Brown 1982). response: the driven sprocket's speed in the mode when the drive
    starts from rest position with velocity ``ref`` - modal velocity phi^T M ref / (phi^T M
    phi), times phi_2 - scaled by sqrt(J_2 / ref^T M ref); signed, so that the modes of a
    near-degenerate group add (:func:`_driven_mode`), response^2 = share x mac, and over every
    mode the responses sum to the driven sprocket's own value sqrt(J_2 / ref^T M ref) ref_2 (the
    modal expansion of the initial velocity, at t = 0)."""
    norm = np.einsum("i,ij,ij->j", mass, phi, phi)
    ref_norm = float(ref @ (mass * ref))
    share = np.where(lam > 0.0, mass[driven] * phi[driven] ** 2 / norm, -1.0)
    response = np.where(lam > 0.0, math.sqrt(mass[driven] / ref_norm) * phi[driven]
                        * (phi.T @ (mass * ref)) / norm, 0.0)
    return share, modal_assurance.mac(lam, phi, mass, ref), response


def _clusters(lam) -> list[np.ndarray]:
    """The positive modes of ``lam`` (ascending) in groups whose frequencies lie within
    ``DEGENERATE`` of the group's first: a near-degenerate pair's shapes are any rotation
    within their plane (numerically: the two spans' string modes of a drive whose spans are
    alike, split by a fraction of a per cent), so only the pair's sums are the model's."""
    positive = np.flatnonzero(lam > 0.0)
    groups: list[list[int]] = []
    for i in positive:
        if groups and math.sqrt(lam[i] / lam[groups[-1][0]]) <= 1.0 + DEGENERATE:
            groups[-1].append(int(i))
        else:
            groups.append([int(i)])
    return [np.asarray(g) for g in groups]


def _driven_mode(lam, phi, mass, driven: int, ref, near=None) -> float:
    """omega [rad/s] of the driven-sprocket mode: of the positive modes whose response
    (:func:`mode_measures`, squared) is at least ``MODE_GATE`` times the largest, the one
    with the largest MAC against ``ref``; or with ``near`` [rad/s], of those and the ones whose
    share is at least ``MODE_GATE`` times the largest, the one nearest ``near``.
    Modes within ``DEGENERATE`` of each other count as one (:func:`_clusters`): its response is
    the sum of theirs, its MAC and share the sums of theirs (over M-orthonormal shapes all three
    are invariant under a rotation within the group: the projection of the initial velocity on
    the group, read at the driven sprocket; the squared projection of ``ref`` on it; the
    driving-point residue), its omega^2 their share-weighted mean (continuous where two modes
    veer and exchange their shares). ValueError where no positive mode turns the driven
    sprocket."""
    share, mac, response = mode_measures(lam, phi, mass, driven, ref)
    groups = _clusters(lam)
    g_share = np.array([share[g].sum() for g in groups])
    g_mac = np.array([mac[g].sum() for g in groups])
    g_response = np.array([response[g].sum() for g in groups]) ** 2
    if not (g_share.size and g_share.max() > 0.0 and g_response.max() > 0.0):
        raise ValueError("level 3 linearised at rest has no positive mode in the driven "
                         "sprocket")
    g_omega = np.array([math.sqrt(float(share[g] @ lam[g]) / float(share[g].sum()))
                        if share[g].sum() > 0.0 else math.sqrt(float(lam[g].mean()))
                        for g in groups])
    gated = g_response >= MODE_GATE * g_response.max()
    if near is not None:
        # ref itself may be the other mode here (a flexible shaft's two static modes swap
        # their shares between driver positions), so a mode that turns the driven sprocket
        # by its share alone also counts
        gated = np.flatnonzero(gated | (g_share >= MODE_GATE * g_share.max()))
        return float(g_omega[gated[np.argmin(np.abs(np.log(g_omega[gated] / near)))]])
    gated = np.flatnonzero(gated)
    return float(g_omega[gated[np.argmax(g_mac[gated])]])


def linear_driven_modes(model, solution: StaticSolution, near: float | None = None,
                        wrap_first: bool = True, choice: list | None = None
                        ) -> tuple[float, float]:
    """(omega, omega_s) [rad/s]: level 3's driven-sprocket mode about a static equilibrium
    ``solution`` (no load), small amplitude, undamped, and its static condensation's mode it
    continues.

    K = -diag(m) dA/dq, the accelerations A of the dynamic model's own force law differentiated
    by central differences in every position at zero velocity (the joint and link dampers act
    on velocities only), symmetrised; the input shaft held at the driver's angle, so with a
    rigid shaft the driver is held and otherwise it turns on the shaft's spring; masses the
    sprocket inertias and the link mass per roller (2 + 2 M unknowns, dense; milliseconds for
    the presets' chains). Dense central differences rather than :class:`_Problem`'s coloured
    Jacobian: that one holds the driver (no shaft row) and is one-sided.

    Which mode: first every roller condensed statically onto the sprocket rotations (Guyan:
    each roller follows its static shape, T = [I; -K_rr^-1 K_rs], and carries its mass
    through it); of its modes (two where the driver is free) the one with the largest share of
    its kinetic energy in the driven sprocket and its seated rollers; where the driver is free
    (and ``wrap_first``), the wrap's mode of a two-inertia system on a shaft instead if its
    share is at least ``WRAP_SHARE``: the one whose pitch circles move against each other and
    which keeps less of its strain energy in the input shaft than the other (the one the span
    stiffness moves most). That is the static wrap. ``choice``: a list to which whether the
    wrap's mode was taken is appended (driver free only). Then only the rollers seated on a
    sprocket (in contact at rest) condensed - they turn with their sprocket as levels 1-2's
    chain inertia puts them on it - and the span rollers keep their inertia: at xu2010's 600 Hz, ten times a span's first string mode,
    they do not follow their static shapes (tests/test_top_rung_modes.py: 598.2 Hz with every
    roller's inertia, 601.5 Hz so, 568.4 Hz with none), and on a sagging chain the static
    secant is its sag's, which a span above its string modes does not give. The mode returned
    is, of this model's modes that the static wrap's motion excites in the driven sprocket (a
    response at least ``MODE_GATE`` times the largest: :func:`mode_measures`, the driven
    sprocket's speed in the mode when the drive is set moving in the static mode's shape;
    response^2 = share x MAC), the one with the largest mass-weighted modal assurance criterion
    against the static one's shape (the same mode, moved by the spans' inertia; Allemang &
    Brown, 1982). Without a gate, on a long sagging span, whose static shape is mostly its
    sag's, the closest shape was a string mode that hardly turns the sprocket (C3: 7.67 Hz with
    6 % of its energy in the driven sprocket, against 16.31 Hz with 91 %; the 21/63-tooth
    ``fine``: 7.76 Hz, 0.3 %, against 45.4 Hz, 71 %; level 3's own ring-down: 14.5-16.1 Hz and
    45.6 Hz; docs/reduced_models.md "Which mode is the driven sprocket's"). Without the MAC, the
    largest share alone took a mode level 3's ring-down does not show on a sagging 08B chain
    (567 Hz, against its 209 Hz), and a gate on the share alone lost the torsional mode where a
    kHz mode of the span rollers beside the sprocket holds the largest share with none of the
    wrap's shape (16A 13/13: 93.6 Hz holds 0.25 of the 1.82 kHz mode's share, but 7e5 times its
    response; docs/reduced_models.md "The gate on the response").
    Condensing the seated rollers also removes the local modes of a light sprocket rattling
    against its own rollers at kHz.
    ``near`` [rad/s]: take, of the gated modes and those whose share is at least
    ``MODE_GATE`` times the largest, the one nearest this omega instead (the same mode at
    another driver position, where the shares of a flexible shaft's two modes may swap and the
    static mode's shape with them: xu2010 with half its contact stiffness). Modes within
    ``DEGENERATE`` of each other are taken as one (:func:`_driven_mode`): xu2010 at its tight
    centre distance has its two spans' string modes 0.06-0.35 % apart at 168-172 Hz, their
    shapes turned within their plane from one position to the next, and one of the pair alone
    fell below the share gate at some pretensions (451 N: 535 Hz taken, against 171.7 Hz at 450
    and 452 N).
    Checked against level 3's own ring-down on C1, xu2010 and unseen drives
    (tests/test_wrap_statics.py, docs/reduced_models.md). Raises ValueError where the rollers'
    static stiffness is singular or no positive mode exists."""
    lam, phi, mass, driven, ref, omega_s = linearised_modes(model, solution, wrap_first, choice)
    return _driven_mode(lam, phi, mass, driven, ref, near), omega_s


def linearised_modes(model, solution: StaticSolution, wrap_first: bool = True,
                     choice: list | None = None):
    """(lam [rad^2/s^2], shapes, mass, driven, ref, omega_s [rad/s]) of
    :func:`linear_driven_modes`: the modes of level 3 linearised at ``solution`` with its
    seated rollers condensed, the coordinates' masses, the driven sprocket's coordinate, the
    static condensation's driven-sprocket shape and its mode; for :func:`mode_measures`."""
    n = 2 + 2 * model.M
    P = model.P
    q0 = solution.state[:n].astype(float)
    v0 = np.zeros(n)
    tau = float(solution.driver_angle)
    ws = K.Workspace(model.M)
    acc = np.zeros(n)
    free = np.arange(1 if model.params["input_shaft.rigid"] else 0, n)
    scale = np.ones(n)
    scale[:2] = [max(P[K.I_R1], 1e-3), max(P[K.I_R2], 1e-3)]

    def accelerations(q):
        a, _, _ = accel(q, v0, tau, 0.0, 0.0, 0.0, P, ws, acc)
        return a[free].copy()

    accelerations(q0)
    side = np.concatenate([[1, 2], np.repeat(ws.side[:model.M], 2)])[free]
    A = np.empty((free.size, free.size))
    for col, j in enumerate(free):
        h = FD_STEP / scale[j]
        qp, qm = q0.copy(), q0.copy()
        qp[j] += h
        qm[j] -= h
        A[:, col] = (accelerations(qp) - accelerations(qm)) / (2.0 * h)
    p = model.params
    mass = np.concatenate([[p["driver.inertia"], p["driven.inertia"]],
                           np.full(n - 2, p["chain.link_mass"])])[free]
    k = -mass[:, None] * A
    k = 0.5 * (k + k.T)
    driven = int(np.flatnonzero(free == 1)[0])
    sprockets = np.flatnonzero(free < 2)
    spans = np.flatnonzero(side == 0)
    # the static condensation's driven-sprocket mode: the largest share of its kinetic energy
    # in the driven sprocket and its seated rollers
    lam_s, phi_s = _condensed_modes(k, mass, sprockets)
    seated = np.flatnonzero(side == 2)
    energy = mass[:, None] * phi_s * phi_s
    share_s = np.where(lam_s > 0.0, energy[seated].sum(axis=0) / energy.sum(axis=0), -1.0)
    j = int(np.argmax(share_s))
    if share_s[j] <= 0.0:
        raise ValueError("level 3's static condensation has no positive driven-sprocket mode")
    if wrap_first and sprockets.size == 2:
        # the driver on its shaft's spring: two static modes. The wrap's is the one whose pitch
        # circles move against each other, the chain between them stretched, where it keeps
        # less of its strain energy in the shaft than the other (with a shaft stiffer than the
        # chain that mode is the driver rattling on its shaft); the span stiffness levels 1-2
        # fit moves it most, so it is taken though the other may hold the larger share (xu2010
        # with twice its seat clearance: 0.10 against 0.31)
        shaft = p["input_shaft.stiffness"] * phi_s[0] ** 2
        strain = np.einsum("ij,ik,kj->j", phi_s, k, phi_s)
        if lam_s.size == 2 and np.all(strain > 0.0):
            in_shaft = shaft / strain
            wrap = np.flatnonzero((share_s >= WRAP_SHARE) & (phi_s[0] * phi_s[1] < 0.0)
                                  & (in_shaft < in_shaft[::-1]))
            if wrap.size:
                j = int(wrap[0])
            if choice is not None:
                choice.append(bool(wrap.size))
    lam, phi = _condensed_modes(k, mass, np.concatenate([sprockets, spans]))
    return lam, phi, mass, driven, phi_s[:, j], math.sqrt(lam_s[j])


"""Level 3: the multibody model of seed 003 (Xu et al. 2010) — every roller of the closed chain a
point mass, both sprockets rigid bodies, link spring-dampers, roller-seat contact with clearance,
gravity, a torsionally flexible input shaft and the load torque.

Equations of motion (derived in docs/multibody.md from the appendix's T, U, S by Lagrange's
equation, seed 003 eq 11; eq 12 of the text copy is garbled and not used). Coordinates are
inertial: roller positions z_i = (x_i, y_i) in the lead's XY frame (driven sprocket O at the
origin, driver C at (x_c, y_c)), sprocket rotations phi1, phi2 forward positive (clockwise in XY):

    m z_i''  = F_link(i) - F_link(i-1) + sum_s F_contact(i, s) + m g               (eqs 12-13)
    I1 phi1'' = k_r (tau - phi1) + c_r (tau' - phi1') + sum_i Q_contact(i, 1)      (eq 14)
    I2 phi2'' = sum_i Q_contact(i, 2) - M_load - d2 phi2'                          (eq 15)

* Link i joins roller i and i+1 (mod M): axial force T = k (|d| - l0) + c e.(v_{i+1} - v_i)
  along e = d/|d| while taut (U of eq A2; the dissipation is axial, see below), l0 = p -
  pretension / k; no force while the link is shortened within the pin-bushing play
  ``chain.joint_clearance``, k (|d| - l0 + play) once the plates bear; a damper never pushes a
  taut link (docs/multibody.md "Links carry no compression"; departs from eq A2's spring, which
  pushes).
  Joint dampers (not in seed 003) resist the relative rotation of neighbouring links,
  S_j = c_j/2 sum (w_i - w_{i-1})^2: they damp the spans' transverse vibration, not the rigid
  rotation of wrapped links (default 0.002 N.m.s/rad so that the outputs converge in the step).
* Contact (eqs 5-10): each roller is checked against the seat of each sprocket nearest to it by
  angle about that sprocket's centre, from the sprocket's current rotation (so the assignment
  holds for ever, whatever M and z). The seat is the paper's circle of radius R_t about the seat
  centre (clearance R_t - R_r) over the ISO 606 seating angle, continued by straight flanks
  tangent to it (the paper's circle alone, eq 9, is kept as ``contact.seating_angle >= pi``);
  on sprockets of 11 teeth or fewer the flank is cut where a roller articulating about its
  seated neighbour passes (:func:`articulation_cut`). Penetration delta gives the normal force
  F_n = max(0, k_c delta + c_c delta') on the roller (towards the seat), and its reaction on
  the sprocket.
* Gravity points along -Y rotated by (theta1 - drive.inclination).
* ``multibody.rotating_frame_forces`` adds the appendix's Q (eqs A4-A7) on seated rollers;
  off by default because the coordinates are inertial and m z'' already contains those inertia
  forces (derivation in docs/multibody.md).
* ``multibody.paper_damping`` switches to the appendix's isotropic dissipation function S
  (damps rigid rotation of links and tangential sliding in seats; kept for comparison).
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any, Mapping

import numpy as np

from .. import parameters as PRM
from ..geometry import Drive
from ..kinematics import driven_rotation
from ..kinematics import fourbar as fb
from ..kinematics.wrapping import chain_geometry, roller_positions
from ..kernels import multibody_layout as K
from ..kernels.multibody_forces import accel, link_potential
from ..kernels.multibody_loops import run_held, run_points
from ..kernels.multibody_outputs import engaged_numpy, fill_outputs, span_ends
from ..outputs import O_DRIVER_ANGLE, O_DRIVER_SPEED, O_VELOCITY_RATIO, OUTPUT_NAMES
from ..kernels.spans import geometry_constants, span_geometry
from .base import Inputs, Model, SimulationDiverged

__all__ = ["MultibodyModel", "flank_geometry"]

#: a roller is "engaged" (seated) on a sprocket while it lies within the clearance (plus this
#: fraction of the pitch) of a seat centre, or touches a seat no farther out than the pitch
#: circle plus the clearance
ENGAGED_TOLERANCE = 0.002
#: the driver is "at rest" below this speed [rad/s]; velocity_ratio is then the geometric one
REST_SPEED = 1e-3
#: stretch [m] over which a link's damper engages (Hunt-Crossley: the damping force grows with
#: the contact, so it does not jump when a slack link snaps taut); 1 um is 51 N on xu2010's links
DAMPING_ONSET = 1e-6
#: h omega_max of the automatic step when the links are undamped (see event_step)
IMPACT_STEP = 0.225
#: damping ratio c / sqrt(k m) of the links' zig-zag mode (2 sqrt(k / m)) below which the links
#: count as undamped for the automatic step (seed 003's 100 N.s/m gives 0.11)
UNDAMPED_LINKS = 0.02


def flank_geometry(teeth: int, pitch: float, seating_angle: float) -> tuple[float, float, float]:
    """(gamma, beta, tip) of the seat profile of a sprocket with ``teeth`` teeth.

    ISO 606 gives the roller seating angle as seating_angle - 90 deg / z (120 deg minimum,
    140 deg maximum); the seat circle covers gamma = seating_angle / 2 - 45 deg / z either side
    of the inward radial, and the flanks continue it tangentially, inclined by
    beta = 90 deg - gamma to the radial. The flanks end where a roller centre clears the tooth
    tip: tip = p (0.5625 - 0.4 / z) above the seat centre (ISO 606 mean tip diameter
    d + p (1.125 - 0.8 / z) - d1, plus the roller radius d1 / 2). seating_angle >= pi gives the
    paper's half circle (gamma = 90 deg, no flank, contact only inside the pitch circle).
    """
    if seating_angle >= math.pi:
        return math.pi / 2, 0.0, 0.0
    gamma = seating_angle / 2 - math.pi / (4 * teeth)
    return gamma, math.pi / 2 - gamma, pitch * (0.5625 - 0.4 / teeth)


def articulation_cut(teeth: int, pitch: float, gamma: float, tip: float, roller_radius: float,
                     seat_radius: float) -> tuple[bool, float, float, float, float]:
    """Where the straight flank of :func:`flank_geometry` stands in the way of the chain's
    articulation: (active, a_sl, a_u, k_sl, k_u), in a seat's frame (sl outward along its radial,
    u along the pitch circle towards the neighbouring seat).

    A roller entering or leaving a seat turns about the roller seated next to it: its centre
    runs on the circle of radius p about the neighbouring seat centre (a_sl, a_u) =
    (-R (1 - cos 2 pi/z), R sin 2 pi/z), R the pitch radius, and the roller sweeps the band
    p - R_r ... p + R_r about it on the outer side of the line neighbour-seat. A sprocket the
    chain can wrap over has no tooth there (kinematics: the chain must articulate over its teeth
    even at rest). The straight flank stands in it on small sprockets: its roller-centre line
    meets that circle below the tooth tip for z <= 11 (08A, 10B and 16B at seating angle
    120 deg), so every roller entering or leaving such a sprocket was pressed into the flank, by
    up to 0.66 mm at 9 teeth even at rest, and the chain could not wrap without stretching.
    Active where the flank's roller-centre line (offset by the clearance) crosses the circle of
    radius p below ``tip``; the kernel then cuts the tooth by the circle of radius p - R_r on
    the swept side, with its corner (k_sl, k_u), where the surface flank meets that circle,
    rounded by the roller (kernels.multibody_forces.geometry_pass; tests/test_articulation.py).
    Elsewhere (active False: every sprocket of 12 teeth or more at 120 deg) nothing changes.
    """
    inactive = (False, 0.0, 0.0, 0.0, 0.0)
    if gamma >= math.pi / 2:
        return inactive
    R = pitch / (2.0 * math.sin(math.pi / teeth))
    ta = 2.0 * math.pi / teeth
    a = (-R * (1.0 - math.cos(ta)), R * math.sin(ta))
    direction = (math.sin(gamma), math.cos(gamma))      # along the flank, outward

    def exit_point(offset: float, radius: float):
        """Where the line tangent to the seat circle of radius ``offset`` at gamma leaves the
        circle of ``radius`` about the neighbour going outward (None: it does not meet it)."""
        q0 = (-offset * math.cos(gamma), offset * math.sin(gamma))
        w = (q0[0] - a[0], q0[1] - a[1])
        b = direction[0] * w[0] + direction[1] * w[1]
        disc = b * b - (w[0] * w[0] + w[1] * w[1] - radius * radius)
        if disc < 0.0:
            return None
        s = -b + math.sqrt(disc)
        return (q0[0] + s * direction[0], q0[1] + s * direction[1])

    centre_line = exit_point(seat_radius - roller_radius, pitch)
    if centre_line is None or centre_line[0] > tip:
        return inactive
    corner = exit_point(seat_radius, pitch - roller_radius)
    if corner is None:  # pragma: no cover - the surface line is the centre line offset by R_r
        return inactive
    # a convex corner: the circle's outward normal turns from the flank's (cos g, -sin g)
    # towards the outward radial (the kernel's normal-cone test takes this orientation)
    assert math.cos(gamma) * (corner[1] - a[1]) + math.sin(gamma) * (corner[0] - a[0]) > 0.0
    return True, a[0], a[1], corner[0], corner[1]


#: settled static tensions per (drive, parameters): a scene's every run asks for the same one
_STATIC_CACHE: dict = {}


class MultibodyModel(Model):
    """Level 3 (see module docstring)."""

    level = 3
    name = "multibody"
    second_order = True
    #: the compiled velocity-Verlet loop: the numbers of one force evaluation pair per step
    #: (made of one pass over the positions and two over the velocities) at 90 % of the
    #: stable step (docs/multibody.md, benchmark in docs/performance.md)
    preferred_method = "verlet"

    def __init__(self, drive: Drive, params: Mapping[str, Any]):
        super().__init__(drive, params)
        # the scene validates already; a direct caller gets the same checks and messages
        self.params = p = PRM.validate({k: v for k, v in params.items() if k in PRM.BY_NAME})
        if drive.links < 3:  # pragma: no cover - Drive asks for >= 4
            raise ValueError(f"drive.links must be at least 3, got {drive.links}")
        self.M = M = drive.links
        pitch = drive.pitch
        k = p["chain.link_stiffness"]
        l0 = pitch - p["chain.pretension"] / k
        clearance = p["contact.seat_radius"] - p["chain.roller_radius"]
        s = fb.seating(drive)
        g1 = flank_geometry(drive.n_driver, pitch, p["contact.seating_angle"])
        g2 = flank_geometry(drive.n_driven, pitch, p["contact.seating_angle"])
        th1 = drive.centre_angle
        incl = p["drive.inclination"]
        g = p["gravity"]
        vals = dict(
            m=p["chain.link_mass"], k=k, c=p["chain.link_damping"], l0=l0,
            kc=p["contact.stiffness"], cc=p["contact.damping"], clearance=clearance,
            gx=g * math.sin(th1 - incl), gy=-g * math.cos(th1 - incl),
            I1=p["driver.inertia"], I2=p["driven.inertia"], kr=p["input_shaft.stiffness"],
            cr=p["input_shaft.damping"], c2=p["driven.damping"], cx=drive.x_c, cy=drive.y_c,
            R1=drive.driver.pitch_radius, R2=drive.driven.pitch_radius, phase1=s.theta4,
            phase2=s.theta2, pitch_angle1=2 * math.pi / drive.n_driver,
            pitch_angle2=2 * math.pi / drive.n_driven,
            sin_gamma1=math.sin(g1[0]), cos_gamma1=math.cos(g1[0]), sin_gamma2=math.sin(g2[0]),
            cos_gamma2=math.cos(g2[0]), tip1=g1[2], tip2=g2[2],
            paper_contact=float(p["contact.seating_angle"] >= math.pi),
            paper_damping=float(p["multibody.paper_damping"]),
            q_forces=float(p["multibody.rotating_frame_forces"]),
            rigid_shaft=float(p["input_shaft.rigid"]), l_min=0.5 * pitch, l_max=1.5 * pitch,
            z1=drive.n_driver, z2=drive.n_driven, cj=p["chain.joint_damping"],
            gap=p["chain.joint_clearance"], onset=DAMPING_ONSET,
            roller_radius=p["chain.roller_radius"], pitch=pitch)
        for side, teeth, g in (("1", drive.n_driver, g1), ("2", drive.n_driven, g2)):
            cut = articulation_cut(teeth, pitch, g[0], g[2], p["chain.roller_radius"],
                                   p["contact.seat_radius"])
            for key, value in zip(("cut", "cut_sl", "cut_u", "corner_sl", "corner_u"), cut):
                vals[key + side] = float(value)
        # rollers farther than this from a sprocket centre cannot touch its teeth (the flank
        # ends at tip; sl <= tip needs |r| cos(pi / z) <= R + tip); 0.1 p keeps the engaged
        # test of the outputs inside it
        for key, teeth, R, tip in (("reach1", drive.n_driver, drive.driver.pitch_radius, g1[2]),
                                   ("reach2", drive.n_driven, drive.driven.pitch_radius, g2[2])):
            vals[key] = (R + max(tip, 0.1 * pitch)) / math.cos(math.pi / teeth) + clearance
        vals["role_hold"] = 0.0          # span roles from the inputs (Model.hold_role)
        self.P = K.pack_tables(np.array([vals[f] for f in K.PARAM_FIELDS], float))
        self.flank = {"gamma_driver": g1[0], "gamma_driven": g2[0], "tip_driver": g1[2],
                      "tip_driven": g2[2], "clearance": clearance,
                      "cut_driver": bool(vals["cut1"]), "cut_driven": bool(vals["cut2"])}
        self.ws = K.Workspace(M)
        # fixed points in the middle of each span's straight line in the reference layout: the
        # span tension is measured in the link whose midpoint is nearest to them
        g0 = chain_geometry(drive, np.array([0.0]), np.array([0.0]))
        self._mid_upper = complex(0.5 * (g0.upper.start[0] + g0.upper.end[0]))
        self._mid_lower = complex(0.5 * (g0.lower.start[0] + g0.lower.end[0]))
        self._n_upper, self._n_lower = int(g0.upper_links[0]), int(g0.lower_links[0])
        self._centres = np.array([[drive.x_c, drive.y_c], [0.0, 0.0]])
        self._mids = np.array([[self._mid_upper.real, self._mid_upper.imag],
                               [self._mid_lower.real, self._mid_lower.imag]])
        self._spans_out = np.zeros((2, 3), np.int64)
        self._out14 = np.zeros(len(OUTPUT_NAMES))
        self._engaged_tol = clearance + ENGAGED_TOLERANCE * pitch

    # --- state -----------------------------------------------------------------------------
    @cached_property
    def state_names(self) -> tuple[str, ...]:
        q = ["driver.angle", "driven.angle"]
        v = ["driver.speed", "driven.speed"]
        for i in range(self.M):
            q += [f"roller[{i}].x", f"roller[{i}].y"]
            v += [f"roller[{i}].vx", f"roller[{i}].vy"]
        return tuple(q + v)

    def state_scale(self) -> np.ndarray:
        """Typical magnitude of each state (absolute tolerances of the adaptive steppers)."""
        n = 2 + 2 * self.M
        sc = np.empty(2 * n)
        sc[:2] = 1.0
        sc[2:n] = 1e-2 * self.drive.pitch
        sc[n:n + 2] = 1.0
        sc[n + 2:] = 1e-2
        return sc

    def rest_driven_angle(self, driver_angle: float) -> float:
        """Driven rotation at which both spans of the rigid layout are stretched equally (rest
        with no load: the free driven sprocket balances the span tensions); the four-bar angle
        when the chain wraps without stretch."""
        from scipy.optimize import brentq
        d = self.drive
        phi2_k = float(driven_rotation(d, driver_angle).driven_angle)

        G = geometry_constants(d)

        def unequal(phi2):
            # the scalar compiled twin of chain_geometry (levels 0-2's kernel)
            g = span_geometry(float(driver_angle), float(phi2), G)
            return g[0] / g[3] - g[9] / g[12]

        a_o = math.pi / d.n_driven
        f0 = unequal(phi2_k)
        if abs(f0) < 1e-12 * d.pitch:
            return phi2_k
        lo, hi = (phi2_k - a_o, phi2_k) if f0 < 0 else (phi2_k, phi2_k + a_o)
        try:
            return float(brentq(unequal, lo, hi, xtol=1e-14))
        except ValueError:
            return phi2_k

    def initial_state(self, u: Inputs) -> np.ndarray:
        """At rest in the model's static equilibrium
        (:func:`~chainmodel.models.multibody_statics.static_state`): rollers in their seats and
        spans in their sag, the driven sprocket loaded by ``u.torque``, the driver at
        ``u.angle`` less the input shaft's twist under that load. Levels 0-2 start from their
        loaded equilibrium too (``TorsionalModel.initial_state``), so the ladder's runs share
        their start, and a start-up is the inputs' own, not:

        * the load stepping onto an unloaded chain: a 12B 20/40 drive at 10 rpm and 5 % of its
          breaking load rang for 2 s with 60-160x level 1's driven-speed ripple (an audit,
          twenty-second session of issue 21), and C1's means over 0.6-1.2 s at 60 rpm carried
          that ring, -1.6 / -3.1 % on its spans against this start (docs/multibody.md, "Start");
        * the straight spans' release where the chain must stretch over the wrap (xu2010 at
          197.7 mm: 1238 N in both spans at t = 0, 0 N 0.2 ms later, then a ring for 10 ms);
        * a chain too long for straight spans starting with its links in compression (112 kN
          on xu2010 with two links too many), or one its weight holds dropping into its sag.

        Where the statics find no equilibrium under the load (a chain so long that the load
        drags it over the teeth), the unloaded one; where they find none at all, the rigid
        layout of :meth:`straight_layout`."""
        from .multibody_statics import static_state
        load = float(u.torque)
        sol = None
        self.start_fallback = None
        for m in ((load, 0.0) if load != 0.0 else (0.0,)):
            try:   # under the load, else (a chain the load drags over the teeth) without it
                sol = (self.static_solution() if float(u.angle) == 0.0 and m == 0.0
                       else static_state(self, float(u.angle), m, long_solve=True))
            except ValueError:
                continue
            if sol is not None:
                break
        if sol is None or m != load:
            self.start_fallback = (
                f"level 3 found no static equilibrium under load.torque = {load:g} N.m at the "
                f"start, so the chain started {'unloaded in its statics' if sol is not None else 'unloaded in the rigid layout'}"
                f" and the load stepped onto it at t = 0: the first tens of milliseconds (and "
                f"on a lightly damped drive longer) carry that start's ring, not the inputs' "
                f"(a slack span near 0 N under the load; docs/multibody.md, \"Start\")")
            load = m if sol is not None else load
        if sol is not None and not self.params["input_shaft.rigid"]:
            # the driver where the shaft spring carries the chain's torque on it:
            # k_r (angle - phi_1) + T_chain = 0, T_chain from the accelerations at rest
            twist = self._chain_torque_on_driver(sol.state, u) / self.params[
                "input_shaft.stiffness"]
            try:
                if twist != 0.0:
                    sol = static_state(self, float(u.angle) + twist, load, long_solve=True)
            except ValueError:
                pass     # the untwisted equilibrium: the shaft spring's own start-up only
        if sol is None:
            return self.straight_layout(u)
        rest = np.array(sol.state, float)
        rest[2 + 2 * self.M:] = 0.0
        return rest

    def _chain_torque_on_driver(self, x: np.ndarray, u: Inputs) -> float:
        """The chain's torque on the driver [N m] in state ``x`` at rest, the shaft spring
        relaxed (its input angle at the driver's): driver inertia times its acceleration."""
        rest = np.array(x, float)
        rest[2 + 2 * self.M:] = 0.0
        a = self.rhs(0.0, rest, Inputs(float(rest[0]), 0.0, float(u.torque), 0.0))
        return self.params["driver.inertia"] * float(a[2 + 2 * self.M])

    def hold_role(self, hold: float) -> None:
        self.P[K.I_ROLE] = float(hold)

    def straight_layout(self, u: Inputs) -> np.ndarray:
        """At rest, the chain wrapped with straight spans (kinematics.wrapping.roller_positions)
        at driver rotation u.angle and the driven rotation that stretches both spans equally."""
        phi1 = float(u.angle)
        phi2 = self.rest_driven_angle(phi1)
        z = roller_positions(self.drive, phi1, phi2)
        n = 2 + 2 * self.M
        x = np.zeros(2 * n)
        x[0], x[1] = phi1, phi2
        x[2:n] = z.ravel()
        return x

    # --- dynamics --------------------------------------------------------------------------
    def _accel(self, x, tau, tau_d, tau_dd, load):
        n = 2 + 2 * self.M
        return accel(x[:n], x[n:], tau, tau_d, tau_dd, load, self.P, self.ws)

    def rhs(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        n = 2 + 2 * self.M
        a, _, _ = self._accel(x, u.angle, u.speed, u.acceleration, u.torque)
        out = np.empty(2 * n)
        out[:n] = x[n:]
        out[n:] = a
        return out

    def check(self, t: float, x: np.ndarray) -> None:
        """SimulationDiverged when a link leaves [0.5, 1.5] pitches or the state is not finite,
        with the cause: a chain too soft for its tension (most links stretched by a tenth of a
        pitch or more, none faster than an elastic wave crosses a link: the stiffness, not the step,
        is at fault) or a diverging integration."""
        if not np.all(np.isfinite(x)):
            raise SimulationDiverged(
                f"multibody model diverged at t = {t:.6g} s (non-finite state); try a smaller "
                "solver.step")
        n = 2 + 2 * self.M
        z = x[2:n].reshape(self.M, 2)
        dz = np.diff(z, axis=0, append=z[:1])
        L2 = np.einsum("ij,ij->i", dz, dz) / self.drive.pitch ** 2
        if L2.max() <= 2.25 and L2.min() >= 0.25:
            return
        L = np.sqrt(L2)
        i = int(np.argmax(np.abs(L - 1.0)))
        k = self.params["chain.link_stiffness"]
        p = self.drive.pitch
        stretch = L * p - self.P[K.I_L0]
        taut = stretch > 0
        # a link stretching faster than an elastic wave crosses it, p sqrt(k / m), is the
        # integration running away (h omega past the stability limit), not a soft chain's
        # quasi-static stretch, however many links it has reached by now
        v = x[n + 2:2 * n].reshape(self.M, 2)
        dv = np.diff(v, axis=0, append=v[:1])
        rate = float(np.max(np.abs(np.einsum("ij,ij->i", dz, dv)) / (L * p)))
        wave = p * math.sqrt(k / self.params["chain.link_mass"])
        if rate > wave:
            raise SimulationDiverged(
                f"multibody model diverged at t = {t:.6g} s: link {i} has length {L[i]:.3g} "
                f"pitches and stretches at {rate:.3g} m/s, faster than an elastic wave crosses "
                f"a link ({wave:.3g} m/s): the integration is unstable; try a smaller "
                "solver.step (0 for automatic)")
        if np.count_nonzero(stretch > 0.1 * p) >= max(3, self.M // 4):
            tension = float(np.percentile(k * stretch[taut], 90))
            raise SimulationDiverged(
                f"multibody model stopped at t = {t:.6g} s: the chain is too soft for its "
                f"tension - chain.link_stiffness = {k:g} N/m stretches {np.count_nonzero(stretch > 0.1 * p)} "
                f"of {self.M} links by more than a tenth of a pitch (90th-percentile link tension "
                f"{tension:.4g} N) and link {i} to {L[i]:.3g} pitches; level 3 needs links "
                f"stretched by a few percent at most: raise chain.link_stiffness (at least "
                f"{20 * tension / p:.3g} N/m keeps this tension within 5 % of the pitch)")
        raise SimulationDiverged(
            f"multibody model diverged at t = {t:.6g} s: link {i} has length {L[i]:.3g} "
            "pitches while the rest of the chain is not stretched; try a smaller solver.step")

    # --- compiled stepping (kernels.multibody_loops) ----------------------------------------
    #: fixed-step methods with a compiled loop: advance_points / advance_held
    compiled_methods = ("verlet", "rk4")
    #: the automatic step is the stability bound of the current state (90 % of it, the
    #: stable-step guard re-estimating it every communication step); solver.tolerance is not
    #: used: the bound comes from the stiff roller-seat and link modes, and at that step the
    #: outputs are converged well below it (docs/numerics.md, level 3)
    tolerance_applies = False

    def has_loop_kernel(self, method: str) -> bool:
        """The kernels' loops, compiled or (CHAINMODEL_NUMBA=0) their plain twins."""
        return method in self.compiled_methods

    def advance_points(self, method, x_in, x_out, times, angle, speed, acceleration, torque, cfg,
                       out, states, log, log_cap):
        """The fixed-step loop of ``method`` (verlet exactly as ``Verlet._step``, rk4 as
        ``RK4._step``) through the communication points ``times`` in one compiled call, with
        the outputs at every point (kernels.multibody_loops.points_loop). Inputs inside a
        communication step: a cubic Hermite through its ends' angle and speed (exact for held
        inputs and the scene ramps)."""
        if not self.has_loop_kernel(method):
            return None
        res = run_points(0 if method == "verlet" else 1, x_in, x_out, times, angle,
                         speed, acceleration, torque, self.P, self._omega_constants,
                         self._bounded(cfg), self.ws, self._mids, self._engaged_tol,
                         self.drive.tooth_ratio, self._spans_out, out, states)
        if out.shape[0] and res[1] == 0:
            rows = slice(1, times.shape[0])
            self._ratio_at_rest(out[rows], angle[rows], speed[rows])
        return res

    def advance_held(self, method, x_in, x_out, t0, t1, angle, speed, acceleration, torque, cfg,
                     out, log):
        """:meth:`advance_points` over one communication step with the inputs held first-order
        (the FMU's hold), outputs at t1 in out[1]."""
        if not self.has_loop_kernel(method):
            return None
        res = run_held(0 if method == "verlet" else 1, x_in, x_out, t0, t1, angle,
                       speed, acceleration, torque, self.P, self._omega_constants,
                       self._bounded(cfg), self.ws, self._mids, self._engaged_tol,
                       self.drive.tooth_ratio, self._spans_out, out)
        if res[1] == 0 and abs(out[1, O_DRIVER_SPEED]) < REST_SPEED:
            self._ratio_at_rest(out[1:2], np.array([angle + speed * (t1 - t0)]),
                                np.array([speed]))
        return res

    def _bounded(self, cfg: np.ndarray) -> np.ndarray:
        """The step rule ``cfg`` with its outer bound lowered to :meth:`event_step` (which does
        not depend on the speed at this level): what the Python loop does, for the compiled
        one."""
        h_event = self.__dict__.get("_h_event")
        if h_event is None:
            h_event = self._h_event = self.event_step(0.0)
        if not h_event < cfg[K.CF_MAX]:
            return cfg
        buf = self.__dict__.get("_cfg_buf")
        if buf is None:
            buf = self._cfg_buf = np.empty_like(cfg)
        buf[:] = cfg
        buf[K.CF_MAX] = h_event
        return buf

    def _ratio_at_rest(self, rows, angle, speed) -> None:
        """velocity_ratio of the rows whose driver is at rest (|speed| < REST_SPEED): the exact
        four-bar ratio at the driver's angle (level 0), as :meth:`outputs` reports it."""
        rest = np.abs(rows[:, O_DRIVER_SPEED]) < REST_SPEED
        if not rest.any():
            return
        for rev in (False, True):
            sel = rest & ((np.asarray(speed) < 0) == rev)
            if sel.any():
                rows[sel, O_VELOCITY_RATIO] = driven_rotation(self.drive, rows[sel, O_DRIVER_ANGLE],
                                                              reverse=rev).velocity_ratio

    def outputs_into(self, t, x, angle, speed, acceleration, torque, out) -> None:
        """Every output (ALL_OUTPUTS order) into ``out``: one kernel call."""
        fill_outputs(x, angle, speed, acceleration, torque, self.P, self.ws, self._mids,
                     self._engaged_tol, speed < 0, self.drive.tooth_ratio, self._spans_out, out)
        if abs(out[O_DRIVER_SPEED]) < REST_SPEED:
            self._ratio_at_rest(out.reshape(1, -1), np.array([angle]), np.array([speed]))

    def omega_at(self, t: float, x: np.ndarray, u: Inputs) -> float:
        return self.omega_max(x)

    # --- capabilities ----------------------------------------------------------------------
    def omega_max(self, x=None) -> float:
        """Upper bound of the highest natural frequency [rad/s] (Gershgorin on the
        mass-normalised tangent stiffness; derivation in docs/multibody.md), raised to the
        damping rate (4 c + c_c + 16 c_j / p^2) / m if that is larger. With a state x the links
        count with their current stiffness max(k, |T| / L) (the guard of the compiled loop,
        kernels.multibody_forces.omega_bound, computes the same)."""
        p = self.params
        k = p["chain.link_stiffness"]
        k_link = k
        if x is not None:
            n = 2 + 2 * self.M
            z = np.asarray(x[2:n], float).reshape(self.M, 2)
            L = np.hypot(*(np.roll(z, -1, axis=0) - z).T)
            if np.all(np.isfinite(L)) and np.all(L > 0):
                tension = k * (L - self.P[K.I_L0])
                k_link = max(k, float(np.max(np.abs(tension) / L)))
        om = self._omega_constants
        return max(math.sqrt(max(om[0] * k_link + om[1], om[2])), om[3])

    @cached_property
    def _omega_constants(self) -> np.ndarray:
        """[4 / m, k_c / m + the larger seat coupling, the larger sprocket term, the damping
        rate] of :meth:`omega_max`: a roller's w^2 is (4 k_link + k_c) / m + k_c r /
        sqrt(m I) (r = R + tip) for the sprocket it touches, a sprocket's (extra + z k_c r^2) /
        I + z k_c r / sqrt(m I) with z = min(teeth, M) seats and extra the shaft stiffness."""
        p, d = self.params, self.drive
        m = p["chain.link_mass"]
        kc = p["contact.stiffness"]
        roller, sprocket = 0.0, 0.0
        for teeth, R, tip, inertia, extra in (
                (d.n_driver, d.driver.pitch_radius, self.P[K.I_TIP1], p["driver.inertia"],
                 p["input_shaft.stiffness"]),
                (d.n_driven, d.driven.pitch_radius, self.P[K.I_TIP2], p["driven.inertia"], 0.0)):
            r = R + tip
            coupling = kc * r / math.sqrt(m * inertia)
            seats = min(teeth, self.M)
            roller = max(roller, kc / m + coupling)
            sprocket = max(sprocket, (extra + seats * kc * r * r) / inertia + seats * coupling)
        # joint dampers act through 1/L^2 lever arms on up to 4 joints of a roller's two links
        damping_rate = (4 * p["chain.link_damping"] + p["contact.damping"]
                        + 16 * p["chain.joint_damping"] / d.pitch ** 2) / m
        return np.array([4.0 / m, roller, sprocket, damping_rate])

    def stable_step(self, x: np.ndarray) -> float:
        return 1.0 / self.omega_max(x)

    def event_step(self, speed: float) -> float:
        """Bound on the automatic step: none while the links are damped; with the links' zig-zag
        mode damped less than UNDAMPED_LINKS of critical, IMPACT_STEP / omega_max. A slack link
        snapping taut is then an undamped impact on the link spring (half a period,
        pi / omega, long), and velocity Verlet at 90 % of its stability limit (h omega = 1.8,
        under two steps per impact) gains energy at such impacts until the run diverges; at
        h omega = 0.225 (14 steps per impact) the energy error stays at the scheme's O(h^2)
        (docs/multibody.md "Energy without dissipation")."""
        p = self.params
        zeta = p["chain.link_damping"] / math.sqrt(p["chain.link_stiffness"] * p["chain.link_mass"])
        return math.inf if zeta >= UNDAMPED_LINKS else IMPACT_STEP / self.omega_max()

    def refuse_method(self, method: str) -> str | None:
        """Why ``method`` is refused at this level (None: accepted). The implicit steppers are:
        the model is stiff (link zig-zag mode ~18 kHz) *and* non-smooth (seat contacts open and
        close, links go slack, hundreds of times per tooth period), so Newton iterations fail
        at the kinks and the step collapses below the explicit stable step; the sprocket rows
        of the Jacobian are full (any roller may touch a seat), so scipy's finite differences
        cost a column per state. Measured on xu2010 (0.01 s, docs/multibody.md "Steppers"):
        radau 22 s, bdf 8 s CPU against about 1 s for verlet and rk45, same answer."""
        if method in ("radau", "bdf", "lsoda"):
            return (f"solver.method = {method} is refused at level 3 (multibody): the model is "
                    "stiff and non-smooth (contacts and slack links switch hundreds of times per "
                    "tooth period), so implicit steppers take minutes where verlet takes seconds "
                    "(xu2010, 0.01 s: radau 22 s, bdf 8 s, verlet 1 s CPU); use solver.method = "
                    "verlet (the default, auto) or rk4")
        return None

    def jacobian_sparsity(self):
        """d(rhs)/dx pattern: dq/dt = v; a roller's acceleration depends on the positions and
        velocities of the rollers up to two links away (links; joint dampers span two links) and
        on both sprockets'; the sprockets' on every roller's (any roller may touch a seat)."""
        from scipy.sparse import lil_matrix
        M = self.M
        n = 2 + 2 * M
        S = lil_matrix((2 * n, 2 * n), dtype=np.int8)
        for i in range(n):
            S[i, n + i] = 1
        for base in (0, n):
            S[n:n + 2, base:base + n] = 1
            for i in range(M):
                rows = [n + 2 + 2 * i, n + 3 + 2 * i]
                for j in range(i - 2, i + 3):
                    jj = j % M
                    for r in rows:
                        S[r, base + 2 + 2 * jj] = 1
                        S[r, base + 3 + 2 * jj] = 1
                        S[r, base] = 1
                        S[r, base + 1] = 1
        return S.tocsr()

    def static_tension(self) -> float:
        """Static span tension at rest with no load [N]: the mean of the two span tensions
        (measured as the outputs are, the middle link of each span) at the static equilibrium
        of this model's own force law with the driver held at angle 0, gravity included
        (:func:`~chainmodel.models.multibody_statics.static_state`; docs/multibody.md,
        "Statics"). Where Newton finds no equilibrium (a drive level 3 cannot hold, such as a
        3-tooth sprocket that skips teeth) it falls back to the tension after a damped 60 ms
        relaxation from the initial layout."""
        return self._static[0]

    def static_solution(self):
        """The :class:`~chainmodel.models.multibody_statics.StaticSolution` behind
        :meth:`static_tension` (driver at angle 0, no load; cached per drive and parameters);
        None where the statics found no equilibrium and the tension is the settled one."""
        return self._static[3]

    @cached_property
    def _static(self):
        key = (self.drive, tuple(sorted(self.params.items())))
        if key not in _STATIC_CACHE:
            if len(_STATIC_CACHE) > 64:
                _STATIC_CACHE.clear()
            from .multibody_statics import static_state
            try:
                sol = static_state(self, long_solve=True)
                _STATIC_CACHE[key] = (sol.mean_tension, sol.tension_upper, sol.tension_lower,
                                      sol)
            except ValueError:
                # no static equilibrium found (a drive level 3 cannot hold, e.g. a 3-tooth
                # sprocket that skips): the settled state of a damped 60 ms relaxation
                _STATIC_CACHE[key] = self._settle() + (None,)
        return _STATIC_CACHE[key]

    def _settle(self) -> tuple[float, float, float]:
        """(mean, upper, lower) span tension after the chain has settled for 60 ms from the
        straight layout with extra link damping, the driver held at 0 and no load (the
        fallback of :meth:`static_tension` where the statics find no equilibrium)."""
        relax = dict(self.params)
        m, k = relax["chain.link_mass"], relax["chain.link_stiffness"]
        relax["chain.link_damping"] = max(relax["chain.link_damping"], 0.25 * math.sqrt(k * m))
        relax["driven.damping"] = max(relax["driven.damping"],
                                      0.2 * math.sqrt(relax["driven.inertia"] * 1e4))
        relax["multibody.rotating_frame_forces"] = False
        model = MultibodyModel(self.drive, relax)
        from ..integrate import Verlet
        u = Inputs(0.0, 0.0, 0.0)
        st = Verlet(model, 0.0, model.straight_layout(u), u)
        up, low = [], []
        for i in range(1, 61):
            out = st.advance(i * 1e-3, u)
            if i > 40:
                up.append(out["tight_span.tension"])
                low.append(out["slack_span.tension"])
        tu, tl = float(np.mean(up)), float(np.mean(low))
        return 0.5 * (tu + tl), tu, tl

    # --- outputs ---------------------------------------------------------------------------
    def output_descriptions(self) -> dict[str, str]:
        d = super().output_descriptions()
        d["tight_span.tension"] = ("axial force of the tight-span link whose midpoint is nearest "
                                   "the middle of the span's line; the tight span is the physical "
                                   "span the driver pulls for the sign of the transmitted torque "
                                   "(upper when load.torque + ratio (driven damping x input speed "
                                   "+ driven inertia x input acceleration) > 0, else lower), "
                                   "whatever the momentary forces")
        d["slack_span.tension"] = ("axial force of the slack-span link whose midpoint is nearest "
                                   "the middle of the span's line (the other span)")
        d["tight_span.length"] = ("distance between the tight span's endpoint rollers (the last "
                                  "roller engaged on the sprocket it leaves, the first on the one "
                                  "it runs onto)")
        d["velocity_ratio"] = ("driven speed / driver speed; while the driver is at rest "
                               f"(|speed| < {REST_SPEED:g} rad/s) the exact four-bar ratio at the "
                               "driver's angle (level 0)")
        d["input_shaft.torque"] = ("input-shaft spring and damper torque k_r (tau - phi1) + "
                                   "c_r (tau' - phi1') (rigid shaft: I1 tau'' minus the chain's "
                                   "torque on the driver)")
        d["driven.acceleration"] = "driven sprocket angular acceleration from eq (15)"
        d["tight_span.midspan_deflection"] = (
            "distance of the tight span's middle roller from the line between its endpoint "
            "rollers, positive away from the line of centres")
        d["chain.max_link_tension"] = "largest axial link force in the chain"
        d["contact.max_force"] = "largest roller-seat normal contact force"
        d["chain.min_link_tension"] = ("smallest axial link force in the chain: 0 while a link is "
                                       "slack (inside its pin-bushing play), negative only while "
                                       "its plates bear in compression")
        return d

    def _engaged(self, x):
        """(2, M) bool: roller seated on the driver / driven sprocket (within the clearance of a
        seat centre, or touching a seat within the pitch radius plus the clearance; a roller
        riding a flank farther out is entering or leaving)."""
        return engaged_numpy(np.asarray(x[:2 + 2 * self.M]), self.ws.dist, self.ws.side,
                               self.ws.seat_angle, self._engaged_tol, self.P)

    def _evaluate(self, t, x, u):
        """Forces at (t, x, u) and the spans: ((mid link, start roller, end roller) of the upper
        and the lower span; see kernels.multibody_outputs.span_ends)."""
        n = 2 + 2 * self.M
        acc, status, shaft = self._accel(x, u.angle, u.speed, u.acceleration, u.torque)
        spans = self._spans_out
        span_ends(x[:n], self.ws.dist, self.ws.side, self.ws.seat_angle, self._engaged_tol,
                  self.P, self._mids, spans)
        z = x[2:n].reshape(self.M, 2)
        return acc, shaft, z, tuple(int(i) for i in spans[0]), tuple(int(i) for i in spans[1])

    def outputs(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, float]:
        out = self._out14
        fill_outputs(np.asarray(x, float), u.angle, u.speed, u.acceleration, u.torque, self.P,
                     self.ws, self._mids, self._engaged_tol, u.speed < 0, self.drive.tooth_ratio,
                     self._spans_out, out)
        res = dict(zip(OUTPUT_NAMES, out.tolist()))
        if abs(res["driver.speed"]) < REST_SPEED:
            res["velocity_ratio"] = float(driven_rotation(
                self.drive, res["driver.angle"], reverse=u.speed < 0).velocity_ratio)
        return res

    def snapshot(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, np.ndarray]:
        """Arrays for plots: roller_positions (M, 2) [m], link_tension (M,) [N] (link i joins
        roller i and i+1), contact_force (M,) [N], contact_sprocket (M,) (0 free, 1 driver,
        2 driven), engaged_driver / engaged_driven (M,) bool, tight_span_rollers (2,) (endpoint
        roller indices), seat_positions_driver (z1, 2), seat_positions_driven (z2, 2)."""
        acc, shaft, z, up, low = self._evaluate(t, x, u)
        d = self.drive
        engaged = self._engaged(x)
        t = self.ws.tension
        tight = low if (t[low[0]] > t[up[0]] or (t[low[0]] == t[up[0]] and u.speed < 0)) else up
        seats = []
        for s, (teeth, R, cen) in enumerate(((d.n_driver, d.driver.pitch_radius, self._centres[0]),
                                             (d.n_driven, d.driven.pitch_radius, self._centres[1]))):
            phase = self.P[K.I_PH1 + s] - x[s]
            ang = phase + 2 * math.pi / teeth * np.arange(teeth)
            seats.append(cen + R * np.column_stack([np.cos(ang), np.sin(ang)]))
        return {"roller_positions": z.copy(),
                "link_tension": self.ws.tension.copy(),
                "contact_force": self.ws.fcon.copy(),
                "contact_sprocket": self.ws.side.copy(),
                "engaged_driver": engaged[0].copy(),
                "engaged_driven": engaged[1].copy(),
                "tight_span_rollers": np.array([tight[1], tight[2]]),
                "seat_positions_driver": seats[0],
                "seat_positions_driven": seats[1]}

    # --- energy (tests, docs) -----------------------------------------------------------------
    def energy(self, x: np.ndarray, u: Inputs) -> dict[str, float]:
        """Kinetic energy and the potentials of U (eq A2): links, contacts, gravity, shaft [J]."""
        p = self.params
        n = 2 + 2 * self.M
        q, v = x[:n], x[n:]
        m = p["chain.link_mass"]
        kin = 0.5 * m * float(v[2:] @ v[2:]) + 0.5 * p["driver.inertia"] * v[0] ** 2 \
            + 0.5 * p["driven.inertia"] * v[1] ** 2
        z = q[2:].reshape(self.M, 2)
        L = np.hypot(*(np.roll(z, -1, axis=0) - z).T)
        links = float(np.sum(link_potential(L - self.P[K.I_L0], p["chain.link_stiffness"],
                                            self.P[K.I_GAP])))
        self._accel(x, u.angle, u.speed, u.acceleration, u.torque)
        pen = np.where(self.ws.side > 0, self.ws.fcon / p["contact.stiffness"], 0.0)
        contact = 0.5 * p["contact.stiffness"] * float(pen @ pen)
        grav = -m * float(np.sum(z[:, 0] * self.P[K.I_GX] + z[:, 1] * self.P[K.I_GY]))
        shaft = 0.0 if p["input_shaft.rigid"] else 0.5 * p["input_shaft.stiffness"] * (u.angle - q[0]) ** 2
        return {"kinetic": kin, "links": links, "contact": contact, "gravity": grav,
                "shaft": shaft}


"""The power level 3 loses inside the chain, against the joint friction it stands in for (a
validity check: chainmodel.validity, code ``damper_losses``; docs/multibody.md "Convergence and
default damping", item 5).

Level 3's chain has no friction; it loses power only in its dampers (links, roller-seat contacts
and the joint dampers ``chain.joint_damping``, a viscous stand-in for pin-bushing friction sized
on xu2010's 10B at 120 rpm). A viscous damper matches Coulomb friction at one articulation rate:
its loss grows with the speed squared, the friction's with the speed. Over a window that starts
once the driver has turned one revolution:

* the loss: the work the input shaft does on the driver, int T_shaft w1 dt, less the work into
  the load and the driven damping, int (M + d2 w2) w2 dt, less the change of the kinetic energy
  of the sprockets and the chain moving at the driver's pitch speed (positive whichever way
  the power flows);
* the joint friction of the same drive: every link articulates through 2 pi / z entering and
  leaving each sprocket under the tension of the span it joins, against mu T r_pin, at
  z1 |w1| / 2 pi links per second: P_f = mu r_pin z1 (1/z1 + 1/z2) |w1| (T_tight + T_slack),
  mu = ``FRICTION`` (lubricated steel on steel, the value the joint damping is sized with),
  r_pin = d2 / 2 of the ISO 606 chain of this pitch and roller (chainmodel.chains);
* both as shares of the work the chain transmits, the larger of |input work| and |work into
  the load|: under forward drive the input work, under an overrunning load (the load drives,
  the input shaft brakes: input work negative) the load's.

The result depends on damping no source gives when the loss exceeds ``RATIO`` times that
friction and the excess is more than ``EXCESS`` of the transmitted work (the input torque is
then off by that much).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from .geometry import Drive

__all__ = ["FRICTION", "RATIO", "EXCESS", "OUTPUTS", "pin_radius", "LossBalance",
           "balance_duration", "run_shares"]

#: pin-bushing friction coefficient (lubricated steel on steel; docs/multibody.md)
FRICTION = 0.1
#: the dampers' loss against the joint friction above which the check fires
RATIO = 2.0
#: ... when the excess over that friction is also above this share of the transmitted work
EXCESS = 0.02
#: the outputs the balance needs (besides the input speed and load torque)
OUTPUTS = ("driver.angle", "driver.speed", "driven.speed", "input_shaft.torque",
           "tight_span.tension", "slack_span.tension")


def pin_radius(drive: Drive, params: Mapping[str, Any]) -> tuple[float, str] | None:
    """(d2 / 2 [m], chain name) of the ISO 606 chain of this pitch and roller diameter
    (:func:`~chainmodel.presets.iso606_matches`, as the breaking load's), or None for a pitch
    chainmodel.chains does not list. Of two (10A and 10B share pitch and roller), the one whose
    minimum tensile strength is the scene's ``chain.breaking_load``, else the larger pin."""
    from .chains import DIMENSIONS
    from .presets import iso606_matches
    sizes, _ = iso606_matches(drive.pitch, 2.0 * float(params.get("chain.roller_radius", 0.0)))
    names = [c.name for c in sizes if c.name in DIMENSIONS]
    if not names:
        return None
    strength = float(params.get("chain.breaking_load", math.nan))
    named = [n for n in names if abs(DIMENSIONS[n].size.tensile_strength - strength)
             <= 1e-6 * strength]
    name = named[0] if len(named) == 1 else max(names, key=lambda n: DIMENSIONS[n].pin_diameter)
    return 0.5 * DIMENSIONS[name].pin_diameter, name


class LossBalance:
    """The sums of the module docstring, fed with arrays of consecutive samples (several calls
    continue one another: the last sample is carried over)."""

    def __init__(self, drive: Drive, params: Mapping[str, Any]):
        self.drive = drive
        p = params
        self.j1, self.j2 = float(p["driver.inertia"]), float(p["driven.inertia"])
        self.d2 = float(p["driven.damping"])
        self.chain_mass = (drive.links or 0) * float(p["chain.link_mass"])
        self.r1 = drive.driver.pitch_radius
        pin = pin_radius(drive, p)
        self.pin = pin
        z1, z2 = drive.n_driver, drive.n_driven
        self.friction_factor = (math.nan if pin is None
                                else FRICTION * pin[0] * z1 * (1.0 / z1 + 1.0 / z2))
        self.start_angle = None      # the driver's angle at the first sample
        self.window_angle = None     # ... at the window's first sample
        self.energy0 = 0.0
        self.energy1 = 0.0
        self.work_in = self.work_out = self.friction = 0.0
        self.last = None             # the last sample (t, phi1, p_in, p_out, p_f, energy)

    def _energy(self, w1, w2):
        return 0.5 * (self.j1 * w1 * w1 + self.j2 * w2 * w2
                      + self.chain_mass * (self.r1 * w1) ** 2)

    def add_one(self, t, phi1, w1, w2, shaft, tight, slack, load) -> None:
        """Take one sample (numbers): :meth:`add`'s sums in plain floats, for the FMU's
        communication points."""
        if self.start_angle is None:
            self.start_angle = phi1
        p_in, p_out, p_f = shaft * w1, (load + self.d2 * w2) * w2, abs(w1) * (tight + slack)
        energy = self._energy(w1, w2)
        last = self.last
        self.last = (t, phi1, p_in, p_out, p_f, energy)
        if abs(phi1 - self.start_angle) < 2.0 * math.pi:
            return
        if self.window_angle is None or last is None:
            if self.window_angle is None:
                self.window_angle, self.energy0 = phi1, energy
        else:
            h = 0.5 * (t - last[0])
            self.work_in += h * (p_in + last[2])
            self.work_out += h * (p_out + last[3])
            self.friction += h * (p_f + last[4])
        self.energy1 = energy

    def add(self, t, phi1, w1, w2, shaft, tight, slack, load) -> None:
        """Take samples (arrays; ``load`` may be one number), the same sums as :meth:`add_one`
        on each in turn, vectorised."""
        t, phi1, w1, w2, shaft, tight, slack, load = np.broadcast_arrays(
            *(np.atleast_1d(np.asarray(a, float)) for a in
              (t, phi1, w1, w2, shaft, tight, slack, load)))
        if not t.size:
            return
        if self.start_angle is None:
            self.start_angle = float(phi1[0])
        p_in = shaft * w1
        p_out = (load + self.d2 * w2) * w2
        p_f = np.abs(w1) * (tight + slack)
        energy = self._energy(w1, w2)
        inside = np.abs(phi1 - self.start_angle) >= 2.0 * math.pi
        if self.last is not None:
            lt, lphi, lpin, lpout, lpf, le = self.last
            t = np.r_[lt, t]
            p_in, p_out, p_f = np.r_[lpin, p_in], np.r_[lpout, p_out], np.r_[lpf, p_f]
            energy, phi1 = np.r_[le, energy], np.r_[lphi, phi1]
            inside = np.r_[abs(lphi - self.start_angle) >= 2.0 * math.pi, inside]
        self.last = (float(t[-1]), float(phi1[-1]), float(p_in[-1]), float(p_out[-1]),
                     float(p_f[-1]), float(energy[-1]))
        if not inside.any():
            return
        k = int(np.argmax(inside))
        if self.window_angle is None:
            self.window_angle, self.energy0 = float(phi1[k]), float(energy[k])
        tt = t[k:]
        if tt.size > 1:
            self.work_in += float(np.trapezoid(p_in[k:], tt))
            self.work_out += float(np.trapezoid(p_out[k:], tt))
            self.friction += float(np.trapezoid(p_f[k:], tt))
        self.energy1 = float(energy[-1])

    def shares(self) -> tuple[float, float] | None:
        """(loss, joint friction) as shares of the transmitted work over the window (the
        larger of |input work| and |work into the load|: module docstring), or None before the
        window holds one revolution of the driver, without work transmitted, or without an ISO
        606 chain to size the friction."""
        transmitted = max(abs(self.work_in), abs(self.work_out))
        if (self.window_angle is None or self.last is None or self.pin is None
                or abs(self.last[1] - self.window_angle) < 2.0 * math.pi
                or not transmitted > 0):
            return None
        loss = self.work_in - self.work_out - (self.energy1 - self.energy0)
        return loss / transmitted, self.friction_factor * self.friction / transmitted

    def message(self) -> str | None:
        """The warning's sentence when the dampers' loss exceeds the joint friction (module
        docstring), else None."""
        s = self.shares()
        if s is None:
            return None
        loss, friction = s
        if not (loss > RATIO * friction and loss - friction > EXCESS):
            return None
        work = ("input work" if abs(self.work_in) >= abs(self.work_out) else
                "work the overrunning load puts in")
        return (f"level 3's dampers take {100 * loss:.3g} % of the {work}, {loss / friction:.3g}x "
                f"the pin-bushing friction of this drive ({100 * friction:.3g} %: mu = {FRICTION:g}, "
                f"ISO 606 {self.pin[1]} pin radius {1e3 * self.pin[0]:.3g} mm, the run's span "
                f"tensions): the viscous joint dampers (chain.joint_damping, sized for a 10B chain "
                f"at 120 rpm) grow with the speed squared, friction with the speed, so the input "
                f"torque and the span tensions carry damping no source gives; lower "
                f"chain.joint_damping, or read the result with the trade study's damping band "
                f"(docs/multibody.md)")


def balance_duration(scene, at_least: float = 0.0) -> float:
    """A run long enough for the balance [s]: its window starts once the driver has turned one
    revolution and needs one more, so three revolutions after the ramp (at least ``at_least``);
    ``scene`` a chainmodel.scene.Scene."""
    op = scene.operating
    revolutions = 3.0 * 2.0 * math.pi / abs(op.speed) if op.speed else 0.0
    return max(at_least, revolutions + op.ramp_time)


def run_shares(result) -> tuple[float, float] | None:
    """:meth:`LossBalance.shares` (loss, joint friction) over a whole run (a
    chainmodel.simulation.Result with the :data:`OUTPUTS`), None as there."""
    sc = result.scene
    balance = LossBalance(sc.drive, sc.parameters)
    balance.add(result.time, *(result[n] for n in OUTPUTS), sc.input_arrays(result.time)[3])
    return balance.shares()

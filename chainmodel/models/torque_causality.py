"""Torque causality (``input_shaft.causality = torque``): a motor rotor driven by a torque at the
far end of the input-shaft spring, integrated with the drive.

In angle causality (the default) the far end of the input-shaft spring k_r, c_r (seed 003
eq 14) follows the inputs input_shaft.angle and input_shaft.speed; a motor model outside the
FMU closes the loop through the stiff spring, which explicit co-simulation resolves only at
communication steps h with h omega_c <~ 1, omega_c = sqrt(k_r (1/J_motor + 1/I_driver))
(issue 18). Here the motor rotor of inertia J_m (``motor.inertia``) is a state of the drive::

    J_m theta_m'' = T_m - T_s,      T_s = k_r (theta_m - phi1) + c_r (theta_m' - phi1')

with T_m the input ``motor.torque`` and phi1 the driver's rotation; the drive's own equations
(levels 1-3, unchanged) see (theta_m, theta_m') as their input-shaft angle and speed. The stiff
spring is then inside the model's stepper and a motor controller outside couples through the
soft interface (motor.torque in, motor.speed out).

:class:`TorqueCausalModel` wraps any level 1-3 model with a flexible input shaft; its state is
the wrapped model's [q, v] with theta_m appended to q and theta_m' to v (still second order).
Level 0 and ``input_shaft.rigid = true`` are refused (:func:`torque_causal_model`): without a
shaft spring there is no state for the motor to act through at level 0 (its driver follows the
input angle), and a rigid shaft would make the rotor a part of the driver - give the motor
model the drive's reflected inertia and use angle causality there (docs/fmu.md).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from ..geometry import Drive
from .base import Inputs, Model, SimulationDiverged
from ..outputs import OutputSpec

__all__ = ["TorqueCausalModel", "torque_causal_model", "steady_motor_torque",
           "reflected_inertia", "MOTOR_INPUT", "MOTOR_OUTPUTS"]

#: the FMU's input of torque causality (read only there; 0 and unused in angle causality)
MOTOR_INPUT = OutputSpec("motor.torque", "N.m",
                         "torque driving the motor rotor (input_shaft.causality = torque; "
                         "not read in angle causality)")
#: outputs in both causalities: the far end of the input-shaft spring
MOTOR_OUTPUTS = (
    OutputSpec("motor.angle", "rad",
               "motor rotor angle at the far end of the input-shaft spring (torque causality: "
               "a state; angle causality: input_shaft.angle, which that end follows)"),
    OutputSpec("motor.speed", "rad/s",
               "motor rotor speed (torque causality: a state, what a speed controller reads; "
               "angle causality: input_shaft.speed)"),
)


def torque_causal_model(level: int, drive: Drive, params: Mapping[str, Any],
                        level_class: type[Model]) -> "TorqueCausalModel":
    """The level ``level`` model (of class ``level_class``) in torque causality, or ValueError
    saying why it cannot be."""
    if level == 0:
        raise ValueError(
            "parameter input_shaft.causality = torque needs fidelity 1-3: at fidelity 0 "
            "(kinematic) the driver follows the input-shaft angle rigidly and there is no "
            "shaft spring for a motor rotor to drive; use fidelity 1, 2 or 3, or angle "
            "causality with the drive's reflected inertia in the motor model")
    if params.get("input_shaft.rigid"):
        raise ValueError(
            "parameter input_shaft.causality = torque integrates the input-shaft spring between "
            "the motor rotor and the driver, but input_shaft.rigid = true removes that spring; "
            "set input_shaft.rigid = false or use input_shaft.causality = angle")
    return TorqueCausalModel(level_class(drive, params))


class TorqueCausalModel(Model):
    """A level 1-3 model with the motor rotor at the far end of its input-shaft spring (module
    docstring). Everything the drive computes comes from the wrapped model ``inner``."""

    @property
    def start_fallback(self) -> str | None:
        return self.inner.start_fallback

    def __init__(self, inner: Model):
        super().__init__(inner.drive, inner.params)
        if inner.n_states == 0:
            raise ValueError(f"torque causality needs a dynamic model, got the {inner.name} "
                             "model")
        self.inner = inner
        self.level = inner.level
        self.name = inner.name
        self.preferred_method = inner.preferred_method
        self.second_order = inner.second_order
        self.tolerance_applies = inner.tolerance_applies
        self.switching_names = inner.switching_names
        p = self.params
        self.j_motor = float(p["motor.inertia"])
        self.k_shaft = float(p["input_shaft.stiffness"])
        self.c_shaft = float(p["input_shaft.damping"])
        names = inner.state_names
        n, h = inner.n_states, inner.n_states // 2
        # second order [q, v]: theta_m ends q, theta_m' ends v (the layout stays [q, v]);
        # otherwise (level 2's sprockets then span modes) both are appended
        self._i_th, self._i_w = (h, 2 * h + 1) if inner.second_order else (n, n + 1)
        self._inner_idx = np.array([k for k in range(n + 2) if k not in (self._i_th, self._i_w)])
        self._i_phi1 = names.index("driver.angle")
        self._i_w1 = names.index("driver.speed")
        self._inner_driver_inertia = float(reflected_inertia_parts(inner)[0])
        # largest eigenvalue of the motor's part of the mass-normalised stiffness (an upper
        # bound added to the drive's own: Weyl's inequality)
        a = self.k_shaft / self.j_motor
        b = self.k_shaft / math.sqrt(self.j_motor * self._inner_driver_inertia)
        self._lambda_motor = 0.5 * (a + math.sqrt(a * a + 4 * b * b))
        self._speed_seen = 0.0

    # --- state layout -------------------------------------------------------------------------
    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(self.join(np.array(self.inner.state_names, object), "motor.angle",
                               "motor.speed").tolist())

    def split(self, x):
        """(the wrapped model's state, theta_m, theta_m') of a state x."""
        x = np.asarray(x, float)
        return x[self._inner_idx], float(x[self._i_th]), float(x[self._i_w])

    def join(self, xi, theta_m, w_m) -> np.ndarray:
        x = np.empty(len(xi) + 2, np.asarray(xi).dtype)
        x[self._inner_idx] = xi
        x[self._i_th], x[self._i_w] = theta_m, w_m
        return x

    def motor_outputs(self, x) -> tuple[float, float]:
        """(motor.angle [rad], motor.speed [rad/s]) of state x."""
        return float(x[self._i_th]), float(x[self._i_w])

    def _inner_inputs(self, x, u: Inputs):
        xi, th, w = self.split(x)
        return xi, Inputs(th, w, u.torque, 0.0)

    def shaft_torque(self, x) -> float:
        """T_s = k_r (theta_m - phi1) + c_r (theta_m' - phi1') [N.m] (seed 003 eq 14's spring)."""
        xi, th, w = self.split(x)
        return (self.k_shaft * (th - xi[self._i_phi1])
                + self.c_shaft * (w - xi[self._i_w1]))

    # --- Model contract ---------------------------------------------------------------------------
    def initial_state(self, u: Inputs) -> np.ndarray:
        """At rest: the wrapped model's rest state with its input shaft held at ``u.angle``,
        the motor rotor there at rest."""
        xi = self.inner.initial_state(Inputs(u.angle, 0.0, u.torque, 0.0))
        return self.join(xi, float(u.angle), 0.0)

    def rhs(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        xi, ui = self._inner_inputs(x, u)
        dxi = self.inner.rhs(t, xi, ui)
        ts = self.k_shaft * (ui.angle - xi[self._i_phi1]) + self.c_shaft * (ui.speed - xi[self._i_w1])
        return self.join(dxi, ui.speed, (u.motor_torque - ts) / self.j_motor)

    def outputs(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, float]:
        xi, ui = self._inner_inputs(x, u)
        return self.inner.outputs(t, xi, ui)

    def outputs_into(self, t, x, angle, speed, acceleration, torque, out):
        xi, th, w = self.split(x)
        return self.inner.outputs_into(t, xi, th, w, 0.0, torque, out)

    def output_descriptions(self) -> dict[str, str]:
        d = self.inner.output_descriptions()
        d["input_shaft.torque"] = ("torque in the input-shaft spring between the motor rotor "
                                   "and the driver, k_r (theta_m - phi1) + c_r (w_m - w1)")
        return d

    def role_constants(self) -> tuple[float, float, float]:
        return self.inner.role_constants()

    def hold_role(self, hold: float) -> None:
        self.inner.hold_role(hold)

    def switching_functions(self, t, x, u):
        xi, ui = self._inner_inputs(x, u)
        return self.inner.switching_functions(t, xi, ui)

    def omega_at(self, t, x, u) -> float:
        xi, ui = self._inner_inputs(x, u)
        w = self.inner.omega_at(t, xi, ui)
        return math.sqrt(w * w + self._lambda_motor)

    def stable_step(self, x) -> float:
        xi, _, _ = self.split(x)
        w = 1.0 / self.inner.stable_step(xi)
        return 1.0 / math.sqrt(w * w + self._lambda_motor)

    def event_step(self, speed: float) -> float:
        """The wrapped model's, at the larger of ``speed`` and 1.25 x the largest motor speed
        seen so far (the input speed is not an input here: the motor's speed is a state)."""
        return self.inner.event_step(max(abs(float(speed)), 1.25 * self._speed_seen))

    def state_scale(self):
        sc = self.inner.state_scale()
        if sc is None:
            return None
        return self.join(np.asarray(sc, float), 1e-3, 1.0)

    def refuse_method(self, method: str):
        return self.inner.refuse_method(method)

    def check(self, t: float, x: np.ndarray) -> None:
        xi, th, w = self.split(x)
        self.inner.check(t, xi)
        if not (math.isfinite(th) and math.isfinite(w)):
            raise SimulationDiverged(f"{self.name} model diverged at t = {t:.6g} s: non-finite "
                                     "motor.angle or motor.speed; try a smaller solver.step")
        self._speed_seen = max(self._speed_seen, abs(w))
        w_max, why = self.speed_limit_cached()
        if abs(w) > w_max:
            raise SimulationDiverged(
                f"motor.speed = {w:.6g} rad/s at t = {t:.6g} s is beyond the {self.name} "
                f"model's (level {self.level}) limit of {w_max:.6g} rad/s ({why}): in torque "
                "causality the rotor runs away when motor.torque exceeds what the load takes "
                "(check the motor torque or its speed controller) or, in co-simulation, when "
                "a speed-dependent torque fed back through a held input pumps the drive "
                "(docs/fmu.md, In a system model)")

    def speed_limit_cached(self):
        b = self.__dict__.get("_speed_limit")
        if b is None:
            b = self.__dict__["_speed_limit"] = self.inner.speed_limit()
        return b

    def input_error(self, angle, speed, torque):
        """Only load.torque is an input of the drive here (input_shaft.angle and speed are
        not read; the motor's speed is checked as a state, :meth:`check`)."""
        return self.inner.input_error(0.0, 0.0, torque)

    def speed_limit(self):
        return self.inner.speed_limit()

    def torque_limit(self):
        return self.inner.torque_limit()

    def static_tension(self) -> float:
        return self.inner.static_tension()

    def held_tension(self) -> float:
        return self.inner.held_tension()

    def snapshot(self, t, x, u):
        xi, ui = self._inner_inputs(x, u)
        return self.inner.snapshot(t, xi, ui)


def reflected_inertia_parts(model: Model) -> np.ndarray:
    """[J11, J12, J22] of the sprocket rotations [kg m^2]: level 1-2's mass matrix (chain
    inertia included, chain_inertia.sprocket_mass_matrix); level 3 carries its chain as rollers, for
    which the same lumped matrix of a level-1 model with these parameters stands in."""
    if hasattr(model, "mass_matrix"):
        m = model.mass_matrix()
    else:
        from .chain_inertia import sprocket_mass_matrix
        m = sprocket_mass_matrix(model.drive, model.params)
    return np.array([m[0, 0], m[0, 1], m[1, 1]])


def reflected_inertia(model: TorqueCausalModel) -> float:
    """Inertia of motor rotor + drive reflected to the motor [kg m^2], with the driven
    sprocket turning at the tooth ratio r = z1/z2 of the driver's speed:
    J_m + J11 + 2 r J12 + r^2 J22."""
    j11, j12, j22 = reflected_inertia_parts(model.inner)
    r = model.drive.tooth_ratio
    return model.j_motor + j11 + 2 * r * j12 + r * r * j22


def steady_motor_torque(model: TorqueCausalModel, speed: float, load_torque: float) -> float:
    """Motor torque [N.m] that holds the drive at a steady input speed ``speed`` [rad/s]
    against ``load_torque`` (power balance T_m w1 = (M_load + d2 w2) w2, w2 = r w1)."""
    r = model.drive.tooth_ratio
    d2 = model.params["driven.damping"]
    return r * (load_torque + d2 * r * speed)

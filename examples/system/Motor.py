"""Motor: a PI speed controller driving a rotor, a plain pythonfmu co-simulation FMU (examples/
system, docs/fmu.md "Hosts"). Example values, not a catalogue motor.

The controller's torque is T = kp e + ki \\int e dt with e = speed_reference(t) - speed,
clamped to +-max_torque (the integral stops growing while clamped); speed_reference ramps from 0
to ``speed_reference`` over ``ramp_time``. The default gains place both closed-loop poles at
-50 rad/s for the rotor and the ChainDrive driver sprocket together (J = 0.01 + 0.004 kg m2:
kp = 2 * 50 * J, ki = 50^2 * J).

``causality`` = "angle" (ChainDrive's interface today): input ``shaft.torque``, the torque the
driven shaft takes from the rotor (ChainDrive's ``input_shaft.torque``); the FMU integrates the
rotor J dw/dt = T - shaft.torque (semi-implicit Euler, sub-steps of at most ``max_substep``) and
outputs ``rotor.angle`` and ``rotor.speed`` (to ChainDrive's ``input_shaft.angle`` and
``input_shaft.speed``).

``causality`` = "torque": input ``shaft.speed`` (the speed of the rotor the other FMU
integrates); output ``torque`` only (the controller's torque from that speed).
"""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real, String
from pythonfmu.enums import Fmi2Initial


class Motor(Fmi2Slave):
    author = "ChainDrive examples"
    description = "PI speed-controlled motor (examples/system)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.causality = "angle"
        self.inertia = 0.01            # kg m2
        self.kp = 1.4                  # N m s/rad
        self.ki = 35.0                 # N m/rad
        self.max_torque = 200.0        # N m
        self.speed_reference = 12.566370614359172   # rad/s (120 rpm)
        self.ramp_time = 0.05          # s
        self.max_substep = 1e-5        # s
        self.shaft_torque = 0.0        # input, angle causality [N m]
        self.shaft_speed = 0.0         # input, torque causality [rad/s]
        self.angle = 0.0               # rotor state / outputs
        self.speed = 0.0
        self.torque = 0.0
        self.integral = 0.0
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        for name, attr, desc in (
                ("motor.inertia", "inertia", "rotor inertia [kg.m2]"),
                ("controller.kp", "kp", "proportional gain [N.m.s/rad]"),
                ("controller.ki", "ki", "integral gain [N.m/rad]"),
                ("controller.max_torque", "max_torque", "torque limit [N.m]"),
                ("speed_reference", "speed_reference", "final speed set point [rad/s]"),
                ("ramp_time", "ramp_time", "time to ramp the set point from 0 [s]"),
                ("max_substep", "max_substep", "largest rotor integration sub-step [s]")):
            self.register_variable(Real(name, description=desc, getter=self._get(attr),
                                        setter=self._set(attr), **fixed))
        self.register_variable(String("causality", description='"angle" or "torque"',
                                      getter=lambda: self.causality,
                                      setter=self._set("causality"), **fixed))
        self.register_variable(Real("shaft.torque", causality=Fmi2Causality.input,
                                    variability=Fmi2Variability.continuous,
                                    description="torque the load takes from the rotor (angle "
                                                "causality) [N.m]",
                                    getter=self._get("shaft_torque"),
                                    setter=self._set("shaft_torque")))
        self.register_variable(Real("shaft.speed", causality=Fmi2Causality.input,
                                    variability=Fmi2Variability.continuous,
                                    description="rotor speed integrated elsewhere (torque "
                                                "causality) [rad/s]",
                                    getter=self._get("shaft_speed"),
                                    setter=self._set("shaft_speed")))
        for name, attr, desc in (("rotor.angle", "angle", "rotor angle (angle causality) [rad]"),
                                 ("rotor.speed", "speed", "rotor speed (angle causality) [rad/s]"),
                                 ("torque", "torque", "controller (electromagnetic) torque [N.m]")):
            self.register_variable(Real(name, causality=Fmi2Causality.output,
                                        variability=Fmi2Variability.continuous,
                                        initial=Fmi2Initial.calculated, description=desc,
                                        getter=self._get(attr)))

    def _get(self, attr):
        return lambda: getattr(self, attr)

    def _set(self, attr):
        return lambda value: setattr(self, attr, value)

    def exit_initialization_mode(self):
        if self.causality not in ("angle", "torque"):
            self.log(f'causality must be "angle" or "torque", got {self.causality!r}')
            return False
        if self.inertia <= 0:
            self.log(f"motor.inertia must be > 0, got {self.inertia!r} kg.m2")
            return False
        self.torque = self._control(0.0, self.speed if self.causality == "angle"
                                    else self.shaft_speed, 0.0)
        return True

    def _reference(self, t):
        return self.speed_reference * min(1.0, t / self.ramp_time) if self.ramp_time > 0 \
            else self.speed_reference

    def _control(self, t, speed, dt):
        error = self._reference(t) - speed
        integral = self.integral + error * dt
        torque = self.kp * error + self.ki * integral
        if abs(torque) <= self.max_torque:
            self.integral = integral
        return max(-self.max_torque, min(self.max_torque, torque))

    def do_step(self, current_time, step_size):
        if self.causality == "torque":
            self.torque = self._control(current_time + step_size, self.shaft_speed, step_size)
            return True
        n = max(1, int(step_size / self.max_substep + 0.999999))
        h = step_size / n
        t = current_time
        for _ in range(n):
            self.torque = self._control(t, self.speed, h)
            self.speed += h * (self.torque - self.shaft_torque) / self.inertia
            self.angle += h * self.speed
            t += h
        return True

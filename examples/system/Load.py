"""Load: a speed-dependent load torque, a plain pythonfmu co-simulation FMU (examples/system).
Example values: torque = torque0 + damping * speed, which at the ChainDrive reference speed (120
rpm, 12.566 rad/s) gives the reference scene's 43.2 N m (docs/fmu.md, "Reference output")."""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Initial


class Load(Fmi2Slave):
    author = "ChainDrive examples"
    description = "speed-dependent load torque T0 + c * speed (examples/system)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.torque0 = 21.6                     # N m
        self.damping = 21.6 / 12.566370614359172  # N m s/rad: 43.2 N m at 120 rpm
        self.speed = 0.0
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        self.register_variable(Real("torque0", description="torque at rest [N.m]",
                                    getter=lambda: self.torque0,
                                    setter=lambda v: setattr(self, "torque0", v), **fixed))
        self.register_variable(Real("damping", description="torque per speed [N.m.s/rad]",
                                    getter=lambda: self.damping,
                                    setter=lambda v: setattr(self, "damping", v), **fixed))
        self.register_variable(Real("speed", causality=Fmi2Causality.input,
                                    variability=Fmi2Variability.continuous,
                                    description="speed of the loaded shaft [rad/s]",
                                    getter=lambda: self.speed,
                                    setter=lambda v: setattr(self, "speed", v)))
        self.register_variable(Real("torque", causality=Fmi2Causality.output,
                                    variability=Fmi2Variability.continuous,
                                    initial=Fmi2Initial.calculated,
                                    description="load torque, opposing forward motion [N.m]",
                                    getter=lambda: self.torque0 + self.damping * self.speed))

    def do_step(self, current_time, step_size):
        return True

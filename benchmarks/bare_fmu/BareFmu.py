"""A pythonfmu co-simulation FMU that does nothing: the same three Real inputs and fifteen Real
outputs as ChainDrive.fmu, no parameters, ``do_step`` returns at once. Its cost per communication
step through fmpy is the floor that any pythonfmu FMU pays (ctypes, the C++ wrapper, the GIL,
pythonfmu's Python-side get/set); benchmarks/fmu_cost.py measures ChainDrive next to it."""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real

INPUTS = ("input_shaft.angle", "input_shaft.speed", "load.torque")
OUTPUTS = ("driver.angle", "driver.speed", "driven.angle", "driven.speed", "driven.acceleration",
           "input_shaft.torque", "tight_span.tension", "slack_span.tension", "tight_span.length",
           "velocity_ratio", "transmission_error", "tight_span.midspan_deflection",
           "chain.max_link_tension", "contact.max_force", "chain.min_link_tension")


class BareFmu(Fmi2Slave):
    description = "does nothing (benchmark floor)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.values = {}
        for name, causality in [(n, Fmi2Causality.input) for n in INPUTS] + \
                               [(n, Fmi2Causality.output) for n in OUTPUTS]:
            self.values[name] = 0.0
            self.register_variable(Real(name, causality=causality,
                                        variability=Fmi2Variability.continuous,
                                        getter=lambda n=name: self.values[n],
                                        setter=lambda v, n=name: self.values.__setitem__(n, v)),
                                   nested=False)

    def do_step(self, current_time, step_size):
        return True

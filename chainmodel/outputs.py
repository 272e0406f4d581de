"""The outputs of DESIGN.md, listed once: their names, units and descriptions in order, and
their positions in that order as constants (``O_DRIVER_ANGLE`` ...), generated from the list,
which the compiled kernels use to fill an output row. No imports from the package: a kernel
reading these constants is recompiled only when this list changes (chainmodel.numba_cache)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["OutputSpec", "CORE_OUTPUTS", "EXTRA_OUTPUTS", "ALL_OUTPUTS", "OUTPUT_NAMES",
           "N_OUTPUTS"]


@dataclass(frozen=True)
class OutputSpec:
    name: str
    unit: str
    description: str


CORE_OUTPUTS: tuple[OutputSpec, ...] = (
    OutputSpec("driver.angle", "rad", "driver sprocket rotation, forward positive"),
    OutputSpec("driver.speed", "rad/s", "driver sprocket angular speed"),
    OutputSpec("driven.angle", "rad", "driven sprocket rotation, forward positive"),
    OutputSpec("driven.speed", "rad/s", "driven sprocket angular speed"),
    OutputSpec("driven.acceleration", "rad/s2", "driven sprocket angular acceleration"),
    OutputSpec("input_shaft.torque", "N.m",
               "torque the drive takes from the input shaft (feed back to the motor)"),
    OutputSpec("tight_span.tension", "N",
               "tension of the tight span, the physical span the driver pulls for the direction "
               "of the transmitted torque load.torque + ratio (driven damping x input speed + "
               "driven inertia x input acceleration): the upper span (driven onto driver) when "
               "it is positive, the lower span when negative (reverse drive against a load, "
               "overrunning load), whatever the momentary tensions; centrifugal tension "
               "included"),
    OutputSpec("slack_span.tension", "N", "tension of the other (slack) physical span, "
               "centrifugal tension included"),
    OutputSpec("tight_span.length", "m", "distance between the tight span's endpoint rollers"),
    OutputSpec("velocity_ratio", "", "driven speed / driver speed (instantaneous)"),
    OutputSpec("transmission_error", "rad",
               "driven angle minus the mean-ratio angle (n_driver / n_driven) * driver angle"),
)

EXTRA_OUTPUTS: tuple[OutputSpec, ...] = (
    OutputSpec("tight_span.midspan_deflection", "m",
               "transverse deflection of the tight span at its middle, from the straight line "
               "between its endpoints (positive away from the line of centres)"),
    OutputSpec("chain.max_link_tension", "N", "largest link tension in the chain"),
    OutputSpec("contact.max_force", "N", "largest roller-tooth contact force"),
    OutputSpec("chain.min_link_tension", "N",
               "smallest link tension in the chain (0: a link is slack; negative: its plates "
               "bear in compression)"),
)

ALL_OUTPUTS: tuple[OutputSpec, ...] = CORE_OUTPUTS + EXTRA_OUTPUTS

#: the outputs' names in ALL_OUTPUTS order (the columns of every output row)
OUTPUT_NAMES: tuple[str, ...] = tuple(o.name for o in ALL_OUTPUTS)
N_OUTPUTS = len(ALL_OUTPUTS)

# positions in ALL_OUTPUTS, generated from it: O_<name with dots as underscores, upper case>
_INDEX = {name: k for k, name in enumerate(OUTPUT_NAMES)}
O_DRIVER_ANGLE = _INDEX["driver.angle"]
O_DRIVER_SPEED = _INDEX["driver.speed"]
O_DRIVEN_ANGLE = _INDEX["driven.angle"]
O_DRIVEN_SPEED = _INDEX["driven.speed"]
O_DRIVEN_ACCELERATION = _INDEX["driven.acceleration"]
O_INPUT_SHAFT_TORQUE = _INDEX["input_shaft.torque"]
O_TIGHT_SPAN_TENSION = _INDEX["tight_span.tension"]
O_SLACK_SPAN_TENSION = _INDEX["slack_span.tension"]
O_TIGHT_SPAN_LENGTH = _INDEX["tight_span.length"]
O_VELOCITY_RATIO = _INDEX["velocity_ratio"]
O_TRANSMISSION_ERROR = _INDEX["transmission_error"]
O_TIGHT_SPAN_MIDSPAN_DEFLECTION = _INDEX["tight_span.midspan_deflection"]
O_CHAIN_MAX_LINK_TENSION = _INDEX["chain.max_link_tension"]
O_CONTACT_MAX_FORCE = _INDEX["contact.max_force"]
O_CHAIN_MIN_LINK_TENSION = _INDEX["chain.min_link_tension"]

"""Which physical span is the tight one: the rule every level (0-3) applies, by power flow.

DESIGN.md: "the tight span is the one the driver pulls for the current direction of
transmitted torque; a window's mean is the mean of one physical span". The upper span runs
from the driven sprocket onto the driver, the lower span from the driver onto the driven
sprocket (chainmodel.kernels.spans). The driven sprocket's torque balance
(seed 004 eq 50, R_o the driven pitch radius)

    (T_upper - T_lower) R_o = load.torque + c_2 w_2 + J_2 dw_2/dt

says which span holds the driven sprocket against what it carries: the upper span when the
transmitted torque M = load.torque + c_2 w_2 + J_2 dw_2/dt is positive (the driver, turning
forward or holding back a load that runs it backward, pulls the upper span), the lower span
when M is negative (reverse drive against a load, or an overrunning load under forward drive:
the spans swap roles as DESIGN.md says). M is taken from the INPUTS only - w_2 and dw_2/dt as
the tooth ratio times the input shaft's speed and acceleration - never from the state, so the
role cannot flip with the tension oscillation inside a tooth period (near a torsional
resonance the instantaneous larger tension alternates between the spans every cycle, which
is why the old "larger tension" rule mixed the load with the oscillation). At M = 0 exactly
the span the driver winds on is tight (the upper one forward, the lower one in reverse).

Inputs that themselves reverse M within a tooth period (a load input rippling through zero,
as a co-simulated load can give) would flip the role with them. Where the inputs arrive step
by step (the FMU, ``Stepper.advance`` with held inputs) the role therefore follows M's mean
over about a driver tooth period: :func:`filtered_torque`, a first-order filter with that time
constant, whose sign the kernels take through their role hold (``hold``: +1 upper, -1 lower,
0 decided from the inputs at each evaluation, as a whole run's arrays are: their inputs are a
ramp and a constant load). J_2 is
the driven side's inertia as each level has it (levels 1-2: with the wrapped chain's share,
``torsional.chain_inertia``; levels 0 and 3: ``driven.inertia``); it matters only while the
inputs accelerate and the load and damping torques are small.

Compiled with the kernels that call it (levels 0-3); :func:`lower_tight_many` is the
vectorised twin.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit

__all__ = ["transmitted_torque", "lower_tight", "lower_tight_many", "filtered_torque",
           "role_hold"]


@jit
def transmitted_torque(load, damping, inertia, ratio, speed, acceleration):
    """M = load + ratio (c_2 w_in + J_2 a_in) [N.m]: the torque the chain must put on the
    driven sprocket at the mean motion the inputs ask for (module docstring)."""
    return load + ratio * (damping * speed + inertia * acceleration)


@jit
def lower_tight(load, damping, inertia, ratio, speed, acceleration, hold=0.0):
    """True when the lower span is the tight one (module docstring); ``hold`` +1 / -1 names
    the upper / lower span whatever the inputs (the filtered role of a stepped run)."""
    if hold > 0.5:
        return False
    if hold < -0.5:
        return True
    m = transmitted_torque(load, damping, inertia, ratio, speed, acceleration)
    if m > 0.0:
        return False
    if m < 0.0:
        return True
    return speed < 0.0


def lower_tight_many(load, damping, inertia, ratio, speed, acceleration):
    """:func:`lower_tight` over arrays of inputs (bool array)."""
    load, speed, acceleration = np.broadcast_arrays(
        *(np.asarray(v, float) for v in (load, speed, acceleration)))
    m = load + ratio * (damping * speed + inertia * acceleration)
    return (m < 0.0) | ((m == 0.0) & (speed < 0.0))


def filtered_torque(previous: float, torque: float, dt: float, speed: float,
                    n_driver: int) -> float:
    """The transmitted torque's running mean after a step of ``dt`` [s] that ends at
    ``torque`` (held over the step): a first-order filter whose time constant is one driver
    tooth period at the input speed, 2 pi / (n_driver |speed|), exact for an input held over the
    step; at rest (speed 0) it keeps ``previous`` (no tooth passes)."""
    if not math.isfinite(previous):
        return torque
    if speed == 0.0 or dt <= 0.0:
        return previous
    tau = 2.0 * math.pi / (n_driver * abs(speed))
    return torque + (previous - torque) * math.exp(-dt / tau)


def role_hold(mean_torque: float, speed: float) -> float:
    """+1 (upper span tight) or -1 (lower) from the filtered torque's sign; at 0 the span the
    driver winds on (:func:`lower_tight`'s tie)."""
    if mean_torque > 0.0:
        return 1.0
    if mean_torque < 0.0:
        return -1.0
    return -1.0 if speed < 0.0 else 1.0

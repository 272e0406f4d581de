"""One co-simulated chain drive: what an FMI co-simulation slave of ChainDrive does, without FMI.

:class:`CosimSession` builds the model and stepper of a parameter set (as ``Scene.stepper``
does), holds the inputs a master sets at a communication point, estimates the input shaft's
acceleration by backward difference of the speed input, does a communication step, computes
the outputs for inputs set since (direct feedthrough), and saves and restores its state. The
FMU adapter (fmu_src/ChainDrive.py) maps FMI variables onto it; ``fmu_test.library_run`` drives
it as a fixed-step master drives the FMU.

It also watches the coupling (:class:`CouplingWatch`): an explicit co-simulation of a motor
model's inertia with this drive's stiff input-shaft spring is unstable above a communication
step of about :data:`JACOBI_CONSTANT` / omega_c (:func:`stable_step`); the session then refuses
the step with a message that says so and names the step that holds (docs/fmu.md, "In a system
model"); ``watch_coupling = False`` (the FMU's ``coupling.watch``) turns that off for inputs that
are prescribed, not fed back. And it checks the angle input against where the held input carried
it (:meth:`CosimSession.model_angle`): a jump by whole turns is a master restarting its angle
count and is taken out; any other jump beyond half a driver tooth is refused, naming the input.
No physics here beyond that coupling estimate: the models do the rest.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from .models.base import Inputs, SimulationDiverged

#: the inputs of the session (and of the FMU), in the order of :meth:`CosimSession.set_inputs`
INPUTS = ("input_shaft.angle", "input_shaft.speed", "load.torque")

#: units of the FMU adapter's Real coupling.* variables (build_fmu.py writes them)
FMU_UNITS = {"coupling.motor_inertia": "kg.m2", "coupling.max_step": "s"}
#: the FMU adapter's parameters of the coupling (names)
FMU_PARAMETERS = ("coupling.motor_inertia", "input_shaft.include_drive_inertia",
                  "coupling.watch")

__all__ = ["INPUTS", "FMU_UNITS", "FMU_PARAMETERS", "CosimSession", "CouplingUnstable", "CouplingWatch", "stable_step", "coupling_frequency",
           "JACOBI_CONSTANT", "GAUSS_SEIDEL_CONSTANT", "angle_jump_tolerance"]

#: h_max * omega_c at which the explicit Jacobi coupling of a motor rotor J (fed the held
#: input_shaft.torque) and this drive (fed the held rotor angle and speed) loses stability:
#: the spectral radius of the linear two-inertia map (rotor J, spring k_r with damping c_r,
#: driver I; the drive's step integrated exactly with the angle advancing at the held speed)
#: crosses 1 at h omega_c = 0.41 (J = 0.001 kg m2), 0.42 (0.003), 0.64 (0.01), 1.25 (0.03) for
#: the default k_r, c_r and driver inertia; 0.4 is the smallest (docs/fmu.md, "Angle causality:
#: the stable step", with measured limits)
JACOBI_CONSTANT = 0.4
#: the same for Gauss-Seidel, the drive stepped first and the rotor fed its new torque:
#: 1.47 (J = 0.001), 1.77 (0.003), 2.42 (0.01); 1.4 is the smallest
GAUSS_SEIDEL_CONSTANT = 1.4


def coupling_frequency(motor_inertia: float, driver_inertia: float, stiffness: float) -> float:
    """omega_c = sqrt(k_r (1/J_motor + 1/I_driver)) [rad/s]: the input-shaft spring between the
    motor's rotor and the driver sprocket, the fastest mode an angle-causality coupling sees."""
    for name, value in (("motor inertia", motor_inertia), ("driver.inertia", driver_inertia),
                        ("input_shaft.stiffness", stiffness)):
        if not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return math.sqrt(stiffness * (1.0 / motor_inertia + 1.0 / driver_inertia))


def stable_step(motor_inertia: float, params: Mapping, scheme: str = "jacobi") -> float:
    """Largest communication step [s] an explicit coupling of a motor rotor of inertia
    ``motor_inertia`` [kg m2] to this drive holds in angle causality: C / omega_c with
    C = :data:`JACOBI_CONSTANT` or :data:`GAUSS_SEIDEL_CONSTANT`. With ``input_shaft.rigid``
    there is no spring: inf (the limit is then the feedthrough, :func:`rigid_inertia_limit`)."""
    if scheme not in ("jacobi", "gauss-seidel"):
        raise ValueError(f"scheme must be 'jacobi' or 'gauss-seidel', got {scheme!r}")
    if params["fidelity"] == 0 or params["input_shaft.rigid"]:
        return math.inf
    c = JACOBI_CONSTANT if scheme == "jacobi" else GAUSS_SEIDEL_CONSTANT
    return c / coupling_frequency(motor_inertia, params["driver.inertia"],
                                  params["input_shaft.stiffness"])


#: an accepted angle jump beyond the hold's own miss that the FMU warns of [rad]: a milliradian
#: (12 N.m at once on xu2010's input-shaft spring)
NOTED_JUMP = 1e-3


def angle_jump_tolerance(n_driver: int, hold_miss: float) -> float:
    """Largest difference [rad] between a new input_shaft.angle and where the held input
    carried the old one (angle + speed x step) that is followed: half a driver tooth angle,
    pi / n_driver, plus ``hold_miss``, |speed change| x step (what the first-order hold can miss
    of a speed that moved monotonically within the step)."""
    return math.pi / n_driver + hold_miss


class CouplingUnstable(SimulationDiverged):
    """The master's coupling of this drive to the rest of the system is unstable."""


#: the inputs a master feeds back, watched for an unstable coupling: in angle causality the
#: shaft's speed, in torque causality the motor's torque; the load torque in both
WATCHED_ANGLE = ("input_shaft.speed", "load.torque")
WATCHED_TORQUE = ("motor.torque", "load.torque")


class CouplingWatch:
    """Recognises an unstable explicit coupling in the inputs a master sets.

    The increments of an input from one communication point to the next (input-shaft speed,
    load torque) are cut into half-cycles (runs of one sign), each with its peak |increment|.
    A coupling that goes unstable shows as an oscillation of a few steps per period whose
    amplitude grows: the last :data:`CYCLES` full cycles (pairs of half-cycles, each at most
    :data:`MAX_HALF_CYCLE` steps long) have strictly growing peak-to-peak increments, the last
    :data:`GROWTH` times the first and above ``floor * (1 + |input|)`` (far above round-off).
    A physical transient decays and the drive's own modes are integrated inside the FMU; the
    motor's controller is far slower than a few communication steps."""

    CYCLES = 4
    MAX_HALF_CYCLE = 8
    GROWTH = 1.5
    PEAKS = 2 * CYCLES

    def __init__(self, names=WATCHED_ANGLE, floors=(1e-4, 1e-4)):
        self.names, self.floors = tuple(names), tuple(floors)
        self.reset()

    def reset(self) -> None:
        self._last = [None] * len(self.names)      # last value of each input
        self._sign = [0] * len(self.names)         # sign of the current half-cycle
        self._run = [0] * len(self.names)          # its length in steps
        self._peak = [0.0] * len(self.names)       # its peak |increment|
        self._peaks = [deque(maxlen=self.PEAKS) for _ in self.names]   # finished half-cycles

    def state(self) -> dict:
        return {"last": list(self._last), "sign": list(self._sign), "run": list(self._run),
                "peak": list(self._peak), "peaks": [list(p) for p in self._peaks]}

    def restore(self, s: Mapping) -> None:
        self._last, self._sign = list(s["last"]), list(s["sign"])
        self._run, self._peak = list(s["run"]), list(s["peak"])
        self._peaks = [deque(p, maxlen=self.PEAKS) for p in s["peaks"]]

    def update(self, values) -> str | None:
        """Take the inputs at the next communication point; return the name of the input that
        grows and alternates (the coupling is unstable), else None."""
        found = None
        for i, value in enumerate(values):
            last, self._last[i] = self._last[i], value
            if last is None or not math.isfinite(value):
                continue
            d = float(value) - float(last)
            sign = (d > 0) - (d < 0)
            if sign == 0:
                continue
            if sign != self._sign[i]:
                if self._sign[i]:
                    # a finished half-cycle counts only when it was short
                    if self._run[i] <= self.MAX_HALF_CYCLE:
                        self._peaks[i].append(self._peak[i])
                    else:
                        self._peaks[i].clear()
                self._sign[i], self._run[i], self._peak[i] = sign, 0, 0.0
            self._run[i] += 1
            self._peak[i] = max(self._peak[i], abs(d))
            if found is None and self._growing(i):
                found = self.names[i]
        return found

    def _growing(self, i) -> bool:
        peaks = list(self._peaks[i])
        if len(peaks) < self.PEAKS:
            return False
        cycles = [peaks[k] + peaks[k + 1] for k in range(0, self.PEAKS, 2)]
        scale = self.floors[i] * (1.0 + abs(self._last[i]))
        return (all(b > a for a, b in zip(cycles, cycles[1:]))
                and cycles[-1] >= self.GROWTH * cycles[0] and cycles[-1] > scale)

    def suspect(self) -> str | None:
        """The input whose last three half-cycles (the current one included) were short and
        grew: not proof, but what to blame when a step fails outright before :meth:`update`
        could see whole cycles (a coupling far past its stable step)."""
        for i, name in enumerate(self.names):
            peaks = list(self._peaks[i])[-2:] + [self._peak[i]]
            if (len(peaks) == 3 and self._run[i] <= self.MAX_HALF_CYCLE
                    and peaks[0] < peaks[1] < peaks[2]
                    and peaks[2] > 10 * self.floors[i] * (1.0 + abs(self._last[i]))):
                return name
        return None

    def recent(self, i: int = 0) -> list[float]:
        """Peak-to-peak increments of the last full cycles of input ``i`` (as compared)."""
        peaks = list(self._peaks[i])[-self.PEAKS:]
        return [peaks[k] + peaks[k + 1] for k in range(0, len(peaks) - 1, 2)]


@dataclass
class Built:
    """What :meth:`CosimSession.build` made."""
    stepper: object
    params: dict
    drive: object
    level: int


class CosimSession:
    """A ChainDrive co-simulation slave without FMI (module docstring).

    ``lib``: the chainmodel package to use (the FMU passes its private copy); default this
    package. Inputs: :meth:`set_inputs`; parameters: :meth:`build`; a step: :meth:`step`;
    outputs at the current point for the inputs set: :meth:`outputs`."""

    def __init__(self, lib=None, name: str = "ChainDrive"):
        if lib is None:
            from . import integrate, models, scene
            lib = {"models": models, "integrate": integrate, "scene": scene}
        self._M, self._I, self._S = lib["models"], lib["integrate"], lib["scene"]
        self.name = name
        self.stepper = None
        self.params: dict | None = None
        self.drive = None
        self.angle = self.speed = self.torque = 0.0
        self.motor_torque = 0.0               # input motor.torque (torque causality only)
        self.prev_t: float | None = None     # previous communication point and its speed input
        self.prev_speed = 0.0
        self.motor_inertia = 0.0              # a motor rotor's inertia, for the coupling message
        #: False: input_shaft.torque leaves out the drive's inertia torque (the part linear in the
        #: input's acceleration; level 0 and input_shaft.rigid), the motor model carries it
        self.include_drive_inertia = True
        self.watch = CouplingWatch()
        #: torque causality: (motor.torque, rotor speed) at the last communication points, for
        #: the coupling message's estimate of the motor model's dT/domega
        self._motor_points: deque = deque(maxlen=2)
        #: False: no coupling watch (inputs prescribed open loop; the FMU's coupling.watch)
        self.watch_coupling = True
        #: whole turns between the master's angle count and the model's at the last step (a
        #: master restarting its count, :meth:`model_angle`)
        self.turns_removed = 0
        #: (the largest angle jump accepted beyond the hold's own miss [rad], its time): a jump
        #: below the refusal's tolerance is followed as imposed; the FMU warns of one above
        #: :data:`NOTED_JUMP`
        self.jump_noted = (0.0, 0.0)
        #: (the largest miss of the first-order hold itself [rad], its time, the step, the
        #: speed change over it): an accelerating input's angle runs ahead of (or behind) the
        #: held speed by about a h^2 / 2 each step, and the shaft spring takes that at once
        self.hold_noted = (0.0, 0.0, 0.0, 0.0)
        self._torque_inputs = False

    # --- inputs --------------------------------------------------------------------------------
    def set_inputs(self, angle: float, speed: float, torque: float,
                   motor_torque: float = 0.0) -> None:
        self.angle, self.speed, self.torque = angle, speed, torque
        self.motor_torque = motor_torque

    @property
    def torque_causal(self) -> bool:
        """input_shaft.causality = torque: motor.torque drives a rotor the model integrates
        (chainmodel.models.torque_causality); the angle and speed inputs are not read."""
        return self.stepper is not None and self.params["input_shaft.causality"] == "torque"

    def motor_values(self, fresh: bool = False) -> tuple[float, float]:
        """motor.angle, motor.speed: the rotor's state in torque causality; in angle causality
        the input shaft's angle and speed (``fresh``: as just set, else as held to the end of
        the last step)."""
        st = self.stepper
        if st is not None and self.torque_causal:
            return tuple(float(v) for v in st.model.motor_outputs(st.x))
        if st is not None and not fresh:
            return st.held_angle_speed()      # (an Inputs built every step cost 0.5-0.9 us)
        return self.model_angle(), self.speed

    def model_angle(self) -> float:
        """input_shaft.angle as the model takes it. Compared with where the held input carried
        the last one (the stepper's held angle at the current time): a difference of whole
        turns, to within :func:`angle_jump_tolerance`, is a master restarting its angle count
        (wrapping a rotor angle to one turn) and is taken out, so the drive turns on; any other
        difference beyond that tolerance raises ValueError naming the input (a jump of the
        angle its speed does not explain would wind the input-shaft spring by it)."""
        st, angle = self.stepper, self.angle
        if (st is None or self.prev_t is None or self._torque_inputs or not math.isfinite(angle)
                or not math.isfinite(self.speed)):
            # before the run's first step the angle is where the master starts it (it may set
            # it again in initialization mode); non-finite inputs are refused by the step
            return angle
        held_angle, held_speed = st.held_angle_speed()
        d = angle - held_angle
        hold = abs(self.speed - held_speed) * (st.t - self.prev_t)
        tol = angle_jump_tolerance(self.drive.n_driver, hold)
        turns = round(d / (2.0 * math.pi))
        if abs(d) > tol and turns != 0 and abs(d - 2.0 * math.pi * turns) <= tol:
            d -= 2.0 * math.pi * turns
            angle -= 2.0 * math.pi * turns
        if abs(d) <= tol:
            if abs(d) - hold > self.jump_noted[0]:
                self.jump_noted = (abs(d) - hold, st.t)
            miss = min(abs(d), hold)
            if miss > self.hold_noted[0]:
                self.hold_noted = (miss, st.t, st.t - self.prev_t, self.speed - held_speed)
            return angle
        raise ValueError(
            f"input input_shaft.angle = {angle:.9g} rad at t = {st.t:.9g} s is {d:+.6g} rad "
            f"from where the held input carried it ({held_angle:.9g} rad: the last angle "
            f"advanced at input_shaft.speed = {held_speed:.6g} rad/s), more than a master "
            f"whose angle is the integral of its speed can produce ({tol:.3g} rad: half a "
            f"driver tooth plus the speed change times the step) and not a whole number of "
            "turns (a restart of the angle count, which is taken out): it would "
            + ("wind the input-shaft spring" if self._has_shaft_spring() else "move the driver")
            + " by that angle at once; set input_shaft.angle continuous and consistent with "
            "input_shaft.speed")

    def _has_shaft_spring(self) -> bool:
        return self.params["fidelity"] > 0 and not self.params["input_shaft.rigid"]

    def restart_note(self, t: float) -> str | None:
        """The sentence for a restart of the angle count in effect, else None."""
        if not self.turns_removed:
            return None
        return (f"input_shaft.angle restarted its count by {self.turns_removed:+d} turn(s) "
                f"at t = {t:.9g} s (whole turns from where its speed carried it): taken as a "
                "restart, the drive's angles continue")

    def _taken_at_once(self, angle: float) -> str:
        """What an angle the drive takes at once costs: the shaft spring's torque, or (no
        spring) the driver's move."""
        if self._has_shaft_spring():
            return (f"the input-shaft spring took it at once, "
                    f"{self.params['input_shaft.stiffness'] * angle:.3g} N.m")
        return "the driver moved by it at once"

    def jump_warning(self) -> str | None:
        """The sentence for the largest accepted angle jump when it exceeds
        :data:`NOTED_JUMP` beyond the hold's own miss, else None."""
        jump, when = self.jump_noted
        if not jump > NOTED_JUMP:
            return None
        what = self._taken_at_once(jump)
        return (f"input_shaft.angle jumped by {jump:.3g} rad beyond what input_shaft.speed "
                f"explains at t = {when:.9g} s (below the half driver tooth that is refused, so "
                f"followed as imposed): {what}; set input_shaft.angle to the integral of "
                "input_shaft.speed (docs/fmu.md, \"The angle input\")")

    def hold_warning(self) -> str | None:
        """The sentence for the largest miss of the first-order hold when it exceeds
        :data:`NOTED_JUMP` (an input accelerating over coarse communication steps), else None."""
        miss, when, h, dw = self.hold_noted
        if not (miss > NOTED_JUMP and h > 0 and dw != 0):
            return None
        a = abs(dw) / h
        what = self._taken_at_once(miss)
        return (f"input_shaft.angle at t = {when:.9g} s was {miss:.3g} rad from where the held "
                f"input carried it: the input shaft accelerated (about {a:.3g} rad/s2 over the "
                f"communication step of {h:.3g} s) and this FMU holds its speed over a step "
                f"(first-order hold; the miss is about a h^2 / 2); {what}. Steps up to "
                f"{math.sqrt(2.0 * NOTED_JUMP / a):.2g} s keep the miss below "
                f"{NOTED_JUMP:g} rad at that acceleration (docs/fmu.md, \"Input hold\")")

    def acceleration(self, t: float) -> float:
        """Backward difference of the speed input between communication points,
        a_k = (w_k - w_(k-1)) / (t_k - t_(k-1)); 0 at the first point (no history)."""
        if self.prev_t is not None and t > self.prev_t:
            return (self.speed - self.prev_speed) / (t - self.prev_t)
        return 0.0

    def inputs(self, t: float) -> Inputs:
        return Inputs(self.model_angle(), self.speed, self.torque, self.acceleration(t))

    # --- model ---------------------------------------------------------------------------------
    def build(self, params: dict, t: float, state=None, model=None) -> Built:
        """Model and stepper for validated ``params`` at time ``t`` (from ``state``, a
        StepperState, when given; ``model``: one already built from ``params``). Raises
        ValueError for a level this package lacks."""
        level = params["fidelity"]
        classes = self._M.MODEL_CLASSES
        if level not in classes:
            from .parameters import FIDELITY_NAMES
            raise ValueError(
                f"parameter fidelity = {level} ({FIDELITY_NAMES[level]}) is not available in "
                "this build of the FMU; available: "
                + ", ".join(f"{k} ({FIDELITY_NAMES[k]})" for k in sorted(classes)))
        if model is None:    # build_model: the level's class, wrapped for torque causality
            model = self._M.build_model(level, self._S.drive_from_parameters(params, self.name),
                                        params)
        drive = model.drive
        x0 = None if state is None else state.x
        # the inputs as set: a new model has no held angle to compare them with (a state given
        # brings its own held inputs)
        raw = Inputs(self.angle, self.speed, self.torque, self.acceleration(t))
        stepper = self._I.make_stepper(model, params["solver.method"], t, raw,
                                       step=params["solver.step"], rtol=params["solver.rtol"],
                                       tolerance=params["solver.tolerance"], x0=x0)
        watched = (WATCHED_TORQUE if params["input_shaft.causality"] == "torque"
                   else WATCHED_ANGLE)
        if self.watch.names != watched:
            self.watch = CouplingWatch(watched)
        if state is not None:
            stepper.set_state(state)
        else:
            self.watch.reset()
            self._motor_points.clear()
        self.stepper, self.params, self.drive = stepper, params, drive
        self._torque_inputs = params["input_shaft.causality"] == "torque"   # (torque_causal)
        return Built(stepper, params, drive, level)

    @property
    def t(self) -> float:
        return self.stepper.t

    # --- steps and outputs -----------------------------------------------------------------
    def outputs(self) -> np.ndarray:
        """Every output (ALL_OUTPUTS order) at the current state for the inputs set (direct
        feedthrough); a buffer the next call reuses. Refused inputs raise ValueError."""
        st = self.stepper
        angle = self.model_angle()
        row = st.outputs_held(angle, self.speed, self.acceleration(st.t), self.torque)
        if self.include_drive_inertia:
            return row
        return self._without_drive_inertia(row, angle, self.speed, self.torque)

    def _without_drive_inertia(self, row: np.ndarray, angle, speed, torque) -> np.ndarray:
        """``row`` (a copy) with input_shaft.torque of the same state and inputs but zero input
        acceleration: the drive's inertia torque I_eff(angle) a, and with it the feedthrough
        I_eff / h of the speed input through the backward difference, left to the motor model.
        At levels 1-3 with the shaft spring the acceleration does not enter that torque."""
        from .outputs import O_INPUT_SHAFT_TORQUE
        row = row.copy()
        row[O_INPUT_SHAFT_TORQUE] = self.stepper.outputs_held(angle, speed, 0.0, torque)[
            O_INPUT_SHAFT_TORQUE]
        return row

    def step(self, t: float, h: float, t_end: float | None = None) -> np.ndarray:
        """Advance from ``t`` (the current time) to ``t + h`` (or exactly to ``t_end``, a grid
        point of the master's) with the inputs held first-order;
        return every output there. Raises :class:`CouplingUnstable` (nothing done) when the
        inputs show an unstable coupling, SimulationDiverged or ValueError when the step fails;
        a failed step leaves the session at ``t``."""
        st = self.stepper
        # the watch takes the inputs of this point even when the step then fails: a master
        # retrying the point with the same inputs adds a zero increment, which it skips
        growing = None
        if self.watch_coupling:
            if self._torque_inputs:
                self._motor_points.append((self.motor_torque, self.motor_values()[1]))
                growing = self.watch.update((self.motor_torque, self.torque))
            else:
                growing = self.watch.update((self.speed, self.torque))
        if growing is not None:
            raise CouplingUnstable(self.coupling_message(t, h, growing))
        t_to = t + h if t_end is None else t_end
        angle = self.model_angle()
        try:
            if self.torque_causal:
                out = st.advance(t_to, Inputs(0.0, 0.0, self.torque, 0.0, self.motor_torque))
                row = np.array([out[o.name] for o in self._M.ALL_OUTPUTS])
            else:
                row = st.advance_held(t_to, angle, self.speed, self.acceleration(t),
                                      self.torque)
        except (SimulationDiverged, ValueError) as exc:
            suspect = self.watch.suspect() if self.watch_coupling else None
            if suspect is not None:   # the failure is the coupling's: its advice is not ours
                what = str(exc).split(";")[0]
                raise CouplingUnstable(self.coupling_message(t, h, suspect)
                                       + f" (The step itself failed: {what}.)") from exc
            raise
        self.prev_t, self.prev_speed = t, self.speed
        if angle != self.angle or self.turns_removed:
            self.turns_removed = round((self.angle - angle) / (2.0 * math.pi))
        if not self.include_drive_inertia:
            u = st.inputs      # the held inputs at t + h
            row = self._without_drive_inertia(row, u.angle, u.speed, u.torque)
        return row

    def coupling_message(self, t: float, h: float, name: str) -> str:
        """The sentence for an unstable coupling: which input, what holds instead."""
        p = self.params
        i = self.watch.names.index(name)
        peaks = ", ".join(f"{v:.3g}" for v in self.watch.recent(i))
        unit = "rad/s" if name == "input_shaft.speed" else "N.m"
        text = (f"co-simulation coupling unstable at t = {t:.9g} s: the input {name} set by "
                f"the master oscillates with growing amplitude from step to step (peak-to-peak "
                f"change per step over its last cycles: {peaks} {unit}) - the master's explicit "
                f"coupling at a communication step of {h:.3g} s is unstable, not the chain "
                "drive or its speed limits. ")
        if name == "input_shaft.speed" and not (p["fidelity"] == 0 or p["input_shaft.rigid"]):
            text += (f"A motor rotor of inertia J on the input-shaft spring (k_r = "
                     f"{p['input_shaft.stiffness']:g} N.m/rad, driver {p['driver.inertia']:g} "
                     f"kg.m2) holds at steps up to h = {JACOBI_CONSTANT:g} / omega_c, omega_c = "
                     "sqrt(k_r (1/J + 1/I_driver)) (Jacobi; Gauss-Seidel "
                     f"{GAUSS_SEIDEL_CONSTANT:g} / omega_c): ")
            js = [self.motor_inertia] if self.motor_inertia > 0 else [0.001, 0.01, 0.1]
            text += ", ".join(f"{stable_step(j, p):.3g} s for J = {j:g} kg.m2" for j in js)
            text += "; use such a step or torque causality (the motor's torque in, the rotor "
            text += "integrated inside this FMU). "
        elif name == "motor.torque":
            text += self._motor_torque_advice()
        elif name == "input_shaft.speed":
            text += ("Here the input-shaft torque contains the drive's inertia times the "
                     "backward-difference acceleration of the speed input, a feedthrough of "
                     "I_eff / h: a motor model holds only when its own rotor inertia exceeds the "
                     "drive's reflected inertia; use a smaller step, a larger rotor inertia or "
                     "torque causality. ")
        else:
            text += ("The load model's torque depends on this drive's outputs: use a smaller "
                     "communication step or let the load model integrate the driven inertia. ")
        return text + (f"Step discarded; the FMU stays at t = {t:.9g} s. If the master feeds "
                       "nothing back (the inputs are prescribed and really oscillate so), set "
                       "coupling.watch = false.")

    def _motor_torque_advice(self) -> str:
        """Torque causality: a motor model whose torque falls with the rotor speed it is fed
        (speed controller, a DC motor's back-EMF: dT/domega = -c) drives the rotor explicitly,
        omega_k+1 = omega_k + h / J (T0 - c omega_k): stable only for h < 2 J / c."""
        J = self.params["motor.inertia"]
        text = ("The motor model's torque depends on motor.speed, which this FMU returns and "
                "the master holds over the step (a speed controller, or a DC motor's back-EMF): "
                f"the rotor (motor.inertia J = {J:g} kg.m2) is then integrated explicitly and "
                "holds only at steps below about 2 J / |dT/domega|")
        if len(self._motor_points) == 2:
            (t0, w0), (t1, w1) = self._motor_points
        else:
            t0 = t1 = w0 = w1 = 0.0
        if w1 != w0 and (t1 - t0) * (w1 - w0) < 0:   # a torque that falls with the speed
            slope = (t1 - t0) / (w1 - w0)
            text += (f"; from the last two steps dT/domega = {slope:.3g} N.m.s/rad, so h < "
                     f"{2.0 * J / abs(slope):.3g} s")
        return text + ("; use such a step, or angle causality with the motor model integrating "
                       "its rotor. ")

    # --- state ---------------------------------------------------------------------------------
    def get_state(self) -> dict:
        """JSON-serialisable state (exact float round trip)."""
        s = None
        if self.stepper is not None:
            ss = self.stepper.get_state()
            u = ss.inputs
            s = {"t": ss.t, "x": [float(v) for v in ss.x], "h": ss.h,
                 "inputs": [u.angle, u.speed, u.torque, u.acceleration, u.motor_torque],
                 "extra": dict(ss.extra)}
        return {"stepper": s, "prev_t": self.prev_t, "prev_speed": self.prev_speed,
                "watch": self.watch.state(),
                "motor_points": [list(p) for p in self._motor_points]}

    def stepper_state(self, s: Mapping):
        """A StepperState from :meth:`get_state`'s ``"stepper"`` entry."""
        return self._I.StepperState(s["t"], np.array(s["x"], float), s["h"],
                                    self._M.Inputs(*s["inputs"]), dict(s["extra"]))

    def restore(self, state: Mapping, params: dict | None) -> None:
        """Restore :meth:`get_state`'s result; ``params``: the validated parameters to rebuild
        with when they differ from the current model's (None: keep the model)."""
        self.prev_t, self.prev_speed = state["prev_t"], state["prev_speed"]
        if "watch" in state:
            self.watch.restore(state["watch"])
        self._motor_points = deque((tuple(p) for p in state.get("motor_points", ())), maxlen=2)
        s = state["stepper"]
        if s is None:
            self.stepper = None
            return
        saved = self.stepper_state(s)
        if self.stepper is None or (params is not None and params != self.params):
            watch = self.watch.state()
            self.build(params if params is not None else self.params, saved.t, saved)
            self.watch.restore(watch)
        else:
            self.stepper.set_state(saved)

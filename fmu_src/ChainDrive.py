"""ChainDrive FMU: a thin FMI 2.0 co-simulation adapter over the ``chainmodel`` library.

No physics lives here. The adapter

* generates its parameters from the library's parameter schema (``chainmodel.parameters``) and
  its outputs from the model interface (``chainmodel.models.base.ALL_OUTPUTS``),
* validates the parameters with ``chainmodel.parameters.validate`` when initialization ends,
* builds the model of the chosen fidelity level and its stepper exactly as ``Scene.stepper``
  does (``drive_from_parameters``, ``MODEL_CLASSES[level]``, ``make_stepper``),
* advances the stepper over each communication step with the inputs held first-order,
* and moves values between FMI variables and the library.

Conventions (documented in docs/fmu.md):

Hold
    Over a step from t_k the inputs set at t_k are held first-order: the angle advances at the
    held speed, speed and load torque stay constant (``Inputs.hold``).
Acceleration
    The models also take the input shaft's angular acceleration. The FMU estimates it by
    backward difference of the speed input between communication points,
    a_k = (w_k - w_{k-1}) / (t_k - t_{k-1}); 0 at the first point (no history). The same
    estimate is used for the step from t_k and for outputs at t_k.
Feedthrough
    After fmi2DoStep the outputs at t_k+1 are those of the held inputs (computed in the step's
    compiled call). If the master then sets new inputs at t_k+1 and reads outputs, they are
    recomputed from the state at t_k+1 and the new inputs (every output may depend directly on
    the inputs; ModelStructure says so) - one more compiled call, at every level.
Data path
    One fmi2DoStep is one call of the stepper's ``advance_held`` (one compiled call per level:
    the step, its stable-step guard and every output into a preallocated buffer); the adapter
    copies the 15 values into its table. The stepper builds the new state beside the old one and
    commits it only on success, so a failed step needs no saved copy; fmi2GetFMUstate copies.
Errors
    pythonfmu 0.7 turns any Python exception into fmi2Fatal, so the adapter raises only where it
    must (a bad parameter at fmi2ExitInitializationMode, a state that cannot be restored) and
    logs a sentence naming the parameter first. A step that fails (divergence, non-finite
    inputs, bad step size) returns fmi2Discard with a logged message; the FMU stays at the
    last communication point with its last (finite) outputs and may be stepped again. Outputs
    that cannot be computed when read (non-finite inputs set) keep their last finite values
    and a warning is logged: never NaN.

The adapter imports its own copy of ``chainmodel`` from ``resources/_vendor/chainmodel`` under a
private module name, so another ``chainmodel`` in the host process never gets mixed in. That and
every other workaround for the host and pythonfmu (exit handling, reference counts, messages for
a misconfigured embedding) live in ``embedding.py`` beside this file; the co-simulation itself
(model, stepper, inputs, acceleration estimate, state, coupling watch) is
``chainmodel.cosim.CosimSession``: this module maps FMI variables onto them.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import sys
from pathlib import Path

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status

INPUTS = (
    ("input_shaft.angle", "rad", "angle imposed on the input shaft; the driver follows it rigidly "
     "at fidelity 0 and through the input-shaft spring at 1-3"),
    ("input_shaft.speed", "rad/s", "time derivative of input_shaft.angle: advances the angle "
     "within a step (first-order hold), damps the shaft, and its backward difference between "
     "communication points is the acceleration estimate"),
    ("load.torque", "N.m", "torque applied to the driven sprocket by the load, opposing forward "
     "motion when positive"),
)

#: fmi2 default experiment: the seed 003 drive at the library's output interval
DEFAULT_EXPERIMENT = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-4,
                                       tolerance=1e-6)


def _load_embedding():
    """fmu_src/embedding.py (resources/_vendor/embedding.py in the FMU): the workarounds for
    the host and pythonfmu, loaded under this module's name + ``_embedding``."""
    name = __name__ + "_embedding"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, os.path.join(os.path.dirname(os.path.abspath(__file__)), "embedding.py"))
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    return sys.modules[name]


_E = _load_embedding()
#: called by the entry module (build_fmu.SHIM)
balance_namespace_reference = _E.balance_namespace_reference
_fmi_text, _why, _embedding_error = _E.fmi_text, _E.why, _E.embedding_error


def parameter_description(p) -> str:
    """FMI description of a schema parameter: meaning, valid range, levels that use it."""
    text = p.description
    rng = p.valid_text()
    if rng:
        text += f"; valid: {rng}"
    if tuple(p.levels) != (0, 1, 2, 3):
        text += "; used at fidelity " + ", ".join(str(k) for k in p.levels)
    if p.structural:
        text += "; fixed after initialization"
    return text


class ChainDrive(Fmi2Slave):
    """Roller chain drive, FMI 2.0 co-simulation (see the module docstring)."""

    author = "ChainDrive"
    description = ("Roller chain drive (two sprockets, a roller chain): input-shaft motion and "
                   "load torque in; sprocket motion, span tensions, shaft torque out. Fidelity "
                   "ladder 0 kinematic, 1 torsional, 2 modal, 3 multibody (parameter fidelity).")
    license = "MIT"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if not self.resources:
            raise _embedding_error("the host passed no resources folder (fmuResourceLocation)")
        lib = _E.vendored_chainmodel(self.resources)
        if _E.wrapper_hosts_us(self.resources, type(self).__name__):
            _E.tidy_sys_path(self.resources)
        self._P, self._M, self._I, self._S = (lib["parameters"], lib["models"],
                                              lib["integrate"], lib["scene"])
        self._lib_auto = lib["fidelity_auto"]
        self._validity = lib["validity"]
        self._monitor = None         # chainmodel.validity.Monitor of the run (fmi2Warning logs)
        self._cosim = lib["cosim"]
        self._session = self._cosim.CosimSession(lib, "ChainDrive")
        self.version = getattr(lib["package"], "__version__", None)
        self.default_experiment = DEFAULT_EXPERIMENT

        # one value table per FMI type, keyed by value reference
        self._real: dict[int, float] = {}
        self._int: dict[int, int] = {}
        self._bool: dict[int, bool] = {}
        self._str: dict[int, str] = {}
        self._input_vrs: list[int] = []
        self._output_map: list[tuple[int, str]] = []   # (vr, output name)
        self._params: list[tuple[int, object, dict]] = []  # (vr, Parameter, its value table)
        self._param_by_vr: dict[int, object] = {}
        self._table_of: dict[int, dict] = {}

        for name, unit, desc in INPUTS:
            vr = self._add(Real, name, 0.0, self._real, causality=Fmi2Causality.input,
                           variability=Fmi2Variability.continuous, description=f"{desc} [{unit}]")
            self._input_vrs.append(vr)
        motor = self._M.torque_causality
        for spec in (motor.MOTOR_INPUT,):
            vr = self._add(Real, spec.name, 0.0, self._real, causality=Fmi2Causality.input,
                           variability=Fmi2Variability.continuous,
                           description=f"{spec.description} [{spec.unit}]")
            self._input_vrs.append(vr)
        for spec in self._M.ALL_OUTPUTS:
            vr = self._add(Real, spec.name, 0.0, self._real, causality=Fmi2Causality.output,
                           variability=Fmi2Variability.continuous,
                           initial=Fmi2Initial.calculated,
                           description=f"{spec.description} [{spec.unit or '1'}]")
            self._output_map.append((vr, spec.name))
        self._motor_vrs = tuple(
            self._add(Real, spec.name, 0.0, self._real, causality=Fmi2Causality.output,
                      variability=Fmi2Variability.continuous, initial=Fmi2Initial.calculated,
                      description=f"{spec.description} [{spec.unit}]")
            for spec in motor.MOTOR_OUTPUTS)
        kinds = {float: (Real, self._real), int: (Integer, self._int),
                 bool: (Boolean, self._bool), str: (String, self._str)}
        defaults = _E.build_defaults(Path(self.resources))
        for p in self._P.PARAMETERS:
            cls, table = kinds[p.kind]
            variability = Fmi2Variability.fixed if p.structural else Fmi2Variability.tunable
            vr = self._add(cls, p.name, p.kind(defaults.get(p.name, p.default)), table,
                           causality=Fmi2Causality.parameter, variability=variability,
                           initial=Fmi2Initial.exact, description=parameter_description(p))
            self._params.append((vr, p, table))
            self._param_by_vr[vr] = p
        # fidelity "auto" (chainmodel.fidelity_auto chooses; nothing of it is decided here)
        auto = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                    initial=Fmi2Initial.exact)
        self._auto_vrs = (
            self._add(Boolean, "auto.enabled", False, self._bool, description=(
                "fidelity auto: fidelity and solver.* chosen from the measured trade table "
                "(docs/tradeoff.md) to meet auto.accuracy on auto.outputs"), **auto),
            self._add(String, "auto.outputs", "", self._str, description=(
                "comma-separated outputs auto must get right ('' = every measured figure)"),
                **auto),
            self._add(Real, "auto.accuracy", 0.05, self._real,
                      description="relative error target of auto [1]", **auto),
            self._add(Real, "auto.input_speed", 0.0, self._real, description=(
                "steady input speed auto chooses for [rad/s] (0: the input at initialization)"),
                **auto),
            self._add(Real, "auto.load_torque", 0.0, self._real, description=(
                "load torque auto chooses for [N.m] (0: the input at initialization)"), **auto))
        # the coupling to a motor model (chainmodel.cosim; docs/fmu.md "In a system model")
        self._coupling_vrs = (
            self._add(Real, "coupling.motor_inertia", 0.0, self._real, description=(
                "inertia of the motor rotor a master couples to input_shaft.angle/.speed "
                "(angle causality) [kg.m2], for coupling.max_step and the message of an "
                "unstable coupling (0: unknown)"), **auto),
            self._add(Boolean, "input_shaft.include_drive_inertia", True, self._bool,
                      description=(
                          "input_shaft.torque includes the drive's inertia torque (the part "
                          "proportional to the input's acceleration, at fidelity 0 and with "
                          "input_shaft.rigid); false leaves it to the motor model and removes "
                          "the feedthrough I_eff/h of input_shaft.speed"), **auto),
            self._add(Boolean, "coupling.watch", True, self._bool, description=(
                "refuse a step whose inputs (input_shaft.speed, load.torque) oscillate from "
                "step to step with growing amplitude, the mark of an unstable explicit coupling "
                "(docs/fmu.md, \"In a system model\"); false for inputs prescribed open loop that "
                "really do so"), **auto))
        self._max_step_vr = self._add(
            Real, "coupling.max_step", 0.0, self._real, causality=Fmi2Causality.calculatedParameter,
            variability=Fmi2Variability.fixed, initial=Fmi2Initial.calculated, description=(
                "largest communication step [s] at which a Jacobi master holds a motor rotor of "
                "coupling.motor_inertia on the input-shaft spring (angle causality): "
                f"{self._cosim.JACOBI_CONSTANT:g} / omega_c, omega_c = sqrt(k_r (1/J + "
                "1/I_driver)); Gauss-Seidel holds about 3.5 times more; 0 where no such limit "
                "applies (coupling.motor_inertia 0, fidelity 0, input_shaft.rigid)"))
        self._auto_set = frozenset(self._auto_vrs + self._coupling_vrs)
        self._output_names = [name for _, name in self._output_map]
        self._output_vrs = frozenset(vr for vr, _ in self._output_map) | frozenset(self._motor_vrs)
        self._output_vr_list = [vr for vr, _ in self._output_map]   # ALL_OUTPUTS order
        self._in_angle, self._in_speed, self._in_torque, self._in_motor = self._input_vrs
        self._input_set = frozenset(self._input_vrs)

        # simulation state
        self._t0 = 0.0
        self._initialized = False
        self._stepper = None
        self._model_params: dict | None = None  # validated parameters the model was built with
        self._params_changed = True
        self._stale = False          # outputs must be recomputed (inputs set) before read
        self._told_coupling = False  # an unstable coupling was written to stderr
        self._told_turns = False     # a restart of the angle count was logged
        self._told_jump = False      # an accepted angle jump was warned of
        self._told_hold = False      # the first-order hold's miss was warned of
        self._warned_outputs = False

    def log(self, msg, status=Fmi2Status.ok, category=None, debug=None):
        """pythonfmu's ``log``, with one string object per distinct message: pythonfmu 0.7's
        wrapper keeps a reference to every message string it forwards (clearLogBuffer takes
        ``msg`` with PyObject_GetAttr and never releases it), so a message repeated at every
        instantiation or step costs memory once, not every time."""
        if type(msg) is str:
            shared = _E.MESSAGES.get(msg)
            if shared is None and len(_E.MESSAGES) < _E.MESSAGES_MAX:
                shared = _E.MESSAGES[msg] = msg
            msg = shared if shared is not None else msg
        super().log(msg, status, category)

    # --- variable plumbing --------------------------------------------------------------------
    def _add(self, cls, name, value, table, **kw):
        vr = len(self.vars)
        table[vr] = value
        self._table_of[vr] = table
        var = cls(name, getter=lambda: table[vr], setter=lambda v: self._set_one(vr, v), **kw)
        self.register_variable(var, nested=False)
        assert var.value_reference == vr
        return vr

    def _set_one(self, vr, value):
        table = self._table_of[vr]
        if vr in self._param_by_vr:
            p = self._param_by_vr[vr]
            if self._initialized and p.structural:
                # FMI 2.0 wants fmi2Error here; pythonfmu 0.7 can return only fmi2OK or
                # fmi2Fatal from a setter, so: fmi2OK, the value ignored, an error logged
                self.log(_fmi_text(f"parameter {p.name} is fixed after initialization; the new "
                                   f"value {value!r} is ignored"), Fmi2Status.error)
                return
            table[vr] = value
            self._params_changed = True
        elif vr in self._auto_set:
            if self._initialized:
                self.log(_fmi_text(f"parameter {self.vars[vr].name} is fixed after "
                                   f"initialization; the new value {value!r} is ignored"),
                         Fmi2Status.error)
                return
            table[vr] = value
            self._params_changed = True
        elif vr in self._input_vrs:
            table[vr] = value
            self._stale = True
        else:
            self.log(_fmi_text(f"{self.vars[vr].name} is an output and cannot be set; ignored"),
                     Fmi2Status.error)

    def _getter(self, table, kind, vrs):
        if self._stale or (self._params_changed and not self._initialized):
            outputs = self._output_vrs
            if any(vr in outputs for vr in vrs):
                self._refresh_outputs()
        try:
            return [table[vr] for vr in vrs]
        except KeyError:
            bad = [vr for vr in vrs if vr not in table]
            self._fail(f"value reference(s) {bad} are not of type {kind}")

    def get_real(self, vrs):
        return self._getter(self._real, "Real", vrs)

    def get_integer(self, vrs):
        return self._getter(self._int, "Integer", vrs)

    def get_boolean(self, vrs):
        return self._getter(self._bool, "Boolean", vrs)

    def get_string(self, vrs):
        return self._getter(self._str, "String", vrs)

    def _setter(self, table, kind, vrs, values):
        for vr, value in zip(vrs, values):
            if vr not in table:
                self._fail(f"value reference {vr} is not of type {kind}")
            self._set_one(vr, value)

    def set_real(self, vrs, values):
        # hot path: the three inputs, every step
        real, inputs = self._real, self._input_set
        for vr, value in zip(vrs, values):
            if vr in inputs:
                real[vr] = value
                self._stale = True
            elif vr in real:
                self._set_one(vr, value)
            else:
                self._fail(f"value reference {vr} is not of type Real")

    def set_integer(self, vrs, values):
        self._setter(self._int, "Integer", vrs, values)

    def set_boolean(self, vrs, values):
        self._setter(self._bool, "Boolean", vrs, [bool(v) for v in values])

    def set_string(self, vrs, values):
        self._setter(self._str, "String", vrs, values)

    def _fail(self, message: str):
        """Log ``message`` as an error and raise: pythonfmu reports fmi2Fatal (it has no other
        way to fail a call); :func:`_guard_entry_points` keeps the process consistent."""
        self.log(_fmi_text(message), Fmi2Status.error)
        exc = ValueError(message)
        exc.chaindrive_logged = True
        raise exc

    # --- model ----------------------------------------------------------------------------------
    def _parameter_values(self) -> dict:
        return {p.name: table[vr] for vr, p, table in self._params}

    def _sync_inputs(self):
        """The input values of the value table into the session."""
        real = self._real
        self._session.set_inputs(real[self._in_angle], real[self._in_speed],
                                 real[self._in_torque], real[self._in_motor])
        return self._session

    def _build(self, t: float, state=None):
        """Validate the parameters and build model and stepper at time t (raises ValueError)."""
        P = self._P
        params = P.validate(self._parameter_values())
        on, outputs, accuracy, speed, load = (self._table_of[vr][vr] for vr in self._auto_vrs)
        session = self._sync_inputs()
        if on:
            u0 = session.inputs(t)
            params, choice = self._lib_auto.choose_parameters(
                params, speed if speed else u0.speed, load if load else u0.torque,
                outputs or None, accuracy)
            if choice.message != getattr(self, "_auto_message", None):
                self._auto_message = choice.message
                # a target no measured configuration meets, or an error it cannot promise, is
                # what the user must hear: a warning, not a logAll note a tool may hide
                if choice.met and choice.promised:
                    self.log(_fmi_text(choice.message), Fmi2Status.ok, "logAll")
                else:
                    self.log(_fmi_text(choice.message), Fmi2Status.warning)
        J_vr, inertia_vr, watch_vr = self._coupling_vrs
        session.motor_inertia = self._real[J_vr]
        if not (session.motor_inertia >= 0 and math.isfinite(session.motor_inertia)):
            raise ValueError(f"parameter coupling.motor_inertia = {session.motor_inertia!r} "
                             "kg.m2 is not valid; valid: >= 0 (0: unknown)")
        session.include_drive_inertia = bool(self._bool[inertia_vr])
        session.watch_coupling = bool(self._bool[watch_vr])
        built = session.build(params, t, state)
        h_max = (self._cosim.stable_step(session.motor_inertia, params)
                 if session.motor_inertia > 0 else math.inf)
        self._real[self._max_step_vr] = h_max if math.isfinite(h_max) else 0.0
        if state is None:   # a new run: its validity checks start afresh
            self._monitor = self._validity.Monitor(
                built.drive, params, built.level, self._output_names,
                started_unloaded=bool(built.stepper.model.start_fallback))
        self._stepper, self._model_params = built.stepper, params
        self._params_changed = False
        return built.stepper

    def _store_row(self, row, fresh=False):
        """The outputs row of the stepper (ALL_OUTPUTS order) into the value table; returns the
        values as a list."""
        values = row.tolist()
        self._real.update(zip(self._output_vr_list, values))
        self._real.update(zip(self._motor_vrs, self._session.motor_values(fresh)))
        return values

    def _refresh_outputs(self):
        """Outputs for the current state and the inputs set since (direct feedthrough)."""
        try:
            if self._stepper is None or (self._params_changed and not self._initialized):
                self._build(self._t0)
            row = self._sync_inputs().outputs()
            bad = [n for n, v in zip(self._output_names, row.tolist()) if not math.isfinite(v)]
            if bad:
                raise self._M.SimulationDiverged(f"non-finite outputs {', '.join(bad[:5])}")
        except Exception as exc:  # never raise from a getter: pythonfmu would report fatal
            if not self._warned_outputs:
                self.log(_fmi_text(f"outputs keep their last values: {_why(exc)}"),
                         Fmi2Status.warning)
                self._warned_outputs = True
            return
        self._store_row(row, fresh=True)
        self._stale = False
        self._warned_outputs = False

    # --- FMI ------------------------------------------------------------------------------------
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._t0 = float(start_time)

    def exit_initialization_mode(self):
        try:
            st = self._build(self._t0)
            u = st.inputs
            row = st.outputs_held(u.angle, u.speed, u.acceleration, u.torque)
        except Exception as exc:
            self._fail(f"initialization failed: {_why(exc)}")
        self._store_row(row)
        self._stale = False
        self._initialized = True
        self._check_validity(st.t, row, u.speed, u.torque,
                             self._validity.geometry_problems(st.model.drive, self._model_params,
                                                              st.model.level)
                             + self._validity.start_problems(st.model.start_fallback,
                                                             st.model.level))
        level = self._model_params["fidelity"]
        qs = [n for n, d in st.model.output_descriptions().items()
              if d.startswith(self._M.base.QUASI_STATIC)]
        self.log(_fmi_text(f"fidelity {level} ({self._P.FIDELITY_NAMES[level]}), stepper "
                           f"{type(st).__name__} {getattr(st, 'method', '')}; quasi-static "
                           f"estimates at this level: {', '.join(qs) or 'none'}"),
                 Fmi2Status.ok, "logAll")
        if self._real[self._max_step_vr] > 0:
            self.log(_fmi_text(
                f"angle causality: a motor rotor of coupling.motor_inertia = "
                f"{self._session.motor_inertia:g} kg.m2 on the input-shaft spring holds at "
                f"communication steps up to coupling.max_step = "
                f"{self._real[self._max_step_vr]:.3g} s (Jacobi; docs/fmu.md, \"In a system "
                "model\")"), Fmi2Status.ok, "logAll")

    def do_step(self, current_time, step_size):
        st = self._stepper
        if not self._initialized or st is None:
            self.log("fmi2DoStep called before initialization", Fmi2Status.error)
            return False
        if not (step_size > 0 and math.isfinite(step_size)):
            self.log(_fmi_text(f"communication step size must be positive and finite, got "
                               f"{step_size!r}; step discarded"), Fmi2Status.discard)
            return False
        if abs(current_time - st.t) > 1e-9 * max(1.0, abs(st.t)):
            self.log(_fmi_text(f"fmi2DoStep from t = {current_time!r} s but the FMU is at "
                               f"t = {st.t!r} s; step discarded"), Fmi2Status.discard)
            return False
        if self._params_changed:   # a tunable parameter changed: rebuild, keep the state
            try:
                st = self._build(st.t, st.get_state())
            except Exception as exc:
                self.log(_fmi_text(f"parameter change refused: {_why(exc)}"), Fmi2Status.discard)
                return False
        session = self._sync_inputs()
        speed = session.speed
        try:
            row = session.step(current_time, step_size)
        except Exception as exc:   # diverged, bad input, or a model error: discard the step
            self.log(_fmi_text(f"step from t = {current_time:.9g} s over {step_size:.6g} s "
                               f"discarded, the FMU stays at t = {current_time:.9g} s: "
                               f"{_why(exc)}"),
                     Fmi2Status.discard)
            if isinstance(exc, self._cosim.CouplingUnstable) and not self._told_coupling:
                # hosts that instantiate with logging off (libcosim) would show only that the
                # step failed: this one, the system's fault rather than ours, also goes to stderr
                self._told_coupling = True
                try:
                    print(f"ChainDrive FMU ({self.instance_name}): {exc}", file=sys.stderr,
                          flush=True)
                except Exception:  # pragma: no cover - no usable stderr in the host
                    pass
            return False
        values = self._store_row(row)
        self._stale = False
        # each logged once (the flag tested first: the notes are not looked for again)
        if not self._told_turns:
            self._told_turns = self._log_once(session.restart_note(current_time),
                                              Fmi2Status.ok, "logAll")
        if not self._told_jump:
            self._told_jump = self._log_once(session.jump_warning(), Fmi2Status.warning)
        if not self._told_hold:
            self._told_hold = self._log_once(session.hold_warning(), Fmi2Status.warning)
        if session.torque_causal:   # the validity checks' input speed: the motor rotor's
            speed = session.motor_values()[1]
        self._check_validity(current_time + step_size, values, speed, session.torque)
        return True

    def _log_once(self, note, status, category=None) -> bool:
        """Log ``note`` (None: nothing to say) as said once; whether it was logged."""
        if not note:
            return False
        self.log(_fmi_text(note + " (logged once)"), status, category)
        return True

    def _check_validity(self, t, row, speed, load, found=()):
        """Log as fmi2Warning each validity problem (chainmodel.validity) once, when it first
        appears: ``found`` (the geometry's, at initialization), then what the outputs' checks
        find with this sample."""
        texts = [p.text for p in found]
        if self._monitor is not None:
            texts += self._monitor.update(t, row, speed, load)
        for text in texts:
            self.log(_fmi_text(text), Fmi2Status.warning)

    def terminate(self):
        pass

    # --- FMU state ------------------------------------------------------------------------------
    def _get_fmu_state(self):
        session = self._session.get_state()
        return {"format": "ChainDrive-1",
                "real": list(self._real.items()), "int": list(self._int.items()),
                "bool": list(self._bool.items()), "str": list(self._str.items()),
                "t0": self._t0, "initialized": self._initialized, "stale": self._stale,
                "prev_t": session["prev_t"], "prev_speed": session["prev_speed"],
                "stepper": session["stepper"] if self._stepper is not None else None,
                "watch": session["watch"]}

    def _set_fmu_state(self, state):
        if not isinstance(state, dict) or state.get("format") != "ChainDrive-1":
            self._fail("fmi2SetFMUstate: not a ChainDrive FMU state")
        for key, table in (("real", self._real), ("int", self._int), ("bool", self._bool),
                           ("str", self._str)):
            for vr, value in state[key]:
                table[int(vr)] = value
        self._t0 = state["t0"]
        self._initialized = state["initialized"]
        session = self._sync_inputs()
        session.prev_t, session.prev_speed = state["prev_t"], state["prev_speed"]
        if state["stepper"] is None:
            session.restore(state, None)
            self._stepper, self._model_params, self._params_changed = None, None, True
        else:
            try:
                if (self._stepper is None or self._params_changed
                        or self._P.validate(self._parameter_values()) != self._model_params):
                    self._build(state["stepper"]["t"], session.stepper_state(state["stepper"]))
                session.restore(state, None)
            except Exception as exc:
                self._fail(f"fmi2SetFMUstate: cannot restore this state: {_why(exc)}")
        self._stale = state["stale"]

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        # json writes floats with repr(): exact round trip (non-finite values as NaN/Infinity)
        return json.dumps(state, separators=(",", ":")).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(data: bytes):
        return json.loads(data.decode("utf-8"))


_E.guard_entry_points(ChainDrive)

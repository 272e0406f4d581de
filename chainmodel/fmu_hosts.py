"""Run an FMU through an independent importer (host), with one call sequence for all of them.

This module holds no physics and nothing of ChainDrive's: it drives any FMI 2.0 co-simulation
FMU through fmpy or libcosim (``pip install libcosimpy``) and returns its outputs on the
communication grid, so that results from different hosts can be compared bit for bit
(tests/test_hosts.py; ``chainmodel fmu-test --host`` will reuse it).

The call sequence is libcosim's fixed-step one, reproduced call for call with fmpy:

* times are integer nanoseconds, as libcosim counts them: ``t_k = k * step_ns / 1e9`` and each
  ``fmi2DoStep`` gets ``communicationStepSize = t_(k+1) - t_k`` computed in double precision;
* ``start_values`` are set once before ``fmi2SetupExperiment`` and again, with the inputs at
  t_0, in initialization mode; outputs[0] are read after ``fmi2ExitInitializationMode``;
* step k (k = 1..n): the inputs at t_(k-1) are set, ``fmi2DoStep(t_(k-1), t_k - t_(k-1))``,
  then outputs[k] are read. So outputs[k] are the outputs at t_k under the inputs held since
  t_(k-1) (a master that sets the inputs of t_k before reading would see direct feedthrough).

API::

    run_fmu(fmu, host="fmpy"|"libcosim", *, stop_time, step_size, inputs=None,
            start_values=None, outputs=None) -> HostRun(host, version, time, outputs,
                                                      messages)
    host_versions() -> {"fmpy": "0.3.32", "libcosim": "0.0.6" or None if not importable}
    grid(stop_time, step_size) -> (times, step_ns)

``inputs`` maps an input name to a constant, an array of one value per grid point, or a
function of time; ``outputs`` names the outputs to return (default: every output).
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

__all__ = ["HOSTS", "HostRun", "HostUnavailable", "run_fmu", "host_versions", "grid", "master_loop",
           "FmpyBinding", "LibcosimBinding"]

HOSTS = ("fmpy", "libcosim")


class HostUnavailable(RuntimeError):
    """The requested host is not installed on this platform."""


@dataclass(frozen=True)
class HostRun:
    host: str
    version: str
    time: np.ndarray                      # communication points [s]
    outputs: dict[str, np.ndarray]        # output name -> value at each point
    #: (status, message) the FMU logged, fmpy only (libcosim prints its instances' errors)
    messages: tuple[tuple[int, str], ...] = ()


def host_versions() -> dict[str, str | None]:
    """Installed version of each host, None where it cannot be imported."""
    versions: dict[str, str | None] = {}
    try:
        import fmpy
        versions["fmpy"] = fmpy.__version__
    except ImportError:
        versions["fmpy"] = None
    try:
        from libcosimpy import __about__
        import libcosimpy.CosimExecution  # noqa: F401 - loads the C library
        versions["libcosim"] = __about__.__version__
    except (ImportError, OSError):
        versions["libcosim"] = None
    return versions


def grid(stop_time: float, step_size: float) -> tuple[np.ndarray, int]:
    """Communication points from 0 to ``stop_time`` every ``step_size`` seconds, computed as
    libcosim does from integer nanoseconds; returns (times, step in ns)."""
    step_ns = round(step_size * 1e9)
    if step_ns < 1 or abs(step_ns - step_size * 1e9) > 1e-6 * step_ns:
        raise ValueError(f"step_size must be a positive whole number of nanoseconds, got "
                         f"{step_size!r} s")
    n = round(stop_time * 1e9 / step_ns)
    if n < 1 or abs(n * step_ns - stop_time * 1e9) > 1e-6 * step_ns:
        raise ValueError(f"stop_time must be a positive multiple of step_size ({step_size!r} s), "
                         f"got {stop_time!r} s")
    return np.array([k * step_ns / 1e9 for k in range(n + 1)]), step_ns


def _input_table(inputs: Mapping[str, Any] | None, times: np.ndarray) -> dict[str, np.ndarray]:
    table = {}
    for name, spec in (inputs or {}).items():
        if callable(spec):
            values = np.array([float(spec(float(t))) for t in times])
        else:
            values = np.broadcast_to(np.asarray(spec, float), times.shape).copy() \
                if np.ndim(spec) == 0 else np.asarray(spec, float)
        if values.shape != times.shape:
            raise ValueError(f"input {name!r}: {values.shape[0]} values for {len(times)} "
                             "communication points")
        table[name] = values
    return table


def _variables(fmu: Path, inputs: Mapping, start_values: Mapping, outputs: Sequence[str] | None):
    from fmpy import read_model_description
    md = read_model_description(str(fmu))
    by_name = {v.name: v for v in md.modelVariables}
    for what, names in (("input", inputs), ("start value", start_values)):
        unknown = [n for n in names if n not in by_name]
        if unknown:
            raise ValueError(f"{fmu.name} has no variable(s) {', '.join(unknown)} "
                             f"(given as {what})")
    if outputs is None:
        outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    unknown = [n for n in outputs if n not in by_name]
    if unknown:
        raise ValueError(f"{fmu.name} has no output(s) {', '.join(unknown)}")
    return md, by_name, list(outputs)


def run_fmu(fmu: str | Path, host: str = "fmpy", *, stop_time: float, step_size: float,
            inputs: Mapping[str, float | Sequence[float] | Callable[[float], float]] | None = None,
            start_values: Mapping[str, Any] | None = None,
            outputs: Sequence[str] | None = None) -> HostRun:
    """Simulate ``fmu`` with ``host`` on the grid of :func:`grid` (module docstring)."""
    fmu = Path(fmu)
    if not fmu.is_file():
        raise ValueError(f"FMU {str(fmu)!r} does not exist")
    if host not in HOSTS:
        raise ValueError(f"host must be one of {', '.join(HOSTS)}, got {host!r}")
    version = host_versions()[host]
    if version is None:
        raise HostUnavailable(f"{host} is not installed (pip install "
                              f"{'libcosimpy' if host == 'libcosim' else host})")
    times, step_ns = grid(stop_time, step_size)
    table = _input_table(inputs, times)
    start_values = dict(start_values or {})
    md, by_name, names = _variables(fmu, table, start_values, outputs)
    run = _run_fmpy if host == "fmpy" else _run_libcosim
    data, messages = run(fmu, md, by_name, names, times, step_ns, table, start_values)
    return HostRun(host, version, times, {n: data[:, k].copy() for k, n in enumerate(names)},
                   tuple(messages))


# --- the master loop, one for every host -----------------------------------------------------

def master_loop(binding, times, u, data, *, feedthrough: bool, progress=None) -> int:
    """The fixed-step master loop of every run here and of :class:`chainmodel.fmu.FMUSession`.

    ``binding``: the host's calls (:class:`FmpyBinding`, :class:`LibcosimBinding`) -
    ``set_inputs(row)``, ``step(t, h) -> bool``, ``read(out_row) -> bool``. ``u[k]``: the inputs
    at ``times[k]``; ``data[k]`` receives the outputs at ``times[k]`` (k >= 1). Two call orders:

    * ``feedthrough=False`` (libcosim's, :func:`run_fmu`): the inputs of t_(k-1) set, the step
      from t_(k-1), the outputs at t_k read under the inputs held since t_(k-1);
    * ``feedthrough=True`` (``simulate_fmu``): the step from t_(k-1), then the inputs of t_k set
      and the outputs read, recomputed for them (direct feedthrough).

    Returns ``len(times)``, or the index of the point whose step, set or read failed."""
    set_inputs, step, read = binding.set_inputs, binding.step, binding.read
    t = times.tolist()     # Python floats: ctypes argtypes convert them directly
    update = progress.update if progress is not None else None
    for i in range(1, len(t)):
        if not feedthrough and not set_inputs(u[i - 1]):
            return i
        if not step(t[i - 1], t[i] - t[i - 1]):
            return i
        if feedthrough and not set_inputs(u[i]):
            return i
        if not read(data[i]):
            return i
        if update is not None:
            update(t[i])
    return len(times)


class FmpyBinding:
    """An fmpy FMU2Slave's fmi2DoStep / fmi2SetReal / fmi2GetReal for :func:`master_loop`,
    called directly with buffers made once (fmpy's ``doStep``/``setReal``/``getReal`` build
    ctypes arrays and check the status in Python on every call: about a third of a step's cost
    at 0.1 ms). A call fails when its status is above fmi2Warning (the FMU logged why)."""

    def __init__(self, fmu, in_vr, out_vr):
        from fmpy.fmi2 import fmi2Real, fmi2ValueReference, fmi2Warning
        n_in, n_out = len(in_vr), len(out_vr)
        comp, dll = fmu.component, fmu.dll
        do_step, set_real, get_real = dll.fmi2DoStep, dll.fmi2SetReal, dll.fmi2GetReal
        vr_in = (fmi2ValueReference * n_in)(*in_vr)
        vr_out = (fmi2ValueReference * n_out)(*out_vr)
        buf_in, buf_out = (fmi2Real * n_in)(), (fmi2Real * n_out)()
        view_in = np.ctypeslib.as_array(buf_in) if n_in else None
        view_out = np.ctypeslib.as_array(buf_out)
        warning = fmi2Warning

        def set_inputs(row) -> bool:
            if not n_in:
                return True
            view_in[:] = row
            return set_real(comp, vr_in, n_in, buf_in) <= warning

        def step(t, h) -> bool:
            return do_step(comp, t, h, 1) <= warning

        def read(out) -> bool:
            if get_real(comp, vr_out, n_out, buf_out) > warning:
                return False
            out[:] = view_out
            return True

        self.set_inputs, self.step, self.read = set_inputs, step, read


class LibcosimBinding:
    """One slave of a libcosim execution for :func:`master_loop`: inputs through an override
    manipulator, ``execution.step()`` (libcosim keeps its own time: the loop's t and h are its
    grid), outputs kept by a time-series observer and read after the run (:meth:`collect`)."""

    def __init__(self, execution, manipulator, index, in_vr):
        self.execution, self.manipulator, self.index, self.in_vr = \
            execution, manipulator, index, list(in_vr)

    def set_inputs(self, row) -> bool:
        if self.in_vr:
            self.manipulator.slave_real_values(self.index, self.in_vr, [float(v) for v in row])
        return True

    def step(self, t, h) -> bool:
        return bool(self.execution.step())

    def read(self, out) -> bool:
        return True


def _typed(by_name, values: Mapping[str, Any]) -> dict[str, tuple[list, list]]:
    groups: dict[str, tuple[list, list]] = {}
    for name, value in values.items():
        v = by_name[name]
        refs, vals = groups.setdefault(v.type, ([], []))
        refs.append(v.valueReference)
        vals.append(value)
    return groups


def _run_fmpy(fmu, md, by_name, names, times, step_ns, table,
              start_values) -> tuple[np.ndarray, list]:
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave

    from .fmu_log import FMULog
    folder = extract(str(fmu))
    log = FMULog()
    out_vr = [by_name[n].valueReference for n in names]
    in_vr = [by_name[n].valueReference for n in table]
    groups = _typed(by_name, start_values)
    data = np.empty((len(times), len(names)))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="host_run")
    try:
        slave.instantiate(callbacks=log.callbacks)
        setters = {"Real": slave.setReal, "Integer": slave.setInteger,
                   "Boolean": slave.setBoolean, "String": slave.setString}

        def set_start():
            for typ, (refs, vals) in groups.items():
                setters[typ](refs, vals)

        def set_inputs(k):
            if in_vr:
                slave.setReal(in_vr, [float(table[n][k]) for n in table])

        set_start()
        slave.setupExperiment(startTime=float(times[0]))
        slave.enterInitializationMode()
        slave.getReal(out_vr)              # libcosim reads every variable here ...
        set_start()
        set_inputs(0)
        slave.getReal(out_vr)              # ... and after setting the initial values
        try:
            slave.exitInitializationMode()
        except FMICallException as exc:
            raise RuntimeError(f"{exc}: {log.problems()}") from None
        data[0] = slave.getReal(out_vr)
        u = np.column_stack([table[n] for n in table]) if table else np.empty((len(times), 0))
        k = master_loop(FmpyBinding(slave, in_vr, out_vr), times, u, data, feedthrough=False)
        if k < len(times):
            raise RuntimeError(f"fmpy step to t = {times[k]:.9g} s failed: {log.problems()}")
        slave.terminate()
    finally:
        if slave.component is not None:
            slave.freeInstance()
        shutil.rmtree(folder, ignore_errors=True)
    return data, log.messages


def _run_libcosim(fmu, md, by_name, names, times, step_ns, table,
                  start_values) -> tuple[np.ndarray, tuple]:
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    # the FMU logs its validity warnings whatever loggingOn says (docs/fmu.md, "Log messages");
    # a host comparison keeps them out of its output, as the fmpy path keeps them in messages
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_ns)
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu.resolve()),
                                                      instance_name="host_run"))
    if index < 0:
        raise RuntimeError(f"libcosim could not load {fmu}")
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator)
    observer = CosimObserver.create_time_series(buffer_size=len(times) + 1)
    execution.add_observer(observer)
    initial = {"Real": execution.real_initial_value, "Integer": execution.integer_initial_value,
               "Boolean": execution.boolean_initial_value,
               "String": execution.string_initial_value}
    values = dict(start_values)
    values.update({n: float(table[n][0]) for n in table})
    for name, value in values.items():
        v = by_name[name]
        if not initial[v.type](index, v.valueReference, value):
            raise RuntimeError(f"libcosim refused the initial value {name} = {value!r}")
    out_vr = [by_name[n].valueReference for n in names]
    for vr in out_vr:
        observer.start_time_series(index, vr, CosimVariableType.REAL)
    in_vr = [by_name[n].valueReference for n in table]
    u = np.column_stack([table[n] for n in table]) if table else np.empty((len(times), 0))
    data = np.empty((len(times), len(names)))
    k = master_loop(LibcosimBinding(execution, manipulator, index, in_vr), times, u, data,
                    feedthrough=False)
    if k < len(times):
        raise RuntimeError(f"libcosim step to t = {times[k]:.9g} s failed")
    for j, vr in enumerate(out_vr):
        data[:, j] = _real_samples(observer, index, vr, len(times))
    execution.stop()
    return data, ()


def _real_samples(observer, index: int, vr: int, count: int) -> np.ndarray:
    """Steps 0..count-1 of a time-series observer. libcosimpy 0.0.6's own reader returns its
    three arrays in an order other than the one it documents and trims the result by counting
    zero step numbers, which drops a sample whenever step 0 is included; this calls
    cosim_observer_slave_get_real_samples itself."""
    from ctypes import POINTER, c_double, c_int, c_int64, c_size_t, c_uint32
    from libcosimpy._internal import libcosimc, wrap_function
    from libcosimpy.CosimObserver import CosimObserver
    values, steps, stamps = (c_double * count)(), (c_int64 * count)(), (c_int64 * count)()
    get = wrap_function(lib=libcosimc(), funcname="cosim_observer_slave_get_real_samples",
                        argtypes=[POINTER(CosimObserver), c_int, c_uint32, c_int64, c_size_t,
                                  c_double * count, c_int64 * count, c_int64 * count],
                        restype=c_int64)
    got = get(observer.ptr(), index, vr, 0, count, values, steps, stamps)
    if got != count or list(steps) != list(range(count)):
        raise RuntimeError(f"libcosim returned {got} samples (steps {list(steps)[:3]}...), "
                           f"expected steps 0..{count - 1}")
    return np.array(values[:])

#!/usr/bin/env python
"""Largest stable communication step of an angle-causality coupling, measured (issue 18 item 3).

The example system's Motor FMU (examples/system/Motor.py, angle causality: a PI-controlled rotor
of inertia J fed ChainDrive's input_shaft.torque, giving input_shaft.angle and .speed) drives
ChainDrive.fmu (a constant load torque) through a fixed-step master in fmpy, Jacobi (both FMUs
get the other's outputs of the same communication point) or Gauss-Seidel (ChainDrive steps
first, the motor then gets its new torque). For each rotor inertia the step is bisected on a
geometric grid: a run "holds" when it finishes ``--duration`` seconds with every step accepted
and the motor speed within 10 percent of the set point at the end. The table prints the
measured largest step that holds beside the prediction C / omega_c (chainmodel.cosim.stable_step).

    python build_fmu.py --out /tmp/cd/ChainDrive.fmu -q
    python examples/system/build.py --out /tmp/cd/sys --launch
    python benchmarks/coupling_step.py --fmu /tmp/cd/ChainDrive.fmu --motor /tmp/cd/sys/Motor.fmu
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


class Slave:
    """One fmpy FMU2Slave with variables by name and the messages it logged."""

    def __init__(self, path, name, start=None):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        md = read_model_description(str(path))
        self.folder = extract(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        from chainmodel.fmu_log import FMULog
        self.logger = FMULog()
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=self.folder, instanceName=name,
                             modelIdentifier=md.coSimulation.modelIdentifier)
        self.fmu.instantiate(callbacks=self.logger.callbacks, loggingOn=True)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for key, value in (start or {}).items():
            setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                      "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}
            setter[self.types[key]]([self.vr[key]], [value])
        self.fmu.exitInitializationMode()

    @property
    def messages(self) -> list[str]:
        return [text for _, text in self.logger.messages]

    def get(self, name):
        return self.fmu.getReal([self.vr[name]])[0]

    def put(self, name, value):
        self.fmu.setReal([self.vr[name]], [value])

    def step(self, t, h) -> bool:
        from fmpy.fmi1 import FMICallException
        try:
            self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            return True
        except FMICallException:
            return False

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.folder, ignore_errors=True)


def couple(fmu, motor_fmu, inertia, step, level=1, duration=0.1, scheme="jacobi",
           load_torque=10.0, chain_start=None):
    """Run Motor + ChainDrive; returns (held, t_end, message, peak |input_shaft.torque|)."""
    motor = Slave(motor_fmu, "Motor", {"motor.inertia": inertia, "causality": "angle",
                                       "controller.kp": 2 * 50 * (inertia + 0.004),
                                       "controller.ki": 50 ** 2 * (inertia + 0.004)})
    start = {"fidelity": level}
    start.update(chain_start or {})
    chain = Slave(fmu, "ChainDrive", start)
    n = round(duration / step)
    peak, t, held, message = 0.0, 0.0, True, ""
    try:
        chain.put("load.torque", load_torque)
        for k in range(n):
            t = k * step
            chain.put("input_shaft.angle", motor.get("rotor.angle"))
            chain.put("input_shaft.speed", motor.get("rotor.speed"))
            if scheme == "jacobi":
                motor.put("shaft.torque", chain.get("input_shaft.torque"))
                ok = chain.step(t, step) and motor.step(t, step)
            else:
                ok = chain.step(t, step)
                motor.put("shaft.torque", chain.get("input_shaft.torque"))
                ok = ok and motor.step(t, step)
            peak = max(peak, abs(chain.get("input_shaft.torque")))
            if not ok:
                held = False
                message = " ".join(m for m in chain.messages if "discarded" in m or "unstable" in m)
                break
        else:
            t = n * step
            speed = motor.get("rotor.speed")
            held = abs(speed - 4 * math.pi) < 0.1 * 4 * math.pi
            if not held:
                message = f"finished off the set point: motor speed {speed:.4g} rad/s"
    finally:
        motor.close()
        chain.close()
    return held, t, message, peak


GRID = (1e-5, 2e-5, 3e-5, 5e-5, 7e-5, 1e-4, 1.5e-4, 2e-4, 3e-4, 4e-4, 5e-4, 7e-4, 1e-3, 1.5e-3,
        2e-3)


def largest_stable(fmu, motor, inertia, level, scheme, duration) -> tuple[float, float]:
    """Largest grid step that holds and the smallest that fails above it (bisection on GRID,
    assuming one boundary)."""
    lo, hi = -1, len(GRID)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        held = couple(fmu, motor, inertia, GRID[mid], level, duration, scheme)[0]
        lo, hi = (mid, hi) if held else (lo, mid)
    return (GRID[lo] if lo >= 0 else 0.0), (GRID[hi] if hi < len(GRID) else math.inf)


def main(argv=None) -> int:
    from chainmodel.cosim import stable_step
    from chainmodel.parameters import validate
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fmu", required=True)
    ap.add_argument("--motor", required=True)
    ap.add_argument("--level", type=int, default=1)
    ap.add_argument("--duration", type=float, default=0.1)
    ap.add_argument("--schemes", default="jacobi,gauss-seidel")
    ap.add_argument("--inertias", default="0.001,0.003,0.01,0.03")
    args = ap.parse_args(argv)
    params = validate({"fidelity": args.level})
    print(f"level {args.level}, {args.duration} s, motor set point 4 pi rad/s, load 10 N.m")
    print("| scheme | J_motor [kg m2] | omega_c [rad/s] | predicted h_max [s] | largest step that "
          "held [s] | smallest that failed [s] |")
    print("|---|---|---|---|---|---|")
    for scheme in args.schemes.split(","):
        for j in (float(v) for v in args.inertias.split(",")):
            wc = math.sqrt(params["input_shaft.stiffness"] * (1 / j + 1 / params["driver.inertia"]))
            held, failed = largest_stable(args.fmu, args.motor, j, args.level, scheme,
                                          args.duration)
            print(f"| {scheme} | {j:g} | {wc:.0f} | {stable_step(j, params, scheme):.3g} | "
                  f"{held:.3g} | {failed:.3g} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

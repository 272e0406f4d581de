"""Issue 18 item 5: a process holding ChainDrive.fmu and two plain pythonfmu FMUs (the example
system's Motor and Load, examples/system) exits cleanly. Each run is a fresh Python process;
benchmarks/system_exit.py counts more of them and finds whose crash it is."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

pytestmark = pytest.mark.fmu

ROOT = Path(__file__).resolve().parents[1]

#: FMUS = {name: path} (any of ChainDrive, Motor, Load), LEVEL, STEPS are prepended
SYSTEM_LIFE = textwrap.dedent("""
    import shutil
    from fmpy import read_model_description, extract
    from fmpy.fmi2 import FMU2Slave

    slaves = {}
    for name, path in FMUS.items():
        md = read_model_description(path)
        folder = extract(path)
        s = FMU2Slave(guid=md.guid, unzipDirectory=folder, instanceName=name,
                      modelIdentifier=md.coSimulation.modelIdentifier)
        vr = {v.name: v.valueReference for v in md.modelVariables}
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        if name == "ChainDrive":
            s.setInteger([vr["fidelity"]], [LEVEL])
        s.exitInitializationMode()
        slaves[name] = (s, vr, folder)

    def get(name, var):
        s, vr, _ = slaves[name]
        return s.getReal([vr[var]])[0]

    def put(name, var, value):
        if name in slaves:
            s, vr, _ = slaves[name]
            s.setReal([vr[var]], [value])

    h, t = 1e-4, 0.0
    for k in range(STEPS):     # Jacobi: every FMU gets the others' outputs of the same point
        if "ChainDrive" in slaves:
            torque, driven = get("ChainDrive", "input_shaft.torque"), get("ChainDrive", "driven.speed")
            put("Motor", "shaft.torque", torque)
            put("Load", "speed", driven)
        if "Motor" in slaves:
            angle, speed = get("Motor", "rotor.angle"), get("Motor", "rotor.speed")
            put("ChainDrive", "input_shaft.angle", angle)
            put("ChainDrive", "input_shaft.speed", speed)
        if "Load" in slaves:
            put("ChainDrive", "load.torque", get("Load", "torque"))
        for s, _, _ in slaves.values():
            s.doStep(t, h)
        t += h
    for s, _, folder in slaves.values():
        s.terminate()
        s.freeInstance()
        shutil.rmtree(folder, ignore_errors=True)
    print("done")
""")


def system_script(fmus: dict, level: int = 0, steps: int = 10) -> str:
    return (f"FMUS = {({k: str(v) for k, v in fmus.items()})!r}\nLEVEL = {level}\n"
            f"STEPS = {steps}\n" + SYSTEM_LIFE)


@pytest.fixture(scope="module")
def example_fmus(tmp_path_factory) -> dict:
    """Motor.fmu and Load.fmu built by examples/system/build.py, as a user builds them."""
    out = tmp_path_factory.mktemp("system")
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / "system" / "build.py"),
                           "--out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return {"Motor": out / "Motor.fmu", "Load": out / "Load.fmu"}


def run_processes(script: str, cwd: Path, count: int) -> list:
    def one(_):
        proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                              cwd=cwd, timeout=300, env=dict(os.environ))
        return proc.returncode, proc.stdout.strip(), proc.stderr[-500:]

    with ThreadPoolExecutor(max_workers=2) as pool:
        return list(pool.map(one, range(count)))

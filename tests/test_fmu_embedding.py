"""The FMU inside someone else's process (docs/fmu.md, "Hosts"): builds isolated from each
other, bounded memory over many instantiations, a clean exit after what hosts ordinarily do.

Every scenario runs in a fresh Python process: what is checked is that process's behaviour
(exit status, its own counters), which an in-process test could not see."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

pytestmark = pytest.mark.fmu

ROOT = Path(__file__).resolve().parents[1]


def run_python(script: str, cwd: Path, timeout: float = 300, **env) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout, env=dict(os.environ, **env))


# --- two different builds in one process ------------------------------------------------------

PRETENSION_B = 100.0   # the second build's default of chain.pretension (the first's is 0)


@pytest.fixture(scope="module")
def second_build(tmp_path_factory) -> Path:
    """ChainDrive.fmu built from a copy of the sources whose chain.pretension default is
    PRETENSION_B: a different build with the same model identifier and class name."""
    src = tmp_path_factory.mktemp("src_b")
    shutil.copytree(ROOT / "chainmodel", src / "chainmodel",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "fmu_src", src / "fmu_src")
    shutil.copy2(ROOT / "build_fmu.py", src)
    (src / "docs").mkdir()
    params = src / "chainmodel" / "parameters.py"
    text = params.read_text()
    assert text.count('_p("chain.pretension", 0.0,') == 1
    params.write_text(text.replace('_p("chain.pretension", 0.0,',
                                   f'_p("chain.pretension", {PRETENSION_B},'))
    out = src / "dist" / "ChainDrive.fmu"
    # --warm none: the test runs both builds with CHAINMODEL_NUMBA=0, so compiling this copy's
    # kernels (another source path, so another cache entry: about 30 s) would buy nothing
    proc = subprocess.run([sys.executable, str(src / "build_fmu.py"), "--out", str(out), "-q",
                           "--warm", "none"], capture_output=True, text=True, cwd=src)
    assert proc.returncode == 0, proc.stderr
    return out


TWO_BUILDS = textwrap.dedent("""
    import json, sys
    from fmpy import read_model_description, extract
    from fmpy.fmi2 import FMU2Slave

    def start(path, name):
        md = read_model_description(path)
        vr = {v.name: v.valueReference for v in md.modelVariables}
        s = FMU2Slave(guid=md.guid, unzipDirectory=extract(path), modelIdentifier="ChainDrive",
                      instanceName=name)
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.setInteger([vr["fidelity"]], [0])
        s.exitInitializationMode()
        return s, vr

    def sample(s, vr):
        names = ["chain.pretension", "tight_span.tension", "slack_span.tension"]
        return dict(zip(names, s.getReal([vr[n] for n in names])))

    a, va = start(A, "a")
    b, vb = start(B, "b")
    t, h = 0.0, 1e-3
    for k in range(20):                     # interleaved: a, b, a, b, ...
        for s, vr in ((a, va), (b, vb)):
            s.setReal([vr["input_shaft.angle"], vr["input_shaft.speed"]], [0.0, 0.0])
            s.doStep(t, h)
        t += h
    a2, va2 = start(A, "a2")                # a new instance of the first build after the second
    res = {"a": sample(a, va), "b": sample(b, vb), "a2": sample(a2, va2)}
    mods = sorted(m for m in sys.modules if m.endswith("_adapter") and m.startswith("_chaindrive_"))
    res["adapters"] = mods
    for s in (a, b, a2):
        s.terminate(); s.freeInstance()
    print(json.dumps(res))
""")


def test_two_different_builds_run_side_by_side(chaindrive_fmu, second_build, tmp_path):
    from chainmodel import parameters as P
    from chainmodel.models import MODEL_CLASSES
    from chainmodel.scene import drive_from_parameters

    proc = run_python(f"A = {str(chaindrive_fmu)!r}\nB = {str(second_build)!r}\n" + TWO_BUILDS,
                      tmp_path, CHAINMODEL_NUMBA="0")
    assert proc.returncode == 0, proc.stderr[-3000:]
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert len(res["adapters"]) == 2                      # each build its own adapter module

    def level0(pretension):
        params = P.validate({"fidelity": 0, "chain.pretension": pretension})
        return MODEL_CLASSES[0](drive_from_parameters(params), params)

    def held(pretension):      # what level 0's spans carry at rest (wrap_statics.held_span_tension)
        return level0(pretension).held_tension()

    def static_tension(pretension):
        return level0(pretension).static_tension()

    def raw(t, b, ks):  # the floored, sagging law's raw tension (kernels.kinematic.split)
        return t - (b * b / t if b > 0 else 0.0) - ks / (t * t)

    for key, pretension in (("a", 0.0), ("b", PRETENSION_B), ("a2", 0.0)):
        out = res[key]
        assert out["chain.pretension"] == pretension      # its own schema's default
        # level 0's spans share their raw tensions' sum 2 T_h - 2 b^2 / T_h - (ks_u + ks_l) /
        # T_h^2 (no floor: b = 0; no sag: ks = 0), T_h the tension they hold at rest; the
        # load (43.2 N m) makes the upper span the tight one
        m0 = level0(pretension)
        b, (ks_u, ks_l), t_h = m0._floor, m0._sag_ks, held(pretension)
        assert raw(out["tight_span.tension"], b, ks_u) + raw(out["slack_span.tension"], b,
                                                             ks_l) == \
            pytest.approx(raw(t_h, b, ks_u) + raw(t_h, b, ks_l), rel=1e-12)
    assert static_tension(PRETENSION_B) > static_tension(0.0) + 50.0   # the builds do differ


# --- memory over many instantiations ----------------------------------------------------------

CYCLES = textwrap.dedent("""
    import gc, json, sys
    from fmpy import read_model_description, extract
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(FMU)
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(FMU), modelIdentifier="ChainDrive",
                  instanceName="cycles")

    def state():
        gc.collect()
        shim = next(m for m in sys.modules if m.startswith("chaindrive_"))
        return {"blocks": sys.getallocatedblocks(),
                "rss": int(open("/proc/self/statm").read().split()[1]) * 4096,
                "sys_path": len(sys.path),
                "classes": sum(1 for o in gc.get_objects()
                               if isinstance(o, type) and o.__name__ == "ChainDrive"),
                "namespace_refs": sys.getrefcount(sys.modules[shim].__dict__),
                "mro": len(sys.modules[shim].ChainDrive.__mro__)}

    marks = {}
    for k in range(N + 1):
        if k in (N // 2, N):
            marks[k] = state()
        if k < N:
            s.instantiate()
            s.fmi2FreeInstance(s.component)
    print(json.dumps(marks))
""")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/statm")
def test_memory_is_bounded_over_1000_instantiations(chaindrive_fmu, tmp_path):
    n = 1000
    proc = run_python(f"FMU = {str(chaindrive_fmu)!r}\nN = {n}\n" + CYCLES, tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    marks = json.loads(proc.stdout.strip().splitlines()[-1])
    half, end = marks[str(n // 2)], marks[str(n)]
    # what pythonfmu 0.7 leaked per fmi2Instantiate before: a class object and a sys.path entry
    assert end["classes"] == half["classes"] == 1
    assert end["sys_path"] == half["sys_path"]
    # findClass releases one reference of the entry module's namespace per call; balanced
    assert end["namespace_refs"] == half["namespace_refs"]
    # What is left is pythonfmu's own: per call findClass keeps a list (2 blocks: the object
    # and its items) and, for every class of the MRO, its repr (a str) and that repr's UTF-8
    # bytes. Allowance: a few objects fmpy itself keeps per call (ctypes callbacks). A leaked
    # adapter class would be hundreds of blocks per call.
    per_call = (end["blocks"] - half["blocks"]) / (n - n // 2)
    assert per_call <= 2 + 2 * half["mro"] + 4, per_call
    # and the process's memory over the second 500 instantiations: under 4 MiB (it grew by
    # 25-30 MB per 500 before). The blocks allowed above (about 11.5 per call, pythonfmu's
    # retained reprs) and the allocator's arenas come to 0.6-1.1 MiB, measured on this build
    # and on 3fac491's alike; the earlier 1 MiB bound failed one CI run in three at 1.05 MiB
    assert end["rss"] - half["rss"] < 4 * 2 ** 20


# --- a host's ordinary life, then exit ----------------------------------------------------------

HOST_LIFE = textwrap.dedent("""
    import shutil
    import fmpy
    from fmpy import read_model_description, extract
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi1 import FMICallException

    for k in range(2):          # fmpy's one-call API: extracts, runs, unloads, deletes the folder
        fmpy.simulate_fmu(FMU, start_values={"fidelity": 0}, stop_time=0.005,
                          output_interval=1e-3)
    md = read_model_description(FMU)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    kept = []
    for k in range(3):          # the low-level API, several instances alive at once
        folder = extract(FMU)
        s = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier="ChainDrive",
                      instanceName=f"i{k}")
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.setInteger([vr["fidelity"]], [0])
        s.exitInitializationMode()
        t = 0.0
        for i in range(3):
            s.setReal([vr["input_shaft.speed"]], [10.0])
            s.doStep(t, 1e-3)
            t += 1e-3
        state = s.getFMUstate()
        s.doStep(t, 1e-3)
        s.setFMUstate(state)
        s.freeFMUstate(state)
        if k == 1:              # a fatal error (a state that is not one), then free
            try:
                s.setFMUstate(s.deSerializeFMUstate(b"not a state"))
            except FMICallException:
                pass
        if k == 2:
            kept.append(s)      # left for the process exit
        else:
            s.terminate()
            s.freeInstance()
            shutil.rmtree(folder, ignore_errors=True)
    print("done")
""")


def test_host_life_then_exit_20_processes(chaindrive_fmu, tmp_path):
    """Before the fix about 1 such process in 25 aborted at exit ("corrupted double-linked
    list"); the cause is certain (valgrind: benchmarks/host_exit.py --valgrind), its symptom
    depends on the heap's state at exit, hence many processes."""
    script = f"FMU = {str(chaindrive_fmu)!r}\n" + HOST_LIFE

    def one(_):
        proc = run_python(script, tmp_path)
        return proc.returncode, proc.stdout.strip(), proc.stderr[-500:]

    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(one, range(20)))
    # fmpy's default logger prints the warnings and errors the FMU logs (with loggingOn false
    # too) before the script's last line
    failed = [r for r in results if r[0] != 0 or r[1].splitlines()[-1:] != ["done"]]
    assert not failed, f"{len(failed)} of 20 processes failed: {failed[:3]}"


# --- statuses pythonfmu lets us return ----------------------------------------------------------

def test_refused_sets_return_ok_and_log_an_error_naming_the_variable(chaindrive_fmu_dir):
    """FMI 2.0 prescribes fmi2Error for setting a fixed parameter after initialization or an
    output; pythonfmu 0.7 lets a setter return only fmi2OK or fmi2Fatal (docs/fmu.md,
    "Statuses"), so the value is ignored and an ERROR-status message names the variable."""
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    from chainmodel.fmu_log import FMULog
    md = read_model_description(str(chaindrive_fmu_dir))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    log = FMULog()
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(chaindrive_fmu_dir),
                  modelIdentifier="ChainDrive", instanceName="statuses")
    s.instantiate(callbacks=log.callbacks, loggingOn=True)
    try:
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.setInteger([vr["fidelity"]], [0])
        s.exitInitializationMode()
        before = s.getReal([vr["drive.pitch"], vr["driven.speed"]])
        s.setReal([vr["drive.pitch"]], [0.02])          # fixed parameter: no exception = OK
        s.setReal([vr["driven.speed"]], [123.0])        # an output
        after = s.getReal([vr["drive.pitch"], vr["driven.speed"]])
        assert after == before
        errors = [m for status, m in log.messages if status == 3]   # fmi2Error
        assert any("drive.pitch" in m and "fixed after initialization" in m for m in errors)
        assert any("driven.speed" in m and "output" in m for m in errors)
    finally:
        s.freeInstance()


DROPPED_LOGGER = textwrap.dedent("""
    import gc
    from fmpy import read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave
    from chainmodel.fmu_log import FMULog

    log = FMULog()                 # gives fmpy's logger proxy a logger ...
    del log                      # ... and drops it
    gc.collect()
    md = read_model_description(FOLDER)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=FOLDER, modelIdentifier="ChainDrive",
                  instanceName="default_callbacks")
    s.instantiate()              # fmpy's default callbacks: the proxy's one logger, loggingOn off
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.setInteger([vr["fidelity"]], [7])
    try:
        s.exitInitializationMode()  # refused: the errors are logged without loggingOn
    except FMICallException:
        pass
    s.freeInstance()
    print("survived")
""")


def test_a_dropped_chainmodel_logger_leaves_fmpys_proxy_a_live_one(chaindrive_fmu_dir, tmp_path):
    """fmpy 0.3's logger proxy keeps one C pointer per process, to the logger last given to it.
    A chainmodel logger that was collected left it pointing at freed memory, and the next
    message of any instance (here an error of one on fmpy's default callbacks) crashed the
    process: SIGSEGV in the combined FMU tests once errors reached hosts without loggingOn.
    Every chainmodel logger hands the proxy the same immortal dispatcher."""
    script = f"FOLDER = {str(chaindrive_fmu_dir)!r}\n" + DROPPED_LOGGER
    proc = run_python(script, tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.strip().splitlines()
    assert lines[-1] == "survived"
    # the message went where fmpy's default callbacks send it: printed
    assert any(line.startswith("[ERROR]") and "fidelity" in line for line in lines)


def test_an_incomplete_resources_folder_is_reported_not_crashed(tmp_path, capfd):
    """A host that passes a resources folder without the vendored package gets a sentence
    (naming the folder and the C/C++ recipe) as an ImportError and on stderr."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("_test_adapter_resources",
                                                  ROOT / "fmu_src" / "ChainDrive.py")
    adapter = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(adapter)
    with pytest.raises(ImportError, match="copy of the chainmodel package is missing"):
        adapter.ChainDrive(instance_name="x", resources=str(tmp_path))
    assert "PYTHONHOME" in capfd.readouterr().err


def test_log_messages_carry_no_percent_sign():
    """FMI messages are printf formats; libcosim prints them unformatted, so an escaped '%%'
    showed as "5 %%" (issue 18): the embedding writes the word instead."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("_test_embedding_text",
                                                  ROOT / "fmu_src" / "embedding.py")
    embedding = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(embedding)
    text = embedding.fmi_text("keeps this tension within 5 % of the pitch; 3% more")
    assert text == "keeps this tension within 5 percent of the pitch; 3 percent more"
    assert "%" not in embedding.fmi_text("%%d %s 100%")


def test_an_exception_leaving_an_entry_point_carries_no_percent_sign():
    """pythonfmu's handle_py_exception puts the exception's repr into the message it passes to
    the FMI logger as the format (PythonFMU's PySlaveInstance.cpp; 0.7 as installed says
    "unknown error" instead, a later one the text): the guard round every entry point writes
    the word there too, and keeps the exception's type."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("_test_embedding_guard",
                                                  ROOT / "fmu_src" / "embedding.py")
    embedding = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(embedding)
    logged = []

    class Instance:
        log_queue = []

        def log(self, message, status):
            logged.append(message)

        def exit_initialization_mode(self):
            raise ValueError("would pre-strain the chain by 5 % or more", 7)

    guarded = embedding._guard(Instance.exit_initialization_mode)
    with pytest.raises(ValueError) as err:
        guarded(Instance())
    assert "%" not in repr(err.value) and "5 percent or more" in repr(err.value)
    assert err.value.args[1] == 7
    assert logged and all("%" not in m for m in logged)

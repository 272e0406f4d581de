"""A C host with nothing configured (issue 18 item 1): the FMU's binary is a launcher
(fmu_src/launcher/launcher.c) that starts the Python recorded at build time when the process has
none. A minimal FMI 2.0 co-simulation master written here in C, compiled here with cc, runs the
FMU under ``env -i`` (no PYTHONPATH, PYTHONHOME, PYTHONMALLOC, LD_LIBRARY_PATH, LD_PRELOAD) and
must give fmpy's outputs bit for bit, exit cleanly, and say what it looked for when there is no
Python to start."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from chainmodel.fmu_hosts import grid, run_fmu
from chainmodel.models import ALL_OUTPUTS

pytestmark = [pytest.mark.fmu, pytest.mark.skipif(
    not sys.platform.startswith("linux"),
    reason="the launcher and these C hosts are Linux-only: the C-host tests did NOT run")]

ROOT = Path(__file__).resolve().parents[1]
FMI2_HEADERS = ROOT / "fmu_src" / "launcher" / "fmi2"
CC = next((c for c in (os.environ.get("CC"), "cc", "gcc") if c and shutil.which(c)), None)

#: the call sequence of chainmodel.fmu_hosts (libcosim's), so that fmpy's run through run_fmu
#: sees exactly the same calls with the same values
MASTER_C = r"""
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2String category_unused,
                   ...);

static void log_message(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                        fmi2String category, fmi2String message, ...)
{
    va_list ap;
    (void)env;
    va_start(ap, message);
    fprintf(stderr, "FMI LOG %s status %d %s: ", name ? name : "?", (int)status,
            category ? category : "");
    vfprintf(stderr, message, ap);
    fputc('\n', stderr);
    va_end(ap);
}

#define GET(name) name##TYPE *name = (name##TYPE *)dlsym(lib, #name); \
    if (!name) { fprintf(stderr, "missing %s\n", #name); return 4; }
#define CHECK(call) if ((call) > fmi2Warning) { fprintf(stderr, "failed: %s\n", #call); return 5; }

static double at(long k, long long step_ns) { return (double)(k * step_ns) / 1e9; }

int main(int argc, char **argv)
{
    /* binary resource_uri guid fidelity_vr level steps step_ns angle_vr speed_vr load_vr
       speed load out_vr... */
    if (argc < 14) { fprintf(stderr, "usage: see test_c_host.py\n"); return 2; }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 3; }
    GET(fmi2Instantiate) GET(fmi2SetupExperiment) GET(fmi2EnterInitializationMode)
    GET(fmi2ExitInitializationMode) GET(fmi2SetReal) GET(fmi2SetInteger) GET(fmi2GetReal)
    GET(fmi2DoStep) GET(fmi2Terminate) GET(fmi2FreeInstance)
    fmi2CallbackFunctions cb = {log_message, calloc, free, NULL, NULL};
    fmi2ValueReference fidelity = (fmi2ValueReference)atol(argv[4]);
    fmi2Integer level = atoi(argv[5]);
    long steps = atol(argv[6]);
    long long step_ns = atoll(argv[7]);
    fmi2ValueReference in_vr[3];
    for (int j = 0; j < 3; j++) in_vr[j] = (fmi2ValueReference)atol(argv[8 + j]);
    double speed = atof(argv[11]), load = atof(argv[12]);
    int n_out = argc - 13;
    fmi2ValueReference *out_vr = calloc((size_t)n_out, sizeof *out_vr);
    double *out = calloc((size_t)n_out, sizeof *out);
    for (int j = 0; j < n_out; j++) out_vr[j] = (fmi2ValueReference)atol(argv[13 + j]);

    fmi2Component c = fmi2Instantiate("c_master", fmi2CoSimulation, argv[3], argv[2], &cb,
                                      fmi2False, fmi2False);
    if (!c) { fprintf(stderr, "fmi2Instantiate returned NULL\n"); return 6; }
    double in[3];
#define SET_INPUTS(k) in[0] = speed * at(k, step_ns); in[1] = speed; in[2] = load; \
    CHECK(fmi2SetReal(c, in_vr, 3, in))
    CHECK(fmi2SetInteger(c, &fidelity, 1, &level));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2GetReal(c, out_vr, (size_t)n_out, out));
    CHECK(fmi2SetInteger(c, &fidelity, 1, &level));
    SET_INPUTS(0);
    CHECK(fmi2GetReal(c, out_vr, (size_t)n_out, out));
    CHECK(fmi2ExitInitializationMode(c));
    for (long k = 0; k <= steps; k++) {
        if (k > 0) {
            SET_INPUTS(k - 1);
            CHECK(fmi2DoStep(c, at(k - 1, step_ns), at(k, step_ns) - at(k - 1, step_ns),
                             fmi2True));
        }
        CHECK(fmi2GetReal(c, out_vr, (size_t)n_out, out));
        printf("%.17g", at(k, step_ns));
        for (int j = 0; j < n_out; j++) printf(" %.17g", out[j]);
        printf("\n");
    }
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    dlclose(lib);
    return 0;
}
""".replace("static void logger(fmi2ComponentEnvironment env, fmi2String name, "
            "fmi2String category_unused,\n                   ...);\n", "")

SPEED, LOAD = 12.0, 20.0


@pytest.fixture(scope="module")
def master(tmp_path_factory) -> Path:
    if CC is None:
        pytest.skip("no C compiler (cc, gcc, $CC): the C-host tests did NOT run")
    folder = tmp_path_factory.mktemp("c_master")
    (folder / "master.c").write_text(MASTER_C)
    exe = folder / "master"
    proc = subprocess.run([CC, "-O2", "-Wall", "-Werror", "-I", str(FMI2_HEADERS), "-o",
                           str(exe), str(folder / "master.c"), "-ldl"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return exe


@pytest.fixture(scope="module")
def fmu_vars(chaindrive_fmu):
    from fmpy import read_model_description
    md = read_model_description(str(chaindrive_fmu))
    return md.guid, {v.name: v.valueReference for v in md.modelVariables}


def run_master(master, fmu_dir, fmu_vars, level, steps, step_ns=100_000, env=None,
               outputs=None):
    """Run the C master under a bare environment (``env`` only: what ``env -i`` gives), plus
    the test session's kernel cache folder (CHAINMODEL_CACHE_DIR, tests/conftest.py): without it
    the FMU's Python would compile into the user's ~/.cache, which the suite must leave as it
    found it. No variable that helps a host find or start Python is passed.

    The test session's OpenBLAS kernel choice (``OPENBLAS_*``, e.g. OPENBLAS_CORETYPE) is
    passed too: it selects the BLAS kernels the set-up's linear algebra runs on, whose rounding
    differs (an AMD EPYC with OPENBLAS_CORETYPE=Haswell in the environment against its own
    auto-detected kernels: level 3's statics, and so the wrap fit and the held tension of levels
    0-2, differ in the 10th digit and the outputs after 40 steps by 1e-8 relative). Without it
    the comparison with fmpy in this process measures the two BLAS kernels, not the host."""
    guid, vr = fmu_vars
    cache = os.environ.get("CHAINMODEL_CACHE_DIR")
    blas = {k: v for k, v in os.environ.items() if k.startswith("OPENBLAS_")}
    env = dict(blas, **({"CHAINMODEL_CACHE_DIR": cache} if cache else {}), **(env or {}))
    outputs = outputs or [o.name for o in ALL_OUTPUTS]
    args = [str(master), str(fmu_dir / "binaries" / "linux64" / "ChainDrive.so"),
            (fmu_dir / "resources").as_uri(), guid, str(vr["fidelity"]), str(level),
            str(steps), str(step_ns), str(vr["input_shaft.angle"]), str(vr["input_shaft.speed"]),
            str(vr["load.torque"]), repr(SPEED), repr(LOAD)] + [str(vr[n]) for n in outputs]
    return subprocess.run(["env", "-i"] + [f"{k}={v}" for k, v in (env or {}).items()] + args,
                          capture_output=True, text=True, timeout=600)


def pythonfmus_binary() -> bytes:
    """The Linux binary of the installed pythonfmu (not of a copy an FMU put on sys.path)."""
    from importlib.metadata import distribution
    return Path(distribution("pythonfmu").locate_file(
        "pythonfmu/resources/binaries/linux64/libpythonfmu-export.so")).read_bytes()


def test_the_fmu_ships_the_launcher_in_front_of_pythonfmus_binary(chaindrive_fmu):
    original = pythonfmus_binary()
    with zipfile.ZipFile(chaindrive_fmu) as z:
        assert z.read("binaries/linux64/ChainDrive.pythonfmu.so") == original
        launcher = z.read("binaries/linux64/ChainDrive.so")
    assert launcher != original and len(launcher) < len(original) / 4


@pytest.mark.parametrize("level", [0, 1, 2, 3])
def test_c_host_under_env_i_gives_fmpys_outputs(master, chaindrive_fmu, chaindrive_fmu_dir,
                                                fmu_vars, level):
    stop, step = 0.004, 1e-4
    times, step_ns = grid(stop, step)
    proc = run_master(master, chaindrive_fmu_dir, fmu_vars, level, len(times) - 1, step_ns)
    assert proc.returncode == 0, proc.stderr[-3000:]
    c_host = np.array([[float(x) for x in line.split()] for line in proc.stdout.splitlines()])
    ref = run_fmu(chaindrive_fmu, "fmpy", stop_time=stop, step_size=step,
                  start_values={"fidelity": level},
                  inputs={"input_shaft.angle": lambda t: SPEED * t, "input_shaft.speed": SPEED,
                          "load.torque": LOAD})
    np.testing.assert_array_equal(c_host[:, 0], ref.time)
    names = [o.name for o in ALL_OUTPUTS]
    differing = [n for j, n in enumerate(names)
                 if not np.array_equal(c_host[:, j + 1], ref.outputs[n])]
    assert not differing, differing
    assert np.all(np.diff(c_host[:, 1 + names.index("driver.angle")]) > 0)   # it turned


def test_c_host_without_logging_hears_why_initialization_failed(master, chaindrive_fmu_dir,
                                                               fmu_vars):
    """The master instantiates with loggingOn = false (as many C tools do). A refused
    initialization returns fmi2Error, and the reason reaches its logger: pythonfmu 0.7 alone
    logs nothing then, the launcher passes warnings and errors on whatever loggingOn says."""
    proc = run_master(master, chaindrive_fmu_dir, fmu_vars, 7, 1)
    assert proc.returncode == 5, proc.stderr[-3000:]          # CHECK failed on a status > warning
    assert "failed: fmi2ExitInitializationMode" in proc.stderr
    errors = [line for line in proc.stderr.splitlines()
              if line.startswith("FMI LOG c_master status 3 ")]
    assert any("fidelity" in line and "got 7" in line for line in errors), proc.stderr[-3000:]
    assert any("raised an exception in [exitInitializationMode]" in line for line in errors)
    assert not any(line.startswith("FMI LOG c_master status 0 ")
                   for line in proc.stderr.splitlines())


def test_c_host_exits_cleanly_20_of_20(master, chaindrive_fmu_dir, fmu_vars):
    """20 processes, each 0.01 s at level 0 then fmi2Terminate, fmi2FreeInstance, dlclose,
    return from main: exit code 0, complete output, no heap-corruption message, no signal."""
    def one(_):
        proc = run_master(master, chaindrive_fmu_dir, fmu_vars, 0, 100, outputs=["driver.angle"])
        return proc.returncode, len(proc.stdout.splitlines()), proc.stderr[-400:]

    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(one, range(20)))
    failed = [r for r in results if r[0] != 0 or r[1] != 101 or "corrupted" in r[2]]
    assert not failed, f"{len(failed)} of 20 runs failed: {failed[:3]}"


@pytest.mark.parametrize("given", ["/nonexistent/bin/python3",
                                   "/nonexistent/lib/libpython3.11.so.1.0"])
def test_no_python_is_reported_through_fmi_and_stderr(master, chaindrive_fmu_dir, fmu_vars,
                                                      given):
    proc = run_master(master, chaindrive_fmu_dir, fmu_vars, 0, 1,
                      env={"CHAINDRIVE_PYTHON": given})
    assert proc.returncode == 6, proc.stderr        # fmi2Instantiate returned NULL
    logged = [ln for ln in proc.stderr.splitlines() if ln.startswith("FMI LOG c_master")]
    printed = [ln for ln in proc.stderr.splitlines() if ln.startswith("ChainDrive FMU:")]
    assert len(logged) == 1 and len(printed) == 1, proc.stderr
    assert "status 3" in logged[0]                  # fmi2Error
    for line in logged[0], printed[0]:
        assert "no Python to run in" in line and given in line and "CHAINDRIVE_PYTHON" in line


def test_override_starts_a_venv_whose_pth_files_run(master, chaindrive_fmu_dir, fmu_vars,
                                                    tmp_path):
    """CHAINDRIVE_PYTHON = a venv's python: the embedded interpreter starts as that python
    would (sys.prefix the venv, site runs its .pth files): a .pth file there announces the
    prefix and adds this test's site-packages (numpy, scipy) by a path line."""
    import site
    import sysconfig
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    purelib = Path(sysconfig.get_path("purelib", vars={"base": str(venv)}))
    assert purelib.is_dir()
    (purelib / "zz_announce.pth").write_text(
        "import sys; sys.stderr.write('PTH RAN, prefix ' + sys.prefix + '\\n')\n"
        + "\n".join(site.getsitepackages()) + "\n")
    proc = run_master(master, chaindrive_fmu_dir, fmu_vars, 0, 2,
                      env={"CHAINDRIVE_PYTHON": venv / "bin" / "python"})
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert f"PTH RAN, prefix {venv}" in proc.stderr.splitlines()
    assert len(proc.stdout.splitlines()) == 3


def old_recipe() -> dict:
    """docs/fmu.md's environment for an FMU without the launcher (LD_PRELOAD, PYTHONHOME,
    PYTHONPATH, PYTHONMALLOC)."""
    import sysconfig
    libpython = Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("INSTSONAME")
    return {"LD_PRELOAD": libpython, "PYTHONHOME": sys.base_prefix,
            "PYTHONPATH": sysconfig.get_paths()["purelib"], "PYTHONMALLOC": "malloc"}


@pytest.mark.parametrize("variant", ["libpython preloaded, not initialized", "the old recipe"])
def test_a_host_with_libpython_but_no_interpreter_yet(master, chaindrive_fmu_dir, fmu_vars,
                                                      variant):
    """Py_IsInitialized present but false (a host that loads libpython, or a user still setting
    the old recipe's variables): the launcher starts that Python; same outputs as under env -i."""
    env = old_recipe()
    if variant.startswith("libpython"):
        env = {"LD_PRELOAD": env["LD_PRELOAD"]}
    assert Path(env["LD_PRELOAD"]).is_file()
    bare = run_master(master, chaindrive_fmu_dir, fmu_vars, 0, 5)
    proc = run_master(master, chaindrive_fmu_dir, fmu_vars, 0, 5, env=env)
    assert bare.returncode == 0 and proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout == bare.stdout and len(proc.stdout.splitlines()) == 6


def test_a_python_host_runs_the_fmu_in_its_own_interpreter(chaindrive_fmu_dir, fmu_vars):
    """In fmpy the launcher starts nothing: the FMU's modules appear in this interpreter."""
    from fmpy.fmi2 import FMU2Slave
    guid, _ = fmu_vars
    build = (chaindrive_fmu_dir / "resources" / "_vendor" / "build.json").read_text()
    import json
    adapter = f"_chaindrive_{json.loads(build)['id']}_adapter"
    s = FMU2Slave(guid=guid, unzipDirectory=str(chaindrive_fmu_dir),
                  modelIdentifier="ChainDrive", instanceName="python_host")
    s.instantiate()
    try:
        assert adapter in sys.modules
    finally:
        s.freeInstance()


# --- building the launcher ---------------------------------------------------------------------

def test_without_a_c_compiler_the_build_says_so_and_ships_pythonfmus_binary(tmp_path):
    out = tmp_path / "ChainDrive.fmu"
    env = {k: v for k, v in os.environ.items() if k != "CC"}
    env["PATH"] = str(tmp_path / "no-compilers-here")
    proc = subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--out", str(out), "-q",
                           "--warm", "none"], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert "no C compiler found" in proc.stderr and "pythonfmu's binary" in proc.stderr
    original = pythonfmus_binary()
    with zipfile.ZipFile(out) as z:
        assert z.read("binaries/linux64/ChainDrive.so") == original
        assert "binaries/linux64/ChainDrive.pythonfmu.so" not in z.namelist()


def test_launch_refuses_what_it_cannot_launch(tmp_path, chaindrive_fmu):
    def launch(fmu):
        return subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--launch", str(fmu),
                               "--out", str(tmp_path / "out.fmu")], capture_output=True,
                              text=True)

    proc = launch(chaindrive_fmu)          # already launched
    assert proc.returncode == 2 and "already has a launcher (ChainDrive.pythonfmu.so)" in proc.stderr
    other = tmp_path / "NotPython.fmu"
    with zipfile.ZipFile(chaindrive_fmu) as src, zipfile.ZipFile(other, "w") as dst:
        for name in src.namelist():
            if name.startswith("resources/") or name.endswith(".pythonfmu.so"):
                continue
            dst.writestr(name, src.read(name))
    proc = launch(other)
    assert proc.returncode == 2 and "not a pythonfmu FMU" in proc.stderr
    proc = launch(tmp_path / "missing.fmu")
    assert proc.returncode == 2 and "missing.fmu" in proc.stderr
    assert not (tmp_path / "out.fmu").exists()


def test_c_host_runs_torque_causality_as_fmpy_does(master, tmp_path):
    """An FMU built with torque causality as its default (``build_fmu.py --default
    input_shaft.causality=torque``; the master sets no String) run by the C master under env -i
    at level 1, the master's first input wired to motor.torque instead of input_shaft.angle: the
    outputs, motor.angle and motor.speed among them, equal fmpy's on the same calls bit for
    bit, and the rotor turns under the torque."""
    from fmpy import extract, read_model_description
    fmu = tmp_path / "Torque.fmu"
    proc = subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--out", str(fmu), "-q",
                           "--default", "input_shaft.causality=torque", "--warm", "none"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-3000:]
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    wired = dict(vr, **{"input_shaft.angle": vr["motor.torque"]})
    stop, step = 0.004, 1e-4
    times, step_ns = grid(stop, step)
    names = [o.name for o in ALL_OUTPUTS] + ["motor.angle", "motor.speed"]
    proc = run_master(master, Path(extract(str(fmu), str(tmp_path / "x"))), (md.guid, wired), 1,
                      len(times) - 1, step_ns, outputs=names)
    assert proc.returncode == 0, proc.stderr[-3000:]
    c_host = np.array([[float(x) for x in line.split()] for line in proc.stdout.splitlines()])
    # the master's inputs: first = SPEED * t (here motor.torque, N.m), then SPEED, LOAD
    ref = run_fmu(fmu, "fmpy", stop_time=stop, step_size=step, start_values={"fidelity": 1},
                  inputs={"motor.torque": lambda t: SPEED * t, "input_shaft.speed": SPEED,
                          "load.torque": LOAD}, outputs=names)
    np.testing.assert_array_equal(c_host[:, 0], ref.time)
    differing = [n for j, n in enumerate(names)
                 if not np.array_equal(c_host[:, j + 1], ref.outputs[n])]
    assert not differing, differing
    motor_speed = c_host[:, 1 + names.index("motor.speed")]
    # torque causality, not angle causality (where motor.speed would be the speed input, 12)
    assert np.all(motor_speed[1:] != SPEED) and np.all(np.isfinite(c_host))

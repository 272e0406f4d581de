"""Regression tests of the exported FMU in the FMI Cross-Check layout (issue 13):
``chainmodel fmu-test`` and the committed reference sets in ``references/``."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from chainmodel import parameters as P
from chainmodel.analysis import fmu_test as F
from chainmodel.cli import main

ROOT = Path(__file__).resolve().parents[1]
REFS = ROOT / "references"


def _lines(out: str) -> list[str]:
    return [ln for ln in out.splitlines() if ln.startswith(("pass ", "FAIL "))]


def _subset(tmp_path: Path, names) -> Path:
    root = tmp_path / "refs"
    for name in names:
        shutil.copytree(REFS / name, root / name)
    return root


def test_reference_layout_covers_every_level_and_scenario():
    refs = F.read_references(REFS)
    names = {r.name for r in refs}
    for level in range(4):
        for scenario in ("startup", "speed_step", "load_step", "reversal"):
            assert f"L{level}_{scenario}" in names
    for r in refs:
        assert set(r.outputs) == set(F.OUTPUT_NAMES)
        assert r.opts["RelTol"] == F.ACCURACY[int(r.name[1])]
        assert (r.path / "README.md").read_text().count("Meaningful outputs") == 1
        # the in.csv angle is the integral of the in.csv speed (trapezoids of a piecewise
        # linear speed are exact): the inputs a host holds are consistent
        t, w, a = r.time, r.inputs["input_shaft.speed"], r.inputs["input_shaft.angle"]
        integral = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
        assert np.allclose(a, integral, rtol=0, atol=1e-9 * max(1.0, np.max(np.abs(a))))


def test_level0_references_keep_the_exact_tooth_ratio():
    """Physics, independent of the code under test: the mean velocity ratio of a chain drive
    is the tooth ratio 25/17 (seed 000), and the polygonal action only makes the driven angle
    oscillate about driver angle x 25/17 by a small part of a tooth angle, so after 0.2 s the
    two increments agree to within 5 % of the driven tooth angle."""
    r = F.read_reference(REFS / "L0_startup")
    d1 = r.outputs["driver.angle"][-1] - r.outputs["driver.angle"][0]
    d2 = r.outputs["driven.angle"][-1] - r.outputs["driven.angle"][0]
    tooth_angle = 2 * np.pi / 17
    assert d1 > 2.0          # 0.35 rev of the driver: the ramp and 0.15 s at 120 rpm
    assert abs(d2 - d1 * 25 / 17) < 0.05 * tooth_angle


def test_committed_references_are_what_the_library_gives_now(tmp_path):
    """The committed files are not stale: regenerated from the library they fall inside their
    own tubes (the references must follow the library's final numerics)."""
    fresh = F.make_references(tmp_path)
    for folder in fresh:
        new = F.read_reference(folder)
        old = F.read_reference(REFS / folder.name)
        for name in old.outputs:
            assert F.tube(old, name, new.time, new.outputs[name]).passed, (folder.name, name)


@pytest.mark.parametrize("host", ["fmpy", "libcosim"])
def test_fresh_fmu_passes_every_reference(chaindrive_fmu, host, capsys):
    """The FMU built now passes every shipped reference (taken from its own documentation/)."""
    with zipfile.ZipFile(chaindrive_fmu) as z:
        shipped = {Path(m).parent.name for m in z.namelist()
                   if m.startswith("documentation/fmu_references/") and m.endswith("ref.opt")}
    assert shipped == {p.name for p in REFS.iterdir() if p.is_dir()}
    assert main(["fmu-test", str(chaindrive_fmu), "--host", host]) == 0
    lines = _lines(capsys.readouterr().out)
    assert len(lines) == 16 * len(F.OUTPUT_NAMES)
    assert all(ln.startswith("pass ") for ln in lines)


def test_pure_numpy_twin_passes(chaindrive_fmu, tmp_path):
    """A host without numba (CHAINMODEL_NUMBA=0: the FMU runs the pure-numpy twins, other
    operations in another order) computes differently in the last bits and must still pass:
    the tube is about what a build may legitimately change, not about today's exact values."""
    import os
    refs = _subset(tmp_path, ["L1_load_step", "L2_speed_step"])
    proc = subprocess.run([sys.executable, "-m", "chainmodel", "fmu-test", str(chaindrive_fmu),
                           "--references", str(refs)], capture_output=True, text=True,
                          env=dict(os.environ, CHAINMODEL_NUMBA="0"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert len(_lines(proc.stdout)) == 2 * len(F.OUTPUT_NAMES)


def test_perturbed_link_stiffness_fails_naming_the_outputs(tmp_path):
    """A build whose chain.link_stiffness default is 2 % higher fails: the tensions at every
    level (the quasi-static tension of level 0 and the span dynamics of level 1 follow the
    link stiffness), while the driver angle - imposed by the input shaft, its elastic wind-up
    a few mrad against a range of radians - stays inside its tube. Built with no kernels
    warmed and run on the pure-numpy twins (CHAINMODEL_NUMBA=0, which pass the same tubes:
    test_pure_numpy_twin_passes), so a second build does not compile every kernel again
    (about 20 s of the suite)."""
    import os
    k = P.BY_NAME["chain.link_stiffness"].default * 1.02
    fmu = tmp_path / "Perturbed.fmu"
    proc = subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--out", str(fmu), "-q",
                           "--default", f"chain.link_stiffness={k!r}", "--warm", "none"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    with zipfile.ZipFile(fmu) as z:
        xml = z.read("modelDescription.xml").decode()
    assert f'start="{k!r}"' in xml or f'start="{k:.0f}"' in xml
    refs = _subset(tmp_path, ["L0_load_step", "L1_load_step"])
    proc = subprocess.run([sys.executable, "-m", "chainmodel", "fmu-test", str(fmu),
                           "--references", str(refs)], capture_output=True, text=True,
                          env=dict(os.environ, CHAINMODEL_NUMBA="0"), cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    out = proc.stdout
    failed = {tuple(ln.split()[1:3]) for ln in _lines(out) if ln.startswith("FAIL")}
    passed = {tuple(ln.split()[1:3]) for ln in _lines(out) if ln.startswith("pass")}
    for level in (0, 1):
        assert (f"L{level}_load_step", "tight_span.tension") in failed
        assert (f"L{level}_load_step", "driver.angle") in passed
    summary = out.strip().splitlines()[-1]
    assert "outputs that moved:" in summary and "tight_span.tension" in summary
    assert "driver.angle" not in summary


def test_build_refuses_an_unknown_default(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--out",
                           str(tmp_path / "x.fmu"), "-q", "--default", "chain.nope=3"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    assert "chain.nope" in proc.stderr and not (tmp_path / "x.fmu").exists()


def test_record_then_check_passes(chaindrive_fmu, tmp_path, capsys):
    refs = _subset(tmp_path, ["L0_reversal", "L1_speed_step"])
    rec = tmp_path / "recorded"
    assert main(["fmu-test", str(chaindrive_fmu), "--references", str(refs),
                 "--record", str(rec)]) == 0
    assert sorted(p.name for p in rec.iterdir()) == ["L0_reversal", "L1_speed_step"]
    assert main(["fmu-test", str(chaindrive_fmu), "--references", str(rec)]) == 0
    # a user's own scene, recorded and then checked the same way
    scene = tmp_path / "mine.toml"
    scene.write_text('name = "mine"\npreset = "xu2010"\nfidelity = 1\nduration = 0.05\n'
                     'output_interval = 1e-3\n[operating]\ninput_speed_rpm = 90\n'
                     'ramp_time = 0.02\nload_torque = 30\n[parameters]\n'
                     '"chain.link_damping" = 80\n')
    mine = tmp_path / "mine_refs"
    assert main(["fmu-test", str(chaindrive_fmu), "--record", str(mine),
                 "--scene", str(scene)]) == 0
    r = F.read_reference(mine / "mine")
    assert r.start_values == {"chain.link_damping": 80.0}
    assert r.opts["StepSize"] == pytest.approx(1e-3) and r.opts["StopTime"] == pytest.approx(0.05)
    capsys.readouterr()
    assert main(["fmu-test", str(chaindrive_fmu), "--references", str(mine)]) == 0
    assert all(ln.startswith("pass") for ln in _lines(capsys.readouterr().out))


def test_malformed_reference_folders_are_refused(chaindrive_fmu, tmp_path, capsys):
    refs = _subset(tmp_path, ["L0_startup"])
    folder = refs / "L0_startup"
    (folder / "ref.opt").unlink()
    assert main(["fmu-test", str(chaindrive_fmu), "--references", str(refs)]) == 2
    err = capsys.readouterr().err
    assert str(folder / "ref.opt") in err and "missing" in err

    shutil.copy2(REFS / "L0_startup" / "ref.opt", folder / "ref.opt")
    lines = (folder / "ref.csv").read_text().splitlines()
    lines = [lines[0] + ',"not_an_output"'] + [ln + ",0.0" for ln in lines[1:]]
    (folder / "ref.csv").write_text("\n".join(lines) + "\n")
    assert main(["fmu-test", str(chaindrive_fmu), "--references", str(refs)]) == 2
    err = capsys.readouterr().err
    assert str(folder / "ref.csv") in err and "not_an_output" in err


def test_usage_errors_exit_2(tmp_path, capsys):
    assert main(["fmu-test", str(tmp_path / "none.fmu")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["fmu-test", "x.fmu", "--host", "ecos"]) == 2

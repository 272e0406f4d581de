"""Issue 19 item 3: the command-line examples of docs/cli.md and the README are what the
commands print today (docs/scripts/cli_examples.py rewrites them; this test fails when one is
stale), and docs/cli.md lists every subcommand."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

import chainmodel
from chainmodel import cli

ROOT = Path(__file__).resolve().parent.parent
CLI_MD = ROOT / "docs" / "cli.md"
README = ROOT / "README.md"


def _examples():
    spec = importlib.util.spec_from_file_location("cli_examples",
                                                  ROOT / "docs" / "scripts" / "cli_examples.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


examples = _examples()


def check(path: Path, fmu=None) -> int:
    found = examples.blocks(path.read_text())
    for block in found:
        if "fmu" in block["options"] and fmu is None:
            continue
        now = examples.render_block(block, fmu)
        assert examples.same(examples.mask(now), examples.mask(block["body"])), (
            f"{path.name}: the example of `$ {block['commands'][0]}` is stale; regenerate it "
            f"with python docs/scripts/cli_examples.py\n--- now:\n{now}")
    return len(found)


def test_cli_md_examples_are_the_real_output():
    assert check(CLI_MD) >= 8


def test_readme_examples_are_the_real_output():
    assert check(README) >= 2            # the wrap example here, the FMU one below


@pytest.mark.fmu
def test_readme_first_command_through_the_fmu(chaindrive_fmu):
    """The README's first command, run as after its quick start (dist/ChainDrive.fmu)."""
    blocks = [b for b in examples.blocks(README.read_text()) if "fmu" in b["options"]]
    assert blocks and blocks[0]["commands"][0].startswith("chainmodel run xu2010 --via-fmu")
    for block in blocks:
        now = examples.render_block(block, lambda: chaindrive_fmu)
        assert examples.same(examples.mask(now), examples.mask(block["body"])), (
            f"README.md: the example of `$ {block['commands'][0]}` is stale; regenerate it "
            f"with python docs/scripts/cli_examples.py\n--- now:\n{now}")


def test_the_check_sees_a_changed_number_and_ignores_timings():
    body = ("$ chainmodel run xu2010\nstatic tension   607.64 N\n"
            "wall time        1 s  (real-time factor 0.999)\n"
            '{"a": 1.0,\n "wall_time_s": 0.5,\n "real_time_factor": 2.0}\n')
    timing = body.replace("1 s  (real-time factor 0.999)", "2.5 s  (real-time factor 0.4)") \
        .replace('"wall_time_s": 0.5', '"wall_time_s": 0.7')
    assert examples.same(examples.mask(body), examples.mask(timing))
    ratio = "tooth ratio      1.470588235  (exact 25/17 = 1.470588235, error {})\n"
    assert examples.same(examples.mask(ratio.format("3.4e-13")), examples.mask(ratio.format("2e-16")))
    assert not examples.same(examples.mask(ratio.format("6.5e-06")),
                             examples.mask(ratio.format("6.6e-06")))
    for changed in (body.replace("607.64", "607.65"), body.replace('"a": 1.0', '"a": 1.001'),
                    body.replace('"a": 1.0', '"b": 1.0')):
        assert not examples.same(examples.mask(body), examples.mask(changed))


def test_every_subcommand_is_in_the_table():
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    table = CLI_MD.read_text().split("## Conventions")[0]
    listed = set(re.findall(r"^\| `chainmodel ([a-z-]+)", table, re.M))
    assert set(sub.choices) <= listed, set(sub.choices) - listed


def test_readme_library_error_is_the_real_message():
    text = README.read_text()
    shown = re.search(r"^ValueError: (.+)$", text, re.M)[1]
    with pytest.raises(ValueError) as info:
        chainmodel.Drive(n_driver=2, n_driven=18, pitch=0.0254, span_pitches=11,
                         pitch_fraction=0.4)
    assert str(info.value) == shown

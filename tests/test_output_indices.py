"""The outputs are listed once (chainmodel/outputs.py) and the kernels write an output row only
through the positions generated from that list (issue 20, item 2): O_<NAME> is the index of
<name> in OUTPUT_NAMES for every output, and no kernel function that fills a row writes
``out[<number>]``."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from chainmodel import outputs

KERNELS = Path(__file__).resolve().parents[1] / "chainmodel" / "kernels"
#: (kernel module, function) of every function that fills an output row
ROW_WRITERS = (("rk4_loop.py", "fill_outputs"), ("kinematic.py", "level0_outputs"),
               ("multibody_outputs.py", "outputs_row"))


def test_every_output_has_its_generated_index():
    for k, name in enumerate(outputs.OUTPUT_NAMES):
        const = "O_" + name.replace(".", "_").upper()
        assert getattr(outputs, const) == k, const
    assert outputs.N_OUTPUTS == len(outputs.ALL_OUTPUTS) == 15


def _literal_row_writes(source: str, function: str) -> tuple[list[int], list[str]]:
    """(lines writing out[<int>], names used as out[<name>]) in ``function`` of ``source``."""
    tree = ast.parse(source)
    fn = next(n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name == function)
    literal, named = [], []
    for node in ast.walk(fn):
        if (isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store)
                and isinstance(node.value, ast.Name) and node.value.id == "out"):
            if isinstance(node.slice, ast.Constant):
                literal.append(node.lineno)
            elif isinstance(node.slice, ast.Name):
                named.append(node.slice.id)
    return literal, named


def test_the_check_finds_a_literal_index():
    src = "def f(out, x):\n    out[O_A] = x\n    out[3] = x\n"
    assert _literal_row_writes(src, "f") == ([3], ["O_A"])


@pytest.mark.parametrize("module, function", ROW_WRITERS)
def test_kernels_write_outputs_by_generated_index(module, function):
    literal, named = _literal_row_writes((KERNELS / module).read_text(), function)
    assert literal == [], f"{module}:{function} writes out[<number>] on lines {literal}"
    o_names = {n for n in named if n.startswith("O_")}
    assert len(o_names) == len(outputs.OUTPUT_NAMES), sorted(o_names)   # every output written
    assert all(hasattr(outputs, n) for n in o_names)
